// The fit's uncertainty carried to what a fitted ore makes (docs/
// grinding-intervals.md): what a batch-test fit leaves open (the covariance
// of its free parameters, the range its held ones may take, alone and
// together), and the 95 % interval of any number computed from the ore:
// linearised propagation (the delta method) in the free parameters,
// combined in quadrature with how far the held ones move the number.
// One statistical basis throughout: S_min, the least weighted sum of
// squares over every parameter named (free and held), and its degrees of
// freedom ν = data − free − held (interval_dof); s² = S_min / ν scales the
// free parameters' covariance, Student's t with ν is the delta method's
// quantile, and F(1, ν) = t² the profiles'.
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
// The parameter's key in the ore file: "rates.efficiency", "breakage.phi".
std::string ore_file_key(const std::string& parameter);

// What the fit leaves open. A held parameter (unidentified, or on its
// bound) is given the range over which the free ones and the other held
// ones, refitted with it there, stay within the data: its profile. The
// limit is S_min (1 + t²/ν): S the weighted sum of squares, S_min the
// least the profiles meet, t Student's at 0.975 with ν = interval_dof
// (F(1, ν) = t² at 95 %). A profile's point is the lower S of two refits
// from the point before: everything else refitted, and (where that one is
// past the limit or fails: a refit along a flat direction can end in a
// worse valley) the free ones alone, the other held ones kept.
//  1. Where the held ones fit best: each in turn moved through the best
//     point met, stepped out (a factor of e for a scale, a quarter of its
//     file range for a value) to the file's range or past the limit, its
//     least S refined by golden sections (to a thousandth of a step, or a
//     flat profile; at most 16 refits).
//  2. Through that point, each one's stretch within the limit: its ends by
//     halvings to 2 % of their distance from it (at most twenty), the
//     range widened to hold where the parameter is held.
//  3. Two to four held together, from the best point toward each corner of
//     their ranges, as far as the limit allows (the corner, or six
//     halvings short of it; four past it); five or more: their ranges alone.
// The best point and the edge points (2, 3) are kept with the covariance.
// The free parameters' covariance and the information (JᵀJ / s², every
// variable) are taken at the best point (best_point), where the intervals
// are centred; without held ones, at the fit.
FitCovariance fit_covariance(const BatchFit& fit, const std::vector<SpectrumBin>& spectrum, double power_W,
                             double holdup_kg, const BatchTest& test);
// The same for tests fitted together (fit_batch_tests).
FitCovariance fit_covariance(const BatchFit& fit, const std::vector<TestInMill>& tests);
// The profile's limit of S: S_min (1 + t²/ν).
double profile_limit(double ssr_min, int dof);

// The degrees of freedom of the intervals: the data less every parameter
// fitted at S_min, the free and the held ones (the fit's dof less the held
// count). S_min is the least S over all of them, so its ν counts them all.
int interval_dof(const FitCovariance& u);
// s² of the intervals: S_min / interval_dof, S_min where the held
// parameters fit best (ssr_best); the fit's own s² without held ones. An
// ore that kept no ssr_best: the fit's S over interval_dof.
double interval_variance(const FitCovariance& u);
// The free parameters' covariance at that s²: the fit's, whose s² is S at
// the held point over the fit's dof, scaled by interval_variance / s².
std::vector<std::vector<double>> interval_covariance(const FitCovariance& u);

// The quantile of Student's t with `dof` degrees of freedom at probability
// p (0.975 for a 95 % interval); the normal's for dof <= 0. Closed forms
// for 1 and 2 degrees of freedom, else the distribution function (the
// regularised incomplete beta function of pbm.h) inverted by bisection.
double t_quantile(double p, int dof);

// An interval; an end at ±infinity is open (the number goes past any
// bound there: a throughput whose ore cannot reach the target).
struct Interval {
  double lo = std::numeric_limits<double>::quiet_NaN(), hi = std::numeric_limits<double>::quiet_NaN();
  bool valid() const { return lo == lo && hi == hi; }
  bool open_below() const { return lo == -std::numeric_limits<double>::infinity(); }
  bool open_above() const { return hi == std::numeric_limits<double>::infinity(); }
};

