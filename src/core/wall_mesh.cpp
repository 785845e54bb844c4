#include "core/wall_mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>

#include "core/layout.hpp"

namespace mc {
namespace {

Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

// Smallest distance from the z axis to a triangle: the distance from the
// origin to its projection on the x–y plane.
double axis_distance(const Triangle& t) {
  const Vec2 p[3] = {{t.v[0].x, t.v[0].y}, {t.v[1].x, t.v[1].y}, {t.v[2].x, t.v[2].y}};
  auto cross2 = [](Vec2 a, Vec2 b, Vec2 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); };
  const Vec2 o{0, 0};
  const double s0 = cross2(p[0], p[1], o), s1 = cross2(p[1], p[2], o), s2 = cross2(p[2], p[0], o);
  if ((s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0)) return 0;  // the axis passes through it
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const Vec2 a = p[k], b = p[(k + 1) % 3];
    const double ex = b.x - a.x, ey = b.y - a.y;
    const double len2 = ex * ex + ey * ey;
    double u = len2 > 0 ? -(a.x * ex + a.y * ey) / len2 : 0;
    u = std::clamp(u, 0.0, 1.0);
    best = std::min(best, std::hypot(a.x + u * ex, a.y + u * ey));
  }
  return best;
}

struct UnionFind {
  std::vector<int> up;
  explicit UnionFind(int n) : up(n) { std::iota(up.begin(), up.end(), 0); }
  int find(int a) {
    while (up[a] != a) a = up[a] = up[up[a]];
    return a;
  }
  void join(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) up[std::max(a, b)] = std::min(a, b);
  }
};

}  // namespace

Vec3 triangle_unit_normal(const Triangle& t) {
  const Vec3 n = cross(t.v[1] - t.v[0], t.v[2] - t.v[0]);
  const double len = n.norm();
  return len > 0 ? n * (1.0 / len) : Vec3{};
}

std::vector<MeshTriangleRef> mesh_device_order(const std::vector<WallMesh>& meshes) {
  std::vector<MeshTriangleRef> out;
  for (int pass = 0; pass < 2; ++pass)
    for (int m = 0; m < static_cast<int>(meshes.size()); ++m)
      if (meshes[m].turning == (pass == 0))
        for (int t = 0; t < static_cast<int>(meshes[m].triangles.size()); ++t) out.push_back({m, t});
  return out;
}

