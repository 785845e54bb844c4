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

double swept_volume(const std::vector<Triangle>& before, const std::vector<Triangle>& after) {
  // The closed solid between each triangle and its moved self: the old
  // triangle (facing out of the solid, as it faced the charge), the new
  // one reversed, and the three sides, each a quad cut in two. Summed by
  // the divergence theorem; the sides of neighbours cancel.
  double v6 = 0;
  for (std::size_t i = 0; i < before.size(); ++i) {
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
  }
  return v6 / 6.0;
}

MeshWear wear_mesh(const std::vector<Triangle>& triangles, const std::vector<double>& volume_m3,
                   const MeshBounds& bounds, int smoothing, const std::string& name) {
  if (volume_m3.size() != triangles.size())
    throw std::invalid_argument(fmt::format("{}: {} wear volumes for {} triangles", name, volume_m3.size(),
                                            triangles.size()));
  const WeldedMesh w = weld(triangles);
  const std::size_t nv = w.points.size();
  std::vector<Vec3> normal(nv);       // area-weighted, summed
  std::vector<double> area(nv, 0.0);  // of the triangles around
  std::vector<double> depth(nv, 0.0); // area-weighted depth, summed
  MeshWear out;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const double v = volume_m3[t];
    if (!(std::isfinite(v) && v >= 0))
      throw std::invalid_argument(fmt::format("{}: triangle {}: wear volume {} is not a volume (finite, >= 0)", name,
                                              t + 1, v));
    out.booked_m3 += v;
    const auto& c = w.corners[t];
    const Vec3 av = area_vector(w.points[c[0]], w.points[c[1]], w.points[c[2]]);
    const double a = 0.5 * av.norm();
    for (int k = 0; k < 3; ++k) {
      normal[c[k]] = normal[c[k]] + av * 0.5;
      area[c[k]] += a;
      depth[c[k]] += v;  // a · (v / a): the triangle's depth weighed by its area
    }
  }
  for (std::size_t i = 0; i < nv; ++i) {
    depth[i] = area[i] > 0 ? depth[i] / area[i] : 0.0;
    const double n = normal[i].norm();
    normal[i] = n > 0 ? normal[i] * (1.0 / n) : Vec3{};
  }
  // Smoothing: each pass averages a vertex's depth with the mean of its
  // neighbours' (those it shares a triangle with).
  if (smoothing > 0) {
    std::vector<std::vector<int>> near(nv);
    for (const auto& c : w.corners)
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j)
          if (j != k) near[c[k]].push_back(c[j]);
    for (auto& n : near) {
      std::sort(n.begin(), n.end());
      n.erase(std::unique(n.begin(), n.end()), n.end());
    }
    for (int pass = 0; pass < smoothing; ++pass) {
      std::vector<double> next(nv);
      for (std::size_t i = 0; i < nv; ++i) {
        double sum = 0;
        for (int j : near[i]) sum += depth[j];
        next[i] = near[i].empty() ? depth[i] : 0.5 * (depth[i] + sum / near[i].size());
      }
      depth.swap(next);
    }
    out.smoothing = smoothing;
  }
  auto moved = [&](double scale) {
    std::vector<Triangle> m(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const int i = w.corners[t][k];
        m[t].v[k] = w.points[i] - normal[i] * (scale * depth[i]);
      }
    return m;
  };
  // The depth scale whose swept volume is the booked one: the swept volume
  // grows with the scale (a surface moved further into the liner), to
  // first order in proportion.
  double scale = 1;
  std::vector<Triangle> worn = moved(scale);
  if (out.booked_m3 > 0) {
    double s0 = 0, v0 = 0, s1 = 1, v1 = swept_volume(triangles, worn);
    for (int it = 0; it < 40 && std::abs(v1 - out.booked_m3) > 1e-12 * out.booked_m3; ++it) {
      if (!(v1 > v0)) break;
      const double s2 = s1 + (out.booked_m3 - v1) * (s1 - s0) / (v1 - v0);
      s0 = s1, v0 = v1;
      s1 = std::clamp(s2, 0.25 * s1, 4.0 * s1);
      worn = moved(s1);
      v1 = swept_volume(triangles, worn);
    }
    scale = s1;
    out.removed_m3 = v1;
  }
  out.scale = scale;
  for (std::size_t i = 0; i < nv; ++i) out.deepest_m = std::max(out.deepest_m, scale * depth[i]);
  // The worn mesh must be one.
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const auto& a = triangles[t].v;
    const auto& b = worn[t].v;
    const Vec3 na = area_vector(a[0], a[1], a[2]), nb = area_vector(b[0], b[1], b[2]);
    if (nb.dot(na) <= 0)
      throw std::invalid_argument(fmt::format(
          "{}: triangle {}: the wear turns it over (its vertices move past each other, {:.3g} mm deep at most); the "
          "wear is too deep for the mesh: a finer mesh, more smoothing or shorter stages",
          name, t + 1, out.deepest_m * 1000));
    if (nb.norm() < 1e-3 * na.norm())
      throw std::invalid_argument(fmt::format(
          "{}: triangle {}: the wear shrinks it to under a thousandth of its area; a finer mesh, more smoothing or "
          "shorter stages",
          name, t + 1));
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = b[k];
      if (bounds.shell_radius > 0 && std::hypot(p.x, p.y) > bounds.shell_radius * (1 + 1e-3))
        throw std::invalid_argument(fmt::format(
            "{}: triangle {}: the wear takes a vertex to radius {:.4f} m, beyond the shell ({:.4f} m): the liner is "
            "worn through there",
            name, t + 1, std::hypot(p.x, p.y), bounds.shell_radius));
      if (bounds.z1 > bounds.z0 && (p.z < bounds.z0 - 1e-9 || p.z > bounds.z1 + 1e-9))
        throw std::invalid_argument(fmt::format(
            "{}: triangle {}: the wear takes a vertex to z = {:.4f} m, beyond the mill's ends ({:g} to {:g} m)", name,
            t + 1, p.z, bounds.z0, bounds.z1));
    }
  }
  out.triangles = std::move(worn);
  return out;
}

}  // namespace mc::life
