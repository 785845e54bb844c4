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
#include "io/batch_test_file.h"
#include "io/ore_file.h"
#include "io/run_folder.h"

using namespace mc::grind;
namespace fs = std::filesystem;
using mc::test::kHoldup_kg;
using mc::test::known_ore;
using mc::test::kPower_W;
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

// Gauss–Jordan inverse with partial pivoting.
Matrix inverse(Matrix a) {
  const std::size_t n = a.size();
  Matrix inv(n, std::vector<double>(n, 0.0));
  for (std::size_t i = 0; i < n; ++i) inv[i][i] = 1;
  for (std::size_t c = 0; c < n; ++c) {
    std::size_t p = c;
    for (std::size_t r = c + 1; r < n; ++r)
      if (std::fabs(a[r][c]) > std::fabs(a[p][c])) p = r;
    std::swap(a[c], a[p]);
    std::swap(inv[c], inv[p]);
    const double d = a[c][c];
    for (std::size_t k = 0; k < n; ++k) a[c][k] /= d, inv[c][k] /= d;
    for (std::size_t r = 0; r < n; ++r)
      if (r != c) {
        const double f = a[r][c];
        for (std::size_t k = 0; k < n; ++k) a[r][k] -= f * a[c][k], inv[r][k] -= f * inv[c][k];
      }
  }
  return inv;
}

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
  // correction: the mean within 0.015 of ρ (the scatter of a mean of 1000
  // is about 0.004). The plain likelihood on the same residuals, for
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
    CHECK(std::fabs(mean - rho) < 0.015);
    if (rho == 0.7) CHECK(mean_plain < rho - 0.03);
  }
  // Nothing to estimate from: rows of one reading.
  CHECK(sieve_rho_reml({1, 2, 3}, {}, {1, 1, 1}) == 0);
}

TEST_CASE("sieve errors: the fit on whitened residuals is generalised least squares", "[grind][sieve_errors]") {
  // One AR(1) test at ρ = 0.7 fitted with ρ estimated: the standard errors
  // and covariance the fit gives against s² (Jᵀ Σ⁻¹ J)⁻¹, s² = rᵀ Σ⁻¹ r /
  // (n − p), with Σ the AR(1) correlation written out and inverted by
  // Gauss–Jordan at the fit's ρ; and the normal equations Jᵀ Σ⁻¹ r = 0 at
  // the solution (the raw residuals orthogonal to the columns in Σ⁻¹).
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const BatchTest t = ar1_test(truth, 0.7, 5);
  const SieveErrorFit f = fit_with_sieve_errors(start, {TestInMill{t, synthetic_spectrum(), kPower_W, kHoldup_kg}},
                                                {"efficiency", "sigma"}, SieveErrors::automatic);
  INFO("rho " << f.rho << ", r1 as independent " << f.r1_independent << ", rounds " << f.rounds);
  REQUIRE(f.correlated);
  CHECK(f.rho > 0.4);
  CHECK(f.rho < 0.95);
  CHECK(f.rounds >= 1);
  CHECK(f.tests.front().sieve_rho == f.rho);
  const BatchFit& fit = f.fit;
  REQUIRE(fit.covariance.size() == 2);
  const std::size_t n = fit.raw_residuals.size(), len = fit.residual_rows.front();
  Matrix Sinv(len, std::vector<double>(len));
  {
    Matrix S(len, std::vector<double>(len));
    for (std::size_t j = 0; j < len; ++j)
      for (std::size_t k = 0; k < len; ++k)
        S[j][k] = std::pow(f.rho, std::fabs(static_cast<double>(j) - static_cast<double>(k)));
    Sinv = inverse(S);
  }
  Matrix A(2, std::vector<double>(2, 0.0));
  double q = 0, g0 = 0, g1 = 0;
  for (std::size_t at = 0; at < n; at += len)
    for (std::size_t j = 0; j < len; ++j)
      for (std::size_t k = 0; k < len; ++k) {
        const double w = Sinv[j][k];
        q += fit.raw_residuals[at + j] * w * fit.raw_residuals[at + k];
        g0 += fit.raw_jacobian[at + j][0] * w * fit.raw_residuals[at + k];
        g1 += fit.raw_jacobian[at + j][1] * w * fit.raw_residuals[at + k];
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b) A[a][b] += fit.raw_jacobian[at + j][a] * w * fit.raw_jacobian[at + k][b];
      }
  const double s2 = q / static_cast<double>(n - 2);
  CHECK(fit.ssr == Approx(q).epsilon(1e-9));
  CHECK(fit.s2 == Approx(s2).epsilon(1e-9));
  const Matrix cov = inverse(A);
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) CHECK(fit.covariance[a][b] == Approx(s2 * cov[a][b]).epsilon(1e-6));
  // The gradient of the GLS sum at the solution: nil against its scale.
  CHECK(std::fabs(g0) < 1e-5 * std::sqrt(A[0][0] * q));
  CHECK(std::fabs(g1) < 1e-5 * std::sqrt(A[1][1] * q));
  // Whitened by ρ, the residuals no longer correlate along the sieves.
  CHECK(std::fabs(whitened_lag1(fit, f.rho)) < 0.25);
  CHECK(f.r1_independent > kSwitchToCorrelated);

  // Independent errors: auto leaves them independent; `correlated` finds a
  // small ρ; `independent` never estimates one.
  const BatchTest i = synthetic_test(truth, 1.0, 5);
  const std::vector<TestInMill> ti = {TestInMill{i, synthetic_spectrum(), kPower_W, kHoldup_kg}};
  const SieveErrorFit fa = fit_with_sieve_errors(start, ti, {"efficiency", "sigma"}, SieveErrors::automatic);
  const SieveErrorFit fc = fit_with_sieve_errors(start, ti, {"efficiency", "sigma"}, SieveErrors::correlated);
  const SieveErrorFit fi = fit_with_sieve_errors(start, {TestInMill{t, synthetic_spectrum(), kPower_W, kHoldup_kg}},
                                                 {"efficiency", "sigma"}, SieveErrors::independent);
  CHECK_FALSE(fa.correlated);
  CHECK(fa.rho == 0);
  CHECK(fa.rounds == 0);
  CHECK(fc.rho < 0.3);
  CHECK_FALSE(fi.correlated);
  CHECK(fi.rho == 0);
  CHECK(fi.tests.front().sieve_rho == 0);
  // The same data taken as independent: narrower, as the coverage test finds.
  CHECK(fi.fit.covariance[0][0] < fit.covariance[0][0]);
  CHECK(sieve_errors_note(0.6, 0, SieveErrors::independent).find("too narrow") != std::string::npos);
  CHECK(sieve_errors_note(0.6, 0.7, SieveErrors::automatic).find("rho = 0.70") != std::string::npos);
  CHECK(sieve_errors_note(0.1, 0, SieveErrors::automatic).empty());
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
