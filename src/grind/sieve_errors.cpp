// Sieve errors correlated along a product's sieves: the whitening, ρ's
// maximum likelihood and the fit that estimates it (sieve_errors.h).
#include "grind/sieve_errors.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace mc::grind {

// The restricted log-likelihood at ρ (sieve_rho_reml), less constants.
double sieve_rho_restricted_loglik(const std::vector<double>& r, const std::vector<std::vector<double>>& J,
                                   const std::vector<std::size_t>& lengths, double rho) {
  const std::size_t p = J.empty() ? 0 : J.front().size();
  for (const auto& row : J)
    if (row.size() != p) return -std::numeric_limits<double>::infinity();
  std::size_t total = 0;
  for (std::size_t len : lengths) total += len;
  if (total > r.size() || (p > 0 && J.size() != r.size()) || !(rho >= 0 && rho < 1))
    return -std::numeric_limits<double>::infinity();
  const double c = std::sqrt(1 - rho * rho);
  std::vector<double> rw(r.size());
  std::vector<std::vector<double>> Jw(J.size(), std::vector<double>(p));
  std::size_t i = 0, rows = 0;
  for (std::size_t len : lengths) {
    for (std::size_t k = 0; k < len; ++k) {
      const std::size_t at = i + k;
      rw[at] = k == 0 ? c * r[at] : r[at] - rho * r[at - 1];
      for (std::size_t a = 0; a < p; ++a) Jw[at][a] = k == 0 ? c * J[at][a] : J[at][a] - rho * J[at - 1][a];
    }
    rows += len > 0;
    i += len;
  }
  const std::size_t n = i;
  // S = |r|² − bᵀ A⁻¹ b with A = JᵀJ, b = Jᵀr, by Cholesky; ln det A on its diagonal.
  std::vector<std::vector<double>> A(p, std::vector<double>(p, 0.0));
  std::vector<double> b(p, 0.0);
  double s = 0;
  for (std::size_t m = 0; m < n; ++m) {
    s += rw[m] * rw[m];
    for (std::size_t a = 0; a < p; ++a) {
      b[a] += Jw[m][a] * rw[m];
      for (std::size_t q = 0; q <= a; ++q) A[a][q] += Jw[m][a] * Jw[m][q];
    }
  }
  double log_det = 0;
  for (std::size_t a = 0; a < p; ++a) {
    for (std::size_t q = 0; q <= a; ++q) {
      double v = A[a][q];
      for (std::size_t k = 0; k < q; ++k) v -= A[a][k] * A[q][k];
      if (q == a) {
        if (!(v > 0)) return -std::numeric_limits<double>::infinity();
        A[a][a] = std::sqrt(v);
        log_det += 2 * std::log(A[a][a]);
      } else {
        A[a][q] = v / A[q][q];
      }
    }
  }
  for (std::size_t a = 0; a < p; ++a) {  // y = L⁻¹ b: S = |r|² − |y|²
    double v = b[a];
    for (std::size_t k = 0; k < a; ++k) v -= A[a][k] * b[k];
    b[a] = v / A[a][a];
    s -= b[a] * b[a];
  }
  if (!(s > 0) || n <= p) return -std::numeric_limits<double>::infinity();
  return 0.5 * static_cast<double>(rows) * std::log(1 - rho * rho) -
         0.5 * static_cast<double>(n - p) * std::log(s) - 0.5 * log_det;
}

void whiten_rows(double* r, std::size_t rows, std::size_t len, double rho) {
  if (rho == 0 || len == 0) return;
  if (!(rho > 0 && rho < 1)) throw std::invalid_argument("sieve_error_rho: must lie in [0, 1)");
  const double scale = 1 / std::sqrt(1 - rho * rho);
  for (std::size_t t = 0; t < rows; ++t) {
    double* row = r + t * len;
    // From the last back, so that each reads its unwhitened neighbour.
    for (std::size_t k = len; k-- > 1;) row[k] = (row[k] - rho * row[k - 1]) * scale;
  }
}