MeshTopology mesh_topology(const std::vector<WallMesh>& meshes) {
  const std::vector<MeshTriangleRef> order = mesh_device_order(meshes);
  MeshTopology topo;
  topo.n_triangles = static_cast<int>(order.size());
  topo.edges.resize(order.size());
  topo.vertices.resize(order.size());
  // Per mesh: welded vertices and edges, numbered in the order they appear.
  // Vertices within 1e-6 of the mesh's size of each other are one (CAD
  // tools write a shared vertex once per triangle, not always to the bit).
  std::vector<double> tol(meshes.size(), 0);
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (const Triangle& t : meshes[m].triangles)
      for (const Vec3& v : t.v) {
        lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
        hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
      }
    tol[m] = meshes[m].triangles.empty() ? 1e-12 : std::max(1e-12, 1e-6 * (hi - lo).norm());
  }
  using Key = std::tuple<long long, long long, long long>;
  std::vector<std::map<Key, std::vector<int>>> buckets(meshes.size());
  std::vector<Vec3> vertex_at;
  std::vector<std::map<std::pair<int, int>, int>> emap(meshes.size());
  std::vector<int> vertex_first_tri, edge_first_tri;
  std::vector<std::vector<int>> edge_tris;
  auto weld = [&](int m, const Vec3& v, int k) {
    const double h = tol[m];
    const long long qx = static_cast<long long>(std::floor(v.x / h)), qy = static_cast<long long>(std::floor(v.y / h)),
                    qz = static_cast<long long>(std::floor(v.z / h));
    for (long long dx = -1; dx <= 1; ++dx)
      for (long long dy = -1; dy <= 1; ++dy)
        for (long long dz = -1; dz <= 1; ++dz) {
          auto it = buckets[m].find({qx + dx, qy + dy, qz + dz});
          if (it == buckets[m].end()) continue;
          for (int id : it->second) {
            const Vec3 d = vertex_at[id] - v;
            if (std::max({std::fabs(d.x), std::fabs(d.y), std::fabs(d.z)}) <= h) return id;
          }
        }
    const int id = topo.n_vertices++;
    vertex_at.push_back(v);
    vertex_first_tri.push_back(k);
    buckets[m][{qx, qy, qz}].push_back(id);
    return id;
  };
  for (int k = 0; k < topo.n_triangles; ++k) {
    const auto [m, t] = order[k];
    const Triangle& tri = meshes[m].triangles[t];
    for (int c = 0; c < 3; ++c) topo.vertices[k][c] = weld(m, tri.v[c], k);
    for (int c = 0; c < 3; ++c) {
      const int a = topo.vertices[k][c], b = topo.vertices[k][(c + 1) % 3];
      auto [it, fresh] = emap[m].try_emplace({std::min(a, b), std::max(a, b)}, topo.n_edges);
      if (fresh) {
        ++topo.n_edges;
        edge_first_tri.push_back(k);
        edge_tris.emplace_back();
      }
      topo.edges[k][c] = it->second;
      edge_tris[it->second].push_back(k);
    }
  }
  // Smooth patches: triangles joined across edges where their normals differ
  // by less than kSmoothDegrees.
  UnionFind uf(topo.n_triangles);
  const double cos_smooth = std::cos(kSmoothDegrees * M_PI / 180.0);
  std::vector<Vec3> normal(topo.n_triangles);
  for (int k = 0; k < topo.n_triangles; ++k)
    normal[k] = triangle_unit_normal(meshes[order[k].mesh].triangles[order[k].triangle]);
  for (const auto& tris : edge_tris)
    for (std::size_t a = 0; a < tris.size(); ++a)
      for (std::size_t b = a + 1; b < tris.size(); ++b)
        if (normal[tris[a]].dot(normal[tris[b]]) > cos_smooth) uf.join(tris[a], tris[b]);
  std::map<int, int> patch_id;
  auto patch_of_tri = [&](int k) {
    auto [it, fresh] = patch_id.try_emplace(uf.find(k), static_cast<int>(patch_id.size()));
    return it->second;
  };
  topo.patch.resize(topo.features());
  for (int k = 0; k < topo.n_triangles; ++k) topo.patch[k] = patch_of_tri(k);
  for (int e = 0; e < topo.n_edges; ++e) topo.patch[topo.n_triangles + e] = patch_of_tri(edge_first_tri[e]);
  for (int v = 0; v < topo.n_vertices; ++v)
    topo.patch[topo.n_triangles + topo.n_edges + v] = patch_of_tri(vertex_first_tri[v]);
  topo.n_patches = static_cast<int>(patch_id.size());
  // The triangles round each edge and vertex.
  std::vector<std::vector<int>> vertex_tris(topo.n_vertices);
  for (int k = 0; k < topo.n_triangles; ++k)
    for (int c = 0; c < 3; ++c) {
      std::vector<int>& v = vertex_tris[topo.vertices[k][c]];
      if (v.empty() || v.back() != k) v.push_back(k);  // a degenerate triangle names a vertex twice
    }
  topo.adj_start.assign(static_cast<std::size_t>(topo.n_triangles) + 1, 0);
  auto append = [&](const std::vector<int>& tris) {
    topo.adj_tris.insert(topo.adj_tris.end(), tris.begin(), tris.end());
    topo.adj_start.push_back(static_cast<int>(topo.adj_tris.size()));
  };
  for (const auto& tris : edge_tris) append(tris);
  for (const auto& tris : vertex_tris) append(tris);
  return topo;
}

// The kernels' own closest point (cl/mesh.h, Ericson §5.1.5), in double.
Vec3 closest_on_triangle(const Triangle& t, const Vec3& p) {
  using f64::real3;
  auto r3 = [](const Vec3& v) { return real3{v.x, v.y, v.z}; };
  int region = 0;
  const real3 q = f64::triangle_closest(r3(p), r3(t.v[0]), r3(t.v[1]), r3(t.v[2]), &region);
  return {q.x, q.y, q.z};
}

bool triangle_near_cell(const Triangle& t, const Vec3& centre, double limit) {
  return (closest_on_triangle(t, centre) - centre).norm() <= limit;
}

