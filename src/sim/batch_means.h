// The standard error of a run's mean from batch means: the values of the
// averaging window in equal batches (here eighths of a revolution of the
// mill, the window itself whole revolutions), each batch's mean, and the
// spread of those means. Batches only give an
// honest error when their means are uncorrelated; where the lag-1
// autocorrelation of the means is significant, neighbouring batches are
// merged (the batch doubled) and the test repeated (Flyvbjerg and Petersen,
// J. Chem. Phys. 91, 461, 1989; Law, Simulation Modeling and Analysis, 5th
// ed. 2015, sec. 9.5.3). Plain numbers: no solver, no files.
#pragma once

#include <limits>
#include <vector>

namespace mc {

// Base batches a revolution is cut into. The power of a turning charge
// forgets itself within a few lifter passes (mill D: the autocorrelation of
// its 0.05 s means is gone by 0.15 s, 1/30 of a revolution), so an eighth
// of a revolution is already a long batch; where it is not, the means come
// out correlated and are merged.
inline constexpr int kBatchesPerRevolution = 8;

// Fewest batches an automatic run stops on: eight batch means give the
// standard error to within about ±27 % (one standard deviation). With
// eighths that is one revolution; merged quarters take two.
inline constexpr int kMinBatches = 8;

struct BatchMeans {
  int values = 0;        // base batches given
  int batches = 0;       // batches the error was taken from
  int batch_length = 1;  // base batches per batch after merging
  double mean = std::numeric_limits<double>::quiet_NaN();  // of all the values
  // Standard error of the mean, sd(batch means) / sqrt(batches); NaN with
  // fewer than two batches.
  double sem = std::numeric_limits<double>::quiet_NaN();
  double lag1 = std::numeric_limits<double>::quiet_NaN();  // of the batch means used
  // The means were still correlated where no further merging was possible
  // (fewer than three batches left to test): the error is an underestimate.
  bool correlated = false;
};

// Lag-1 autocorrelation of the batch means above which they count as
// correlated: two standard deviations of its estimate for independent means
// (1/sqrt(n), Bartlett), and never above 0.5, so that a handful of strongly
// correlated means is caught too.
double lag1_limit(int batches);

// `values`: one mean per base batch of equal length, in time order (NaNs,
// such as a batch without a toe, are left out). When the count is not
// a multiple of the batch length, the earliest values, those nearest the
// warm-up, are the ones left out of the error (not out of the mean).
BatchMeans batch_means(const std::vector<double>& values);

// sd / sqrt(n) of the values as if they were independent: what the batch
// means correct.
double naive_sem(const std::vector<double>& values);

// An automatic run's stop rule, checked at the end of each whole
// revolution: at least kMinBatches uncorrelated batches and a standard error
// of at most `tolerance` of the mean.
bool converged(const BatchMeans& b, double tolerance);

}  // namespace mc
