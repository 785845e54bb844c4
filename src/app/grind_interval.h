// The 95 % intervals of `grind`'s products from a fitted ore's covariance
// (src/grind/interval.h): every number grind reports, as one list the
// intervals are propagated through, and back into the console, grind.csv,
// grind.json and grind.png (docs/grinding.md, "Intervals").
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
  std::vector<ProductInterval> products;
  grind::Interval work_index_kWh_t, bond_p80_um, gbp_g_rev, throughput_t_h;
};

// The intervals of what `make` gives for the ore; none (given false) for an
// ore whose [fitted] table has no covariance.
GrindIntervals grind_intervals(const grind::Ore& ore, const GrindNumbers& made,
                               const std::function<GrindNumbers(const grind::Ore&)>& make);

// " [lo, hi]" with the value's format, or "" without an interval.
std::string bracket(const grind::Interval& i, double scale, const char* format);

}  // namespace mc::app
