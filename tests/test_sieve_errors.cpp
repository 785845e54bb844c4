// Sieve errors correlated along a product's sieves (src/grind/sieve_errors.h):
// the whitening against the AR(1) covariance written out, ρ's restricted
// likelihood against seeded autoregressions, the fit on whitened residuals
// against generalised least squares computed with the covariance inverted
// by hand, and the command: fit.json, the ore file's key, bad input.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "app/grind.h"
#include "bond_run.h"
#include "grind/fit.h"
#include "grind/interval.h"
#include "grind/sieve_errors.h"
#include "grind_synthetic.h"
#include "small_matrix.h"
#include "io/batch_test_file.h"
#include "io/ore_file.h"
#include "io/run_folder.h"

using namespace mc::grind;
namespace fs = std::filesystem;
using mc::test::kHoldup_kg;
using mc::test::known_ore;
using mc::test::kPower_W;
using mc::test::inverse;
using mc::test::Scatter;
using mc::test::synthetic_spectrum;
using mc::test::synthetic_test;

namespace {

using Matrix = std::vector<std::vector<double>>;

// Standard normal deviates from the seeded uniform scatter (Box–Muller).
struct Normal {
  Scatter u;
  explicit Normal(std::uint64_t seed) : u(seed) {}
  double next() {
    const double a = 0.5 * (u.next() + 1), b = 0.5 * (u.next() + 1);
    return std::sqrt(-2 * std::log(std::max(a, 1e-300))) * std::cos(2 * M_PI * b);
  }
};

// A 5 x 13 test of `truth` whose readings' errors follow the AR(1) model
// along each time's sieves: normal, 1 pp each, neighbours correlated by rho.
BatchTest ar1_test(const Ore& truth, double rho, std::uint64_t seed) {
  BatchTest t = synthetic_test(truth, 0.0, seed);
  t.noise_pp = 1.0;
  Normal z(seed);
  for (auto& row : t.passing) {
    double e = 0;
    for (std::size_t k = 1; k < row.size(); ++k) {
      e = k == 1 ? z.next() : rho * e + std::sqrt(1 - rho * rho) * z.next();
      row[k] += e / 100;
    }
  }
  return t;
}

fs::path temp(const std::string& name) {
  return fs::temp_directory_path() / ("millcharge_test_sieve_" + std::to_string(::getpid()) + "_" + name);
}

nlohmann::json json_of(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

}  // namespace

TEST_CASE("sieve errors: the whitening makes the AR(1) covariance the identity, and its inverse undoes it",
          "[grind][sieve_errors]") {
  for (double rho : {0.0, 0.3, 0.7, 0.95})
    for (std::size_t len : {std::size_t{1}, std::size_t{2}, std::size_t{12}}) {
      // W, column by column: the whitening of each unit vector.
      Matrix W(len, std::vector<double>(len, 0.0));
      for (std::size_t j = 0; j < len; ++j) {
        std::vector<double> e(len, 0.0);
        e[j] = 1;
        whiten_rows(e.data(), 1, len, rho);
        for (std::size_t i = 0; i < len; ++i) W[i][j] = e[i];
      }
      // W Σ Wᵀ with Σ_jk = ρ^|j−k| (unit marginal variance).
      for (std::size_t a = 0; a < len; ++a)
        for (std::size_t b = 0; b < len; ++b) {
          double v = 0;
          for (std::size_t j = 0; j < len; ++j)
            for (std::size_t k = 0; k < len; ++k)
              v += W[a][j] * std::pow(rho, std::fabs(static_cast<double>(j) - static_cast<double>(k))) * W[b][k];
          INFO("rho " << rho << ", len " << len << ", (" << a << ", " << b << ")");
          CHECK(v == Approx(a == b ? 1.0 : 0.0).margin(1e-12));
        }
      std::vector<double> r(len), back;
      for (std::size_t k = 0; k < len; ++k) r[k] = std::sin(1.0 + k);
      back = r;
      whiten_rows(back.data(), 1, len, rho);
      unwhiten_row(back.data(), len, rho);
      for (std::size_t k = 0; k < len; ++k) CHECK(back[k] == Approx(r[k]).margin(1e-13));
    }
  // Rows apart: the second row's first reading does not see the first's last.
  std::vector<double> two = {1, 1, 1, 1};
  whiten_rows(two.data(), 2, 2, 0.5);
  CHECK(two[2] == 1);
  CHECK(two[3] == Approx((1 - 0.5) / std::sqrt(0.75)));
  std::vector<double> bad = {1, 2};
  CHECK_THROWS_WITH(whiten_rows(bad.data(), 1, 2, 1.0), Catch::Contains("[0, 1)"));
}

TEST_CASE("sieve errors: the restricted likelihood finds rho of seeded autoregressions without bias",
          "[grind][sieve_errors]") {
  // 5 rows of 12 readings (a batch test's shape), AR(1) Gaussian errors
  // about a fitted line per test (a level and a slope along the sieves:
  // p = 2, the residuals those of least squares). 1000 draws at each ρ.
  // Restricted likelihood with the fit's share taken out and the 2ρ/n
  // correction: the mean within 0.012 of ρ (the scatter of a mean of 1000
  // is about 0.003). The plain likelihood on the same residuals, for
  // comparison, comes out low by more than 0.03 at ρ = 0.7.
  const std::size_t rows = 5, len = 12, n = rows * len;
  Matrix J(n, std::vector<double>(2));
  for (std::size_t i = 0; i < n; ++i) J[i][0] = 1, J[i][1] = static_cast<double>(i % len) / len - 0.5;
  const std::vector<std::size_t> lengths(rows, len);
  // (JᵀJ)⁻¹Jᵀ, for the least-squares residuals.
  Matrix JtJ(2, std::vector<double>(2, 0.0));
  for (const auto& row : J)
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) JtJ[a][b] += row[a] * row[b];
  const Matrix inv = inverse(JtJ);
  for (double rho : {0.3, 0.7}) {
    double mean = 0, mean_plain = 0;
    const int draws = 1000;
    for (int d = 0; d < draws; ++d) {
      Normal z(1000 * static_cast<std::uint64_t>(rho * 10) + d);
      std::vector<double> e(n);
      for (std::size_t i = 0; i < n; ++i)
        e[i] = i % len == 0 ? z.next() : rho * e[i - 1] + std::sqrt(1 - rho * rho) * z.next();
      double b0 = 0, b1 = 0;
      for (std::size_t i = 0; i < n; ++i) b0 += J[i][0] * e[i], b1 += J[i][1] * e[i];
      const double c0 = inv[0][0] * b0 + inv[0][1] * b1, c1 = inv[1][0] * b0 + inv[1][1] * b1;
      std::vector<double> r(n);
      for (std::size_t i = 0; i < n; ++i) r[i] = e[i] - c0 * J[i][0] - c1 * J[i][1];
      mean += sieve_rho_reml(r, J, lengths) / draws;
      mean_plain += sieve_rho_reml(r, {}, lengths) / draws * (n - 2) / n;  // the plain ML, uncorrected
    }
    std::printf("rho %.1f over 5 x 12 readings, 1000 draws: restricted %.4f, plain %.4f\n", rho, mean, mean_plain);
    // Within 0.012 (three of the mean's scatter); the n/(n − 2) factor is
    // worth 0.023 at ρ = 0.7, so the check fails without it there.
    CHECK(std::fabs(mean - rho) < 0.012);
    if (rho == 0.7) CHECK(mean_plain < rho - 0.03);
  }
  // Nothing to estimate from: rows of one reading.
  CHECK(sieve_rho_reml({1, 2, 3}, {}, {1, 1, 1}) == 0);
}

