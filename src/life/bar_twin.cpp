#include "life/bar_twin.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/lifters.h"

namespace mc::life {

double default_twin_edge(double largest_ball_diameter, double length, int segments) {
  const double radius = 0.5 * largest_ball_diameter;
  return segments > 0 ? std::min(radius, 0.5 * length / segments) : radius;
}

std::vector<Triangle> bar_twin_triangles(const MillCase& c, const MillDerived& d, double max_edge_m) {
  const Scene w = build_walls(c, d);
  std::vector<Triangle> t = lifter_triangles(bars_on_shell(w.walls.lifters, w.walls.shell_radius), c.length, max_edge_m);
  // As a binary STL holds them (32-bit floats): the study's stage 0 reads
  // the twin from its file, and the mesh it wears is the same.
  for (Triangle& tr : t)
    for (Vec3& v : tr.v) v = {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
  return t;
}

double twin_triangle_estimate(const MillCase& c, const MillDerived& d, double max_edge_m) {
  const Scene w = build_walls(c, d);
  const double along = std::ceil(c.length / max_edge_m);
  double n = 0;
  for (const std::vector<Vec2>& bar : bars_on_shell(w.walls.lifters, w.walls.shell_radius))
    for (std::size_t i = 0; i < bar.size(); ++i) {
      const Vec2 a = bar[i], b = bar[(i + 1) % bar.size()];
      n += 2 * along * std::ceil(std::hypot(b.x - a.x, b.y - a.y) / max_edge_m);
    }
  return n;
}

MillCase with_bar_twin(const MillCase& c, std::vector<Triangle> twin, const std::string& file) {
  MillCase t = c;
  t.lifter_rows = 0;
  MeshSpec m;
  m.file = m.path = file;
  m.units = "m";
  m.part = MeshPart::lifters;
  m.turning = true;
  m.triangles = std::move(twin);
  t.meshes.push_back(std::move(m));
  return t;
}

}  // namespace mc::life
