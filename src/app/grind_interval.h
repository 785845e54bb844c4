// The 95 % intervals of `grind`'s products from a fitted ore's covariance
// (src/grind/interval.h): every number grind reports, as one list the
// intervals are propagated through, and back into the console, grind.csv,
// grind.json and grind.png (docs/grinding-intervals.md).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "grind/bond.h"
#include "grind/circuit.h"
#include "grind/interval.h"
#include "grind/ore.h"

namespace mc::app {

// What grind makes of one ore: the products (their P80, kWh/t, feed rate,
// circulating load and cumulative passing at the class tops), Bond's test
// and the throughput at a target.
struct GrindNumbers {
  std::vector<grind::Product> products;
  bool bond = false;  // Bond's test asked for
  grind::BondResult bond_result;
  double target_rate_t_h = 0;
  bool target = false;
};
std::vector<double> flatten(const GrindNumbers& g);

struct ProductInterval {
  grind::Interval p80_um, kWh_t, feed_t_h, circulating_load;
  std::vector<grind::Interval> passing;  // at each class top
};
struct GrindIntervals {
  bool given = false;
  // Why none were made though the ore has a covariance: a fitted or held
  // parameter of the ore differs from the value the covariance was computed
  // at (grind::stale_covariance), or another key of its [sizes],
  // [breakage] or [rates] tables was edited (io::changed_tables); ""
  // otherwise.
  std::string stale;
  std::string stale_key;  // the [fitted] key it differs from: covariance_values or tables_fnv1a
  std::vector<grind::Correlated> correlated;  // pairs beyond |r| > 0.99
  std::vector<std::string> open_held;  // grind::open_held: held parameters the data do not bound in the file's range
  std::string outside;  // grind::outside_region: the held values outside the data's 95 % region ("" : inside)
  std::vector<ProductInterval> products;
  grind::Interval work_index_kWh_t, bond_p80_um, gbp_g_rev, throughput_t_h;
};

// Why the ore's covariance no longer describes it: a fitted or held
// parameter moved (grind::stale_covariance; key covariance_values), or
// another key of its tables edited (io::changed_tables; key
// tables_fnv1a). Empty `what`: it does. For intervals and --next-test alike.
struct Staleness {
  std::string what, key;
};
Staleness covariance_staleness(const grind::Ore& ore);

// The intervals of what `make` gives for the ore; none (given false) for an
// ore whose [fitted] table has no covariance, or whose fitted values were
// changed since (`stale` says which).
GrindIntervals grind_intervals(const grind::Ore& ore, const GrindNumbers& made,
                               const std::function<GrindNumbers(const grind::Ore&)>& make);

// " [lo, hi]" with the value's format, " [> lo]" or " [< hi]" for an
// interval open at one end, or "" without an interval.
std::string bracket(const grind::Interval& i, double scale, const char* format);

}  // namespace mc::app