TEST_CASE("sieve errors: the restricted likelihood against the textbook formula with the covariance written out",
          "[grind][sieve_errors]") {
  // ℓ_R(ρ) = −½ ln|Σ| − ½ ln|XᵀΣ⁻¹X| − ((n − p)/2) ln(rᵀPr), P = Σ⁻¹ −
  // Σ⁻¹X(XᵀΣ⁻¹X)⁻¹XᵀΣ⁻¹, Σ block-diagonal by rows with Σ_jk =
  // ρ^|j−k| / (1 − ρ²) (unit innovations): on rows of 4 and 3 readings and
  // two columns, its differences between values of ρ against the code's
  // (which drops terms that do not depend on ρ) to 1e-9.
  const std::vector<double> r = {0.3, -1.2, 0.8, 0.5, -0.4, 1.1, 0.2};
  const Matrix X = {{1, 0.2}, {1, -0.5}, {1, 0.9}, {1, 0.1}, {1, 0.4}, {1, -0.3}, {1, 0.7}};
  const std::vector<std::size_t> lengths = {4, 1, 2};  // a row of one reading among them
  auto det = [](Matrix a) {
    double d = 1;
    for (std::size_t c = 0; c < a.size(); ++c) {
      std::size_t p = c;
      for (std::size_t i = c + 1; i < a.size(); ++i)
        if (std::fabs(a[i][c]) > std::fabs(a[p][c])) p = i;
      if (p != c) std::swap(a[p], a[c]), d = -d;
      d *= a[c][c];
      for (std::size_t i = c + 1; i < a.size(); ++i) {
        const double f = a[i][c] / a[c][c];
        for (std::size_t k = c; k < a.size(); ++k) a[i][k] -= f * a[c][k];
      }
    }
    return d;
  };
  auto textbook = [&](double rho) {
    const std::size_t n = r.size(), p = 2;
    Matrix S(n, std::vector<double>(n, 0.0));
    std::size_t at = 0;
    for (std::size_t len : lengths) {
      for (std::size_t j = 0; j < len; ++j)
        for (std::size_t k = 0; k < len; ++k)
          S[at + j][at + k] = std::pow(rho, std::fabs(double(j) - double(k))) / (1 - rho * rho);
      at += len;
    }
    const Matrix Si = inverse(S);
    Matrix XtSiX(p, std::vector<double>(p, 0.0));
    std::vector<double> XtSir(p, 0.0);
    double rSir = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = 0; k < n; ++k) {
        rSir += r[i] * Si[i][k] * r[k];
        for (std::size_t a = 0; a < p; ++a) {
          XtSir[a] += X[i][a] * Si[i][k] * r[k];
          for (std::size_t b = 0; b < p; ++b) XtSiX[a][b] += X[i][a] * Si[i][k] * X[k][b];
        }
      }
    const Matrix inv = inverse(XtSiX);
    double rPr = rSir;
    for (std::size_t a = 0; a < p; ++a)
      for (std::size_t b = 0; b < p; ++b) rPr -= XtSir[a] * inv[a][b] * XtSir[b];
    return -0.5 * std::log(det(S)) - 0.5 * std::log(det(XtSiX)) - 0.5 * double(n - p) * std::log(rPr);
  };
  for (double rho : {0.1, 0.5, 0.9}) {
    INFO("rho " << rho);
    CHECK(sieve_rho_restricted_loglik(r, X, lengths, rho) - sieve_rho_restricted_loglik(r, X, lengths, 0.3) ==
          Approx(textbook(rho) - textbook(0.3)).margin(1e-9));
  }
  CHECK(std::isinf(sieve_rho_restricted_loglik(r, X, lengths, 1.0)));
  CHECK(std::isinf(sieve_rho_restricted_loglik(r, {{1, 0}}, lengths, 0.5)));  // J not of r's rows
}

