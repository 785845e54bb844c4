// The fit's uncertainty carried to a fitted ore's products (src/grind/
// interval.h, the [fitted] table's covariance in src/io/ore_file.cpp): the
// covariance kept with the ore and read back, an ore fitted before it was
// kept, bad covariance keys refused by name, and the coverage of the 95 %
// intervals over many synthetic batch tests with seeded scatter, on a
// synthetic spectrum (no DEM run): about 95 %, and far below at half the
// width, so the check fails for intervals too narrow; and with sieve
// errors correlated between sieves, taken as independent (too narrow) and
// as the fit takes them by default (sieve_errors.h), with the figures of
// docs/grinding-intervals.md.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "grind/circuit.h"
#include "grind/fit.h"
#include "grind/interval.h"
#include "grind/sieve_errors.h"
#include "app/commands.h"
#include "bond_run.h"
#include "grind_synthetic.h"
#include "app/grind.h"
#include "io/batch_test_file.h"
#include "io/ore_file.h"
#include "io/run_folder.h"

using namespace mc::grind;
namespace fs = std::filesystem;

using mc::test::harder_spectrum;
using mc::test::kHoldup_kg;
using mc::test::known_ore;
using mc::test::kPower_W;
using mc::test::p80_at_20_min;
using mc::test::Scatter;
using mc::test::synthetic_spectrum;
using mc::test::synthetic_test;

namespace {

fs::path temp(const std::string& name) {
  return fs::temp_directory_path() / ("millcharge_test_interval_" + std::to_string(::getpid()) + "_" + name);
}

}  // namespace

namespace {

// P(0 <= T <= t) for Student's t with nu degrees of freedom: its density
// integrated by Simpson's rule on 40,000 intervals, independently of the
// code's incomplete beta function.
double t_mass_to(double t, int nu) {
  const double v = nu;
  const double c = std::exp(std::lgamma(0.5 * (v + 1)) - std::lgamma(0.5 * v)) / std::sqrt(v * M_PI);
  auto f = [&](double x) { return c * std::pow(1 + x * x / v, -0.5 * (v + 1)); };
  const int n = 40000;
  const double h = t / n;
  double sum = f(0) + f(t);
  for (int k = 1; k < n; ++k) sum += (k % 2 ? 4 : 2) * f(k * h);
  return sum * h / 3;
}

}  // namespace

TEST_CASE("grind intervals: Student's t quantile, exact for every degree of freedom", "[grind][interval]") {
  // Closed forms: nu = 1, the Cauchy distribution, tan(pi (p - 1/2)); nu =
  // 2, (2p - 1) / sqrt(2 p (1 - p)).
  for (double p : {0.6, 0.9, 0.975, 0.995}) {
    CHECK(t_quantile(p, 1) == Approx(std::tan(M_PI * (p - 0.5))).epsilon(1e-12));
    CHECK(t_quantile(p, 2) == Approx((2 * p - 1) / std::sqrt(2 * p * (1 - p))).epsilon(1e-12));
  }
  // The density integrated up to the quantile gives back p - 1/2.
  for (int nu : {1, 2, 3, 4, 5, 6, 8, 10, 30, 100})
    for (double p : {0.9, 0.975, 0.995}) {
      INFO("nu " << nu << ", p " << p << ", t " << t_quantile(p, nu));
      CHECK(t_mass_to(t_quantile(p, nu), nu) == Approx(p - 0.5).margin(1e-9));
    }
  // The tables' values at 0.975 (to their 6 decimals), symmetry, the normal.
  const std::pair<int, double> table[] = {{1, 12.706205}, {2, 4.302653}, {3, 3.182446}, {4, 2.776445},
                                          {5, 2.570582},  {10, 2.228139}, {30, 2.042272}, {60, 2.000298}};
  for (const auto& [nu, t] : table) CHECK(t_quantile(0.975, nu) == Approx(t).margin(1e-6));
  CHECK(t_quantile(0.025, 7) == Approx(-t_quantile(0.975, 7)).epsilon(1e-12));
  CHECK(t_quantile(0.5, 3) == 0);
  CHECK(t_quantile(0.975, 0) == Approx(1.959964).epsilon(1e-6));
}

