// Shared set-up for the tests: one OpenCL context per process, and scenes of
// a few balls with or without walls.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <utility>
#include <vector>

#include "compute/context.h"
#include "core/scene.h"
#include "sim/solver.h"

namespace mc::test {

// Listed pairs as (lower id, higher id): neighbour_pairs() gives each pair
// once, in the list that holds it.
inline std::set<std::pair<int, int>> unordered(const std::vector<std::pair<int, int>>& pairs) {
  std::set<std::pair<int, int>> out;
  for (const auto& [a, b] : pairs) out.insert({std::min(a, b), std::max(a, b)});
  return out;
}

inline compute::Context& context() {
  static compute::Context ctx;  // MILLCHARGE_DEVICE picks the device
  return ctx;
}

inline constexpr double kPi = 3.14159265358979323846;

// Where a solver has taken a scene's balls (positions, velocities, spins)
// and its mill (the angle), written back into the scene: to start another
// solver from that state.
inline void take_motion(Solver& from, Scene& into) {
  const std::vector<BallState> now = from.balls();
  into.mill_angle = from.mill_angle();
  for (std::size_t i = 0; i < into.balls.size(); ++i) {
    into.balls[i].position = now[i].position;
    into.balls[i].velocity = now[i].velocity;
    into.balls[i].omega = now[i].omega;
  }
}

inline double sphere_mass(double density, double r) { return density * 4.0 / 3.0 * kPi * r * r * r; }

// One ball material and a wall material, all pairs alike, no gravity.
inline Scene bare_scene(const Material& ball, const Material& wall, const Interaction& in,
                        ContactLaw law, Precision precision = Precision::single) {
  Scene s;
  s.materials = {ball};
  s.wall_material = wall;
  s.set_all_interactions(in);
  s.numerics.law = law;
  s.numerics.precision = precision;
  s.numerics.gravity = {0, 0, 0};
  return s;
}

// A rigid wall for the impact tests: stiff enough that E* is the ball's own.
inline Material rigid_wall() { return Material{"rigid", 1.0, 1.0e30, 0.0}; }

inline double rel_err(double a, double b) { return std::fabs(a - b) / std::fabs(b); }

}  // namespace mc::test