void unwhiten_row(double* r, std::size_t len, double rho) {
  if (rho == 0) return;
  const double c = std::sqrt(1 - rho * rho);
  for (std::size_t k = 1; k < len; ++k) r[k] = r[k] * c + rho * r[k - 1];
}

double sieve_rho_reml(const std::vector<double>& r, const std::vector<std::vector<double>>& J,
                      const std::vector<std::size_t>& lengths) {
  std::size_t total = 0, informative = 0;
  for (std::size_t len : lengths) total += len, informative += len >= 2 ? len : 0;
  if (informative < 3 || total > r.size() || (!J.empty() && J.size() != r.size())) return 0;
  auto ell = [&](double rho) { return sieve_rho_restricted_loglik(r, J, lengths, rho); };
  double best = 0, best_l = ell(0);
  for (int k = 1; k <= static_cast<int>(kMaxSieveRho * 1000 + 0.5); ++k) {
    const double l = ell(k * 1e-3);
    if (l > best_l) best_l = l, best = k * 1e-3;
  }
  // Golden section within a grid step either side.
  double a = std::max(0.0, best - 1e-3), b = std::min(kMaxSieveRho, best + 1e-3);
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double c = b - g * (b - a), d = a + g * (b - a);
  double lc = ell(c), ld = ell(d);
  for (int it = 0; it < 40; ++it) {
    if (lc > ld) b = d, d = c, ld = lc, c = b - g * (b - a), lc = ell(c);
    else a = c, c = d, lc = ld, d = a + g * (b - a), ld = ell(d);
  }
  const double x = 0.5 * (a + b);
  const double found = ell(x) > best_l ? x : best;
  // The estimate of an autoregression's ρ from a short series comes out
  // low by about 2ρ/n (n readings in rows of two or more; the same for
  // rows pooled): undone.
  const double n = static_cast<double>(informative);
  return std::min(kMaxSieveRho, found * n / (n - 2));
}

double whitened_lag1(const BatchFit& f, double rho) {
  std::vector<double> w = f.raw_residuals;
  std::size_t i = 0;
  for (std::size_t len : f.residual_rows) {
    if (i + len > w.size()) return std::numeric_limits<double>::quiet_NaN();
    whiten_rows(w.data() + i, 1, len, rho);
    i += len;
  }
  return residual_lag1(w, f.residual_rows);
}

std::optional<SieveErrors> parse_sieve_errors(const std::string& s) {
  if (s == "auto") return SieveErrors::automatic;
  if (s == "independent") return SieveErrors::independent;
  if (s == "correlated") return SieveErrors::correlated;
  return std::nullopt;
}

const char* sieve_errors_name(SieveErrors e) {
  return e == SieveErrors::automatic ? "auto" : e == SieveErrors::independent ? "independent" : "correlated";
}