namespace {

// Generalised least squares checked by hand at a fit's solution: the raw
// residuals r (each test's weighted by noise of the first over its own,
// time by time, its informative sieves coarse to fine) and their Jacobian
// J_fd in the fitted variables (the logarithms of the scales) by central
// differences of the products, independently of the fit's own Jacobian;
// Σ⁻¹ of each row written out (ρ^|j−k|) and inverted by Gauss–Jordan.
// Then: the fit's sum of squares is rᵀΣ⁻¹r, its covariance s²(J_fdᵀΣ⁻¹J_fd)⁻¹
// with s² = rᵀΣ⁻¹r / (n − p), and J_fdᵀΣ⁻¹r vanishes (the GLS normal
// equations).
void check_gls(const BatchFit& fit, const std::vector<TestInMill>& tests, const std::vector<std::string>& names,
               double rho) {
  const std::size_t p = names.size();
  const std::vector<double> w = test_weights(tests);
  std::vector<double> r;
  Matrix J;
  std::vector<std::size_t> rows;
  for (std::size_t m = 0; m < tests.size(); ++m) {
    const TestInMill& tm = tests[m];
    const std::vector<std::size_t> used = informative_sieves(tm.test);
    auto products = [&](const Ore& o) { return batch_test_products(o, tm.spectrum, tm.power_W, tm.holdup_kg, tm.test); };
    const auto pred = products(fit.ore);
    std::vector<std::vector<std::vector<double>>> up(p), down(p);
    const double h = 1e-5;
    for (std::size_t a = 0; a < p; ++a) {
      const OreParameter& q = *find_ore_parameter(names[a]);
      REQUIRE(q.log);  // fitted as its logarithm: the variable differenced below
      Ore hi = fit.ore, lo = fit.ore;
      q.set(hi, q.get(fit.ore) * std::exp(h));
      q.set(lo, q.get(fit.ore) * std::exp(-h));
      up[a] = products(hi);
      down[a] = products(lo);
    }
    for (std::size_t t = 0; t < tm.test.times_min.size(); ++t) {
      rows.push_back(used.size());
      for (std::size_t k : used) {
        r.push_back(w[m] * 100 * (pred[t][k] - tm.test.passing[t][k]));
        std::vector<double> row(p);
        for (std::size_t a = 0; a < p; ++a) row[a] = w[m] * 100 * (up[a][t][k] - down[a][t][k]) / (2 * h);
        J.push_back(row);
      }
    }
  }
  Matrix A(p, std::vector<double>(p, 0.0));
  std::vector<double> g(p, 0.0);
  double q = 0;
  std::size_t at = 0;
  for (std::size_t len : rows) {
    Matrix S(len, std::vector<double>(len));
    for (std::size_t j = 0; j < len; ++j)
      for (std::size_t k = 0; k < len; ++k)
        S[j][k] = std::pow(rho, std::fabs(static_cast<double>(j) - static_cast<double>(k)));
    const Matrix Si = inverse(S);
    for (std::size_t j = 0; j < len; ++j)
      for (std::size_t k = 0; k < len; ++k) {
        q += r[at + j] * Si[j][k] * r[at + k];
        for (std::size_t a = 0; a < p; ++a) {
          g[a] += J[at + j][a] * Si[j][k] * r[at + k];
          for (std::size_t b = 0; b < p; ++b) A[a][b] += J[at + j][a] * Si[j][k] * J[at + k][b];
        }
      }
    at += len;
  }
  REQUIRE(at == r.size());
  const double s2 = q / static_cast<double>(r.size() - p);
  CHECK(fit.ssr == Approx(q).epsilon(1e-9));
  CHECK(fit.s2 == Approx(s2).epsilon(1e-9));
  const Matrix cov = inverse(A);
  REQUIRE(fit.covariance.size() == p);
  for (std::size_t a = 0; a < p; ++a)
    for (std::size_t b = 0; b < p; ++b) {
      INFO("covariance (" << a << ", " << b << ")");
      CHECK(fit.covariance[a][b] == Approx(s2 * cov[a][b]).epsilon(2e-3).margin(2e-3 * s2 * std::sqrt(cov[a][a] * cov[b][b])));
    }
  for (std::size_t a = 0; a < p; ++a) CHECK(std::fabs(g[a]) < 1e-4 * std::sqrt(A[a][a] * q));
  // Taken as independent, the same solution would have another
  // covariance: the check above can tell them apart.
  double q0 = 0;
  Matrix A0(p, std::vector<double>(p, 0.0));
  for (std::size_t i = 0; i < r.size(); ++i) {
    q0 += r[i] * r[i];
    for (std::size_t a = 0; a < p; ++a)
      for (std::size_t b = 0; b < p; ++b) A0[a][b] += J[i][a] * J[i][b];
  }
  const double independent_var = q0 / static_cast<double>(r.size() - p) * inverse(A0)[0][0];
  CHECK(std::fabs(independent_var / fit.covariance[0][0] - 1) > 0.1);
}

}  // namespace