MeshGridSpec mesh_grid_spec(const std::vector<Triangle>& tris, double reach) {
  MeshGridSpec g;
  g.reach = reach;
  g.n_triangles = static_cast<int>(tris.size());
  if (tris.empty()) {
    g.nx = g.ny = g.nz = 1;
    g.cell = 1;
    return g;
  }
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const Triangle& t : tris)
    for (const Vec3& v : t.v) {
      lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
      hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
    }
  const Vec3 grow{reach, reach, reach};
  lo = lo - grow;
  hi = hi + grow;
  const Vec3 span = hi - lo;
  double cell = std::max(reach, 1e-6);
  auto count = [&](double c) {
    return std::max(1.0, std::ceil(span.x / c)) * std::max(1.0, std::ceil(span.y / c)) *
           std::max(1.0, std::ceil(span.z / c));
  };
  while (count(cell) > static_cast<double>(kMaxMeshCells)) cell *= 1.25;
  g.cell = cell;
  g.origin = lo;
  g.nx = static_cast<int>(std::max(1.0, std::ceil(span.x / cell)));
  g.ny = static_cast<int>(std::max(1.0, std::ceil(span.y / cell)));
  g.nz = static_cast<int>(std::max(1.0, std::ceil(span.z / cell)));

  // The core: a cylinder about the axis that no triangle comes within reach
  // of. Two candidates, the larger kept: all triangles held off by radius;
  // or the triangles wholly below (above) the middle of the set held off by
  // the core's lower (upper) end and the rest by radius (cone ends and end
  // lifters at the ends, liners and lifters along the length).
  const double z_mid = 0.5 * (lo.z + hi.z);
  double r_all = 1e300, r_across = 1e300, z0 = -1e300, z1 = 1e300;
  for (const Triangle& t : tris) {
    const double rho = axis_distance(t);
    const double tz0 = std::min({t.v[0].z, t.v[1].z, t.v[2].z});
    const double tz1 = std::max({t.v[0].z, t.v[1].z, t.v[2].z});
    r_all = std::min(r_all, rho - reach);
    if (tz1 < z_mid) z0 = std::max(z0, tz1 + reach);
    else if (tz0 > z_mid) z1 = std::min(z1, tz0 - reach);
    else r_across = std::min(r_across, rho - reach);
  }
  const double radius_span = std::max(span.x, span.y);
  const double r_b = std::min(r_across, radius_span);
  const double vol_all = r_all > 0 ? r_all * r_all * span.z : 0;
  const double vol_b = r_b > 0 && z1 > z0 ? r_b * r_b * (std::min(z1, hi.z) - std::max(z0, lo.z)) : 0;
  if (vol_b > vol_all) {
    g.core_r2 = r_b * r_b;
    g.core_z0 = z0;
    g.core_z1 = z1;
  } else {
    g.core_r2 = r_all > 0 ? r_all * r_all : 0;
    g.core_z0 = -1e30;
    g.core_z1 = 1e30;
  }
  return g;
}

void mesh_bin_host(const MeshGridSpec& g, const std::vector<Triangle>& tris, int first, std::vector<int>& starts,
                   std::vector<int>& out) {
  const long n_cells = g.cells();
  std::vector<std::vector<int>> cells(static_cast<std::size_t>(n_cells));
  const double limit = g.reach + 0.5 * std::sqrt(3.0) * g.cell * (1 + 1e-4);
  for (int k = 0; k < static_cast<int>(tris.size()); ++k) {
    const Triangle& t = tris[k];
    Vec3 lo = t.v[0], hi = t.v[0];
    for (const Vec3& v : t.v) {
      lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
      hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
    }
    auto range = [&](double a, double b, double o, int n, int& c0, int& c1) {
      c0 = std::clamp(static_cast<int>(std::floor((a - g.reach - o) / g.cell)), 0, n - 1);
      c1 = std::clamp(static_cast<int>(std::floor((b + g.reach - o) / g.cell)), 0, n - 1);
    };
    int x0, x1, y0, y1, z0, z1;
    range(lo.x, hi.x, g.origin.x, g.nx, x0, x1);
    range(lo.y, hi.y, g.origin.y, g.ny, y0, y1);
    range(lo.z, hi.z, g.origin.z, g.nz, z0, z1);
    for (int cz = z0; cz <= z1; ++cz)
      for (int cy = y0; cy <= y1; ++cy)
        for (int cx = x0; cx <= x1; ++cx) {
          const Vec3 centre{g.origin.x + (cx + 0.5) * g.cell, g.origin.y + (cy + 0.5) * g.cell,
                            g.origin.z + (cz + 0.5) * g.cell};
          if (triangle_near_cell(t, centre, limit))
            cells[(static_cast<std::size_t>(cz) * g.ny + cy) * g.nx + cx].push_back(first + k);
        }
  }
  starts.assign(static_cast<std::size_t>(n_cells) + 1, 0);
  out.clear();
  for (long c = 0; c < n_cells; ++c) {
    starts[c] = static_cast<int>(out.size());
    out.insert(out.end(), cells[c].begin(), cells[c].end());
  }
  starts[n_cells] = static_cast<int>(out.size());
}