SieveErrorFit fit_with_sieve_errors(const Ore& start, std::vector<TestInMill> tests,
                                    const std::vector<std::string>& names, SieveErrors mode, int max_iterations) {
  SieveErrorFit out;
  for (TestInMill& t : tests) t.sieve_rho = 0;
  out.fit = fit_batch_tests(start, tests, names, max_iterations);
  out.r1_independent = out.fit.residual_r1;
  const bool estimate = mode == SieveErrors::correlated ||
                        (mode == SieveErrors::automatic && out.fit.free > 0 && out.r1_independent > kSwitchToCorrelated);
  if (estimate) {
    const BatchFit independent = out.fit;
    const std::vector<TestInMill> as_independent = tests;
    // A round's fit from the start, as the fit at ρ = 0 was made; where it
    // does not converge, from that fit's parameters; where neither does,
    // the fit at ρ = 0 stands, and says why.
    auto fit_at = [&](BatchFit& f) {
      try {
        f = fit_batch_tests(start, tests, names, max_iterations);
        return true;
      } catch (const std::invalid_argument&) {
      }
      try {
        BatchFit warm = fit_batch_tests(independent.ore, tests, names, max_iterations);
        for (std::size_t k = 0; k < warm.parameters.size() && k < independent.parameters.size(); ++k)
          warm.parameters[k].start = independent.parameters[k].start;
        f = warm;
        return true;
      } catch (const std::invalid_argument& e) {
        out.why_failed = e.what();
        return false;
      }
    };
    double rho = sieve_rho_reml(out.fit.raw_residuals, out.fit.raw_jacobian, out.fit.residual_rows);
    out.settled = rho == 0;
    for (int round = 0; round < kSieveRhoRounds && rho > 0; ++round) {
      const std::vector<TestInMill> before = tests;
      for (TestInMill& t : tests) t.sieve_rho = rho;
      BatchFit f;
      if (!fit_at(f)) {
        // The last fit that converged stands: at ρ = 0 in the first round
        // (then nothing is left to settle), else at the ρ before.
        tests = before;
        out.settled = round == 0;
        break;
      }
      out.fit = f;
      ++out.rounds;
      const double next = sieve_rho_reml(out.fit.raw_residuals, out.fit.raw_jacobian, out.fit.residual_rows);
      if (next == 0) {  // the likelihood's best came back to independence
        out.fit = independent;
        tests = as_independent;
        out.settled = true;
        break;
      }
      if (std::fabs(next - rho) < 2e-3) {
        out.settled = true;
        break;
      }
      rho = next;
    }
    out.rho = tests.front().sieve_rho;
    out.correlated = out.rho > 0;
    out.at_cap = out.rho >= kMaxSieveRho - 1e-9;
  }
  out.tests = tests;
  return out;
}

std::vector<std::string> sieve_errors_warnings(const SieveErrorFit& f) {
  std::vector<std::string> out;
  if (!f.why_failed.empty())
    out.push_back(f.correlated
                      ? fmt::format("note: a refit at a new rho of the sieve errors did not converge ({}); the fit at "
                                    "rho {:.2f} stands",
                                    f.why_failed, f.rho)
                      : "note: the fit with the sieve errors correlated did not converge (" + f.why_failed +
                            "); the fit with them independent stands, and its intervals are likely too narrow");
  if (f.at_cap)
    out.push_back(fmt::format(
        "note: the sieve errors' rho came out on its cap, {:.2f}: the residuals move together more than a "
        "correlation from sieve to sieve describes (a model that cannot follow the test, or errors that build up "
        "along the sieves); the intervals allow for rho {:.2f} only",
        kMaxSieveRho, kMaxSieveRho));
  if (!f.settled)
    out.push_back(fmt::format("note: the sieve errors' rho had not settled after {} rounds of refits (last {:.3f})",
                              f.rounds, f.rho));
  return out;
}

std::string sieve_errors_note(double r1, double rho, SieveErrors mode) {
  if (rho > 0)
    return fmt::format(
        "the sieve errors were taken as correlated from one sieve to the next (rho = {:.2f}, estimated from the "
        "residuals{}): the standard errors and intervals allow for it (docs/grinding-intervals.md#sieve-errors-"
        "correlated-between-sieves)",
        rho, std::isfinite(r1) ? fmt::format("; their lag-1 autocorrelation fitted as independent, r1 = {:.2f}", r1)
                                : std::string());
  if (mode == SieveErrors::independent && r1 > kSwitchToCorrelated)
    return fmt::format(
        "note: the fit's residuals are correlated along the sieves (lag-1 autocorrelation r1 = {:.2f}, above {:.2f}) "
        "and the ore was fitted with them taken as independent: the 95 % intervals are then likely too narrow; fit "
        "again with --sieve-errors correlated (docs/grinding-intervals.md#sieve-errors-correlated-between-sieves)",
        r1, kSwitchToCorrelated);
  return "";
}

}  // namespace mc::grind