TEST_CASE("grind intervals: the fit's covariance kept with the ore and read back, an ore fitted before has none",
          "[grind][interval]") {
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  start.fracture.e_inf_J_kg = 60;
  const BatchTest t = synthetic_test(truth, 1.0, 3);
  const auto spectrum = synthetic_spectrum();
  // Three named; E∞ and η trade in one mill: one is held, with its range.
  const BatchFit f = fit_batch_test(start, spectrum, kPower_W, kHoldup_kg, t, {"efficiency", "e_inf_J_kg", "sigma"});
  Ore fitted = f.ore;
  fitted.fitted_under.law = "linear";
  fitted.fitted_under.restitution = 0.5;
  fitted.fitted_under.friction = 0.3;
  fitted.fitted_under.stiffness_N_m = 1e5;
  fitted.fitted_under.covariance = fit_covariance(f, spectrum, kPower_W, kHoldup_kg, t);
  const FitCovariance& u = fitted.fitted_under.covariance;
  INFO("free " << u.names.size() << ", held " << u.held.size());
  REQUIRE(u.given);
  REQUIRE(u.names.size() + u.held.size() == 3);
  CHECK(u.dof == f.data - static_cast<int>(u.names.size()));
  CHECK(u.residual_variance_pp2 == Approx(1.0 / 3).epsilon(0.3));  // uniform ±1 pp: 1/3 pp²
  for (std::size_t a = 0; a < u.names.size(); ++a) {
    // The diagonal is the standard error squared, in the fitted variable.
    const FittedParameter* p = nullptr;
    for (const FittedParameter& q : f.parameters)
      if (q.name == u.names[a]) p = &q;
    REQUIRE(p);
    CHECK(std::sqrt(u.matrix[a][a]) == Approx(p->se / p->value).epsilon(1e-6));
  }
  for (const HeldParameter& h : u.held) {
    INFO(h.name << " held at " << h.value << ", open " << h.lo << " to " << h.hi);
    CHECK(h.lo <= h.value);
    CHECK(h.hi >= h.value);
    CHECK(h.hi > h.lo);  // the data leave it some room
  }
  // Through the file and back.
  const fs::path path = temp("fitted.toml");
  {
    std::ofstream(path) << mc::io::ore_toml(fitted, "# test\n");
  }
  const Ore back = mc::io::read_ore(path);
  const FitCovariance& v = back.fitted_under.covariance;
  REQUIRE(v.given);
  CHECK(v.names == u.names);
  CHECK(v.dof == u.dof);
  for (std::size_t a = 0; a < u.names.size(); ++a)
    for (std::size_t b = 0; b < u.names.size(); ++b) CHECK(v.matrix[a][b] == Approx(u.matrix[a][b]).epsilon(1e-9));
  REQUIRE(v.held.size() == u.held.size());
  REQUIRE(v.information.size() == u.names.size() + u.held.size());
  CHECK(v.information[0][0] == Approx(u.information[0][0]).epsilon(1e-9));
  REQUIRE(v.edges.size() == u.edges.size());
  int profile_ends = 0;
  for (std::size_t e = 0; e < u.edges.size(); ++e) {
    CHECK(v.edges[e].of == u.edges[e].of);  // a profile's end says whose (profile_of)
    profile_ends += u.edges[e].of >= 0;
  }
  if (!u.held.empty()) CHECK(profile_ends >= 1);
  REQUIRE(v.best.held.size() == u.best.held.size());
  for (std::size_t k = 0; k < u.best.held.size(); ++k) CHECK(v.best.held[k] == Approx(u.best.held[k]).epsilon(1e-9));
  for (std::size_t k = 0; k < u.held.size(); ++k) {
    CHECK(v.held[k].lo == Approx(u.held[k].lo).epsilon(1e-9));
    CHECK(v.held[k].free_at_hi.size() == u.names.size());
  }
  // The interval of the P80 from the file's ore: the same as from the fit's.
  const auto a = propagate(fitted, u, p80_at_20_min), b = propagate(back, v, p80_at_20_min);
  REQUIRE(a[0].valid());
  CHECK(b[0].lo == Approx(a[0].lo).epsilon(1e-6));
  CHECK(b[0].hi == Approx(a[0].hi).epsilon(1e-6));
  // An ore fitted before covariances were kept: no covariance, read as such.
  std::string text = mc::io::ore_toml(fitted, "");
  text = text.substr(0, text.find("# What the fit leaves open"));
  {
    std::ofstream(path) << text;
  }
  CHECK_FALSE(mc::io::read_ore(path).fitted_under.covariance.given);
  // Bad keys: named.
  auto refused = [&](const std::string& from, const std::string& to, const std::string& message) {
    std::string bad = mc::io::ore_toml(fitted, "");
    const std::size_t at = bad.find(from);
    REQUIRE(at != std::string::npos);
    bad.replace(at, from.size(), to);
    {
      std::ofstream(path) << bad;
    }
    CHECK_THROWS_WITH(mc::io::read_ore(path), Catch::Contains(message));
  };
  refused("covariance_variables = [\"log(", "covariance_variables = [\"logx(",
          "fitted.covariance_variables: \"logx(");
  refused("degrees_of_freedom = ", "degrees_of_freedom = -", "fitted.degrees_of_freedom");
  refused("covariance = [[", "covariance = [[1, ", "fitted.covariance: must be a symmetric");
  fs::remove(path);
}

