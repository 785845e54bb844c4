// The intervals of grind's products (grind_interval.h).
#include "app/grind_interval.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "grind/pbm.h"
#include "io/ore_file.h"

namespace mc::app {

using namespace mc::grind;

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
double um(double m) { return std::isfinite(m) ? m * 1e6 : kNaN; }
}  // namespace

// Per product: P80 (um), kWh/t, feed rate, circulating load, the passing at
// each class top; then Bond's Wi, P80 and Gbp; then the throughput.
std::vector<double> flatten(const GrindNumbers& g) {
  std::vector<double> v;
  for (const Product& p : g.products) {
    v.insert(v.end(), {um(p.p80_m), p.kWh_t, p.feed_t_h, p.circulating_load});
    const std::vector<double> pp = passing(p.m);
    v.insert(v.end(), pp.begin(), pp.end());
  }
  if (g.bond) v.insert(v.end(), {g.bond_result.wi_kWh_t, g.bond_result.p80_um, g.bond_result.gbp_g_rev});
  if (g.target) v.push_back(g.target_rate_t_h);
  return v;
}

Staleness covariance_staleness(const Ore& ore) {
  const FitCovariance& u = ore.fitted_under.covariance;
  Staleness st{stale_covariance(ore, u), "covariance_values"};
  if (st.what.empty()) {
    // Any other key of the ore's tables edited (breakage.beta, sizes, the basis).
    const std::string t = io::changed_tables(ore, u.tables_hash);
    if (!t.empty()) st.what = t + " differ from the tables the ore was fitted with";
    st.key = "tables_fnv1a";
  }
  return st;
}

GrindIntervals grind_intervals(const Ore& ore, const GrindNumbers& made,
                               const std::function<GrindNumbers(const Ore&)>& make) {
  GrindIntervals out;
  const FitCovariance& u = ore.fitted_under.covariance;
  if (!u.given) return out;
  const Staleness st = covariance_staleness(ore);
  out.stale = st.what;
  out.stale_key = st.key;
  if (!out.stale.empty()) return out;
  out.correlated = correlated_pairs(u);
  out.outside = outside_region(u);
  out.open_held = open_held(u);
  const std::size_t n = flatten(made).size();
  const std::vector<Interval> all = propagate(ore, u, [&](const Ore& o) {
    const std::vector<double> v = flatten(make(o));
    if (v.size() != n) throw std::runtime_error("another set of numbers");
    return v;
  });
  out.given = true;
  std::size_t k = 0;
  for (const Product& p : made.products) {
    ProductInterval q;
    q.p80_um = all[k++];
    q.kWh_t = all[k++];
    q.feed_t_h = all[k++];
    q.circulating_load = all[k++];
    for (std::size_t i = 0; i < p.m.size(); ++i) q.passing.push_back(all[k++]);
    out.products.push_back(q);
  }
  if (made.bond) {
    out.work_index_kWh_t = all[k++];
    out.bond_p80_um = all[k++];
    out.gbp_g_rev = all[k++];
  }
  if (made.target) out.throughput_t_h = all[k++];
  return out;
}

std::string bracket(const Interval& i, double scale, const char* format) {
  if (!i.valid()) return "";
  if (i.open_below() && i.open_above()) return " [open: no bound either way]";
  if (i.open_above()) return fmt::format(fmt::runtime(std::string(" [> ") + format + "]"), i.lo * scale);
  if (i.open_below()) return fmt::format(fmt::runtime(std::string(" [< ") + format + "]"), i.hi * scale);
  const std::string f = std::string(" [") + format + ", " + format + "]";
  return fmt::format(fmt::runtime(f), i.lo * scale, i.hi * scale);
}

}  // namespace mc::app
