#include "sim/charge_profile.h"

#include <algorithm>
#include <cmath>

namespace mc {

ChargeAngles toe_and_shoulder(const std::vector<long>& counts, double threshold, int smooth_bins) {
  ChargeAngles out;
  const int n = static_cast<int>(counts.size());
  if (n < 8) return out;
  const int half = std::max(0, smooth_bins / 2);
  std::vector<double> s(n, 0.0);
  for (int k = 0; k < n; ++k) {
    double sum = 0;
    for (int j = -half; j <= half; ++j) sum += static_cast<double>(counts[((k + j) % n + n) % n]);
    s[k] = sum / (2 * half + 1);
  }
  const int peak = static_cast<int>(std::max_element(s.begin(), s.end()) - s.begin());
  if (!(s[peak] > 0)) return out;
  const double level = threshold * s[peak];
  auto at = [&](int k) { return s[((k % n) + n) % n]; };
  const double w = 360.0 / n;
  // Walk down in angle from the peak to the first bin below the level: the toe.
  int lo = peak;
  int steps = 0;
  while (at(lo - 1) >= level && steps < n) --lo, ++steps;
  if (steps >= n) return out;  // contacts all round: no band
  int hi = peak;
  steps = 0;
  while (at(hi + 1) >= level && steps < n) ++hi, ++steps;
  // Crossings between bin centres, linearly.
  auto cross = [&](int inside, int outside) {
    const double a = at(inside), b = at(outside);
    const double t = (a - level) / std::max(1e-300, a - b);  // 0 at inside, 1 at outside
    return (inside + 0.5 + t * (outside - inside)) * w;
  };
  auto wrap = [](double deg) {
    double d = std::fmod(deg, 360.0);
    return d < 0 ? d + 360.0 : d;
  };
  out.toe_deg = wrap(cross(lo, lo - 1));
  out.shoulder_deg = wrap(cross(hi, hi + 1));
  out.found = true;
  return out;
}

}  // namespace mc
