#include "core/drum.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace mc {

double critical_omega(double diameter, double ball_diameter) {
  const double rpm = 42.3 / std::sqrt(diameter - ball_diameter);
  return rpm * 2.0 * M_PI / 60.0;
}

double contact_time_linear(double kn, double m_eff) { return M_PI * std::sqrt(m_eff / kn); }

double contact_time_hertz(double e_star, double r_eff, double m_eff, double v) {
  return 2.868 * std::pow(m_eff * m_eff / (r_eff * e_star * e_star * v), 0.2);
}

Scene make_drum(const DrumSpec& spec) {
  if (!(spec.radius_min > 0 && spec.radius_max >= spec.radius_min))
    throw std::invalid_argument("drum: need 0 < radius_min <= radius_max");
  Scene s;
  Material steel{"steel", 7800.0, 2.0e11, 0.3};
  s.materials = {steel};
  s.wall_material = Material{"liner", 7800.0, 2.0e11, 0.3};
  Interaction in;
  in.restitution = spec.restitution;
  in.mu_slide = spec.mu_slide;
  in.mu_roll = spec.mu_roll;
  in.kn = spec.kn;
  s.set_all_interactions(in);
  const double R = 0.5 * spec.diameter;
  s.walls.shell_radius = R;
  s.walls.length = spec.length;
  s.walls.lifters = lifter_rows(R, spec.lifter_rows, {spec.lifter}, 0.0);
  s.numerics.law = spec.law;
  s.numerics.precision = spec.precision;
  s.mill_omega = spec.speed_fraction * critical_omega(spec.diameter, 2 * spec.radius_max);

  std::mt19937 rng(spec.seed);
  std::uniform_real_distribution<double> radius(spec.radius_min, spec.radius_max);
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  const double pitch = 2.0 * spec.radius_max * 1.05;
  const double j = 0.02 * spec.radius_max;
  // Candidate sites bottom up, then left to right, front to back.
  std::vector<Vec3> sites;
  for (double y = -R + pitch; y < R - pitch; y += pitch)
    for (double z = spec.radius_max * 1.05; z <= spec.length - spec.radius_max * 1.05; z += pitch)
      for (double x = -R + pitch; x < R - pitch; x += pitch) {
        if (std::hypot(x, y) > R - spec.radius_max * 1.1) continue;
        bool clear = true;
        for (const auto& poly : s.walls.lifters)
          if (polygon_signed_distance(poly, x, y) < spec.radius_max * 1.1) clear = false;
        if (clear) sites.push_back({x, y, z});
      }
  if (static_cast<int>(sites.size()) < spec.n_balls)
    throw std::invalid_argument("drum: " + std::to_string(spec.n_balls) + " balls do not fit (" +
                                std::to_string(sites.size()) + " sites)");
  std::stable_sort(sites.begin(), sites.end(), [](const Vec3& a, const Vec3& b) { return a.y < b.y; });
  for (int i = 0; i < spec.n_balls; ++i) {
    Ball b;
    b.id = i;
    b.material = 0;
    b.radius = radius(rng);
    b.position = {sites[i].x + j * jitter(rng), sites[i].y + j * jitter(rng), sites[i].z + j * jitter(rng)};
    s.balls.push_back(b);
  }

  // dt from the shortest contact: the smallest pair.
  const double m_min = ball_mass(s, s.balls.front()) * std::pow(spec.radius_min / s.balls.front().radius, 3);
  double tc;
  if (spec.law == ContactLaw::linear) {
    tc = contact_time_linear(spec.kn, 0.5 * m_min);
  } else {
    const PairCoefficients c = pair_coefficients(s, 0, 0);
    const double tip = std::max(s.mill_omega * R, 1.0);
    tc = contact_time_hertz(c.e_star, 0.5 * spec.radius_min, 0.5 * m_min, tip);
  }
  s.numerics.dt = tc * spec.dt_fraction;
  return s;
}

}  // namespace mc
