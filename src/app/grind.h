// `millcharge grind RUN_DIR --ore ORE.toml`: the product size a mill makes,
// from a finished run's power and normal energy spectrum and an ore's
// breakage parameters (docs/grinding.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace mc::app {

struct GrindOptions {
  std::string run_dir;
  std::string ore;                 // --ore FILE
  std::vector<double> times_min;   // --time, batch grinding times (min)
  double feed_rate_t_h = 0;        // --feed-rate, a continuous mill (t/h)
  double target_p80_um = 0;        // --target-p80: the feed rate that gives it
  int tanks = 0;                   // --tanks, 0: the ore file's (default 1)
  double bond_p1_um = 0;           // --bond: the locked-cycle test at this closing sieve
  double classifier_d50c_um = 0;   // --classifier: the continuous mill closed by a classifier
  double classifier_alpha = 3;     // --sharpness
  double classifier_bypass = 0;    // --bypass
  std::string out;                 // --out, default RUN_DIR/grind (RUN_DIR/fit for a fit)
  bool quiet = false;
  // Calibration (grind_fit.cpp): the ore fitted to a laboratory batch test
  // through this run, or one of its rates' scales to a measured Bond work
  // index (with --bond).
  std::vector<std::string> fit_tests;   // --fit TEST.toml, once or more (fitted together)
  std::vector<std::string> fit_params;  // --fit-params NAME,... (default: the rate model's scale)
  double fit_wi_kWh_t = 0;              // --fit-wi: the measured work index to meet
  // --sieve-errors auto|independent|correlated: how --fit takes the sieve
  // errors (grind/sieve_errors.h); "" not given (auto).
  std::string sieve_errors;
  // Scale-up: beside the spectrum model's products in this run, those of
  // the energy-specific rates the ore has in a laboratory run.
  std::string scale_from;               // --scale-from LAB_RUN
  // Which test to run next (grind_next.cpp): candidate mills' runs, sets of
  // grinding times, and the product whose interval they should narrow.
  std::vector<std::string> next_tests;           // --next-test RUN, once or more
  std::vector<std::vector<double>> next_times;   // --next-times MIN,..., once or more
  std::string next_for;                          // --next-for wi|throughput|p80:K
  // The refits that size each candidate's expected width (next_refit.h):
  // simulated tests per candidate, their seed, and how many candidates
  // (the linear ranking's first) are refitted.
  int next_draws = 8;                            // --next-draws N
  std::uint64_t next_seed = 1;                   // --next-seed S
  int next_refit = 3;                            // --next-refit K (0 or more; -1, not from the command line: every candidate)
};

int cmd_grind(const GrindOptions& o);
// --fit or --fit-wi: writes the fitted ore, fit.json, and for a batch test
// fit_residuals.csv and fit.png.
int cmd_grind_fit(const GrindOptions& o);

}  // namespace mc::app
