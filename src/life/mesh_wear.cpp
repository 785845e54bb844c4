// A mesh liner worn by its booked wear (mesh_wear.h).
#include "life/mesh_wear.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

namespace mc::life {

namespace {

Vec3 cross(const Vec3& a, const Vec3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

// Twice the triangle's area along its normal (the unnormalised normal).
Vec3 area_vector(const Vec3& a, const Vec3& b, const Vec3& c) { return cross(b - a, c - a); }

// Six times the signed volume of the tetrahedron (o, a, b, c).
double tet6(const Vec3& a, const Vec3& b, const Vec3& c) { return a.dot(cross(b, c)); }

// The normals of triangles that meet at less than this angle count as one
// direction: a crease sharper than it is an edge whose faces each keep
// their own depth.
constexpr double kCreaseDegrees = 13.0;

// x with M x = b over the eigen-directions of the symmetric M whose
// eigenvalue is at least sin²(crease) of the largest (Jacobi rotations);
// the others, where the normals around a vertex hardly differ, left out.
Vec3 crease_solve(std::array<double, 9> a, const Vec3& b) {
  double v[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int sweep = 0; sweep < 50; ++sweep) {
    const double off = a[1] * a[1] + a[2] * a[2] + a[5] * a[5];
    if (off < 1e-30 * (a[0] * a[0] + a[4] * a[4] + a[8] * a[8]) || off == 0) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        const double apq = a[3 * p + q];
        if (apq == 0) continue;
        const double theta = 0.5 * (a[3 * q + q] - a[3 * p + p]) / apq;
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double c = 1 / std::sqrt(t * t + 1), s = t * c;
        for (int k = 0; k < 3; ++k) {  // a = Jᵀ a J
          const double akp = a[3 * k + p], akq = a[3 * k + q];
          a[3 * k + p] = c * akp - s * akq, a[3 * k + q] = s * akp + c * akq;
        }
        for (int k = 0; k < 3; ++k) {
          const double apk = a[3 * p + k], aqk = a[3 * q + k];
          a[3 * p + k] = c * apk - s * aqk, a[3 * q + k] = s * apk + c * aqk;
        }
        for (int k = 0; k < 3; ++k) {
          const double vkp = v[3 * k + p], vkq = v[3 * k + q];
          v[3 * k + p] = c * vkp - s * vkq, v[3 * k + q] = s * vkp + c * vkq;
        }
      }
  }
  const double top = std::max({a[0], a[4], a[8]});
  const double floor = top * std::pow(std::sin(kCreaseDegrees * 3.14159265358979323846 / 180), 2);
  const double bb[3] = {b.x, b.y, b.z};
  double x[3] = {0, 0, 0};
  for (int e = 0; e < 3; ++e) {
    const double lambda = a[4 * e];
    if (!(lambda > floor) || !(lambda > 0)) continue;
    double proj = 0;
    for (int k = 0; k < 3; ++k) proj += v[3 * k + e] * bb[k];
    for (int k = 0; k < 3; ++k) x[k] += v[3 * k + e] * proj / lambda;
  }
  return {x[0], x[1], x[2]};
}


// Vertices free to slide when the mesh is relaxed: no two normals of the
// triangles round them differ by more than this (a face of a bar, the
// shell, a corner the wear has rounded); the others (a bar's sharp edges
// and corners) stay put, as do vertices on an open edge of the mesh (a
// scan's rim, where it meets the shell) and those more than a few edges
// from a spoiled triangle.
constexpr double kRelaxSmoothDegrees = 50.0;
constexpr int kRelaxPasses = 40;
constexpr int kRelaxRings = 3;

// Tangential relaxation round the spoiled triangles: each free vertex
// slides toward the centroid of its neighbours (those it shares an edge
// with), within the plane normal to the unworn surface there, half the way
// per pass; a vertex on an end plane slides within it. `at`: the worn
// positions. Returns each vertex's slide from them.
std::vector<Vec3> relax_slides(const WeldedMesh& w, const std::vector<Vec3>& at, const std::vector<char>& bad_triangle,
                               const MeshBounds& bounds, int& moved) {
  const std::size_t nv = w.points.size();
  std::vector<Vec3> normal(nv);
  std::vector<std::vector<Vec3>> around(nv);
  std::vector<std::vector<int>> next(nv);
  std::map<std::pair<int, int>, int> edge_uses;
  for (const auto& c : w.corners) {
    const Vec3 av = area_vector(w.points[c[0]], w.points[c[1]], w.points[c[2]]);
    const double a = av.norm();
    for (int k = 0; k < 3; ++k) {
      normal[c[k]] = normal[c[k]] + av;
      if (a > 0) around[c[k]].push_back(av * (1 / a));
      const int o = c[(k + 1) % 3];
      ++edge_uses[{std::min(c[k], o), std::max(c[k], o)}];
      for (int j = 1; j < 3; ++j) {
        const int u = c[(k + j) % 3];
        if (std::find(next[c[k]].begin(), next[c[k]].end(), u) == next[c[k]].end()) next[c[k]].push_back(u);
      }
    }
  }
  const double cos_smooth = std::cos(kRelaxSmoothDegrees * 3.14159265358979323846 / 180);
  // Near a spoiled triangle: its corners and the vertices a few edges on.
  std::vector<char> near(nv, 0);
  for (std::size_t t = 0; t < w.corners.size(); ++t)
    if (bad_triangle[t])
      for (int v : w.corners[t]) near[v] = 1;
  for (int ring = 0; ring < kRelaxRings; ++ring) {
    std::vector<char> grown = near;
    for (std::size_t i = 0; i < nv; ++i)
      if (near[i])
        for (int o : next[i]) grown[o] = 1;
    near.swap(grown);
  }
  std::vector<char> free(nv, 0);
  for (std::size_t i = 0; i < nv; ++i) {
    const double len = normal[i].norm();
    if (!near[i] || !(len > 0) || next[i].empty()) continue;
    // The plane it slides in: the unworn surface's there (a face worn
    // back parallel to itself has the same; the slides are measured from
    // the unworn mesh, and what they sweep counts in the scale).
    normal[i] = normal[i] * (1 / len);
    bool smooth = true;
    for (std::size_t a = 0; a < around[i].size() && smooth; ++a)
      for (std::size_t b = a + 1; b < around[i].size() && smooth; ++b) smooth = around[i][a].dot(around[i][b]) >= cos_smooth;
    free[i] = smooth;
  }
  // An open edge holds its ends (a scan's rim on the shell stays there),
  // but for one that lies in an end plane: its ends slide within it.
  auto end_plane = [&](int v) {
    if (!(bounds.z1 > bounds.z0)) return 0;
    return std::abs(w.points[v].z - bounds.z0) <= bounds.on_end ? 1 : std::abs(w.points[v].z - bounds.z1) <= bounds.on_end ? 2 : 0;
  };
  for (const auto& [e, uses] : edge_uses)
    if (uses < 2 && !(end_plane(e.first) > 0 && end_plane(e.first) == end_plane(e.second)))
      free[e.first] = free[e.second] = 0;
  std::vector<Vec3> q = at;
  for (int pass = 0; pass < kRelaxPasses; ++pass) {
    std::vector<Vec3> step(nv);
    for (std::size_t i = 0; i < nv; ++i) {
      if (!free[i]) continue;
      Vec3 c{};
      for (int o : next[i]) c = c + q[o];
      Vec3 d = c * (1.0 / static_cast<double>(next[i].size())) - q[i];
      d = d - normal[i] * normal[i].dot(d);
      if (bounds.z1 > bounds.z0 &&
          (std::abs(w.points[i].z - bounds.z0) <= bounds.on_end || std::abs(w.points[i].z - bounds.z1) <= bounds.on_end))
        d.z = 0;
      step[i] = d * 0.5;
    }
    for (std::size_t i = 0; i < nv; ++i) q[i] = q[i] + step[i];
  }
  std::vector<Vec3> slide(nv);
  moved = 0;
  for (std::size_t i = 0; i < nv; ++i) {
    slide[i] = q[i] - at[i];
    moved += slide[i].norm() > 1e-6;
  }
  return slide;
}

// Triangles the worn mesh turns over or crushes below `share` of their area.
int spoiled(const std::vector<Triangle>& before, const std::vector<Triangle>& after, double share) {
  int n = 0;
  for (std::size_t t = 0; t < before.size(); ++t) {
    const auto& a = before[t].v;
    const auto& b = after[t].v;
    const Vec3 na = area_vector(a[0], a[1], a[2]), nb = area_vector(b[0], b[1], b[2]);
    n += nb.dot(na) <= 0 || nb.norm() < share * na.norm();
  }
  return n;
}

}  // namespace

WeldedMesh weld(const std::vector<Triangle>& triangles) {
  WeldedMesh w;
  std::map<std::tuple<double, double, double>, int> index;
  for (const Triangle& t : triangles) {
    std::array<int, 3> c{};
    for (int k = 0; k < 3; ++k) {
      const auto key = std::make_tuple(t.v[k].x, t.v[k].y, t.v[k].z);
      auto [it, fresh] = index.emplace(key, static_cast<int>(w.points.size()));
      if (fresh) w.points.push_back(t.v[k]);
      c[k] = it->second;
    }
    w.corners.push_back(c);
  }
  return w;
}

std::vector<std::vector<int>> connected_parts(const std::vector<Triangle>& triangles) {
  const WeldedMesh w = weld(triangles);
  std::vector<int> up(w.points.size());
  for (std::size_t i = 0; i < up.size(); ++i) up[i] = static_cast<int>(i);
  auto root = [&](int i) {
    while (up[i] != i) i = up[i] = up[up[i]];
    return i;
  };
  for (const auto& c : w.corners)
    for (int k = 1; k < 3; ++k) up[root(c[k])] = root(c[0]);
  std::vector<std::vector<int>> parts;
  std::map<int, std::size_t> part_of;  // root to part
  for (std::size_t t = 0; t < w.corners.size(); ++t) {
    auto [it, fresh] = part_of.emplace(root(w.corners[t][0]), parts.size());
    if (fresh) parts.emplace_back();
    parts[it->second].push_back(static_cast<int>(t));
  }
  return parts;
}

std::vector<double> smooth_wear(const std::vector<Triangle>& triangles, const std::vector<double>& volume_m3,
                                double across, double along) {
  const std::size_t nt = triangles.size();
  if (!(across > 0) || nt == 0) return volume_m3;
  if (!(along > 0)) along = across;
  std::vector<int> part(nt, 0);
  {
    const std::vector<std::vector<int>> parts = connected_parts(triangles);
    for (std::size_t p = 0; p < parts.size(); ++p)
      for (int t : parts[p]) part[t] = static_cast<int>(p);
  }
  std::vector<Vec3> centre(nt), unit(nt);
  std::vector<double> area(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& v = triangles[t].v;
    centre[t] = (v[0] + v[1] + v[2]) * (1.0 / 3.0);
    const Vec3 av = area_vector(v[0], v[1], v[2]);
    area[t] = 0.5 * av.norm();
    unit[t] = area[t] > 0 ? av * (0.5 / area[t]) : Vec3{};
  }
  // Cells of three standard deviations: the neighbours within them.
  const double cx = 3 * across, cz = 3 * along;
  using Cell = std::tuple<long, long, long>;
  auto cell_of = [&](const Vec3& p) {
    return Cell{static_cast<long>(std::floor(p.x / cx)), static_cast<long>(std::floor(p.y / cx)),
                static_cast<long>(std::floor(p.z / cz))};
  };
  std::map<Cell, std::vector<int>> cells;
  for (std::size_t t = 0; t < nt; ++t) cells[cell_of(centre[t])].push_back(static_cast<int>(t));
  const double cos_limit = std::cos(30.0 * 3.14159265358979323846 / 180);
  // Each triangle's volume shared out over the triangles around it (those
  // of its part within 30° of its normal), in proportion to their areas
  // times the Gaussian of the distance: every triangle's volume is kept,
  // and so every part's and every face's.
  auto each_neighbour = [&](std::size_t t, auto&& f) {
    const auto [ix, iy, iz] = cell_of(centre[t]);
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          const auto it = cells.find(Cell{ix + dx, iy + dy, iz + dz});
          if (it == cells.end()) continue;
          for (int u : it->second) {
            if (part[u] != part[t] || unit[u].dot(unit[t]) < cos_limit) continue;
            const Vec3 d = centre[u] - centre[t];
            f(u, area[u] * std::exp(-0.5 * ((d.x * d.x + d.y * d.y) / (across * across) + d.z * d.z / (along * along))));
          }
        }
  };
  std::vector<double> out(nt, 0.0);
  for (std::size_t t = 0; t < nt; ++t) {
    if (volume_m3[t] == 0 || !std::isfinite(volume_m3[t])) continue;  // a negative one spreads as well
    double weight = 0;
    each_neighbour(t, [&](int, double w) { weight += w; });
    if (!(weight > 0)) {  // a triangle of no area keeps its own
      out[t] += volume_m3[t];
      continue;
    }
    each_neighbour(t, [&](int u, double w) { out[u] += volume_m3[t] * w / weight; });
  }
  return out;
}