double closed_mesh_volume(const std::vector<Triangle>& tris) {
  std::map<std::tuple<double, double, double>, int> vid;
  std::map<std::pair<int, int>, int> edges;
  double v6 = 0;
  for (const Triangle& t : tris) {
    int id[3];
    for (int c = 0; c < 3; ++c) id[c] = vid.try_emplace({t.v[c].x, t.v[c].y, t.v[c].z}, static_cast<int>(vid.size())).first->second;
    for (int c = 0; c < 3; ++c) ++edges[{std::min(id[c], id[(c + 1) % 3]), std::max(id[c], id[(c + 1) % 3])}];
    v6 += t.v[0].dot(cross(t.v[1], t.v[2]));
  }
  for (const auto& [e, n] : edges)
    if (n != 2) return 0;
  return std::fabs(v6) / 6;
}

double cone_depth(const EndsSpec& e, double R) {
  return e.cones() ? (R - 0.5 * e.trunnion_diameter) * std::tan(e.cone_angle_deg * M_PI / 180.0) : 0.0;
}

std::vector<Triangle> cone_triangles(const EndsSpec& e, double R, double L, int segments) {
  std::vector<Triangle> out;
  if (!e.cones()) return out;
  const double rt = 0.5 * e.trunnion_diameter, depth = cone_depth(e, R);
  // Rings about as far apart along the cone as the facets are wide at the
  // shell, at least 4.
  const double slant = std::hypot(R - rt, depth);
  const int rings = std::max(4, static_cast<int>(std::ceil(slant / (2 * M_PI * R / segments))));
  auto at = [&](double rho, double th, double z) { return Vec3{rho * std::cos(th), rho * std::sin(th), z}; };
  for (int end = 0; end < 2; ++end) {
    // Feed end: z from 0 (ρ = R) to −depth (ρ = rt); discharge end mirrored.
    auto z_of = [&](double rho) {
      const double d = (R - rho) / (R - rt) * depth;
      return end == 0 ? -d : L + d;
    };
    for (int k = 0; k < segments; ++k) {
      const double t0 = 2 * M_PI * k / segments, t1 = 2 * M_PI * (k + 1) / segments;
      for (int j = 0; j < rings; ++j) {
        const double r0 = R - (R - rt) * j / rings, r1 = R - (R - rt) * (j + 1) / rings;
        const Vec3 a = at(r0, t0, z_of(r0)), b = at(r0, t1, z_of(r0)), c = at(r1, t1, z_of(r1)),
                   d = at(r1, t0, z_of(r1));
        // Facing the charge: into the mill (+z at the feed end) and towards the axis.
        if (end == 0) {
          out.push_back({{a, b, c}});
          out.push_back({{a, c, d}});
        } else {
          out.push_back({{a, c, b}});
          out.push_back({{a, d, c}});
        }
      }
      // The trunnion's disc, closing the opening.
      const Vec3 o{0, 0, z_of(rt)}, p0 = at(rt, t0, z_of(rt)), p1 = at(rt, t1, z_of(rt));
      if (end == 0) out.push_back({{o, p0, p1}});
      else out.push_back({{o, p1, p0}});
    }
  }
  return out;
}

