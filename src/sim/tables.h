// The device tables of a scene, derived once in double: run parameters (all
// but the grid), the material-pair table and the lifter polygons. The solver
// converts them to its precision; the CPU reference uses them as they are,
// so both always see the same derived values.
#pragma once

#include <vector>

#include "core/scene.h"
#include "sim/layout.hpp"
#include "sim/solver.h"

namespace mc {

struct SceneTables {
  f64::SimParams params{};  // grid fields left zero
  std::vector<f64::PairParams> pairs;
  std::vector<f64::LifterPolygon> lifters;  // at least one entry
  f64::BookParams books{};                  // spectra and liner (core/liner.h)
};

SceneTables scene_tables(const Scene& scene);

// A ball as the host reports it, velocities synchronised to the step:
// v(n) = v(n−½) + ½·dt·F(n)/m (the arrays hold 1/m and 1/I in .w).
template <class real4>
BallState ball_state(int id, int material, const real4& p, const real4& v, const real4& w,
                     const real4& f, const real4& t, double dt) {
  const double h = 0.5 * dt;
  BallState b;
  b.id = id;
  b.material = material;
  b.radius = p.w;
  b.position = {p.x, p.y, p.z};
  b.velocity = {v.x + h * f.x * v.w, v.y + h * f.y * v.w, v.z + h * f.z * v.w};
  b.omega = {w.x + h * t.x * w.w, w.y + h * t.y * w.w, w.z + h * t.z * w.w};
  b.force = {f.x, f.y, f.z};
  b.torque = {t.x, t.y, t.z};
  return b;
}

}  // namespace mc
