// The hold-up, the rates and the products of an ore in a mill (circuit.h).
#include "grind/circuit.h"

#include <cmath>
#include <vector>

namespace mc::grind {

double mill_holdup_kg(const Ore& ore, double ball_bed_porosity, double filling, double mill_volume_m3) {
  return ore.holdup_kg > 0 ? ore.holdup_kg
                           : ore.powder_filling * ball_bed_porosity * filling * mill_volume_m3 * ore.density *
                                 (1 - ore.bed_porosity);
}

MillRates mill_rates(const Ore& ore, const std::vector<SpectrumBin>& spectrum, double power_W, double holdup_kg) {
  const SizeSeries& s = ore.sizes;
  const int n = s.size();
  // Rates per minute.
  std::vector<double> S(n, 0.0), SE(n, 0.0);
  const double power_kW = power_W / 1000, holdup_t = holdup_kg / 1000;
  if (ore.model == RateModel::austin) S = austin_rates(s, ore.austin);
  if (ore.model == RateModel::energy) {
    SE = energy_specific_rates(s, ore.energy);
    for (int i = 0; i < n; ++i) S[i] = SE[i] * power_kW / holdup_t / 60;
  }
  if (ore.model == RateModel::spectrum) {
    S = spectrum_rates(s, spectrum, ore.fracture, ore.density, ore.packing, ore.efficiency, holdup_kg);
    // Tavares' t10: of what a collision breaks, the progeny finer than the
    // class leave it; the rest stays (t10_breakage_matrix).
    std::vector<double> leaving(n, 1.0);
    if (ore.appearance == Appearance::t10)
      t10_breakage_matrix(s, spectrum, ore.fracture, ore.t10, ore.density, ore.packing, nullptr, &leaving);
    for (int i = 0; i < n; ++i) S[i] *= 60 * leaving[i];
  }
  if (ore.model != RateModel::energy)
    for (int i = 0; i < n; ++i) SE[i] = S[i] * 60 * holdup_t / power_kW;
  S[n - 1] = SE[n - 1] = 0;
  return {S, SE};
}

std::vector<std::vector<double>> appearance_matrix(const Ore& ore, const std::vector<SpectrumBin>& spectrum,
                                                   std::vector<double>* t10_mean) {
  if (t10_mean) t10_mean->clear();
  if (ore.appearance == Appearance::t10)
    return t10_breakage_matrix(ore.sizes, spectrum, ore.fracture, ore.t10, ore.density, ore.packing, t10_mean);
  return breakage_matrix(ore.sizes, ore.breakage);
}

Product batch_product(const Circuit& c, double t_min) {
  Product p;
  p.t_min = t_min;
  p.m = batch_grind(c.feed, c.S_per_min, c.b, t_min);
  p.kWh_t = c.power_kW * t_min / 60 / c.holdup_t;
  p.p80_m = passing_size(c.sizes, p.m, 0.8);
  return p;
}

Product continuous_product(const Circuit& c, double feed_t_h) {
  Product p;
  p.feed_t_h = feed_t_h;
  if (c.closed) {
    std::vector<double> fresh(c.feed);
    for (double& f : fresh) f *= feed_t_h;
    const ClosedCircuit cc = closed_circuit(c.sizes, fresh, c.S_per_min, c.b, c.holdup_t, c.tanks, c.classifier);
    p.m = cc.product;
    for (double& m : p.m) m /= feed_t_h;
    p.t_min = cc.residence_min;
    p.circulating_load = cc.circulating_load;
    p.converged = cc.converged;
  } else {
    p.t_min = c.holdup_t / feed_t_h * 60;  // mean residence time
    p.m = continuous_grind(c.feed, c.S_per_min, c.b, p.t_min, c.tanks);
  }
  p.kWh_t = c.power_kW / feed_t_h;
  p.p80_m = passing_size(c.sizes, p.m, 0.8);
  return p;
}

TargetFeed feed_rate_for_p80(const Circuit& c, double target_m) {
  TargetFeed r;
  // P80 rises with the feed rate: bisect its logarithm between the rates
  // the solver brackets.
  double lo = kSlowestFeed_t_h, hi = kFastestFeed_t_h;
  auto p80 = [&](double f) {
    const double x = continuous_product(c, f).p80_m;
    return std::isfinite(x) ? x : 0.0;
  };
  r.p80_slowest_m = p80(lo);
  r.p80_fastest_m = p80(hi);
  if (!(r.p80_slowest_m < target_m)) {
    r.outcome = TargetFeed::Outcome::coarse_when_slowest;
    return r;
  }
  if (!(r.p80_fastest_m > target_m)) {
    r.outcome = TargetFeed::Outcome::fine_when_fastest;
    return r;
  }
  for (int k = 0; k < 200 && hi / lo > 1 + 1e-10; ++k) {
    const double mid = std::sqrt(lo * hi);
    (p80(mid) < target_m ? lo : hi) = mid;
  }
  r.rate_t_h = std::sqrt(lo * hi);
  r.product = continuous_product(c, r.rate_t_h);
  // The bisection assumes P80 rises with the rate; a circuit where it
  // does not (or a step in P80) leaves a product off the target: said,
  // never shown as the answer.
  r.outcome = std::fabs(r.product.p80_m - target_m) <= 0.01 * target_m ? TargetFeed::Outcome::met
                                                                          : TargetFeed::Outcome::missed;
  return r;
}

}  // namespace mc::grind