std::vector<Triangle> end_lifter_triangles(const EndsSpec& e, double R, double L) {
  std::vector<Triangle> out;
  if (e.lifter_rows <= 0) return out;
  const double r_in = e.lifter_inner_diameter > 0 ? 0.5 * e.lifter_inner_diameter
                      : e.cones()                 ? 0.5 * e.trunnion_diameter
                                                  : R / 3;
  const double depth = cone_depth(e, R);
  const double rt = 0.5 * e.trunnion_diameter;
  for (int end = 0; end < 2; ++end) {
    const double sign = end == 0 ? 1.0 : -1.0;  // into the mill along z
    for (int k = 0; k < e.lifter_rows; ++k) {
      const double th = e.lifter_first_angle_deg * M_PI / 180.0 + 2 * M_PI * k / e.lifter_rows;
      const Vec3 rad{std::cos(th), std::sin(th), 0}, tan{-std::sin(th), std::cos(th), 0};
      // The end's surface along the bar: z(ρ), and its normal into the mill.
      auto surf = [&](double rho) {
        const double d = e.cones() ? (R - rho) / (R - rt) * depth : 0.0;
        return rad * rho + Vec3{0, 0, end == 0 ? -d : L + d};
      };
      // From just inside the shell (the bar's corners on it) towards the axis.
      const double r_out = std::sqrt(std::max(0.0, R * R - 0.25 * e.lifter_width * e.lifter_width)) * (1 - 1e-9);
      const Vec3 along = surf(r_in) - surf(r_out);
      const double len = along.norm();
      const Vec3 u = along * (1.0 / len);
      // Normal into the mill: perpendicular to u in the plane of rad and z.
      Vec3 n = Vec3{0, 0, sign} - u * Vec3{0, 0, sign}.dot(u);
      n = n * (1.0 / n.norm());
      const double hw = 0.5 * e.lifter_width, h = e.lifter_height;
      // The box's corners: c[i] for (along 0/1, side −/+, height 0/1).
      Vec3 c[8];
      for (int i = 0; i < 8; ++i) {
        const double a = (i & 1) ? len : 0.0, v = (i & 2) ? hw : -hw, w = (i & 4) ? h : 0.0;
        c[i] = surf(r_out) + u * a + tan * v + n * w;
      }
      // Each face as two triangles turned to face out of the box.
      Vec3 centre{};
      for (const Vec3& p : c) centre = centre + p * 0.125;
      const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
      for (const auto& q : quads) {
        const Vec3 mid = (c[q[0]] + c[q[1]] + c[q[2]] + c[q[3]]) * 0.25;
        for (Triangle t : {Triangle{{c[q[0]], c[q[1]], c[q[2]]}}, Triangle{{c[q[0]], c[q[2]], c[q[3]]}}}) {
          if (triangle_unit_normal(t).dot(mid - centre) < 0) std::swap(t.v[1], t.v[2]);
          out.push_back(t);
        }
      }
    }
  }
  return out;
}

