// `grind RUN --ore FITTED --next-test RUN2 ...`: which batch test to run
// next (src/grind/next_test.h, the linear width; src/grind/next_refit.h,
// the refits that size it; docs/grinding-intervals.md, "Which test to run
// next"). The candidates are checked before anything is computed; the
// ranking is computed before anything is written.
#pragma once

#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/grind.h"
#include "app/grind_interval.h"
#include "grind/interval.h"
#include "grind/next_refit.h"
#include "grind/ore.h"
#include "io/run_folder.h"

namespace mc::app {

// The candidate mills, read: each --next-test run with the ore's hold-up
// in its mill, and the sets of times.
struct NextPlan {
  bool asked = false;
  std::vector<std::string> runs;
  std::vector<io::Run> read;
  std::vector<double> holdup_kg;
  std::vector<std::vector<double>> times;
  // The user's tests as the ore's [fitted] table names them (test, run,
  // parameters), for the refits; `refit_note` says why there are none.
  grind::RealTests real;
  std::string refit_note;
  int draws = 8, refit = 3;
  std::uint64_t seed = 1;
};
// Throws std::invalid_argument, naming the option and the run, for a
// candidate that is not a run folder, lacks the normal energy spectrum or
// was run under another contact than the ore's fit, for an ore without a
// usable covariance, and for --next-times or --next-for without
// --next-test.
NextPlan plan_next(const GrindOptions& o, const grind::Ore& ore);

// The product the candidates should narrow: its index among flatten()'s
// numbers and its name.
struct NextTarget {
  std::size_t index = 0;
  std::string name, unit;
};
NextTarget next_target(const GrindOptions& o, const GrindNumbers& made);

struct NextRow {
  std::string run;
  std::vector<double> times;
  grind::Interval expected;  // the linear expectation (next_test.h), centred where the interval now is
  double width = 0;          // its width: the linear width
  std::vector<std::string> fixes;
  bool refitted = false;     // the refits' expected width (below) was computed
  grind::RefitWidth refit;
};
struct NextRanking {
  NextTarget target;
  double value = 0;
  grind::Interval now;
  double width_now = 0;
  // The refitted candidates first, by grind::ranks_before (the smallest
  // median width over every draw, a draw with no width infinitely wide);
  // then the rest by their linear width.
  std::vector<NextRow> rows;
  int draws = 0, refitted = 0;  // draws per refitted candidate; candidates refitted
  std::uint64_t seed = 1;
  std::string refit_note;       // why no candidate was refitted ("": some were)
  std::vector<std::string> held_still;  // held parameters the truths cannot move (grind::held_without_edges)
  double seconds = 0, refit_seconds = 0;
};
// Every candidate (run x times): the linear expected width of the
// target's interval, then, for the first plan.refit of that order (all:
// -1), the refitted one (next_refit.h); ranked by it. `number` makes the
// target's value for an ore.
NextRanking rank_next(const NextPlan& plan, const grind::Ore& ore, const NextTarget& target,
                      const GrindIntervals& ci, const GrindNumbers& made,
                      const std::function<double(const grind::Ore&)>& number);

void print_next(const NextRanking& r);
// next_test.csv, and grind.json's `next_test`.
void write_next_csv(const std::filesystem::path& out, const NextRanking& r);
nlohmann::ordered_json next_json(const NextRanking& r);

}  // namespace mc::app
