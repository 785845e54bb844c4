#include "sim/tables.h"

#include <algorithm>
#include <cmath>

#include "core/liner.h"

namespace mc {

SceneTables scene_tables(const Scene& scene) {
  validate(scene);
  SceneTables t;
  const int nm = scene.wall_index();
  for (int a = 0; a <= nm; ++a)
    for (int b = 0; b <= nm; ++b) {
      const PairCoefficients c = pair_coefficients(scene, a, b);
      t.pairs.push_back({c.kn, c.kt_over_kn, c.e_star, c.g_star, c.damping, c.mu_slide, c.mu_roll,
                         c.restitution});
    }
  const Walls& w = scene.walls;
  double r_max = 0;
  for (const Ball& b : scene.balls) r_max = std::max(r_max, b.radius);
  double reach = w.shell_radius;
  for (const auto& poly : w.lifters) {
    f64::LifterPolygon p{};
    p.n_vertices = static_cast<int>(poly.size());
    double cx = 0, cy = 0;
    for (std::size_t v = 0; v < poly.size(); ++v) {
      p.vertices[v] = {poly[v].x, poly[v].y};
      reach = std::min(reach, std::hypot(poly[v].x, poly[v].y));
      cx += poly[v].x / static_cast<double>(poly.size());
      cy += poly[v].y / static_cast<double>(poly.size());
    }
    double radius = 0;
    for (const auto& v : poly) radius = std::max(radius, std::hypot(v.x - cx, v.y - cy));
    // A little over, so that rounding in float never rejects a touching ball.
    p.bound = {cx, cy, radius * (1 + 1e-4) + 1e-6, w.shell_radius > 0 ? lifter_half_angle(poly, w.shell_radius) : 0.0};
    t.lifters.push_back(p);
  }
  if (t.lifters.empty()) t.lifters.push_back(f64::LifterPolygon{});
  const int nl = static_cast<int>(w.lifters.size());
  f64::SimParams& sp = t.params;
  const Vec3 g = scene.numerics.gravity;
  sp.gravity = {g.x, g.y, g.z, 0};
  sp.dt = scene.numerics.dt;
  sp.skin = scene.numerics.skin > 0 ? scene.numerics.skin : default_skin(scene);
  sp.shell_radius = w.shell_radius;
  sp.length = w.has_end_plates() ? w.length : 0.0;
  sp.period = w.periodic ? w.length : 0.0;
  // A ball centre farther than this from the axis may touch a lifter.
  sp.lifter_reach = std::max(0.0, reach - 1.01 * r_max);
  sp.lifter_first_angle = w.lifter_first_angle;
  sp.lifter_spacing = nl > 0 ? 2.0 * M_PI / nl : 1.0;
  sp.n_balls = static_cast<int>(scene.balls.size());
  sp.n_materials = nm;
  sp.n_lifters = nl;
  sp.law = scene.numerics.law == ContactLaw::hertz ? MC_LAW_HERTZ : MC_LAW_LINEAR;

  // The books: fixed-point units from the scale of the mill (the heaviest
  // ball lifted across the diameter), 2^-44 of it, so an element's sums hold
  // 2^19 such lifts and resolve a part in 10^13 of one.
  const LinerLayout liner = liner_layout(scene);
  double m_max = 0;
  for (const Ball& b : scene.balls) m_max = std::max(m_max, ball_mass(scene, b));
  const double lift = std::max(m_max, 1e-6) * 9.81 * (w.shell_radius > 0 ? 2 * w.shell_radius : 1.0);
  f64::BookParams& bp = t.books;
  bp.energy_unit = std::ldexp(lift, -44);
  bp.wear_k = scene.wall_material.wear_coefficient;
  bp.wear_unit = std::max(bp.wear_k, 1e-30) * bp.energy_unit;
  bp.plate_ring_width = (w.shell_radius > 0 ? w.shell_radius : 1.0) / liner.plate_rings;
  bp.n_types = n_pair_types(nm);
  bp.n_elements = liner.size();
  bp.shell_bins = liner.shell_bins;
  bp.axial_bins = liner.axial_bins;
  bp.plate_rings = liner.plate_rings;
  bp.plate_sectors = liner.plate_sectors;
  bp.first_lifter_element = liner.first_lifter;
  bp.first_plate_element = liner.first_plate;
  return t;
}

}  // namespace mc