double swept_volume(const std::vector<Triangle>& before, const std::vector<Triangle>& after) {
  double v = 0;
  for (double x : swept_volumes(before, after)) v += x;
  return v;
}

std::vector<double> swept_volumes(const std::vector<Triangle>& before, const std::vector<Triangle>& after) {
  // The closed solid between each triangle and its moved self: the old
  // triangle (facing out of the solid, as it faced the charge), the new
  // one reversed, and the three sides, each a quad cut in two. Summed by
  // the divergence theorem; the sides of neighbours cancel.
  if (after.size() != before.size())
    throw std::invalid_argument(fmt::format("swept_volumes: {} triangles moved to {}: not the same mesh corner for corner",
                                            before.size(), after.size()));
  std::vector<double> out(before.size());
  for (std::size_t i = 0; i < before.size(); ++i) {
    double v6 = 0;
    const auto& a = before[i].v;
    const auto& b = after[i].v;
    v6 += tet6(a[0], a[1], a[2]);
    v6 -= tet6(b[0], b[1], b[2]);
    for (int k = 0; k < 3; ++k) {
      const int n = (k + 1) % 3;
      // The side over edge (a_k, a_n): a_k, b_k, b_n, a_n, wound outward,
      // cut along the diagonal from the edge's lesser end (by coordinates),
      // so that the neighbour across the edge cuts its side the same way
      // and the two cancel.
      const auto key = [](const Vec3& p) { return std::make_tuple(p.x, p.y, p.z); };
      if (key(a[k]) < key(a[n])) v6 += tet6(a[k], b[k], b[n]) + tet6(a[k], b[n], a[n]);
      else v6 += tet6(a[k], b[k], a[n]) + tet6(b[k], b[n], a[n]);
    }
    out[i] = v6 / 6.0;
  }
  return out;
}

