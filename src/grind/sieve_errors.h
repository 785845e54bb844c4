// Sieve errors correlated along a product's sieves (docs/grinding-intervals.md,
// "Sieve errors correlated between sieves"). A sieve that keeps too much
// leaves too little for the next, so the errors of a product's readings
// move together from one sieve to the next. The model: along each test
// time's readings, coarse sieve to fine, a first-order autoregression
//   e_0 = σ ξ_0,  e_k = ρ e_{k−1} + σ √(1 − ρ²) ξ_k,   ξ independent, unit,
// so that every reading scatters by σ and neighbours correlate by ρ; the
// test times (separate products) and the tests are independent. The fit
// then minimises the residuals whitened by the Prais–Winsten transform,
//   w_0 = r_0,  w_k = (r_k − ρ r_{k−1}) / √(1 − ρ²),
// which are independent of one variance σ² (pp², as the readings): least
// squares on w is generalised least squares on r, and every interval,
// profile and information computed from the whitened residuals counts the
// readings for what they tell. ρ is estimated by maximum likelihood from
// the fit's own residuals, the parameters refitted at it, until it
// settles (feasible GLS, Cochrane–Orcutt style).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "grind/fit.h"

namespace mc::grind {

// Whiten `rows` consecutive rows of `len` residuals each, in place
// (Prais–Winsten as above). ρ = 0 leaves them. ρ must lie in [0, 1).
void whiten_rows(double* r, std::size_t rows, std::size_t len, double rho);

// Its inverse on one row of `len`.
void unwhiten_row(double* r, std::size_t len, double rho);

// The AR(1) ρ of the largest restricted likelihood (REML) for a fit's
// residual rows r (each row one test time's residuals, coarse to fine)
// with their Jacobian J in the p fitted variables, the model taken as
// linear about the fit and σ² profiled out:
//   ℓ(ρ) = (R/2) ln(1 − ρ²) − ((n − p)/2) ln S(ρ) − ½ ln det(J_ρᵀ J_ρ),
// J_ρ, r_ρ the rows whitened without the 1/√(1 − ρ²) scale (the first of
// each row times √(1 − ρ²), the rest r_k − ρ r_{k−1}), S(ρ) the least sum
// of squares of r_ρ + J_ρ δ over δ, n readings, R rows. The last term and
// n − p in place of n take the fit's share of the residuals out of the
// estimate: the plain likelihood (p = 0, no J) comes out low by about
// 0.06 at ρ = 0.7 on 5 × 12 readings. Searched over [0, kMaxSieveRho] on a
// grid of 0.001 and refined by golden section, then multiplied by
// n / (n − 2): an autoregression's ρ estimated from n readings comes out
// low by about 2ρ/n, n the readings in rows of two or more
// (tests/test_sieve_errors.cpp measures both). 0 with fewer than three
// such readings.
double sieve_rho_reml(const std::vector<double>& r, const std::vector<std::vector<double>>& J,
                      const std::vector<std::size_t>& row_lengths);
// ℓ(ρ) above (less terms that do not depend on ρ); −∞ where it cannot be
// taken (ρ outside [0, 1), J not of r's rows, no residual left).
double sieve_rho_restricted_loglik(const std::vector<double>& r, const std::vector<std::vector<double>>& J,
                                   const std::vector<std::size_t>& row_lengths, double rho);
// Rounds of refits at a new ρ at most.
constexpr int kSieveRhoRounds = 8;
constexpr double kMaxSieveRho = 0.98;

// How a fit takes the sieve errors: `automatic` fits them as independent
// and, where the residuals' lag-1 autocorrelation along the sieves is above
// kSwitchToCorrelated, again with ρ estimated; `independent` never;
// `correlated` always estimates ρ.
// For independent errors r1 is about −0.1 ± 0.13 on 5 × 12 readings, so
// 0.15 (two of its scatter above) takes about 5 % of independent tests as
// correlated, where ρ comes out small and the interval a little wider;
// at 0.3 errors correlated by ρ = 0.4 went unseen in 45 % of tests, and
// the intervals of all covered 0.90 against 0.94 (docs/grinding-intervals.md).
constexpr double kSwitchToCorrelated = 0.15;
enum class SieveErrors { automatic, independent, correlated };
std::optional<SieveErrors> parse_sieve_errors(const std::string& s);
const char* sieve_errors_name(SieveErrors e);

struct SieveErrorFit {
  BatchFit fit;                   // at the final ρ
  std::vector<TestInMill> tests;  // the tests with that ρ (sieve_rho): for fit_covariance and refits
  double rho = 0;                 // 0: independent
  double r1_independent = 0;      // the residuals' lag-1 autocorrelation of the fit at ρ = 0 (NaN: none)
  int rounds = 0;                 // fits at an estimated ρ
  bool correlated = false;        // the fit used the AR(1) model
  bool settled = true;            // ρ moved by less than 0.002 in the last round (else kSieveRhoRounds ran out)
  bool at_cap = false;            // ρ on kMaxSieveRho: errors (or misfit) AR(1) does not describe
  std::string why_failed;         // a fit at a new ρ failed: the last that converged stands, and this is why
};
// Fits the tests (fit_batch_tests) under the error model `mode`. The
// estimated ρ is one for every test (pooled). ρ stops when a round moves
// it by less than 0.002 or after kSieveRhoRounds rounds. Each round's fit
// starts where the fit at ρ = 0 started; one that does not converge is
// tried from that fit's parameters, and where that fails too the last fit
// that converged stands (why_failed): the fit at ρ = 0 in the first round,
// else the round before (not settled). A new ρ of 0 goes back to the fit
// at ρ = 0.
SieveErrorFit fit_with_sieve_errors(const Ore& start, std::vector<TestInMill> tests,
                                    const std::vector<std::string>& names, SieveErrors mode,
                                    int max_iterations = 300);

// The lag-1 autocorrelation (residual_lag1) of the fit's residuals whitened
// by rho: near 0 where the AR(1) model took the correlation up.
double whitened_lag1(const BatchFit& fit, double rho);

// The note the console prints once for a fit (empty: nothing to say).
std::string sieve_errors_note(double r1_independent, double rho, SieveErrors mode);
// The notes on how ρ's estimate ended (on its cap, not settled, a failed
// round), each a line; empty where there is nothing to say.
std::vector<std::string> sieve_errors_warnings(const SieveErrorFit& f);

}  // namespace mc::grind
