// Which batch test to run next, by refits (docs/grinding-next-test.md): a preposterior Monte Carlo of the width a
// product's 95 % interval has once a candidate test is fitted with the
// user's. Plausible truths are drawn from what the current tests leave
// open (along the search's rays from the best point, through the 95 %
// region's edge and past it as the normal posterior goes, the free
// parameters refitted there and scattered by their covariance);
// at each, the candidate's readings are made with seeded Gaussian scatter,
// fitted together with the real tests as `--fit` fits them, and the
// product's interval taken as `grind` takes it (fit_covariance, propagate).
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "grind/fit.h"
#include "grind/interval.h"
#include "grind/ore.h"

namespace mc::grind {

// Normal deviates, the same on every machine for a seed (xorshift64* and
// the Box–Muller transform; std::normal_distribution differs by library).
class SeededNormal {
 public:
  explicit SeededNormal(std::uint64_t seed);
  double uniform();  // in (0, 1)
  double next();     // N(0, 1)

 private:
  std::uint64_t state_;
  double spare_ = 0;
  bool has_spare_ = false;
};

// The user's tests, each in its mill, and the parameters they were fitted
// for (--fit-params, free and held): what a candidate is fitted with.
struct RealTests {
  std::vector<TestInMill> tests;
  std::vector<std::string> names;
};

// A plausible truth: an ore drawn from what the current tests leave open.
struct PlausibleTruth {
  Ore ore;
  int edge = -1;          // the edge point whose ray it lies on (-1: none, no held parameter)
  double fraction = 0;    // how far along it, from the best point (0) through the edge (1) and on
  bool refitted = false;  // the free parameters refitted to the real tests there (else interpolated)
};

// n truths, seeded. With held parameters: an edge point of the fitted ore
// ([fitted.edge]) chosen uniformly, a fraction r along the ray from the
// best point through it (each variable, the logarithm of a scale, moved
// by r of its way to the edge, r > 1 past it), clamped to the ore file's
// ranges; r = |z| / t with z a standard normal vector of as many
// components as held parameters (|z| chi-distributed) and t Student's at
// 0.975 with the intervals' ν: where the model is linear the edge points
// lie at t in the coordinates where the region is a ball, and this is the
// normal posterior along the ray, uncut. The free ones refitted there to
// the real tests, then moved by a draw from their covariance
// (interval_covariance: given the held ones). Without held parameters, or
// with held ones but no stored edges (held_without_edges says which): the
// fitted ore moved by that draw alone, the held ones where it holds them.
std::vector<PlausibleTruth> plausible_truths(const Ore& ore, const RealTests& real, int n, std::uint64_t seed);

// The held parameters plausible_truths cannot move (no [fitted.edge]
// reaches them): they stay where the fit holds them. Empty: none.
std::vector<std::string> held_without_edges(const Ore& ore);

// The candidate's test made at `truth`: its sieves, feed and times, the
// products the truth makes in its mill, each informative reading moved by
// a normal deviate of scatter_pp (percentage points), not clipped; along
// each time's sieves correlated by the candidate's sieve_rho (AR(1)).
BatchTest simulated_test(const Ore& truth, const TestInMill& candidate, double scatter_pp, SeededNormal& noise);

// The refitted widths of one candidate over the truths. A draw whose fit
// failed, or whose interval of the product is open, counts as infinitely
// wide (for a user who needs a width it is the worst outcome).
struct RefitWidth {
  int draws = 0, converged = 0;  // converged: a fit and a finite interval
  double median = std::numeric_limits<double>::quiet_NaN();  // over every draw (inf: half or more gave no width)
  double p10 = std::numeric_limits<double>::quiet_NaN(), p90 = std::numeric_limits<double>::quiet_NaN();  // likewise
  double mean = std::numeric_limits<double>::quiet_NaN();    // over the converged draws only
  double wide = std::numeric_limits<double>::quiet_NaN();    // share of draws wider than width_now, or no width
  std::vector<double> per_draw;       // each draw's width, in draw order (inf: none)
  std::vector<double> widths;         // the converged draws' widths, in draw order
  std::vector<std::string> failures;  // each other draw: why it gave no width
};

// The figures of one candidate's draws: per_draw each draw's width (not
// finite: none, `why` saying why, in draw order of those), wide against
// width_now (infinite: the draws with no width alone).
RefitWidth summarise_draws(const std::vector<double>& per_draw, const std::vector<std::string>& why,
                           double width_now = std::numeric_limits<double>::infinity());

// Whether a ranks before b (the better next test): the smaller median
// width (a draw with no width infinitely wide), then the smaller share of
// wide draws, then the smaller 90th percentile, then the smaller mean.
bool ranks_before(const RefitWidth& a, const RefitWidth& b);

// For each truth k: the candidate simulated there (seeded by seed and k, so
// that every candidate sees the same truths and scatter draws), fitted
// with the real tests from `ore` (the fitted ore: its free parameters at
// their fitted values, the held ones where it holds them) for
// real.names, held ones found as --fit finds them; its covariance, profiles
// and rays (fit_covariance); the number's interval (propagate). The
// candidate's readings scatter by scatter_pp and count as the first real
// test's (its noise_pp).
RefitWidth refitted_width(const Ore& ore, const RealTests& real, const std::vector<PlausibleTruth>& truths,
                          const TestInMill& candidate, const std::function<double(const Ore&)>& number,
                          double scatter_pp, std::uint64_t seed);

// The same for several candidates at once, their draws shared out over
// `threads` threads together (0: the machine's cores; the result does not
// depend on how many).
std::vector<RefitWidth> refitted_widths(const Ore& ore, const RealTests& real,
                                        const std::vector<PlausibleTruth>& truths,
                                        const std::vector<TestInMill>& candidates,
                                        const std::function<double(const Ore&)>& number, double scatter_pp,
                                        std::uint64_t seed, unsigned threads = 0);

// The q-quantile of values (0 ≤ q ≤ 1), linear between order statistics
// (+inf where it reaches an infinite one).
double quantile(std::vector<double> values, double q);

}  // namespace mc::grind
