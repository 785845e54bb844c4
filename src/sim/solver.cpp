// The solver's interface functions: make_solver, the default skin, the
// books' helpers. The implementation is SolverImpl (solver_impl.h).
#include "sim/solver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include "sim/solver_impl.h"

namespace mc {

using detail::SolverImpl;

double BookSums::at(int row, int bin, int field) const {
  return spectra[(static_cast<std::size_t>(row) * MC_SPECTRA_BINS + bin) * MC_SPECTRA_FIELDS + field];
}

double BookSums::liner_at(int element, int field) const {
  return liner[static_cast<std::size_t>(element) * MC_LINER_FIELDS + field];
}

double BookSums::closed_loss_J() const {
  double e = 0;
  for (int r = 0; r <= n_types; ++r)
    for (int b = 0; b < MC_SPECTRA_BINS; ++b)
      e += at(r, b, MC_SPECTRA_NORMAL) + at(r, b, MC_SPECTRA_TANGENTIAL) + at(r, b, MC_SPECTRA_ROLLING);
  return e;
}

double spectra_edge_J(int bin) {
  return std::pow(10.0, MC_SPECTRA_LOG_MIN + (std::max(bin, 1) - 1) / static_cast<double>(MC_SPECTRA_PER_DECADE));
}

void Solver::write_instances(const cl::Buffer&) {
  throw std::logic_error("this solver cannot feed the viewer (write_instances)");
}

double default_skin(const Scene& scene) {
  if (scene.balls.empty()) return 0.0;
  double r_min = std::numeric_limits<double>::max(), r_max = 0;
  for (const Ball& b : scene.balls) {
    r_min = std::min(r_min, b.radius);
    r_max = std::max(r_max, b.radius);
  }
  // The lists are rebuilt when a ball has moved half the skin. In a big mill
  // at the seed's step a ball thrown from the shoulder crosses 20 % of a
  // radius in a few steps (mill D: a rebuild every 9 steps, 38 % of the
  // time), so the skin also allows kSkinSteps steps at the speed of a ball
  // fallen across the mill, sqrt(2 g D), up to the smallest radius (the
  // lists grow as the skin's cube). In a periodic slice the grid keeps its
  // 3 cells along the axis.
  const Vec3 g = scene.numerics.gravity;
  const double fall = scene.walls.shell_radius > 0 ? std::sqrt(2 * g.norm() * 2 * scene.walls.shell_radius) : 0.0;
  double skin = std::clamp(2 * kSkinSteps * fall * scene.numerics.dt, 0.2 * r_min, r_min);
  if (scene.walls.periodic && scene.walls.length > 0)
    skin = std::max(0.2 * r_min, std::min(skin, 0.99 * (scene.walls.length / 3 - 2 * r_max)));
  return skin;
}

std::unique_ptr<Solver> make_solver(compute::Context& ctx, const Scene& scene) {
  validate(scene);
  if (scene.numerics.precision == Precision::double_)
    return std::make_unique<SolverImpl<double>>(ctx, scene);
  return std::make_unique<SolverImpl<float>>(ctx, scene);
}

}  // namespace mc
