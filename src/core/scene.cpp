#include "core/scene.h"

#include "core/lifters.h"
#include "core/plate_wear.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace mc {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

void Scene::set_interaction(int a, int b, const Interaction& in) {
  const int m = wall_index() + 1;
  if (static_cast<int>(interactions.size()) != m * m) interactions.assign(m * m, Interaction{});
  interactions[a * m + b] = in;
  interactions[b * m + a] = in;
}

void Scene::set_all_interactions(const Interaction& in) {
  const int m = wall_index() + 1;
  interactions.assign(m * m, in);
}

const Interaction& Scene::interaction(int a, int b) const {
  const int m = wall_index() + 1;
  if (static_cast<int>(interactions.size()) != m * m)
    throw std::invalid_argument("scene: interaction table has " + std::to_string(interactions.size()) +
                                " entries, needs " + std::to_string(m * m));
  return interactions[a * m + b];
}

PairCoefficients pair_coefficients(const Scene& scene, int a, int b) {
  auto mat = [&](int k) -> const Material& {
    return k == scene.wall_index() ? scene.wall_material : scene.materials.at(k);
  };
  const Material& ma = mat(a);
  const Material& mb = mat(b);
  const Interaction& in = scene.interaction(a, b);
  PairCoefficients c{};
  c.kn = in.kn;
  c.kt_over_kn = in.kt_over_kn;
  c.e_star = 1.0 / ((1 - ma.poisson_ratio * ma.poisson_ratio) / ma.youngs_modulus +
                    (1 - mb.poisson_ratio * mb.poisson_ratio) / mb.youngs_modulus);
  c.g_star = 1.0 / (2 * (2 - ma.poisson_ratio) * (1 + ma.poisson_ratio) / ma.youngs_modulus +
                    2 * (2 - mb.poisson_ratio) * (1 + mb.poisson_ratio) / mb.youngs_modulus);
  c.damping = damping_for_restitution(scene.numerics.law, in.restitution);
  c.mu_slide = in.mu_slide;
  c.mu_roll = in.mu_roll;
  c.restitution = in.restitution;
  return c;
}

double ball_mass(const Scene& scene, const Ball& b) {
  return scene.materials.at(b.material).density * 4.0 / 3.0 * kPi * b.radius * b.radius * b.radius;
}

Vec3 rotate(const std::array<double, 4>& q, const Vec3& v) {
  const Vec3 u{q[0], q[1], q[2]};
  auto cross = [](const Vec3& a, const Vec3& b) {
    return Vec3{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
  };
  const Vec3 t = cross(u, v) * 2.0;
  return v + t * q[3] + cross(u, t);
}

namespace {

// Bodies: each a block of component ids after every free ball, in order,
// with a finite positive mass and inertia and a unit orientation.
void validate_bodies(const Scene& scene) {
  auto fail = [](const std::string& m) { throw std::invalid_argument(m); };
  if (scene.bodies.empty()) {
    for (const Ball& b : scene.balls)
      if (b.body != -1) fail("ball " + std::to_string(b.id) + ": names body " + std::to_string(b.body) + " of none");
    return;
  }
  const int n = static_cast<int>(scene.balls.size());
  int n_comp = 0;
  for (const Body& b : scene.bodies) n_comp += b.count;
  const int first = n - n_comp;
  std::vector<int> body_of(n, -2);
  for (const Ball& b : scene.balls) {
    if (b.id < 0 || b.id >= n || body_of[b.id] != -2)
      fail("ball " + std::to_string(b.id) + ": ids of a scene with bodies run from 0 to " + std::to_string(n - 1) +
           ", each once");
    body_of[b.id] = b.body;
  }
  int next = first;
  for (std::size_t k = 0; k < scene.bodies.size(); ++k) {
    const Body& b = scene.bodies[k];
    const std::string at = "body " + std::to_string(k);
    if (b.count < 1) fail(at + ": no component spheres");
    if (b.first != next) fail(at + ": its components must follow the previous body's (first id " + std::to_string(next) + ")");
    for (int c = b.first; c < b.first + b.count; ++c)
      if (body_of[c] != static_cast<int>(k)) fail(at + ": ball " + std::to_string(c) + " is not its component");
    next += b.count;
    if (!(std::isfinite(b.mass) && b.mass > 0)) fail(at + ": the mass of its union must be finite and > 0");
    if (!(std::isfinite(b.inertia.x) && std::isfinite(b.inertia.y) && std::isfinite(b.inertia.z) &&
          b.inertia.x > 0 && b.inertia.y > 0 && b.inertia.z > 0))
      fail(at + ": its principal moments of inertia must be finite and > 0");
    const auto& q = b.orientation;
    const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(std::abs(qn - 1) < 1e-6)) fail(at + ": its orientation is not a unit quaternion");
  }
  for (int c = 0; c < first; ++c)
    if (body_of[c] != -1) fail("ball " + std::to_string(c) + ": a free ball's id must come before every component's");
}

}  // namespace