TEST_CASE("grind intervals: the 95 % interval of a P80 outside the test holds the truth in about 95 % of tests",
          "[grind][interval]") {
  const auto t0 = std::chrono::steady_clock::now();
  const Ore truth = known_ore();
  const double true_p80 = p80_at_20_min(truth)[0];
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const auto spectrum = synthetic_spectrum();
  // N seeded tests with ±1 pp of uniform scatter, each fitted (η and σ) and
  // its interval of the P80 after 20 min (the test stops at 8) checked
  // against the truth's, at the width the method gives, at 0.8 of it and
  // at twice it.
  const int n = 1000;
  int held = 0, held_narrow = 0, held_wide = 0;
  double width = 0, sum_z = 0, sum_z2 = 0;  // z: the P80's distance from the truth in its standard errors
  for (int seed = 0; seed < n; ++seed) {
    const BatchTest t = synthetic_test(truth, 1.0, 1000 + seed);
    const BatchFit f = fit_batch_test(start, spectrum, kPower_W, kHoldup_kg, t, {"efficiency", "sigma"});
    const FitCovariance u = fit_covariance(f, spectrum, kPower_W, kHoldup_kg, t);
    REQUIRE(u.held.empty());
    const Interval i = propagate(f.ore, u, p80_at_20_min)[0];
    const Interval narrow = propagate(f.ore, u, p80_at_20_min, 0.8)[0];
    const Interval wide = propagate(f.ore, u, p80_at_20_min, 2.0)[0];
    REQUIRE(i.valid());
    held += i.lo <= true_p80 && true_p80 <= i.hi;
    held_narrow += narrow.lo <= true_p80 && true_p80 <= narrow.hi;
    held_wide += wide.lo <= true_p80 && true_p80 <= wide.hi;
    width += (i.hi - i.lo) / true_p80 / n;
    const double z = (0.5 * (i.lo + i.hi) - true_p80) / (0.5 * (i.hi - i.lo) / t_quantile(0.975, u.dof));
    sum_z += z / n;
    sum_z2 += z * z / n;
  }
  const double coverage = static_cast<double>(held) / n;
  const double narrow = static_cast<double>(held_narrow) / n, wide = static_cast<double>(held_wide) / n;
  // Three binomial standard deviations of a share of n at 0.95: ±0.021.
  const double tolerance = 3 * std::sqrt(0.95 * 0.05 / n);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("interval coverage: true P80 %.1f um at 20 min; %d tests, mean width %.2f %% of it: %.3f held at the "
              "method's width, %.3f at 0.8 of it, %.4f at twice it (tolerance +-%.3f); z mean %.3f, rms %.3f; "
              "%.1f s\n",
              true_p80, n, 100 * width, coverage, narrow, wide, tolerance, sum_z, std::sqrt(sum_z2), seconds);
  CHECK(std::fabs(coverage - 0.95) <= tolerance);
  // Intervals 0.8 of the width hold the truth in about 88 % of tests (a
  // normal's share within 0.8 x 1.96): clearly below, so the check above
  // fails for intervals too narrow; twice the width in all but about
  // 1 in 10,000: clearly above, so it fails for intervals too wide.
  CHECK(narrow < 0.95 - tolerance);
  CHECK(narrow > 0.80);
  CHECK(wide > 0.95 + tolerance);
  CHECK(width > 0.001);  // an interval that says something, not a point
  CHECK(width < 0.2);
}

// The figure docs/grinding-intervals.md gives for readings clipped to 0..1,
// as a sieve reports them: not run with the suite (hidden), run by name:
// millcharge_tests "[interval_clipped]".
TEST_CASE("grind intervals: coverage with the readings clipped to 0..1", "[.][interval_clipped]") {
  const Ore truth = known_ore();
  const double true_p80 = p80_at_20_min(truth)[0];
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const auto spectrum = synthetic_spectrum();
  const int n = 1000;
  int held = 0;
  for (int seed = 0; seed < n; ++seed) {
    const BatchTest t = synthetic_test(truth, 1.0, 1000 + seed, spectrum, {0.5, 1, 2, 4, 8}, true);
    const BatchFit f = fit_batch_test(start, spectrum, kPower_W, kHoldup_kg, t, {"efficiency", "sigma"});
    const Interval i = propagate(f.ore, fit_covariance(f, spectrum, kPower_W, kHoldup_kg, t), p80_at_20_min)[0];
    held += i.valid() && i.lo <= true_p80 && true_p80 <= i.hi;
  }
  std::printf("interval coverage with the readings clipped to 0..1: %.3f of %d tests\n",
              static_cast<double>(held) / n, n);
  CHECK(static_cast<double>(held) / n < 0.95);  // below what is wanted: s² understates the informative readings
}