MeshWear wear_mesh(const std::vector<Triangle>& triangles, const std::vector<double>& volume_m3,
                   const MeshBounds& bounds, int smoothing, const std::string& name, bool relax) {
  if (volume_m3.size() != triangles.size())
    throw std::invalid_argument(fmt::format("{}: {} wear volumes for {} triangles", name, volume_m3.size(),
                                            triangles.size()));
  const WeldedMesh w = weld(triangles);
  const std::size_t nv = w.points.size(), nt = triangles.size();
  std::vector<Vec3> unit(nt);            // each triangle's unit normal
  std::vector<double> area(nt, 0.0), depth(nt, 0.0);
  MeshWear out;
  for (std::size_t t = 0; t < nt; ++t) {
    const double v = volume_m3[t];
    if (!(std::isfinite(v) && v >= 0))
      throw std::invalid_argument(fmt::format("{}: triangle {}: wear volume {} is not a volume (finite, >= 0)", name,
                                              t + 1, v));
    out.booked_m3 += v;
    const auto& c = w.corners[t];
    const Vec3 av = area_vector(w.points[c[0]], w.points[c[1]], w.points[c[2]]);
    area[t] = 0.5 * av.norm();
    unit[t] = area[t] > 0 ? av * (0.5 / area[t]) : Vec3{};
    depth[t] = area[t] > 0 ? v / area[t] : 0.0;
  }
  // Smoothing: each pass averages a triangle's depth with the mean of its
  // neighbours' (those it shares a vertex with), weighed by their areas.
  if (smoothing > 0) {
    std::vector<std::vector<int>> at_vertex(nv);
    for (std::size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) at_vertex[w.corners[t][k]].push_back(static_cast<int>(t));
    for (int pass = 0; pass < smoothing; ++pass) {
      std::vector<double> next(nt);
      for (std::size_t t = 0; t < nt; ++t) {
        double sum = 0, weight = 0;
        for (int k = 0; k < 3; ++k)
          for (int u : at_vertex[w.corners[t][k]])
            if (u != static_cast<int>(t)) sum += area[u] * depth[u], weight += area[u];
        next[t] = weight > 0 ? 0.5 * (depth[t] + sum / weight) : depth[t];
      }
      depth.swap(next);
    }
    out.smoothing = smoothing;
  }
  // Each vertex's move: the least-squares offset that takes each triangle
  // around it its own depth along its normal, sum a (n.x + d)^2 least,
  // over the directions in which the triangles' normals differ by more
  // than a crease (a flat or gently curved patch moves along its mean
  // normal; an edge or a corner moves each face by its own depth, so that
  // a worn top leaves its unworn sides where they are).
  std::vector<Vec3> move(nv);
  {
    std::vector<std::array<double, 9>> m(nv, std::array<double, 9>{});
    std::vector<Vec3> b(nv);
    for (std::size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) {
        const int i = w.corners[t][k];
        const Vec3& n = unit[t];
        const double nn[3] = {n.x, n.y, n.z};
        for (int r = 0; r < 3; ++r)
          for (int q = 0; q < 3; ++q) m[i][3 * r + q] += area[t] * nn[r] * nn[q];
        b[i] = b[i] + n * (area[t] * depth[t]);
      }
    for (std::size_t i = 0; i < nv; ++i) move[i] = crease_solve(m[i], b[i]) * -1.0;
    // A vertex on an end plane stays on it: its move along the axis (a
    // rounding of the least squares where the faces around it lean a
    // little after earlier wear) is dropped.
    if (bounds.z1 > bounds.z0)
      for (std::size_t i = 0; i < nv; ++i)
        if (std::abs(w.points[i].z - bounds.z0) <= bounds.on_end || std::abs(w.points[i].z - bounds.z1) <= bounds.on_end)
          move[i].z = 0;
  }
  // Each vertex's slide along the surface (tangential relaxation, below):
  // none unless the move spoils a triangle.
  std::vector<Vec3> slide(nv);
  auto moved = [&](double scale) {
    std::vector<Triangle> m(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int i = w.corners[t][k];
        m[t].v[k] = w.points[i] + move[i] * scale + slide[i];
      }
    return m;
  };
  // The depth scale whose swept volume is the booked one: the swept volume
  // grows with the scale (a surface moved further into the liner), to
  // first order in proportion.
  double scale = 1;
  std::vector<Triangle> worn;
  auto fit_scale = [&] {
    scale = 1;
    worn = moved(scale);
    if (!(out.booked_m3 > 0)) return;
    // At scale 0 the slides alone (none unless relaxed): what they sweep
    // counts with the move's. The scale is bracketed (doubled until the
    // move removes the booked volume) and found by regula falsi (Illinois).
    double s0 = 0, v0 = swept_volume(triangles, moved(0)), s1 = 1, v1 = swept_volume(triangles, worn);
    for (int it = 0; it < 16 && v1 < out.booked_m3; ++it) s0 = s1, v0 = v1, s1 *= 2, v1 = swept_volume(triangles, moved(s1));
    const double tol = 1e-12 * out.booked_m3;
    if (v0 <= out.booked_m3 && v1 >= out.booked_m3) {
      // f0, f1 the residuals the steps use (Illinois halves one where the
      // same end stays twice); the best point is chosen on true residuals.
      double f0 = v0 - out.booked_m3, f1 = v1 - out.booked_m3;
      double best_s = std::abs(f0) < std::abs(f1) ? s0 : s1, best_f = std::min(std::abs(f0), std::abs(f1));
      int side = 0;
      for (int it = 0; it < 100 && best_f > tol; ++it) {
        const double sm = f1 != f0 ? s1 - f1 * (s1 - s0) / (f1 - f0) : 0.5 * (s0 + s1);
        const double fm = swept_volume(triangles, moved(sm)) - out.booked_m3;
        if (std::abs(fm) < best_f) best_f = std::abs(fm), best_s = sm;
        if ((fm < 0) == (f0 < 0)) {
          s0 = sm, f0 = fm;
          if (side == -1) f1 *= 0.5;
          side = -1;
        } else {
          s1 = sm, f1 = fm;
          if (side == 1) f0 *= 0.5;
          side = 1;
        }
      }
      s1 = best_s;
      worn = moved(s1);
      v1 = swept_volume(triangles, worn);
    }
    scale = s1;
    out.removed_m3 = v1;
    if (!(std::abs(v1 - out.booked_m3) <= 1e-6 * out.booked_m3))
      throw MeshSpoiled(fmt::format(
          "{}: no move of the mesh removes the {:.6g} m3 booked (the nearest removes {:.6g} m3); the wear is too "
          "deep for the mesh: more smoothing or shorter stages",
          name, out.booked_m3, v1));
  };
  fit_scale();
  // Keep the mesh one: where the move turns a triangle over or crushes it
  // to under a tenth of its area (a worn corner has gone past the first
  // row of vertices on the face below it), the vertices of the smooth
  // patches slide along the surface to their neighbours' centroid, so
  // that they space out again between the edges that hold them, and the
  // depth scale is found again with the slides (a slide along a flat face
  // removes nothing; on a curved one, what it does is in the scale).
  if (relax && spoiled(triangles, worn, 0.1) > 0) {
    std::vector<Vec3> at(nv);
    for (std::size_t i = 0; i < nv; ++i) at[i] = w.points[i] + move[i] * scale;
    std::vector<char> bad(nt, 0);
    for (std::size_t t = 0; t < nt; ++t) {
      const auto& a = triangles[t].v;
      const auto& b = worn[t].v;
      const Vec3 na = area_vector(a[0], a[1], a[2]), nb = area_vector(b[0], b[1], b[2]);
      bad[t] = nb.dot(na) <= 0 || nb.norm() < 0.1 * na.norm();
    }
    slide = relax_slides(w, at, bad, bounds, out.relaxed);
    fit_scale();
  }
  out.scale = scale;
  for (std::size_t i = 0; i < nv; ++i) out.deepest_m = std::max(out.deepest_m, scale * move[i].norm());
  // The worn mesh must be one: every triangle checked for a spoiled move
  // first (which a coarser mesh may pass), then for the bounds.
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const auto& a = triangles[t].v;
    const auto& b = worn[t].v;
    const Vec3 na = area_vector(a[0], a[1], a[2]), nb = area_vector(b[0], b[1], b[2]);
    const Vec3 at{(a[0].x + a[1].x + a[2].x) / 3, (a[0].y + a[1].y + a[2].y) / 3, (a[0].z + a[1].z + a[2].z) / 3};
    if (nb.dot(na) <= 0)
      throw MeshSpoiled(fmt::format(
          "{}: triangle {} (at x {:.4f}, y {:.4f}, z {:.4f} m): the wear turns it over (its vertices move past each "
          "other, {:.3g} mm deep at most{}); the wear is too deep for the mesh: more smoothing or shorter stages",
          name, t + 1, at.x, at.y, at.z, out.deepest_m * 1000, out.relaxed > 0 ? ", with the mesh relaxed" : ""));
    if (nb.norm() < 1e-3 * na.norm())
      throw MeshSpoiled(fmt::format(
          "{}: triangle {} (at x {:.4f}, y {:.4f}, z {:.4f} m): the wear shrinks it to under a thousandth of its "
          "area; more smoothing or shorter stages",
          name, t + 1, at.x, at.y, at.z));
  }
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = worn[t].v[k];
      if (bounds.shell_radius > 0 && std::hypot(p.x, p.y) > bounds.shell_radius + 1e-6)
        throw MeshOutside(fmt::format(
            "{}: triangle {}: the wear takes a vertex to radius {:.4f} m, beyond the shell ({:.4f} m): the liner is "
            "worn through there",
            name, t + 1, std::hypot(p.x, p.y), bounds.shell_radius));
      if (bounds.z1 > bounds.z0 && (p.z < bounds.z0 - 1e-9 || p.z > bounds.z1 + 1e-9))
        throw MeshOutside(fmt::format(
            "{}: triangle {}: the wear takes a vertex to z = {:.4f} m, beyond the mill's ends ({:g} to {:g} m)", name,
            t + 1, p.z, bounds.z0, bounds.z1));
    }
  out.triangles = std::move(worn);
  return out;
}

}  // namespace mc::life