void validate(const Scene& scene) {
  auto fail = [](const std::string& m) { throw std::invalid_argument(m); };
  if (scene.materials.empty()) fail("scene: no ball material");
  auto check_material = [&](const Material& m, const std::string& where) {
    if (!(m.density > 0)) fail(where + ".density must be > 0");
    if (!(m.youngs_modulus > 0)) fail(where + ".youngs_modulus must be > 0");
    if (!(m.poisson_ratio > -1 && m.poisson_ratio < 0.5)) fail(where + ".poisson_ratio must be in (-1, 0.5)");
    if (!(m.wear_coefficient >= 0 && m.wear_coefficient < 1e-6))
      fail(where + ".wear_coefficient must be in [0, 1e-6) m^3/(N m)");
    if (!(m.impact_wear_coefficient >= 0 && m.impact_wear_coefficient < 1e-6))
      fail(where + ".impact_wear_coefficient must be in [0, 1e-6) m^3/J");
    if (!(m.impact_wear_threshold_speed >= 0 && m.impact_wear_threshold_speed < 100))
      fail(where + ".impact_wear_threshold_speed must be in [0, 100) m/s");
  };
  for (std::size_t k = 0; k < scene.materials.size(); ++k)
    check_material(scene.materials[k], "materials." + scene.materials[k].name);
  check_material(scene.wall_material, "wall_material");
  const int m = scene.wall_index() + 1;
  if (static_cast<int>(scene.interactions.size()) != m * m) fail("scene: interaction table incomplete");
  for (const Interaction& in : scene.interactions) {
    if (!(in.restitution > 0 && in.restitution <= 1)) fail("interaction.restitution must be in (0, 1]");
    if (!(in.mu_slide >= 0)) fail("interaction.mu_slide must be >= 0");
    if (!(in.mu_roll >= 0)) fail("interaction.mu_roll must be >= 0");
    if (scene.numerics.law == ContactLaw::linear && !(in.kn > 0)) fail("interaction.kn must be > 0");
  }
  if (!(scene.numerics.dt > 0)) fail("numerics.dt must be > 0");
  for (const Ball& b : scene.balls) {
    if (!(b.radius > 0)) fail("ball " + std::to_string(b.id) + ": radius must be > 0");
    if (b.material < 0 || b.material >= scene.wall_index())
      fail("ball " + std::to_string(b.id) + ": unknown material " + std::to_string(b.material));
  }
  validate_bodies(scene);
  if (scene.walls.periodic && !(scene.walls.length > 0)) fail("walls.length: a periodic slice needs a length > 0");
  for (const auto& poly : scene.walls.lifters) {
    if (poly.size() < 3 || poly.size() > static_cast<std::size_t>(kLifterMaxPoints))
      fail("lifter polygon needs 3 to " + std::to_string(kLifterMaxPoints) + " vertices");
  }
  const LinerGrid& g = scene.liner;
  if (g.shell_bins < 1 || g.shell_bins > 64) fail("liner.shell_bins must be in [1, 64]");
  if (g.smooth_shell_bins < 4 || g.smooth_shell_bins > 720) fail("liner.smooth_shell_bins must be in [4, 720]");
  if (g.axial_bins < 0 || g.axial_bins > 256) fail("liner.axial_bins must be in [0, 256] (0: auto)");
  if (g.plate_rings < 1 || g.plate_rings > 64) fail("liner.plate_rings must be in [1, 64]");
  if (g.plate_sectors < 0 || g.plate_sectors > 720) fail("liner.plate_sectors must be in [0, 720] (0: auto)");
  if (scene.walls.plates_worn()) {
    const std::string why = check_plate_depths(scene.walls.plate_depth, g.plate_rings, scene.walls.shell_radius,
                                               scene.walls.has_end_plates() ? scene.walls.length : 0);
    if (!why.empty()) fail("liner.plate_depth_mm" + why);
  }
}

}  // namespace mc