TEST_CASE("sieve errors: the fit on whitened residuals is generalised least squares", "[grind][sieve_errors]") {
  // One AR(1) test at ρ = 0.7 fitted with ρ estimated; and two tests in
  // two mills, sieved to 0.5 and 1 pp, the second on its nine coarser
  // sieves only (rows of other lengths, weights other than 1): each
  // against generalised least squares by hand (check_gls).
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const std::vector<std::string> names = {"efficiency", "sigma"};
  const BatchTest t = ar1_test(truth, 0.7, 5);
  const SieveErrorFit f = fit_with_sieve_errors(start, {TestInMill{t, synthetic_spectrum(), kPower_W, kHoldup_kg}},
                                                names, SieveErrors::automatic);
  INFO("rho " << f.rho << ", r1 as independent " << f.r1_independent << ", rounds " << f.rounds);
  REQUIRE(f.correlated);
  CHECK(f.rho > 0.4);
  CHECK(f.rho < 0.95);
  CHECK(f.rounds >= 1);
  CHECK(f.settled);
  CHECK_FALSE(f.at_cap);
  CHECK(f.why_failed.empty());
  CHECK(f.tests.front().sieve_rho == f.rho);
  check_gls(f.fit, f.tests, names, f.rho);
  // Whitened by ρ, the residuals no longer correlate along the sieves.
  CHECK(std::fabs(whitened_lag1(f.fit, f.rho)) < 0.25);
  CHECK(f.r1_independent > kSwitchToCorrelated);
  {
    BatchTest a = ar1_test(truth, 0.6, 11), b = ar1_test(truth, 0.6, 12);
    const BatchTest exact_a = synthetic_test(truth, 0.0, 11), exact_b = synthetic_test(truth, 0.0, 12);
    for (std::size_t i = 0; i < a.passing.size(); ++i)
      for (std::size_t k = 1; k < a.passing[i].size(); ++k)
        a.passing[i][k] = exact_a.passing[i][k] + 0.5 * (a.passing[i][k] - exact_a.passing[i][k]);
    a.noise_pp = 0.5;
    // The second in the harder mill, on its coarser sieves.
    BatchTest bh = synthetic_test(truth, 0.0, 12);  // no scatter: b's errors added below
    bh.passing = batch_test_products(truth, mc::test::harder_spectrum(), kPower_W, kHoldup_kg, bh);
    for (std::size_t i = 0; i < bh.passing.size(); ++i)
      for (std::size_t k = 1; k < bh.passing[i].size(); ++k) bh.passing[i][k] += b.passing[i][k] - exact_b.passing[i][k];
    bh.noise_pp = 1.0;
    bh.sieve_m.resize(10);
    bh.feed_passing.resize(10);
    for (auto& row : bh.passing) row.resize(10);
    const std::vector<TestInMill> two = {TestInMill{a, synthetic_spectrum(), kPower_W, kHoldup_kg},
                                         TestInMill{bh, mc::test::harder_spectrum(), kPower_W, kHoldup_kg}};
    const SieveErrorFit f2 = fit_with_sieve_errors(start, two, names, SieveErrors::correlated);
    INFO("two tests: rho " << f2.rho << ", rounds " << f2.rounds);
    REQUIRE(f2.correlated);
    CHECK(f2.fit.residual_rows.front() != f2.fit.residual_rows.back());
    check_gls(f2.fit, f2.tests, names, f2.rho);
  }

  // Independent errors: auto leaves them independent; `correlated` finds a
  // small ρ; `independent` never estimates one.
  const BatchTest i = synthetic_test(truth, 1.0, 5);
  const std::vector<TestInMill> ti = {TestInMill{i, synthetic_spectrum(), kPower_W, kHoldup_kg}};
  const SieveErrorFit fa = fit_with_sieve_errors(start, ti, names, SieveErrors::automatic);
  const SieveErrorFit fc = fit_with_sieve_errors(start, ti, names, SieveErrors::correlated);
  const SieveErrorFit fi = fit_with_sieve_errors(start, {TestInMill{t, synthetic_spectrum(), kPower_W, kHoldup_kg}},
                                                 names, SieveErrors::independent);
  CHECK_FALSE(fa.correlated);
  CHECK(fa.rho == 0);
  CHECK(fa.rounds == 0);
  CHECK(fc.rho < 0.3);
  CHECK_FALSE(fi.correlated);
  CHECK(fi.rho == 0);
  CHECK(fi.tests.front().sieve_rho == 0);
  // The same data taken as independent: narrower, as the coverage test finds.
  CHECK(fi.fit.covariance[0][0] < f.fit.covariance[0][0]);
  CHECK(sieve_errors_note(0.6, 0, SieveErrors::independent).find("too narrow") != std::string::npos);
  CHECK(sieve_errors_note(0.6, 0.7, SieveErrors::automatic).find("rho = 0.70") != std::string::npos);
  CHECK(sieve_errors_note(0.1, 0, SieveErrors::automatic).empty());
  // The warnings: none for this fit; on the cap, unsettled, a failed round.
  CHECK(sieve_errors_warnings(f).empty());
  SieveErrorFit odd = f;  // a later round failed: the fit at the ρ before stands, unsettled
  odd.at_cap = true;
  odd.settled = false;
  odd.why_failed = "did not converge";
  const std::vector<std::string> w = sieve_errors_warnings(odd);
  REQUIRE(w.size() == 3);
  CHECK(w[0].find("a refit at a new rho") != std::string::npos);
  CHECK(w[1].find("cap, 0.98") != std::string::npos);
  CHECK(w[2].find("had not settled") != std::string::npos);
  SieveErrorFit first = fa;  // the first round failed: independent, nothing left to settle
  first.why_failed = "did not converge";
  const std::vector<std::string> w1 = sieve_errors_warnings(first);
  REQUIRE(w1.size() == 1);
  CHECK(w1[0].find("independent stands") != std::string::npos);
}