TEST_CASE("grind intervals: the delta method's interval against a parametric bootstrap's", "[grind][interval]") {
  // One synthetic test fitted (η and σ); then 300 tests made from the fitted
  // ore with the same scatter, each fitted again: the 2.5 and 97.5 %
  // percentiles of their P80 after 20 min are the bootstrap's interval. The
  // two agree where the product is close to linear in the fitted variables.
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const auto spectrum = synthetic_spectrum();
  const std::vector<std::string> names = {"efficiency", "sigma"};
  const BatchTest t = synthetic_test(truth, 1.0, 7);
  const BatchFit f = fit_batch_test(start, spectrum, kPower_W, kHoldup_kg, t, names);
  const Interval delta = propagate(f.ore, fit_covariance(f, spectrum, kPower_W, kHoldup_kg, t), p80_at_20_min)[0];
  std::vector<double> p80;
  for (int b = 0; b < 300; ++b) {
    const BatchTest tb = synthetic_test(f.ore, 1.0, 5000 + b);
    p80.push_back(p80_at_20_min(fit_batch_test(start, spectrum, kPower_W, kHoldup_kg, tb, names).ore)[0]);
  }
  std::sort(p80.begin(), p80.end());
  // The 2.5 and 97.5 % points of 300, and the bootstrap's noise on them:
  // about 10 % of the width for 300 draws.
  const double lo = p80[7], hi = p80[292], fitted = p80_at_20_min(f.ore)[0];
  std::printf("delta method: P80 %.2f um [%.2f, %.2f]; parametric bootstrap of 300: [%.2f, %.2f]\n", fitted,
              delta.lo, delta.hi, lo, hi);
  REQUIRE(delta.valid());
  CHECK((hi - lo) == Approx(delta.hi - delta.lo).epsilon(0.2));
  CHECK(std::fabs(0.5 * (lo + hi) - 0.5 * (delta.lo + delta.hi)) < 0.15 * (delta.hi - delta.lo));
}