void check_meshes(const Walls& w) {
  const double r_tol = w.shell_radius * 1e-3;
  const double z_tol = std::max(1e-6, w.length * 1e-6);
  for (const WallMesh& m : w.meshes) {
    if (m.triangles.empty()) throw std::invalid_argument(m.name + ": the mesh has no triangles");
    for (std::size_t k = 0; k < m.triangles.size(); ++k) {
      const Triangle& t = m.triangles[k];
      const std::string at = m.name + ": triangle " + std::to_string(k + 1);
      for (const Vec3& v : t.v) {
        if (!(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z)))
          throw std::invalid_argument(at + " has a vertex that is not a finite number");
        const double rho = std::hypot(v.x, v.y);
        if (w.shell_radius > 0 && rho > w.shell_radius + r_tol) {
          char buf[200];
          std::snprintf(buf, sizeof buf,
                        " lies outside the mill: a vertex at %.4g m from the axis, the shell's inside radius is "
                        "%.4g m (check walls.mesh units, offset and angle)",
                        rho, w.shell_radius);
          throw std::invalid_argument(at + buf);
        }
        if (w.length > 0 && w.has_end_plates() && (v.z < -z_tol || v.z > w.length + z_tol)) {
          char buf[200];
          std::snprintf(buf, sizeof buf,
                        " lies outside the mill: a vertex at z = %.4g m, the end plates are at z = 0 and %.4g m "
                        "(check walls.mesh units and offset)",
                        v.z, w.length);
          throw std::invalid_argument(at + buf);
        }
        if (w.periodic && (v.z < -z_tol || v.z > w.length + z_tol)) {
          char buf[200];
          std::snprintf(buf, sizeof buf, " lies outside the slice: a vertex at z = %.4g m, the slice is 0 to %.4g m",
                        v.z, w.length);
          throw std::invalid_argument(at + buf);
        }
      }
      if (w.periodic) {
        // A slice repeats along the axis: its meshes must too. Triangles
        // along the axis (normal across it) are; caps on the seams are
        // dropped by the reader; anything else would end inside the slice.
        const Vec3 n = triangle_unit_normal(t);
        if (std::fabs(n.z) > 1e-3)
          throw std::invalid_argument(
              at + " does not run along the axis (its normal has an axial part " + std::to_string(n.z) +
              "): a periodic slice (mill.ends = \"periodic\") takes only meshes that are the same all along it, "
              "such as lifter bars extruded over the slice");
      }
    }
    // A liner (bars, a shell's plates, a scan) faces the charge, and so
    // the axis, where it comes nearest it: in each connected part (a bar,
    // a plate, a scan), the triangles round its innermost vertex, their
    // area vectors summed, point toward the axis. A part wound inside out
    // points them at the shell: every triangle of it would be touched from
    // behind (no contact: a hole) and a life study would wear it outward.
    // A part whose innermost vertex is within a thousandth of the shell's
    // radius of the axis has no direction to the axis there, and one whose
    // innermost vertex is a corner of one triangle only has no surface
    // round it: not checked.
    if (m.part == MeshPart::ends) continue;
    std::map<std::tuple<double, double, double>, int> index;
    std::vector<const Vec3*> at;
    std::vector<std::array<int, 3>> corner(m.triangles.size());
    for (std::size_t k = 0; k < m.triangles.size(); ++k)
      for (int j = 0; j < 3; ++j) {
        const Vec3& v = m.triangles[k].v[j];
        const auto [it, fresh] = index.emplace(std::make_tuple(v.x, v.y, v.z), static_cast<int>(at.size()));
        if (fresh) at.push_back(&v);
        corner[k][j] = it->second;
      }
    UnionFind parts(static_cast<int>(at.size()));
    for (const auto& c : corner) parts.join(c[0], c[1]), parts.join(c[0], c[2]);
    std::map<int, int> inner;  // part: its innermost vertex
    for (int v = 0; v < static_cast<int>(at.size()); ++v) {
      const auto [it, fresh] = inner.emplace(parts.find(v), v);
      if (!fresh && std::hypot(at[v]->x, at[v]->y) < std::hypot(at[it->second]->x, at[it->second]->y)) it->second = v;
    }
    std::map<int, Vec3> round;  // innermost vertex: the area vectors round it
    std::map<int, int> size;    // part: its triangles
    for (const auto& [part, v] : inner) round[v] = Vec3{};
    for (std::size_t k = 0; k < m.triangles.size(); ++k) {
      ++size[parts.find(corner[k][0])];
      for (int j = 0; j < 3; ++j) {
        const auto it = round.find(corner[k][j]);
        if (it != round.end()) {
          const Triangle& t = m.triangles[k];
          it->second = it->second + cross(t.v[1] - t.v[0], t.v[2] - t.v[0]);
        }
      }
    }
    const Vec3* nearest = nullptr;  // the innermost vertex of the part wound inside out that comes nearest
    std::size_t turned = 0, checked = 0;
    for (const auto& [v, n] : round) {
      const Vec3& p = *at[v];
      const double rho = std::hypot(p.x, p.y);
      // A lone triangle (a file whose triangles share no corner) has no
      // surface round its corner to tell a side from: not checked.
      if (!(rho > 1e-3 * w.shell_radius) || !(rho > 0) || size[parts.find(v)] < 2) continue;
      ++checked;
      if (!(-(n.x * p.x + n.y * p.y) / rho > 0)) {
        ++turned;
        if (!nearest || rho < std::hypot(nearest->x, nearest->y)) nearest = &p;
      }
    }
    if (turned > 0) {
      const std::size_t skipped = round.size() - checked;
      const std::string which = turned == checked && skipped == 0
                                    ? std::string("the mesh comes")
                                    : std::to_string(turned) + " of its " + std::to_string(round.size()) +
                                          (turned == 1 ? " parts comes" : " parts come");
      const std::string unchecked =
          skipped > 0 ? "; " + std::to_string(skipped) + " not checked (lone triangles, or at the axis)" : std::string();
      char buf[640];
      std::snprintf(buf, sizeof buf,
                    ": its triangles face away from the axis where %s nearest it (x %.4g, y %.4g, z %.4g m, "
                    "%.4g m from the axis): wound inside out for a liner, whose charge side faces the axis (a "
                    "triangle is touched only from the side its normal faces)%s; %s",
                    which.c_str(), nearest->x, nearest->y, nearest->z, std::hypot(nearest->x, nearest->y),
                    unchecked.c_str(),
                    turned == checked ? "toggle the mesh's flip key (it turns every triangle of the file)"
                                      : "export those parts the other way round (the mesh's flip key turns every "
                                        "triangle of the file)");
      throw std::invalid_argument(m.name + buf);
    }
  }
}

}  // namespace mc