TEST_CASE("grind --fit --sieve-errors through the command: fit.json, the ore's key, the products, bad input",
          "[grind][sieve_errors][failures]") {
  const fs::path run_dir = mc::test::short_bond_run();
  const mc::io::Run run = mc::io::read_run(run_dir, true);
  const Ore truth = known_ore();
  const mc::test::TempDir dir{temp("cmd")};
  fs::create_directories(dir.path);
  mc::io::BatchTestFile tf;
  tf.title = "correlated";
  tf.test = synthetic_test(truth, 0.0, 7);
  tf.test.passing = batch_test_products(truth, run.spectrum, run.power_W, kHoldup_kg, tf.test);
  tf.test.holdup_kg = kHoldup_kg;
  tf.test.noise_pp = 0.5;
  {
    const BatchTest noisy = ar1_test(truth, 0.7, 7), exact = synthetic_test(truth, 0.0, 7);
    for (std::size_t i = 0; i < tf.test.passing.size(); ++i)
      for (std::size_t k = 1; k < tf.test.passing[i].size(); ++k)
        tf.test.passing[i][k] += 0.5 * (noisy.passing[i][k] - exact.passing[i][k]);  // 0.5 pp: products in order
  }
  const fs::path test_file = dir.path / "correlated.toml";
  std::ofstream(test_file) << mc::io::batch_test_toml(tf);
  mc::app::GrindOptions o;
  o.run_dir = run_dir.string();
  o.ore = (fs::path(MC_ASSET_DIR) / "ores" / "example_spectrum.toml").string();
  o.fit_tests = {test_file.string()};
  o.fit_params = {"efficiency", "sigma"};
  o.quiet = true;
  auto fit_as = [&](const std::string& mode, const std::string& out) {
    mc::app::GrindOptions a = o;
    a.sieve_errors = mode;
    a.out = (dir.path / out).string();
    REQUIRE(mc::app::cmd_grind(a) == 0);
    return json_of(dir.path / out / "fit.json");
  };
  const nlohmann::json ja = fit_as("", "auto"), ji = fit_as("independent", "independent");
  INFO(ja["sieve_errors"].dump());
  CHECK(ja["sieve_errors"]["asked"] == "auto");
  CHECK(ja["sieve_errors"]["model"] == "correlated");
  const double rho = ja["sieve_errors"]["rho"].get<double>();
  CHECK(rho > 0.4);
  CHECK(rho < 0.95);
  CHECK(ja["residuals_correlated"].get<bool>());
  CHECK(std::fabs(ja["sieve_errors"]["residual_lag1_whitened"].get<double>()) < 0.25);
  CHECK(ji["sieve_errors"]["model"] == "independent");
  CHECK(ji["sieve_errors"]["rho"].get<double>() == 0);
  CHECK(ji["sieve_errors"]["residual_lag1_whitened"].is_null());
  // The ore keeps ρ; read back, its key is the fit's.
  const Ore fitted = mc::io::read_ore(dir.path / "auto" / "ore_fitted.toml");
  CHECK(fitted.fitted_under.sieve_error_rho == Approx(rho).epsilon(1e-6));
  CHECK(mc::io::read_ore(dir.path / "independent" / "ore_fitted.toml").fitted_under.sieve_error_rho == 0);
  // The products of each fitted ore: the interval of the correlated fit wider.
  auto p80_width = [&](const std::string& from) {
    mc::app::GrindOptions g;
    g.run_dir = run_dir.string();
    g.ore = (dir.path / from / "ore_fitted.toml").string();
    g.times_min = {20};
    g.out = (dir.path / (from + "_grind")).string();
    g.quiet = true;
    REQUIRE(mc::app::cmd_grind(g) == 0);
    const nlohmann::json gj = json_of(dir.path / (from + "_grind") / "grind.json");
    const auto& iv = gj["products"][0]["P80_um_95"];
    REQUIRE(iv.is_array());
    return (iv[1].get<double>() - iv[0].get<double>()) / gj["products"][0]["P80_um"].get<double>();
  };
  const double wa = p80_width("auto"), wi = p80_width("independent");
  std::printf("P80 after 20 min, 95 %% interval width: %.2f %% with rho %.3f, %.2f %% as independent\n", 100 * wa,
              rho, 100 * wi);
  CHECK(wa > 1.3 * wi);
  // The next test from the correlated ore: its tests are read back with ρ
  // (else its sum of squares on them would not be the one kept, and the
  // ore would be refused as changed), one candidate refitted twice.
  {
    mc::app::GrindOptions g;
    g.run_dir = run_dir.string();
    g.ore = (dir.path / "auto" / "ore_fitted.toml").string();
    g.times_min = {20};
    g.next_tests = {run_dir.string()};
    g.next_times = {{1, 2, 4, 8, 16}};
    g.next_draws = 2;
    g.next_refit = 1;
    g.out = (dir.path / "next").string();
    g.quiet = true;
    REQUIRE(mc::app::cmd_grind(g) == 0);
    const nlohmann::json nj = json_of(dir.path / "next" / "grind.json")["next_test"];
    INFO(nj.dump().substr(0, 600));
    CHECK_FALSE(nj.contains("no_refits"));
    REQUIRE(nj["candidates"].size() == 1);
    CHECK(nj["candidates"][0]["draws_converged"].get<int>() == 2);
    CHECK(nj["candidates"][0]["linear_width"].get<double>() > 0);
  }
  // Bad input: named, nothing written.
  mc::app::GrindOptions b = o;
  b.fit_tests.clear();
  b.fit_params.clear();
  b.sieve_errors = "correlated";
  b.times_min = {20};
  b.out = (dir.path / "refused").string();
  CHECK_THROWS_WITH(mc::app::cmd_grind(b), Catch::Contains("--sieve-errors: says how --fit takes"));
  b.fit_wi_kWh_t = 12;
  b.bond_p1_um = 106;
  b.times_min.clear();
  CHECK_THROWS_WITH(mc::app::cmd_grind(b), Catch::Contains("--sieve-errors"));
  CHECK_FALSE(fs::exists(dir.path / "refused"));
  // The ore file's key out of range.
  std::string text;
  {
    std::ifstream in(dir.path / "auto" / "ore_fitted.toml");
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  const std::size_t at = text.find("sieve_error_rho = ");
  REQUIRE(at != std::string::npos);
  text.replace(at, text.find('\n', at) - at, "sieve_error_rho = 1.2");
  std::ofstream(dir.path / "bad_rho.toml") << text;
  CHECK_THROWS_WITH(mc::io::read_ore(dir.path / "bad_rho.toml"), Catch::Contains("fitted.sieve_error_rho"));
}