namespace {


nlohmann::json json_of(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

std::string first_line(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  return line;
}

}  // namespace

TEST_CASE("grind intervals through the command: --fit keeps the covariance, grind gives every product its interval",
          "[grind][interval][outputs]") {
  const fs::path run_dir = mc::test::short_bond_run();
  const mc::io::Run run = mc::io::read_run(run_dir, true);
  const Ore truth = known_ore();
  mc::io::BatchTestFile tf;
  tf.title = "synthetic test, efficiency 0.35, +-1 pp";
  BatchTest t;
  t.sieve_m.push_back(3.35e-3);
  for (int k = 0; k < 12; ++k) t.sieve_m.push_back(2.36e-3 / std::pow(std::sqrt(2.0), k));
  for (double x : t.sieve_m) t.feed_passing.push_back(passing_at(truth.sizes, truth.feed, x));
  t.feed_passing[0] = 1;
  t.times_min = {1, 2, 4, 8, 16};
  t.holdup_kg = 1.2;
  t.passing = batch_test_products(truth, run.spectrum, run.power_W, 1.2, t);
  Scatter sc(11);
  for (auto& row : t.passing)
    for (std::size_t k = 1; k < row.size(); ++k) row[k] = std::clamp(row[k] + 0.01 * sc.next(), 0.0, 1.0);
  tf.test = t;
  const mc::test::TempDir dir{temp("command")};
  fs::create_directories(dir.path);
  std::ofstream(dir.path / "test.toml") << mc::io::batch_test_toml(tf);

  mc::app::GrindOptions o;
  o.run_dir = run_dir.string();
  o.ore = (fs::path(MC_ASSET_DIR) / "ores" / "example_spectrum.toml").string();
  o.fit_tests = {(dir.path / "test.toml").string()};
  o.fit_params = {"efficiency", "e_inf_J_kg", "sigma"};
  o.out = (dir.path / "fit").string();
  o.quiet = true;
  REQUIRE(mc::app::cmd_grind(o) == 0);
  const Ore fitted = mc::io::read_ore(dir.path / "fit" / "ore_fitted.toml");
  const FitCovariance& u = fitted.fitted_under.covariance;
  REQUIRE(u.given);
  CHECK(u.names.size() + u.held.size() == 3);
  const nlohmann::json fj = json_of(dir.path / "fit" / "fit.json");
  REQUIRE(fj["covariance"]["correlation"].size() == u.names.size());
  for (std::size_t a = 0; a < u.names.size(); ++a) CHECK(fj["covariance"]["correlation"][a][a].get<double>() == Approx(1));
  // The intervals' ν: the fit's less the held parameters.
  CHECK(fj["covariance"]["interval_degrees_of_freedom"].get<int>() ==
        fj["covariance"]["degrees_of_freedom"].get<int>() - static_cast<int>(u.held.size()));
  CHECK(fj.contains("covariance_seconds"));

  // The fitted ore's products, and the truth's, in the same run.
  auto grind = [&](const fs::path& ore, const std::string& out) {
    mc::app::GrindOptions g;
    g.run_dir = run_dir.string();
    g.ore = ore.string();
    g.times_min = {30};  // past the test's 16 min
    g.bond_p1_um = 106;
    g.out = (dir.path / out).string();
    g.quiet = true;
    REQUIRE(mc::app::cmd_grind(g) == 0);
    return json_of(dir.path / out / "grind.json");
  };
  std::ofstream(dir.path / "truth.toml") << mc::io::ore_toml(truth, "");
  const nlohmann::json tj = grind(dir.path / "truth.toml", "truth");
  const nlohmann::json gj = grind(dir.path / "fit" / "ore_fitted.toml", "grind");
  const double p80 = gj["products"][0]["P80_um"], true_p80 = tj["products"][0]["P80_um"];
  const auto p80_95 = gj["products"][0]["P80_um_95"].get<std::vector<double>>();
  const double wi = gj["bond"]["work_index_kWh_t"], true_wi = tj["bond"]["work_index_kWh_t"];
  const auto wi_95 = gj["bond"]["work_index_kWh_t_95"].get<std::vector<double>>();
  std::printf("through the command: P80 at 30 min %.1f um [%.1f, %.1f] (true %.1f); Wi %.2f [%.2f, %.2f] (true %.2f)\n",
              p80, p80_95[0], p80_95[1], true_p80, wi, wi_95[0], wi_95[1], true_wi);
  REQUIRE(p80_95.size() == 2);
  CHECK(p80_95[0] < p80);
  CHECK(p80 < p80_95[1]);
  CHECK(p80_95[0] <= true_p80);  // seed 11's draw: the truth inside, as 95 % of draws have it
  CHECK(true_p80 <= p80_95[1]);
  CHECK(wi_95[0] < wi);
  CHECK(wi < wi_95[1]);
  CHECK(wi_95[0] <= true_wi);
  CHECK(true_wi <= wi_95[1]);
  CHECK(first_line(dir.path / "grind" / "grind.csv").find("\"batch 30 min lower 95\",\"batch 30 min upper 95\"") !=
        std::string::npos);
  // The truth's ore has no fit: no intervals.
  CHECK_FALSE(tj["products"][0].contains("P80_um_95"));
  CHECK(first_line(dir.path / "truth" / "grind.csv").find("lower 95") == std::string::npos);
}

// ------------------------------------------------------------ tests fitted together

namespace {

TestInMill in_mill(const Ore& truth, const std::vector<SpectrumBin>& spectrum, std::uint64_t seed) {
  return {synthetic_test(truth, 1.0, seed, spectrum), spectrum, kPower_W, kHoldup_kg};
}

}  // namespace

TEST_CASE("grind --fit twice: a second mill fixes what the first leaves loose, and the interval narrows",
          "[grind][interval][joint]") {
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.e_inf_J_kg = 40;
  start.fracture.sigma = 1.0;
  const std::vector<std::string> names = {"efficiency", "e_inf_J_kg", "sigma"};
  const TestInMill a = in_mill(truth, synthetic_spectrum(), 21), b = in_mill(truth, harder_spectrum(), 22);
  const BatchFit fa = fit_batch_tests(start, {a}, names), fb = fit_batch_tests(start, {b}, names);
  const BatchFit fab = fit_batch_tests(start, {a, b}, names);
  auto identified = [](const BatchFit& f) {
    int n = 0;
    for (const FittedParameter& p : f.parameters) n += p.identified && !p.at_bound;
    return n;
  };
  std::printf("identified: %d of 3 by the first mill's test, %d by the second's, %d by both\n", identified(fa),
              identified(fb), identified(fab));
  CHECK(identified(fab) == 3);
  // E∞ against η: the second mill's spectrum, ten times harder, fixes E∞.
  const double se_a = fa.parameters[1].se, se_ab = fab.parameters[1].se;
  std::printf("E_inf standard error: %.3g by the first test alone, %.3g by both\n", se_a, se_ab);
  CHECK(se_ab < 0.5 * se_a);
  REQUIRE(fab.rms_by_test.size() == 2);
  CHECK(fab.data == 2 * fa.data);
  for (double r : fab.rms_by_test) CHECK(r == Approx(1 / std::sqrt(3.0)).epsilon(0.3));
  for (const FittedParameter& p : fab.parameters) {
    INFO(p.name << " " << p.value << " +- " << p.se);
    CHECK(std::fabs(p.value - find_ore_parameter(p.name)->get(truth)) < 3 * p.se);
  }
  // A third mill's product: the interval with both tests inside that with
  // the first alone's width, and holding the truth.
  const std::vector<SpectrumBin> third = {{3e3, 4e-3, 0.015}, {300, 4e-2, 0.015}};
  auto p80_third = [&](const Ore& o) {
    const MillRates r = mill_rates(o, third, 200, 5);
    return std::vector<double>{passing_size(o.sizes, batch_grind(o.feed, r.S_per_min, appearance_matrix(o, third), 10),
                                            0.8) * 1e6};
  };
  const double true_p80 = p80_third(truth)[0];
  const Interval ia = propagate(fa.ore, fit_covariance(fa, {a}), p80_third)[0];
  const Interval iab = propagate(fab.ore, fit_covariance(fab, {a, b}), p80_third)[0];
  std::printf("third mill's P80 (true %.1f um): first test alone [%.1f, %.1f], both [%.1f, %.1f]\n", true_p80, ia.lo,
              ia.hi, iab.lo, iab.hi);
  REQUIRE(iab.valid());
  CHECK(iab.lo <= true_p80);
  CHECK(true_p80 <= iab.hi);
  CHECK(iab.hi - iab.lo < ia.hi - ia.lo);
}

TEST_CASE("grind --fit twice through the command: the run key, the tests side by side, bad input named",
          "[grind][interval][joint][failures]") {
  const fs::path run_dir = mc::test::short_bond_run();
  const mc::io::Run run = mc::io::read_run(run_dir, true);
  const Ore truth = known_ore();
  const mc::test::TempDir dir{temp("joint")};
  fs::create_directories(dir.path / "tests");
  // A copy of the run as the second test's mill, named by its run key
  // relative to the test file; one without its spectrum.
  fs::copy(run_dir, dir.path / "mill2", fs::copy_options::recursive);
  fs::copy(run_dir, dir.path / "nospectrum", fs::copy_options::recursive);
  fs::remove(dir.path / "nospectrum" / "spectra.csv");
  auto write_test = [&](const std::string& name, std::uint64_t seed, const std::string& run_key) {
    mc::io::BatchTestFile tf;
    tf.title = name;
    tf.run = run_key;
    tf.test = synthetic_test(truth, 1.0, seed);
    tf.test.passing = batch_test_products(truth, run.spectrum, run.power_W, kHoldup_kg, tf.test);
    Scatter s(seed);
    for (auto& row : tf.test.passing)
      for (std::size_t k = 1; k < row.size(); ++k) row[k] = std::clamp(row[k] + 0.01 * s.next(), 0.0, 1.0);
    const fs::path p = dir.path / "tests" / (name + ".toml");
    std::ofstream(p) << mc::io::batch_test_toml(tf);
    return p.string();
  };
  const std::string t1 = write_test("one", 31, ""), t2 = write_test("two", 32, "../mill2");
  mc::app::GrindOptions o;
  o.run_dir = run_dir.string();
  o.ore = (fs::path(MC_ASSET_DIR) / "ores" / "example_spectrum.toml").string();
  o.fit_tests = {t1, t2};
  o.fit_params = {"efficiency", "sigma"};
  o.out = (dir.path / "fit").string();
  o.quiet = true;
  REQUIRE(mc::app::cmd_grind(o) == 0);
  const nlohmann::json j = json_of(dir.path / "fit" / "fit.json");
  REQUIRE(j["tests"].size() == 2);
  CHECK(j["tests"][1]["run"].get<std::string>() == (dir.path / "mill2").lexically_normal().string());
  CHECK(j["data"].get<int>() == 120);
  CHECK(fs::exists(dir.path / "fit" / "fit_2.png"));
  CHECK(first_line(dir.path / "fit" / "fit_residuals.csv").rfind("test,time_min", 0) == 0);
  CHECK(mc::io::read_ore(dir.path / "fit" / "ore_fitted.toml").fitted_under.covariance.dof == 118);

  // Bad input: one message naming the file and the key, nothing written.
  auto refused = [&](std::vector<std::string> tests, const std::string& message) {
    mc::app::GrindOptions b = o;
    b.fit_tests = std::move(tests);
    b.out = (dir.path / "refused").string();
    CHECK_THROWS_WITH(mc::app::cmd_grind(b), Catch::Contains(message));
    CHECK_FALSE(fs::exists(dir.path / "refused"));
  };
  refused({t1, write_test("nowhere", 33, "../no_such_run")},
          "nowhere.toml: run: \"../no_such_run\" (" + (dir.path / "no_such_run").string() + ") is not a run folder");
  refused({t1, write_test("nospec", 34, "../nospectrum")}, "nospec.toml: run: \"../nospectrum\": ");
  refused({t1, t1}, "--fit " + t1 + ": the same test twice");
  std::filesystem::copy_file(t2, dir.path / "tests" / "copy.toml");
  refused({t2, (dir.path / "tests" / "copy.toml").string()}, "copy.toml: the same test as");
  // Sieves past the ore's top: the test cannot share the ore's one series.
  {
    std::string text = mc::io::batch_test_toml(mc::io::read_batch_test(t2));
    text.replace(text.find("sieve_mm = [3.35"), 16, "sieve_mm = [4.75");
    std::ofstream(dir.path / "tests" / "coarse.toml") << text;
  }
  refused({t1, (dir.path / "tests" / "coarse.toml").string()}, "coarse.toml: sieve_mm: 4.75 to");
}

namespace {

// A 5 x 13 test of `truth` in the first mill whose sieve errors are
// correlated between sieves. "adjacent": along each product's sieves,
// e_k = ρ e_{k−1} + √(1 − ρ²) ξ_k, ξ uniform in ±1 pp (every reading's
// scatter as the independent tests': ±1 pp uniform, 1/3 pp²). "cumulative":
// an independent error in each size class's mass (uniform, ±a pp), the
// passing at a sieve carrying the sum of the classes below it, so that
// the coarser the sieve the larger its error, and neighbours share most of
// theirs; a chosen so that the readings' mean square is 1/3 pp² as well.
BatchTest correlated_test(const Ore& truth, const std::string& model, double rho, std::uint64_t seed) {
  BatchTest t = synthetic_test(truth, 0.0, seed);
  t.noise_pp = 1.0;
  Scatter s(seed);
  const std::size_t ns = t.sieve_m.size();  // readings at sieves 1 .. ns − 1 (the top passes 1)
  // The reading at sieve k carries ns − k classes' errors, ns / 2 on
  // average over k = 1 .. ns − 1: a² / 3 · ns / 2 = 1/3.
  const double a = std::sqrt(2.0 / static_cast<double>(ns));
  for (auto& row : t.passing) {
    std::vector<double> e(ns, 0.0);
    if (model == "adjacent") {
      for (std::size_t k = 1; k < ns; ++k)
        e[k] = (k == 1 ? 0.0 : rho * e[k - 1]) + (k == 1 ? 1.0 : std::sqrt(1 - rho * rho)) * s.next();
    } else {
      double below = 0;
      for (std::size_t k = ns; k-- > 1;) {
        below += a * s.next();
        e[k] = below;
      }
    }
    for (std::size_t k = 1; k < ns; ++k) row[k] += e[k] / 100;
  }
  return t;
}

}  // namespace

TEST_CASE("grind intervals: coverage with sieve errors correlated between sieves", "[grind][interval][correlated]") {
  // The coverage check's setting (the P80 after 20 min, η and σ fitted,
  // the same ±1 pp scatter per reading) with errors correlated between
  // sieves: adjacent sieves at ρ = 0.7, and the cumulative model. Taken
  // as independent (--sieve-errors independent), the intervals hold the
  // truth in about 70 % of tests; as grind --fit takes them by default
  // (auto: the residuals correlate, so ρ is estimated and the fit made on
  // the whitened residuals, sieve_errors.h), in about 95 %. The measured
  // figures are docs/grinding-intervals.md's; the check holds each within
  // three binomial standard deviations of its figure, the independent ones
  // well below 95 % and the correlated ones within three of 95 %.
  const auto t0 = std::chrono::steady_clock::now();
  const Ore truth = known_ore();
  const double true_p80 = p80_at_20_min(truth)[0];
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const auto spectrum = synthetic_spectrum();
  const int n = 400;
  const BatchTest exact = synthetic_test(truth, 0.0, 1);
  struct Case {
    std::string model;
    double rho;
  };
  for (const Case& c : {Case{"adjacent", 0.7}, Case{"cumulative", 0}, Case{"adjacent", 0.4}, Case{"adjacent", 0.0}})
    for (const SieveErrors mode : {SieveErrors::independent, SieveErrors::automatic}) {
      const std::string& model = c.model;
      int held = 0, switched = 0;
      double width = 0, ms = 0, s2 = 0, z2 = 0, rho = 0;  // z: the P80's distance from the truth in its standard errors
      for (int seed = 0; seed < n; ++seed) {
        const BatchTest t = correlated_test(truth, model, c.rho, 20000 + seed);
        for (std::size_t i = 0; i < t.passing.size(); ++i)
          for (std::size_t k = 1; k < t.passing[i].size(); ++k) {
            const double e = 100 * (t.passing[i][k] - exact.passing[i][k]);
            ms += e * e / (n * t.passing.size() * (t.passing[i].size() - 1));
          }
        const SieveErrorFit f = fit_with_sieve_errors(start, {TestInMill{t, spectrum, kPower_W, kHoldup_kg}},
                                                      {"efficiency", "sigma"}, mode);
        const FitCovariance u = fit_covariance(f.fit, f.tests);
        const Interval i = propagate(f.fit.ore, u, p80_at_20_min)[0];
        REQUIRE(i.valid());
        held += i.lo <= true_p80 && true_p80 <= i.hi;
        switched += f.correlated;
        rho += f.rho / n;
        width += (i.hi - i.lo) / true_p80 / n;
        s2 += u.residual_variance_pp2 / n;
        const double z = std::log(std::sqrt(i.lo * i.hi) / true_p80) /
                         (0.5 * std::log(i.hi / i.lo) / t_quantile(0.975, interval_dof(u)));
        z2 += z * z / n;
      }
      const double coverage = static_cast<double>(held) / n;
      std::printf("interval coverage, sieve errors %s (rho %.1f; 0 for cumulative), taken %s: %d tests (%d as correlated, mean rho %.3f), "
                  "readings' mean square %.3f pp2, s2 %.3f pp2, mean width %.2f %%: %.3f held; z rms %.2f (%.1f s "
                  "so far)\n",
                  model.c_str(), c.rho, sieve_errors_name(mode), n, switched, rho, ms, s2, 100 * width, coverage,
                  std::sqrt(z2), std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      const double band95 = 3 * std::sqrt(0.95 * 0.05 / n);
      const bool as_independent = mode == SieveErrors::independent;
      // The documented figures: coverage taken as independent and by auto,
      // and how many tests auto took as correlated.
      const double documented = c.rho == 0.7 ? (as_independent ? 0.718 : 0.943)
                                : c.model == "cumulative" ? (as_independent ? 0.695 : 0.940)
                                : c.rho == 0.4 ? (as_independent ? 0.807 : 0.938)
                                               : 0.932;
      const int documented_switched = as_independent ? 0 : c.rho == 0.7 || c.model == "cumulative" ? 400
                                                       : c.rho == 0.4 ? 367 : 19;
      CHECK(std::fabs(coverage - documented) <= 3 * std::sqrt(documented * (1 - documented) / n));
      // The mean ρ auto found, as documented (the seeds are fixed: this
      // moves only with the estimator).
      const double documented_rho = as_independent ? 0 : c.rho == 0.7 ? 0.704 : c.model == "cumulative" ? 0.929
                                                       : c.rho == 0.4 ? 0.392 : 0.013;
      CHECK(rho == Approx(documented_rho).margin(0.01));
      if (c.rho == 0 && c.model == "adjacent") {
        // Independent errors: about 95 % either way; auto takes a few
        // (r1 above 0.15 by chance) as correlated, to no harm.
        CHECK(std::fabs(coverage - 0.95) <= band95);
        CHECK(switched <= 40);
      } else if (as_independent) {
        // Well below 95 % (its three standard deviations: 0.033): the
        // independent model under-covers here.
        CHECK(coverage < 0.95 - band95);
        CHECK(switched == 0);
      } else {
        CHECK(std::fabs(coverage - 0.95) <= band95);
        CHECK(std::abs(switched - documented_switched) <= 20);
      }
    }
}

TEST_CASE("grind fit: residuals correlated along the sieves are said, independent ones not",
          "[grind][interval][correlated]") {
  // The fit's residuals' lag-1 autocorrelation along the sieves (pooled
  // over the test times): for cumulative sieve errors (the case whose
  // intervals cover about 70 % taken as independent) above 0.15, with the
  // note where the fit took them as independent; for independent errors
  // near 0, without it. Ten seeded tests each; and r1 by hand from
  // the fit's residuals for the first.
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const auto spectrum = synthetic_spectrum();
  double least_correlated = 1, most_independent = 0, mean_independent = 0;
  for (int seed = 0; seed < 10; ++seed) {
    const BatchTest c = correlated_test(truth, "cumulative", 0.7, 30000 + seed);
    const BatchTest i = synthetic_test(truth, 1.0, 30000 + seed);
    const BatchFit fc = fit_batch_test(start, spectrum, kPower_W, kHoldup_kg, c, {"efficiency", "sigma"});
    const BatchFit fi = fit_batch_test(start, spectrum, kPower_W, kHoldup_kg, i, {"efficiency", "sigma"});
    least_correlated = std::min(least_correlated, fc.residual_r1);
    most_independent = std::max(most_independent, std::fabs(fi.residual_r1));
    mean_independent += fi.residual_r1 / 10;
    CHECK_FALSE(sieve_errors_note(fc.residual_r1, 0, SieveErrors::independent).empty());
    CHECK(sieve_errors_note(fi.residual_r1, 0, SieveErrors::independent).empty());
    if (seed == 0) {
      // By hand: the residuals at each time along the sieves the fit reads.
      const std::vector<std::size_t> used = informative_sieves(c);
      double mean = 0, num = 0, den = 0;
      std::size_t n = 0;
      for (std::size_t t = 0; t < c.times_min.size(); ++t)
        for (std::size_t k : used) mean += fc.predicted[t][k] - c.passing[t][k], ++n;
      mean /= static_cast<double>(n);
      for (std::size_t t = 0; t < c.times_min.size(); ++t)
        for (std::size_t a = 0; a < used.size(); ++a) {
          const double d = fc.predicted[t][used[a]] - c.passing[t][used[a]] - mean;
          den += d * d;
          if (a + 1 < used.size()) num += d * (fc.predicted[t][used[a + 1]] - c.passing[t][used[a + 1]] - mean);
        }
      CHECK(fc.residual_r1 == Approx(num / den).epsilon(1e-6));
    }
  }
  std::printf("residuals' lag-1 autocorrelation along the sieves, 10 tests: cumulative errors at least %.3f; "
              "independent at most |%.3f|, mean %.3f\n",
              least_correlated, most_independent, mean_independent);
  CHECK(least_correlated > kSwitchToCorrelated);
  // Independent errors: 5 times x 12 sieves give 55 neighbours, so one
  // test's r1 scatters by about 1/√55 = 0.13 about a mean a little below
  // 0 (−1/12 for noise less its mean; the fit takes a little more):
  // measured −0.37 to +0.06, mean −0.11. Each within 0.45 (3.3 of its
  // scatter), the mean of ten within ±0.15 (0.04 its scatter).
  CHECK(most_independent < 0.45);
  CHECK(std::fabs(mean_independent) < 0.15);
  const std::string note = sieve_errors_note(0.5, 0, SieveErrors::independent);
  CHECK(note.find("r1 = 0.50") != std::string::npos);
  CHECK(note.find("docs/grinding-intervals.md#sieve-errors-correlated-between-sieves") != std::string::npos);
  CHECK(sieve_errors_note(std::numeric_limits<double>::quiet_NaN(), 0, SieveErrors::independent).empty());
  CHECK(sieve_errors_note(0.5, 0, SieveErrors::automatic).empty());  // auto would have taken them as correlated
}
