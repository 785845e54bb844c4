// An ore fitted to a laboratory batch grinding test (docs/grinding-fit.md):
// the test (the feed and the products' cumulative passing at the same
// sieves after each grinding time), the ore's parameters a fit may move,
// a small Levenberg–Marquardt least-squares solver with a numerical
// Jacobian, the parameters' standard errors from (JᵀJ)⁻¹ s² at the
// solution and which of them the data cannot fix, and the fit of one
// parameter to a measured Bond work index.
#pragma once

#include <functional>
#include <optional>
#include <limits>
#include <string>
#include <vector>

#include "grind/bond.h"
#include "grind/ore.h"
#include "grind/pbm.h"

namespace mc::grind {

// A batch grinding test in the laboratory mill (src/io/batch_test_file.h
// reads one): one set of sieves for the feed and every product.
struct BatchTest {
  std::vector<double> sieve_m;               // descending, coarsest first
  std::vector<double> feed_passing;          // at each sieve, the first 1
  std::vector<double> times_min;             // ascending, > 0
  std::vector<std::vector<double>> passing;  // [time][sieve], 0..1
  double holdup_kg = 0;                      // the ore in the test mill; 0: the ore file's
  double noise_pp = 1;                       // the sieving's scatter, percentage points
};

// Cumulative passing of class masses m (summing to 1) at size x: log-linear
// between the class tops, 1 above the top class. x must not lie below the
// finest class top.
double passing_at(const SizeSeries& s, const std::vector<double>& m, double x_m);

// The test's products as the ore makes them in a mill of this power and
// spectrum with this hold-up: [time][sieve]. The ore's own feed is replaced
// by the test's.
std::vector<std::vector<double>> batch_test_products(const Ore& ore, const std::vector<SpectrumBin>& spectrum,
                                                     double power_W, double holdup_kg, const BatchTest& test);

// ------------------------------------------------------------ parameters

// An ore parameter a fit may move, named by its key in the ore file
// ("efficiency", "e_inf_J_kg", "breakage.beta", ...), in the file's units.
// `log`: fitted as its logarithm (a positive scale); else as itself.
struct OreParameter {
  std::string name;
  bool log = true;
  double lo = 0, hi = 0;  // the ore file's range, file units
  bool any_model = false;  // the appearance function: every rate model
  RateModel model = RateModel::spectrum;
  double (*get)(const Ore&) = nullptr;
  void (*set)(Ore&, double) = nullptr;
  std::optional<Appearance> appearance;  // a parameter of this appearance function only
};
const std::vector<OreParameter>& ore_parameters();
// nullptr: no such name. "phi" alone is ambiguous (rates.phi, breakage.phi).
const OreParameter* find_ore_parameter(const std::string& name);
// The parameter a name not found most likely meant: the one it matches
// ignoring case, else the nearest by edit distance (case ignored).
std::string closest_ore_parameter(const std::string& name);

// ------------------------------------------------------------ least squares

// Minimise sum r_i(x)² over x within [lo, hi] (componentwise):
// Levenberg–Marquardt with Marquardt's diagonal scaling and a central-
// difference Jacobian. Converged when the residuals are orthogonal to
// every column of J (cosine below 1e-8), when a step changes no x by more
// than 1e-10 (1 + |x|) and the sum by less than 1e-12 of itself, or when
// the sum falls below 1e-28.
struct LmProblem {
  std::function<void(const std::vector<double>& x, std::vector<double>& r)> residuals;
  std::vector<double> x0, lo, hi;
  int n_data = 0;
  int max_iterations = 300;
};
struct LmResult {
  std::vector<double> x, r;
  std::vector<std::vector<double>> J;  // [data][parameter] at x
  double ssr = 0;
  int iterations = 0, evaluations = 0;
  bool converged = false;
};
LmResult levenberg_marquardt(const LmProblem& p);

// Standard errors of the parameters from (JᵀJ)⁻¹ s², s² = ssr / (n - p),
// through the eigen-decomposition of JᵀJ scaled to a unit diagonal. A
// parameter is unidentified when it has the largest component of a
// direction of JᵀJ whose eigenvalue is below 1e-10 of the largest (a
// singular direction: the others can take its part), when the data do not
// depend on it at all, or when its standard error (in the fitted variable:
// the logarithm for a scale) is above se_limit (by parameter; empty: 1, a
// factor of e for a logarithm).
struct Identification {
  std::vector<double> se;        // of the fitted variables; NaN where unidentified
  std::vector<bool> identified;
  std::vector<std::string> why;  // for the unidentified
  double condition = 0;          // largest over smallest eigenvalue of the scaled JᵀJ
};
Identification identify(const std::vector<std::vector<double>>& J, double ssr,
                        const std::vector<double>& se_limit = {});

// s² (JᵀJ)⁻¹ with s² = ssr / (n − p), through the same scaled eigen-
// decomposition as identify (directions below 1e-10 of the largest left out).
std::vector<std::vector<double>> covariance_matrix(const std::vector<std::vector<double>>& J, double ssr);

// ------------------------------------------------------------ the fit

struct FittedParameter {
  std::string name;
  double start = 0, value = 0;
  double se = 0;            // standard error in the parameter's units (NaN: unidentified or on its bound)
  bool identified = true;   // false: held at its start and refitted without it
  bool at_bound = false;    // the fit ended on the ore file's range: no standard error
  std::string why;          // why it is unidentified
};
struct BatchFit {
  Ore ore;                                      // the start with the fitted values
  std::vector<FittedParameter> parameters;
  std::vector<std::vector<double>> predicted;   // [time][sieve] of the first test
  std::vector<std::vector<std::vector<double>>> predicted_by_test;
  std::vector<double> rms_by_test;              // pp
  double rms_pp = 0;                            // of every test's products, pp as measured
  double ssr = 0;                               // weighted by the tests' noise (fit_batch_tests)
  int iterations = 0, evaluations = 0, data = 0, refits = 0;
  int free = 0;                                 // parameters left free (0: every one held)
  double condition = 0;
  // The covariance of the free parameters off their bounds, in their fitted
  // variables (the logarithm of a scale): s² (JᵀJ)⁻¹ at the solution.
  std::vector<std::size_t> covariance_of;       // indices into `parameters`
  std::vector<std::vector<double>> covariance;
  double s2 = 0;                                // ssr / (data − free), pp² of the first test
  int dof = 0;
  // The raw residuals' lag-1 autocorrelation along the sieves
  // (residual_lag1): near 0 for independent sieve errors; well above for
  // errors that move neighbouring sieves together (sieve_errors.h).
  double residual_r1 = std::numeric_limits<double>::quiet_NaN();
  // The weighted residuals before whitening (pp of the first test), row by
  // row: each test's times in turn, each row a time's informative sieves,
  // coarse to fine (what the sieve errors' ρ is estimated from).
  std::vector<double> raw_residuals;
  std::vector<std::size_t> residual_rows;
  // Their Jacobian in the variables of `covariance_of`, [data][variable]
  // (the restricted likelihood of the sieve errors' ρ reads it).
  std::vector<std::vector<double>> raw_jacobian;
};
// The lag-1 autocorrelation of residuals along the sieves, pooled: rows
// of `row_lengths` consecutive residuals (a test time's, its sieves coarse
// to fine), r1 = Σ d_k d_{k+1} / Σ d_k² over every row's neighbours, d the
// residual less the mean of all. NaN with no neighbours or no scatter.
double residual_lag1(const std::vector<double>& residuals, const std::vector<std::size_t>& row_lengths);
// Fits the named parameters of `start` to the test through the mill's
// spectrum and power, with the hold-up `holdup_kg`. An unidentified
// parameter is held at its start and the rest fitted again, one at a time.
// A scale (fitted as its logarithm) is unidentified past a standard error of
// 1 (a factor of e), any other past a quarter of its range. Throws
// std::invalid_argument for a name it does not know or that the ore's rate
// model lacks, more parameters than data, sieves below the finest class,
// and a fit that does not converge.
BatchFit fit_batch_test(const Ore& start, const std::vector<SpectrumBin>& spectrum, double power_W,
                        double holdup_kg, const BatchTest& test, const std::vector<std::string>& names,
                        int max_iterations = 300);

// Several batch tests of one ore, each in the mill it was made in (its
// run's spectrum and power, the test's hold-up), fitted together: their
// residuals side by side, the rest as fit_batch_test.
struct TestInMill {
  BatchTest test;
  std::vector<SpectrumBin> spectrum;
  double power_W = 0, holdup_kg = 0;
  // The sieve errors' correlation from one sieve to the next along each
  // time's readings (sieve_errors.h): 0, independent; else the residuals
  // are whitened by it before they are squared.
  double sieve_rho = 0;
};
// Each test's residuals count by 1/noise_pp²: a test sieved to 0.5 pp
// counts four times one sieved to 1 pp. The weights are taken relative to
// the first test's noise, so that the sum of squares and s² are in pp² of
// a reading of the first test, and tests of equal noise fit as unweighted.
// A parameter the fit ends within kBoundWhisker of its range (in the
// fitted variable) from a bound is put on the bound. hold_unidentified
// false: none is held (a refit of parameters known to be free, for a
// profile).
BatchFit fit_batch_tests(const Ore& start, const std::vector<TestInMill>& tests, const std::vector<std::string>& names,
                         int max_iterations = 300, bool hold_unidentified = true);
constexpr double kBoundWhisker = 1e-6;
// The tests' residual weights, noise_pp of the first over each's (all 1
// where the noises are alike). Throws std::invalid_argument for a noise of
// 0 beside others.
std::vector<double> test_weights(const std::vector<TestInMill>& tests);
// The weighted residuals of the ore's products against the tests (pp of
// the first test), over the sieves the fit reads, time by time, each
// time's sieves whitened by the test's sieve_rho (what the fit minimises),
// and their sum of squares.
std::vector<double> weighted_residuals(const Ore& ore, const std::vector<TestInMill>& tests);
double weighted_ssr(const Ore& ore, const std::vector<TestInMill>& tests);
// The sieves of a test that carry information: not passing 1 in the feed
// and every product.
std::vector<std::size_t> informative_sieves(const BatchTest& test);

// One parameter set so that Bond's test (bond.h) in this mill gives the
// work index `wi_kWh_t`: bisection on the parameter's logarithm over its
// range, to 1e-4 of the index. Throws std::invalid_argument where the
// range cannot reach it (naming the index at the ends) or it is not met.
struct WiFit {
  double value = 0, start = 0;
  double dvalue_dwi = 0;  // the parameter's change per kWh/t at the solution
  BondResult bond;
  int evaluations = 0;
};
WiFit fit_work_index(const Ore& ore_on_p1, const std::vector<SpectrumBin>& spectrum, double power_W, double rpm,
                     double p1_m, double wi_kWh_t, const std::string& name);

// What differs between the contact an ore was fitted under and a run's
// ("restitution 0.4 -> 0.7, ..."); empty when they agree to 1e-6 relative
// or the ore was not fitted.
std::string contact_mismatch(const ContactRecord& fitted, const ContactRecord& run);

}  // namespace mc::grind