// What propagation needs of one number f makes: its value, whether it is
// taken as its logarithm, its gradient in the free variables (and, asked
// for, in the held ones with the free ones fixed), and how far the held
// parameters move it below and above (down <= 0 <= up; -inf or +inf: past
// any bound).
struct Sensitivity {
  bool ok = false;
  double value = std::numeric_limits<double>::quiet_NaN();
  bool log = false;
  std::vector<double> g, g_held;
  // The centre the interval is built around (the logarithm where `log`):
  // the number where the held parameters fit the data best, the free ones
  // refitted there (FitCovariance::best); the value itself without held
  // ones. down and up: the held parameters' reach from it, below and
  // above, over their points and where they are held.
  double center = std::numeric_limits<double>::quiet_NaN();
  double down = 0, up = 0;
  std::vector<double> down_by_held, up_by_held;  // each held parameter's range alone
};

// The numbers f makes from the ore, and their sensitivities: the gradient
// at best_point (where the interval is centred; the free ones' covariance
// is taken there too) by differences in the fitted variables (steps of a tenth of each one's
// standard error: central, or one-sided of second order where a step
// would cross the ore file's range); the held parameters at their best
// point and their edge points, the free ones as refitted there (an ore
// written without them: each held one at its range's ends). A number
// positive at every point is taken as its logarithm (its interval stays
// above 0). A NaN or a throw at a point leaves that number without one (ok
// false); -inf or +inf at a held parameter's point opens that end.
std::vector<Sensitivity> sensitivities(const Ore& ore, const FitCovariance& u,
                                       const std::function<std::vector<double>(const Ore&)>& f,
                                       bool held_gradient = false);
// The interval of one number: around its centre, the delta method's
// half-width q √(gᵀ C g) (q = t · width_scale) combined in quadrature with
// the held parameters' reach to each side (times width_scale). For a
// model linear in its parameters this is the interval of the number's
// profile over every parameter at the limit S_min (1 + t²/ν).
Interval interval_of(const Sensitivity& s, const std::vector<std::vector<double>>& C, double q, double width_scale);

// The 95 % intervals of the numbers f makes (NaN where one cannot be made):
// interval_of with interval_covariance and t at interval_dof. width_scale 1
// but for tests of the coverage.
std::vector<Interval> propagate(const Ore& ore, const FitCovariance& u,
                                const std::function<std::vector<double>(const Ore&)>& f, double width_scale = 1.0);

// The ore with the fitted variables x of u's free parameters.
Ore with_variables(const Ore& ore, const FitCovariance& u, const std::vector<double>& x);
// The point the intervals are centred at and their free part taken: the
// held parameters where they fit best, the free ones refitted there
// (FitCovariance::best); `ore` itself without held ones or a best point.
Ore best_point(const Ore& ore, const FitCovariance& u);

// "" when the ore's free and held parameters have the values the
// covariance was computed at (to 1e-7); else the first that differs, by its
// ore file key: "rates.efficiency = 0.4, the covariance is at 0.3519"
// (a hand edit: the covariance no longer describes this ore).
std::string stale_covariance(const Ore& ore, const FitCovariance& u);

// "" unless the held parameters' own values lie outside the data's 95 %
// region (the sum of squares where they are held above the limit from
// where they fit best): then a sentence naming them, S there against the
// limit, and where they fit best.
std::string outside_region(const FitCovariance& u);

// The held parameters (not on a bound) whose range reaches the ore file's
// range on a side, "d0_mm (0.0001 to 1000)": there the data do not bound
// them, and a product's reach is the file's range, not a 95 % statement.
std::vector<std::string> open_held(const FitCovariance& u);

// Pairs of fitted variables correlated beyond |r| > limit: the tests fix
// only their combination.
struct Correlated {
  std::string a, b;  // variable names
  double r = 0;
};
std::vector<Correlated> correlated_pairs(const FitCovariance& u, double limit = 0.99);

}  // namespace mc::grind
