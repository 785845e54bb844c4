#include "core/restitution.h"

#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace mc {

namespace {

double accel(ContactLaw law, double d, double x, double v) {
  const double xp = x > 0.0 ? x : 0.0;
  if (law == ContactLaw::linear) return -xp - d * v;
  return -xp * std::sqrt(xp) - d * std::sqrt(1.5) * std::sqrt(std::sqrt(xp)) * v;
}

}  // namespace

double restitution_for_damping(ContactLaw law, double d) {
  // RK4 in dimensionless time; the undamped contact lasts about 3.2 (Hertz)
  // or π (linear) units, so 1e-4 steps resolve it far below the 2 % the tests
  // ask of the DEM.
  const double h = 1e-4;
  double x = 0.0, v = 1.0;
  for (int step = 0; step < 2000000; ++step) {
    const double k1x = v, k1v = accel(law, d, x, v);
    const double k2x = v + 0.5 * h * k1v, k2v = accel(law, d, x + 0.5 * h * k1x, v + 0.5 * h * k1v);
    const double k3x = v + 0.5 * h * k2v, k3v = accel(law, d, x + 0.5 * h * k2x, v + 0.5 * h * k2v);
    const double k4x = v + h * k3v, k4v = accel(law, d, x + h * k3x, v + h * k3v);
    x += h / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x);
    v += h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
    if (x <= 0.0) return -v;                                   // overlap gone
    if (v < 0.0 && accel(law, d, x, v) >= 0.0) return -v;     // force reached zero
  }
  return 0.0;  // overdamped: the ball stays
}

namespace {

double solve_damping(ContactLaw law, double e) {
  // The ratio falls monotonically with d; bracket then bisect.
  double lo = 0.0, hi = 1.0;
  while (restitution_for_damping(law, hi) > e) hi *= 2.0;
  for (int it = 0; it < 50; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (restitution_for_damping(law, mid) > e)
      lo = mid;
    else
      hi = mid;
    if (hi - lo < 1e-9 * hi) break;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

double damping_for_restitution(ContactLaw law, double e) {
  if (!(e > 0.0 && e <= 1.0))
    throw std::invalid_argument("restitution must be in (0, 1], got " + std::to_string(e));
  if (e >= 1.0) return 0.0;
  // The bisection integrates some thirty contacts (about 46 ms), and every
  // scene built (a run's start, each edit in the viewer's panel) asks again
  // for the same few materials: each (law, e) is solved once per process.
  static std::mutex mutex;
  static std::map<std::pair<int, double>, double> solved;
  const std::pair<int, double> key{static_cast<int>(law), e};
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = solved.find(key); it != solved.end()) return it->second;
  }
  const double d = solve_damping(law, e);
  const std::lock_guard<std::mutex> lock(mutex);
  solved.emplace(key, d);
  return d;
}

}  // namespace mc
