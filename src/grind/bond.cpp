// Bond's locked-cycle test (bond.h).
#include "grind/bond.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace mc::grind {

namespace {

// The part of m finer than x (the class that x cuts, in log proportion).
std::vector<double> part_below(const SizeSeries& s, const std::vector<double>& m, double x) {
  std::vector<double> u(m.size(), 0.0);
  const int n = s.size();
  for (int i = 0; i < n; ++i) {
    const double hi = s.top_m[i], lo = i + 1 < n ? s.top_m[i + 1] : 0.0;
    if (hi <= x) u[i] = m[i];
    else if (lo < x) u[i] = m[i] * (lo > 0 ? std::log(x / lo) / std::log(hi / lo) : 1.0);
  }
  return u;
}

double mass_below(const SizeSeries& s, const std::vector<double>& m, double x) {
  double below = 0;
  for (double v : part_below(s, m, x)) below += v;
  return below;
}

}  // namespace

double bond_charge_kg(const Ore& ore) { return 700e-6 * ore.bulk_density; }

void put_sieve_on_class_top(Ore& ore, double p1_m) {
  const double top = ore.sizes.top_m.front();
  const double k = std::ceil(std::log(top / p1_m) / std::log(ore.ratio) - 1e-9);
  ore.sizes = geometric_series(p1_m * std::pow(ore.ratio, k), ore.ratio, ore.sizes.size());
  ore.feed = feed_masses(ore.sizes, ore.sieve_m, ore.sieve_passing);
  ore.f80_m = passing_size(ore.sizes, ore.feed, 0.8);  // on the moved series, as the test's
}

void check_bond_sieve(const SizeSeries& s, double p1_m) {
  // The product is what passes P1; its P80 needs class tops below P1 (the
  // sink alone has no size). P1 on a class top (put_sieve_on_class_top)
  // at the finest top, or below it, leaves only the sink.
  const int n = s.size();
  if (n < 3 || !(p1_m > s.top_m[n - 1] * (1 + 1e-9)))
    throw std::invalid_argument(fmt::format(
        "--bond {:g}: the closing sieve must lie above the finest class top ({:.1f} um), so that the test's "
        "product has classes below it: more sizes.classes",
        p1_m * 1e6, s.top_m[n - 1] * 1e6));
}

BondResult bond_test(const SizeSeries& s, const std::vector<double>& feed, const std::vector<double>& S_per_min,
                     const std::vector<std::vector<double>>& b, double rpm, double charge_kg, double p1_m) {
  BondResult r;
  r.p1_um = p1_m * 1e6;
  r.charge_g = charge_kg * 1000;
  const double fresh_fines = mass_below(s, feed, p1_m);  // fraction of fresh feed already below P1
  std::vector<double> m(feed.size());
  for (std::size_t i = 0; i < m.size(); ++i) m[i] = feed[i] * r.charge_g;  // grams
  double revs = 100;
  std::vector<double> product;
  double u = 0;
  for (int c = 1; c <= kBondMaxCycles; ++c) {
    const double fines_in = mass_below(s, m, p1_m);
    m = batch_grind(m, S_per_min, b, revs / rpm);
    const std::vector<double> under = part_below(s, m, p1_m);
    u = 0;
    for (double x : under) u += x;
    const double gbp = (u - fines_in) / revs;
    r.gbp_by_cycle.push_back(gbp);
    r.revs_by_cycle.push_back(revs);
    product = under;
    // Replace the undersize by fresh feed of the same mass.
    for (std::size_t i = 0; i < m.size(); ++i) m[i] += -under[i] + feed[i] * u;
    r.cycles = c;
    // The equilibrium the procedure aims at: Gbp and the load no longer
    // change (the laboratory stops at 3 % over three cycles; the model
    // goes on to the fixed point, where the load is 250 %).
    const std::size_t k = r.gbp_by_cycle.size();
    const double cl = (r.charge_g - u) / u;
    if (k >= 2 && gbp > 0 && std::fabs(gbp - r.gbp_by_cycle[k - 2]) <= kBondSteady * gbp &&
        std::fabs(cl - 2.5) <= 1e-5) {
      r.steady = true;
      break;
    }
    // Next cycle: undersize made to 1/3.5 of the charge.
    const double target = r.charge_g / 3.5 - fresh_fines * u;
    revs = gbp > 0 ? std::clamp(target / gbp, 10.0, 5000.0) : 5000.0;
  }
  r.gbp_g_rev = r.gbp_by_cycle.back();
  r.circulating_load = (r.charge_g - u) / u;
  r.p80_um = passing_size(s, product, 0.8) * 1e6;
  r.f80_um = passing_size(s, feed, 0.8) * 1e6;
  // Bond's formula gives kWh per short ton (907.18474 kg): per tonne, times
  // 1000 / 907.18474 = 1.10231.
  r.wi_kWh_t = kShortTonsPerTonne * 44.5 /
               (std::pow(r.p1_um, 0.23) * std::pow(r.gbp_g_rev, 0.82) *
                (10 / std::sqrt(r.p80_um) - 10 / std::sqrt(r.f80_um)));
  return r;
}

}  // namespace mc::grind
