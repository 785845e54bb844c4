// The fit's uncertainty carried to what a fitted ore makes (docs/grinding.md,
// "Intervals"): what a batch-test fit leaves open (the covariance of its
// free parameters, the range its held ones may take), and the 95 % interval
// of any number computed from the ore by linearised propagation (the delta
// method) widened by the held parameters' envelope.
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "grind/fit.h"
#include "grind/ore.h"

namespace mc::grind {

// The fitted variable's name in the ore file: "log(efficiency)", "zeta1".
std::string variable_name(const std::string& parameter);
// The parameter a fitted variable's name names; "" when it is none.
std::string parameter_of_variable(const std::string& variable);

// What the fit leaves open. A held parameter (unidentified, or on its bound)
// is given the range over which the free ones, refitted with it there, stay
// within the data: its profile, stepped out from where it is held (a factor
// of e at a time for a scale, a quarter of its file range for a value) until
// the sum of squares has risen by more than 3.84 s² (χ²₁ at 95 %) or the
// ore file's range ends, at most 6 steps a side.
FitCovariance fit_covariance(const BatchFit& fit, const std::vector<SpectrumBin>& spectrum, double power_W,
                             double holdup_kg, const BatchTest& test);
// The same for tests fitted together (fit_batch_tests).
FitCovariance fit_covariance(const BatchFit& fit, const std::vector<TestInMill>& tests);

// The two-sided quantile of Student's t with `dof` degrees of freedom at
// probability p (0.975 for a 95 % interval); the normal's for dof <= 0.
double t_quantile(double p, int dof);

struct Interval {
  double lo = std::numeric_limits<double>::quiet_NaN(), hi = std::numeric_limits<double>::quiet_NaN();
  bool valid() const { return lo == lo && hi == hi; }
};

// Intervals of the numbers f makes from the ore (NaN where one cannot be
// made): f(ore) ± q sqrt(gᵀ C g) · width_scale, g by central differences
// in the fitted variables (steps of a tenth of each one's standard error),
// q Student's t at 0.975; each held parameter moves the interval's ends by
// the furthest f reaches at its range's ends (the free ones there as
// refitted), below and above. A number positive at every point is
// propagated as its logarithm (its interval stays above 0). width_scale 1
// but for tests of the coverage. An f that is NaN or throws at any point
// leaves that number without one.
std::vector<Interval> propagate(const Ore& ore, const FitCovariance& u,
                                const std::function<std::vector<double>(const Ore&)>& f, double width_scale = 1.0);

// The ore with the fitted variables x of u's free parameters.
Ore with_variables(const Ore& ore, const FitCovariance& u, const std::vector<double>& x);

}  // namespace mc::grind
