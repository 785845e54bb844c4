// What a fit leaves open beyond its free parameters' covariance (src/grind/
// interval.h, fit.h): held parameters combined jointly and in quadrature
// around where they fit best, their profiles' limit from the profile's
// minimum (F(1, ν) = t², ν counting the held ones), true profiles (the
// other held ones refitted), the search's reach against a brute-force
// grid, the coverage of an interval with a held parameter, parameters at
// a bound, tests weighted by their noise, a
// fitted ore edited by hand, strongly correlated parameters, and an
// interval open at one end.
#include <catch2/catch.hpp>

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "app/grind.h"
#include "app/grind_interval.h"
#include "bond_run.h"
#include "grind/fit.h"
#include "grind/interval.h"
#include "grind_synthetic.h"
#include "io/batch_test_file.h"
#include "io/ore_file.h"
#include "io/run_folder.h"

using namespace mc::grind;
using namespace mc::test;
namespace fs = std::filesystem;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A covariance made by hand: efficiency free (a standard error of 0.1 in
// its logarithm), 50 degrees of freedom, no held parameter.
FitCovariance one_free(const Ore& ore) {
  FitCovariance u;
  u.given = true;
  u.names = {"efficiency"};
  u.values = {std::log(ore.efficiency)};
  u.matrix = {{0.01}};
  u.residual_variance_pp2 = 0.3;
  u.dof = 50;
  return u;
}

HeldParameter held(const std::string& name, double value, double lo, double hi, const FitCovariance& u) {
  HeldParameter h;
  h.name = name;
  h.value = value;
  h.lo = lo;
  h.hi = hi;
  h.why = "held for the test";
  h.free_at_lo = h.free_at_hi = u.values;
  return h;
}

// The free parameters refitted with the ore's other parameters as they are:
// the weighted sum of squares.
double refit_ssr(const Ore& o, const std::vector<TestInMill>& tests, const std::vector<std::string>& free) {
  return fit_batch_tests(o, tests, free, 300, false).ssr;
}

fs::path temp(const std::string& name) {
  return fs::temp_directory_path() / ("millcharge_test_held_" + std::to_string(::getpid()) + "_" + name);
}

nlohmann::json json_of(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

// A command's exit status and what it wrote to stdout and stderr.
std::string run_binary(const std::string& args, int& status) {
  FILE* p = popen((std::string(MC_BINARY) + " " + args + " 2>&1").c_str(), "r");
  std::string out;
  char buf[512];
  while (p && fgets(buf, sizeof buf, p)) out += buf;
  const int rc = p ? pclose(p) : -1;
  status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  return out;
}

int count_of(const std::string& text, const std::string& piece) {
  int n = 0;
  for (std::size_t at = text.find(piece); at != std::string::npos; at = text.find(piece, at + 1)) ++n;
  return n;
}

}  // namespace

TEST_CASE("grind intervals: held parameters together at their corners, in quadrature with the free ones",
          "[grind][interval][held]") {
  const Ore ore = known_ore();
  // Two held with S_min 12: ν = 50 − 2 = 48, s² = 12 / 48 against the
  // fit's 0.3, so the free half-width is t₄₈ · 0.1 · √(0.25 / 0.3).
  const double t = t_quantile(0.975, 48), half = t * 0.1 * std::sqrt(0.25 / 0.3), e = std::exp(1.0);
  // η E∞ d₀: its logarithm is the sum of the three; E∞ and d₀ held, each
  // over a factor of e either way, the free η unmoved at their ends.
  auto product = [](const Ore& o) {
    return std::vector<double>{o.efficiency * o.fracture.e_inf_J_kg * o.fracture.d0_m * 1e3};
  };
  const double p0 = product(ore)[0];
  FitCovariance u = one_free(ore);
  u.held = {held("e_inf_J_kg", 60, 60 / e, 60 * e, u), held("d0_mm", 2, 2 / e, 2 * e, u)};
  for (double a : {60 / e, 60 * e})
    for (double b : {2 / e, 2 * e}) u.edges.push_back({{a, b}, u.values});
  u.best = {{60, 2}, u.values};
  u.ssr_best = 12;
  REQUIRE(interval_dof(u) == 48);
  const Interval i = propagate(ore, u, product)[0];
  // Together they reach a factor of e² (each alone, e); with the free one's
  // half-width in quadrature, not added to it.
  CHECK(i.hi == Approx(p0 * std::exp(std::hypot(half, 2.0))).epsilon(1e-6));
  CHECK(i.lo == Approx(p0 * std::exp(-std::hypot(half, 2.0))).epsilon(1e-6));
  // Around where the held ones fit best: E∞ held at 60, best at 60 e^½,
  // its range 60 to 60 e: the interval spans e^½ either side of the best
  // point (the held value inside it), the free half-width in quadrature.
  // No S_min kept: the fit's S (0.3 × 50) over ν = 49.
  FitCovariance v = one_free(ore);
  v.held = {held("e_inf_J_kg", 60, 60, 60 * e, v)};
  v.best = {{60 * std::exp(0.5)}, v.values};
  const Interval j = propagate(ore, v, product)[0];
  const double centre = p0 * std::exp(0.5), half_v = t_quantile(0.975, 49) * 0.1 * std::sqrt(50.0 / 49);
  CHECK(j.hi == Approx(centre * std::exp(std::hypot(half_v, 0.5))).epsilon(1e-6));
  CHECK(j.lo == Approx(centre * std::exp(-std::hypot(half_v, 0.5))).epsilon(1e-6));
  // Without held ones, the fit's own ν and s².
  const Interval k = propagate(ore, one_free(ore), product)[0];
  CHECK(k.hi == Approx(p0 * std::exp(t_quantile(0.975, 50) * 0.1)).epsilon(1e-9));
}

TEST_CASE("grind intervals: held parameters' ranges are limited from their least S, their edge points within it",
          "[grind][interval][held]") {
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  start.fracture.e_inf_J_kg = 40;  // held wrong, with d₀
  start.fracture.d0_m = 2.8e-3;
  const std::vector<TestInMill> tests = {{synthetic_test(truth, 1.0, 41), synthetic_spectrum(), kPower_W, kHoldup_kg}};
  const std::vector<std::string> free = {"efficiency", "sigma"};
  BatchFit f = fit_batch_tests(start, tests, free);
  for (const char* name : {"e_inf_J_kg", "d0_mm"}) {
    FittedParameter h;
    h.name = name;
    h.start = h.value = find_ore_parameter(name)->get(start);
    h.identified = false;
    h.why = "held for the test";
    f.parameters.push_back(h);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const FitCovariance u = fit_covariance(f, tests);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  REQUIRE(u.held.size() == 2);
  REQUIRE(u.best.held.size() == 2);
  // The least S met lies below the fit's own (the held values are wrong),
  // and is what a refit there gives.
  Ore at_best = with_variables(start, u, u.best.free);
  for (std::size_t k = 0; k < 2; ++k) find_ore_parameter(u.held[k].name)->set(at_best, u.best.held[k]);
  const double s_best = weighted_ssr(at_best, tests), limit = profile_limit(s_best, interval_dof(u));
  std::printf("held profiles: S %.3f at the fit, %.3f at the best point (E_inf %.4g, d0 %.4g); limit %.3f; "
              "E_inf [%.4g, %.4g], d0 [%.4g, %.4g]; %zu edge points; %.2f s\n",
              f.ssr, s_best, u.best.held[0], u.best.held[1], limit, u.held[0].lo, u.held[0].hi, u.held[1].lo,
              u.held[1].hi, u.edges.size(), seconds);
  CHECK(s_best < f.ssr - 0.5 * f.s2);
  CHECK(s_best == Approx(refit_ssr(at_best, tests, free)).epsilon(1e-6));
  // Both sums of squares and the limit kept (fitted.ssr_held, ssr_best,
  // ssr_limit), and the held values said to lie outside the data's region
  // exactly where S there is above the limit.
  CHECK(u.ssr_fit == f.ssr);
  CHECK(u.ssr_best == Approx(s_best).epsilon(1e-9));
  CHECK(u.ssr_limit == Approx(limit).epsilon(1e-9));
  const std::string outside = outside_region(u);
  INFO(outside);
  CHECK(outside.empty() == (f.ssr <= limit));
  if (f.ssr > limit) CHECK(outside.find("e_inf_J_kg") != std::string::npos);
  // Each end of a profile the data set (not the file's range): the other
  // held one and the free ones refitted there, S within the limit; a
  // fortieth of its reach further out (ends found to 2 %), everything else refitted from there,
  // past it. The profile is a true one: at one end at least the other held
  // parameter has moved from its best value, and S with it kept at its
  // best (the conditional profile) lies above S at the end.
  int ends = 0, others_moved = 0;
  for (const HeldEdge& e : u.edges) {
    if (e.of < 0) continue;
    const std::size_t k = static_cast<std::size_t>(e.of), other = 1 - k;
    const HeldParameter& h = u.held[k];
    const OreParameter& p = *find_ore_parameter(h.name);
    const double end = e.held[k];
    if (end <= p.lo || end >= p.hi) continue;
    ++ends;
    Ore o = with_variables(start, u, e.free);
    for (std::size_t m = 0; m < 2; ++m) find_ore_parameter(u.held[m].name)->set(o, e.held[m]);
    const double s_end = weighted_ssr(o, tests);
    const double step = std::log(end / u.best.held[k]);
    p.set(o, end * std::exp(0.025 * step));
    std::vector<std::string> all = free;
    all.push_back(u.held[other].name);
    const double s_past = refit_ssr(o, tests, all);
    Ore conditional = at_best;
    p.set(conditional, end);
    const double s_conditional = refit_ssr(conditional, tests, free);
    const bool moved = std::fabs(e.held[other] / u.best.held[other] - 1) > 1e-3;
    others_moved += moved && s_conditional > s_end * (1 + 1e-6);
    INFO(h.name << " end " << end << " (" << u.held[other].name << " " << e.held[other] << "): S " << s_end
                << ", 2.5 % further " << s_past << ", the other at its best " << s_conditional << ", limit " << limit);
    CHECK(s_end <= limit * (1 + 1e-6));
    CHECK(s_past > limit * (1 - 1e-6));
  }
  CHECK(others_moved >= 1);
  CHECK(ends >= 2);
  // The edge points (each alone, and toward the corners): each within the limit.
  REQUIRE(u.edges.size() >= 4);
  int corners = 0, past = 0;
  for (const HeldEdge& c : u.edges) {
    Ore o = with_variables(start, u, c.free);
    for (std::size_t k = 0; k < 2; ++k) find_ore_parameter(u.held[k].name)->set(o, c.held[k]);
    CHECK(weighted_ssr(o, tests) <= limit * (1 + 1e-6));
    // A corner point (both moved): on the limit or the file's range, not
    // short of them at the corner of the ranges. An eighth
    // further out along its ray from the best point is past the limit,
    // or past the file's range.
    bool both = true, in_file = true;
    Ore further = at_best;
    for (std::size_t k = 0; k < 2; ++k) {
      const OreParameter& p = *find_ore_parameter(u.held[k].name);  // both scales: their logarithms
      both = both && c.held[k] != u.best.held[k];
      const double v = u.best.held[k] * std::pow(c.held[k] / u.best.held[k], 1.125);
      in_file = in_file && v >= p.lo && v <= p.hi;
      if (in_file) p.set(further, v);
    }
    if (!both) continue;
    ++corners;
    if (!in_file) continue;
    const double s_further = refit_ssr(further, tests, free);
    past += s_further > limit * (1 - 1e-6);
    INFO("corner " << c.held[0] << ", " << c.held[1] << ": an eighth further S " << s_further << ", limit " << limit);
    CHECK(s_further > limit * (1 - 1e-6));
  }
  std::printf("held corners: %d corner points, %d checked an eighth further past the limit\n", corners, past);
  CHECK(corners >= 1);
}

TEST_CASE("grind intervals: the free part taken where the held parameters fit best, not where they are held",
          "[grind][interval][held]") {
  // E∞ and d₀ held wrong, η and σ fitted (seed 41): the interval is centred
  // where the held ones fit best, and its free half-width must be taken
  // there too. Independently: the free ones refitted at the best held
  // values (fit_batch_tests from there), that fit's covariance at the
  // intervals' s² (S_min / ν), and log P80's gradient by central
  // differences of the model at the refitted ore.
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  start.fracture.e_inf_J_kg = 40;
  start.fracture.d0_m = 2.8e-3;
  const std::vector<TestInMill> tests = {{synthetic_test(truth, 1.0, 41), synthetic_spectrum(), kPower_W, kHoldup_kg}};
  const std::vector<std::string> free = {"efficiency", "sigma"};
  BatchFit f = fit_batch_tests(start, tests, free);
  for (const char* name : {"e_inf_J_kg", "d0_mm"}) {
    FittedParameter h;
    h.name = name;
    h.start = h.value = find_ore_parameter(name)->get(start);
    h.identified = false;
    h.why = "held for the test";
    f.parameters.push_back(h);
  }
  const FitCovariance u = fit_covariance(f, tests);
  REQUIRE(u.best.held.size() == 2);
  Ore from_best = start;
  for (std::size_t k = 0; k < 2; ++k) find_ore_parameter(u.held[k].name)->set(from_best, u.best.held[k]);
  const BatchFit g = fit_batch_tests(from_best, tests, free);
  REQUIRE(g.covariance.size() == 2);
  const double scale = u.ssr_best / interval_dof(u) / g.s2;
  std::vector<double> grad(2);
  for (std::size_t j = 0; j < 2; ++j) {
    const OreParameter& p = *find_ore_parameter(free[j]);
    const double h = 1e-3;
    Ore a = g.ore, b = g.ore;
    p.set(a, p.get(g.ore) * std::exp(h));
    p.set(b, p.get(g.ore) * std::exp(-h));
    grad[j] = (std::log(p80_third_mill(a)[0]) - std::log(p80_third_mill(b)[0])) / (2 * h);
  }
  double var = 0;
  for (std::size_t a = 0; a < 2; ++a)
    for (std::size_t b = 0; b < 2; ++b) var += grad[a] * g.covariance[a][b] * scale * grad[b];
  const double sd = std::sqrt(var);
  const Sensitivity s = sensitivities(f.ore, u, p80_third_mill).front();
  REQUIRE(s.log);
  const auto C = interval_covariance(u);
  double var_s = 0;
  for (std::size_t a = 0; a < 2; ++a)
    for (std::size_t b = 0; b < 2; ++b) var_s += s.g[a] * C[a][b] * s.g[b];
  const double q = t_quantile(0.975, interval_dof(u));
  const Interval i = propagate(f.ore, u, p80_third_mill)[0];
  const double p80 = p80_third_mill(truth)[0];
  std::printf("free part at the best point: sd of log P80 %.5f (by hand %.5f); interval [%.1f, %.1f] um, truth %.1f; "
              "by hand [%.1f, %.1f]\n",
              std::sqrt(var_s), sd, i.lo, i.hi, p80, std::exp(s.center - std::hypot(q * sd, s.down)),
              std::exp(s.center + std::hypot(q * sd, s.up)));
  CHECK(std::exp(s.center) == Approx(p80_third_mill(g.ore)[0]).epsilon(1e-3));
  CHECK(std::sqrt(var_s) == Approx(sd).epsilon(0.03));
  CHECK(i.lo == Approx(std::exp(s.center - std::hypot(q * sd, s.down))).epsilon(0.005));
  CHECK(i.hi == Approx(std::exp(s.center + std::hypot(q * sd, s.up))).epsilon(0.005));
  CHECK(i.lo < p80);
  CHECK(i.hi > p80);
}

TEST_CASE("grind intervals: with a held parameter, the interval still holds the truth in about 95 % of tests",
          "[grind][interval][held]") {
  // E∞ held at two thirds of its true value, η and σ fitted: the interval
  // of a third mill's P80 (which E∞ moves) over N seeded tests, against
  // the truth; and the delta method alone, as if E∞ were known.
  const auto t0 = std::chrono::steady_clock::now();
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  start.fracture.e_inf_J_kg = 40;
  const double true_p80 = p80_third_mill(truth)[0];
  const int n = 100;
  int held_in = 0, delta_in = 0;
  double width = 0, width_delta = 0;
  for (int seed = 0; seed < n; ++seed) {
    const std::vector<TestInMill> tests = {
        {synthetic_test(truth, 1.0, 7000 + seed), synthetic_spectrum(), kPower_W, kHoldup_kg}};
    BatchFit f = fit_batch_tests(start, tests, {"efficiency", "sigma"});
    FittedParameter h;
    h.name = "e_inf_J_kg";
    h.start = h.value = 40;
    h.identified = false;
    f.parameters.push_back(h);
    const FitCovariance u = fit_covariance(f, tests);
    const Sensitivity s = sensitivities(f.ore, u, p80_third_mill).front();
    const Interval i = interval_of(s, interval_covariance(u), t_quantile(0.975, interval_dof(u)), 1);
    // E∞ taken as known: no held one, at the fit (the fit's own covariance,
    // gradients where E∞ is held), its own s² and ν.
    FitCovariance known = u;
    known.held.clear();
    known.best = {};
    known.edges.clear();
    known.matrix = f.covariance;
    const Interval d = propagate(f.ore, known, p80_third_mill)[0];
    REQUIRE(i.valid());
    held_in += i.lo <= true_p80 && true_p80 <= i.hi;
    delta_in += d.lo <= true_p80 && true_p80 <= d.hi;
    width += (i.hi - i.lo) / true_p80 / n;
    width_delta += (d.hi - d.lo) / true_p80 / n;
  }
  const double coverage = static_cast<double>(held_in) / n, coverage_delta = static_cast<double>(delta_in) / n;
  const double tolerance = 3 * std::sqrt(0.95 * 0.05 / n);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("interval coverage with E_inf held at 40 (true 60): third mill's P80 %.1f um, %d tests, mean width "
              "%.1f %%: %.3f held; by the delta method alone %.3f, mean width %.1f %% (tolerance +-%.3f); %.1f s\n",
              true_p80, n, 100 * width, coverage, coverage_delta, 100 * width_delta, tolerance, seconds);
  CHECK(coverage >= 0.95 - tolerance);
  // The held reach must earn its place: the delta method alone covers
  // 0.910 here, itself above the bound, so without the reach the check
  // above would still pass. The held interval must cover more, and be
  // wider by more than a fifth, than the delta method's.
  CHECK(coverage > coverage_delta);
  CHECK(width > 1.2 * width_delta);
  CHECK(width < 3 * width_delta);  // wider where E∞ matters, not without bound
}

TEST_CASE("grind fit: a parameter within a whisker of its bound is held on it, its steps kept inside its range",
          "[grind][interval][held]") {
  // The truth's η a ten-millionth below its bound of 1, no scatter: the fit
  // ends within the whisker and puts η on the bound.
  Ore truth = known_ore();
  truth.efficiency = 1 - 1e-7;
  Ore start = truth;
  start.efficiency = 0.5;
  start.fracture.sigma = 1.0;
  const std::vector<TestInMill> tests = {{synthetic_test(truth, 0.0, 1), synthetic_spectrum(), kPower_W, kHoldup_kg}};
  const BatchFit f = fit_batch_tests(start, tests, {"efficiency", "sigma"});
  REQUIRE(f.parameters.size() == 2);
  CHECK(f.parameters[0].at_bound);
  CHECK(f.parameters[0].value == 1.0);
  CHECK(f.covariance_of == std::vector<std::size_t>{1});
  const FitCovariance u = fit_covariance(f, tests);
  REQUIRE(u.held.size() == 1);
  CHECK(u.held[0].why == "on its bound");
  CHECK(u.held[0].hi == 1.0);  // one-sided: the data can bound it below only
  CHECK(u.held[0].lo <= 1.0);
  // A free η a hundred-thousandth below 1 with a standard error of 0.1 in
  // its logarithm: the differences step below it only (a number the ore
  // cannot make past its range is NaN there), and the interval is the
  // delta method's all the same.
  Ore near = known_ore();
  near.efficiency = 0.99999;
  const FitCovariance v = one_free(near);
  auto eta = [](const Ore& o) {
    return std::vector<double>{o.efficiency > 1 ? std::numeric_limits<double>::quiet_NaN() : o.efficiency};
  };
  const Interval i = propagate(near, v, eta)[0];
  const double half = t_quantile(0.975, 50) * 0.1;
  REQUIRE(i.valid());
  CHECK(i.lo == Approx(0.99999 * std::exp(-half)).epsilon(1e-6));
  CHECK(i.hi == Approx(0.99999 * std::exp(half)).epsilon(1e-6));
}

TEST_CASE("grind --fit of tests of different noise: each counts by 1/noise^2", "[grind][interval][held]") {
  // Two tests in the same mill of ores that differ (η 0.35 and 0.45), no
  // scatter, η fitted to both: halving one test's noise pulls the fit to
  // it; equal noises, whatever they are, give the unweighted fit.
  Ore a = known_ore(), b = known_ore();
  b.efficiency = 0.45;
  Ore start = a;
  start.efficiency = 0.6;
  auto fit = [&](double noise_a, double noise_b) {
    TestInMill ta{synthetic_test(a, 0.0, 1), synthetic_spectrum(), kPower_W, kHoldup_kg};
    TestInMill tb{synthetic_test(b, 0.0, 2, synthetic_spectrum(), {1, 2, 4, 8, 16}), synthetic_spectrum(), kPower_W,
                  kHoldup_kg};
    ta.test.noise_pp = noise_a;
    tb.test.noise_pp = noise_b;
    return fit_batch_tests(start, {ta, tb}, {"efficiency"});
  };
  const BatchFit same = fit(1, 1), same_half = fit(0.5, 0.5), precise_a = fit(0.5, 1), precise_b = fit(1, 0.5);
  const double eq = same.ore.efficiency, wa = precise_a.ore.efficiency, wb = precise_b.ore.efficiency;
  std::printf("weighted by noise: eta %.5f with equal noises, %.5f with the 0.35 test at 0.5 pp, %.5f with the "
              "0.45 test at 0.5 pp\n",
              eq, wa, wb);
  CHECK(same_half.ore.efficiency == Approx(eq).epsilon(1e-9));
  CHECK(same_half.covariance[0][0] == Approx(same.covariance[0][0]).epsilon(1e-9));
  CHECK(same_half.ssr == Approx(same.ssr).epsilon(1e-9));
  CHECK(wa < eq - 0.01);  // toward 0.35
  CHECK(wb > eq + 0.01);  // toward 0.45
  // Four to one: the fit's distance from each test's η shrinks on the
  // precise side.
  CHECK((wa - 0.35) / (0.45 - wa) < 0.5 * (eq - 0.35) / (0.45 - eq));
  // A noise of 0 beside a noise is an infinite weight: refused.
  CHECK_THROWS_WITH(fit(0, 1), Catch::Contains("noise_pp 0"));
}

TEST_CASE("grind intervals: correlated pairs, and an interval open at one end", "[grind][interval][held]") {
  FitCovariance u;
  u.names = {"efficiency", "e_inf_J_kg", "sigma"};
  u.matrix = {{1, 0.995, 0.5}, {0.995, 1, 0.2}, {0.5, 0.2, 4}};
  const auto pairs = correlated_pairs(u);
  REQUIRE(pairs.size() == 1);
  CHECK(pairs[0].a == "log(efficiency)");
  CHECK(pairs[0].b == "log(e_inf_J_kg)");
  CHECK(pairs[0].r == Approx(0.995));
  // A number past any bound at a held parameter's end (a target the moved
  // ore cannot reach): that end is open.
  const Ore ore = known_ore();
  FitCovariance v = one_free(ore);
  v.held = {held("e_inf_J_kg", 60, 30, 120, v)};
  auto rate = [](double sign) {
    return [sign](const Ore& o) {
      return std::vector<double>{o.fracture.e_inf_J_kg > 100 ? sign * kInf : o.efficiency * o.fracture.e_inf_J_kg};
    };
  };
  const Interval above = propagate(ore, v, rate(+1))[0], below = propagate(ore, v, rate(-1))[0];
  REQUIRE(above.valid());
  CHECK(above.open_above());
  CHECK(std::isfinite(above.lo));
  CHECK(below.open_below());
  CHECK(std::isfinite(below.hi));
  CHECK(mc::app::bracket(above, 1, "{:.3g}") == " [> " + fmt::format("{:.3g}", above.lo) + "]");
  CHECK(mc::app::bracket(below, 1, "{:.3g}") == " [< " + fmt::format("{:.3g}", below.hi) + "]");
}

TEST_CASE("grind intervals through the command: an ore edited by hand, correlated pairs, a target out of reach",
          "[grind][interval][held][outputs]") {
  const fs::path run_dir = short_bond_run();
  const Ore truth = known_ore();
  const TempDir dir{temp("command")};
  fs::create_directories(dir.path);
  const fs::path fitted = fit_synthetic_in_bond_run(truth, 12, dir.path);
  std::stringstream text;
  text << std::ifstream(fitted).rdbuf();
  const std::string ore_text = text.str();
  auto write = [&](const std::string& name, const std::string& body) {
    std::ofstream(dir.path / name) << body;
    return (dir.path / name).string();
  };
  auto grind = [&](const std::string& ore, const std::string& out, const std::string& more, int& status) {
    return run_binary("grind " + run_dir.string() + " --ore " + ore + " --time 4 --out " + (dir.path / out).string() +
                          " " + more,
                      status);
  };
  int status = 0;
  // As fitted: intervals.
  grind(fitted.string(), "as_fitted", "", status);
  REQUIRE(status == 0);
  CHECK(json_of(dir.path / "as_fitted" / "grind.json")["products"][0].contains("P80_um_95"));
  // η edited by hand: no intervals, said once, naming the key.
  std::string edited = ore_text;
  const std::size_t at = edited.find("\nefficiency = ");
  REQUIRE(at != std::string::npos);
  edited.replace(at, edited.find('\n', at + 1) - at, "\nefficiency = 0.9");
  const std::string said = grind(write("edited.toml", edited), "edited", "", status);
  INFO(said);
  CHECK(status == 0);
  CHECK(count_of(said, "rates.efficiency = 0.9") == 1);
  CHECK(count_of(said, "products without intervals") == 1);
  const nlohmann::json ej = json_of(dir.path / "edited" / "grind.json");
  CHECK_FALSE(ej["products"][0].contains("P80_um_95"));
  CHECK(ej["intervals"]["changed"].get<std::string>().find("rates.efficiency") != std::string::npos);
  // breakage.beta edited, neither free nor held: the tables' hash kept by
  // --fit (fitted.tables_fnv1a) differs; no intervals, said once.
  CHECK(ore_text.find("\ntables_fnv1a = \"sizes ") != std::string::npos);
  std::string beta = ore_text;
  const std::size_t bt = beta.find("\nbeta = ");
  REQUIRE(bt != std::string::npos);
  beta.replace(bt, beta.find('\n', bt + 1) - bt, "\nbeta = 3.9");
  const std::string beta_said = grind(write("beta.toml", beta), "beta", "", status);
  INFO(beta_said);
  CHECK(status == 0);
  CHECK(count_of(beta_said, "[breakage] differ from the tables the ore was fitted with ([fitted] tables_fnv1a)") == 1);
  CHECK(count_of(beta_said, "products without intervals") == 1);
  const nlohmann::json bj = json_of(dir.path / "beta" / "grind.json");
  CHECK_FALSE(bj["products"][0].contains("P80_um_95"));
  CHECK(bj["intervals"]["changed"].get<std::string>().find("[breakage]") != std::string::npos);
  // The ore written again as read (its numbers to 10 digits): the same hash.
  CHECK(mc::io::changed_tables(mc::io::read_ore(fitted), mc::io::ore_tables_hash(mc::io::read_ore(fitted))).empty());
  // Correlated beyond 0.99 (the covariance's off-diagonal made so): a note
  // on the console and in grind.json.
  std::string correlated = ore_text;
  const std::size_t cv = correlated.find("\ncovariance = [[");
  REQUIRE(cv != std::string::npos);
  const Ore fo = mc::io::read_ore(fitted);
  const auto& m = fo.fitted_under.covariance.matrix;
  REQUIRE(m.size() == 2);
  const double c = 0.995 * std::sqrt(m[0][0] * m[1][1]);
  correlated.replace(cv, correlated.find('\n', cv + 1) - cv,
                     fmt::format("\ncovariance = [[{:.10g}, {:.10g}], [{:.10g}, {:.10g}]]", m[0][0], c, c, m[1][1]));
  const std::string noted = grind(write("correlated.toml", correlated), "correlated", "", status);
  CHECK(status == 0);
  CHECK(count_of(noted, "log(efficiency) and log(sigma) are correlated at r = +0.9950") == 1);
  const nlohmann::json cj = json_of(dir.path / "correlated" / "grind.json");
  REQUIRE(cj["intervals"]["correlated"].size() == 1);
  CHECK(cj["intervals"]["correlated"][0]["r"].get<double>() == Approx(0.995));
  // E∞ held with a range to 1e5 J/kg, where the ore hardly breaks: the
  // throughput at the target has no lower end.
  const double e_inf = fo.fracture.e_inf_J_kg;
  const std::string values = fmt::format("[{:.10g}, {:.10g}]", fo.fitted_under.covariance.values[0],
                                         fo.fitted_under.covariance.values[1]);
  std::string without = ore_text;  // the tests' information is over the fit's variables: left out
  const std::size_t info = without.find("\ninformation = ");
  REQUIRE(info != std::string::npos);
  without.erase(info, without.find('\n', info + 1) - info);
  const std::string open = without + fmt::format("\n[[fitted.held]]\nname = \"e_inf_J_kg\"\nvalue = {:.10g}\nlo = "
                                                  "{:.10g}\nhi = 100000\nfree_at_lo = {}\nfree_at_hi = {}\n",
                                                  e_inf, e_inf, values, values);
  const std::string shown = grind(write("open.toml", open), "open", "--target-p80 300", status);
  INFO(shown);
  REQUIRE(status == 0);
  CHECK(shown.find("t/h [< ") != std::string::npos);
  const nlohmann::json oj = json_of(dir.path / "open" / "grind.json");
  REQUIRE(oj["throughput_at_target_t_h_95"].size() == 2);
  CHECK(oj["throughput_at_target_t_h_95"][0].is_null());
  CHECK(oj["throughput_at_target_t_h_95"][1].get<double>() > oj["throughput_at_target_t_h"].get<double>());
  CHECK(oj["throughput_at_target_t_h_95_open"] == "below");
  // Its range reaches the file's (1e5 J/kg): said once, no 95 % statement.
  CHECK(count_of(shown, "the data do not bound e_inf_J_kg (60 to 100000) within the ore file's range") == 1);
  REQUIRE(oj["intervals"].contains("open_held"));
  CHECK(oj["intervals"]["open_held"]["parameters"][0].get<std::string>().find("e_inf_J_kg") == 0);
  // E∞ held, the data best at 0.8 of it: with S where it is held above the
  // limit from there (the documented five-parameter fit's 20.61 against
  // 19.66), a note once on the console and in grind.json; below it, none.
  auto held_at = [&](double ssr_held) {
    std::string t = without;
    const std::size_t dof = t.find("\ndegrees_of_freedom = ");
    REQUIRE(dof != std::string::npos);
    t.insert(t.find('\n', dof + 1) + 1, fmt::format("ssr_held = {}\nssr_best = 18.37\nssr_limit = 19.66\n", ssr_held));
    return t + fmt::format("\n[[fitted.held]]\nname = \"e_inf_J_kg\"\nvalue = {:.10g}\nlo = {:.10g}\nhi = {:.10g}\n"
                           "\n[fitted.best]\nheld = [{:.10g}]\nfree = {}\n",
                           e_inf, 0.5 * e_inf, 1.5 * e_inf, 0.8 * e_inf, values);
  };
  const std::string out_said = grind(write("outside.toml", held_at(20.61)), "outside", "", status);
  INFO(out_said);
  REQUIRE(status == 0);
  CHECK(count_of(out_said, "lie outside the data's 95 % region: S 20.61 there against the limit 19.66") == 1);
  CHECK(count_of(out_said, fmt::format("e_inf_J_kg {:.6g}, S 18.37", 0.8 * e_inf)) == 1);
  const nlohmann::json xj = json_of(dir.path / "outside" / "grind.json");
  CHECK(xj["products"][0].contains("P80_um_95"));
  REQUIRE(xj["intervals"].contains("outside_data_region"));
  CHECK(xj["intervals"]["outside_data_region"].get<std::string>().find("e_inf_J_kg") != std::string::npos);
  const Ore back = mc::io::read_ore(dir.path / "outside.toml");
  CHECK(back.fitted_under.covariance.ssr_fit == 20.61);
  CHECK(back.fitted_under.covariance.ssr_limit == 19.66);
  const std::string in_said = grind(write("inside.toml", held_at(19.5)), "inside", "", status);
  REQUIRE(status == 0);
  CHECK(count_of(in_said, "outside the data's 95 % region") == 0);
  CHECK_FALSE(json_of(dir.path / "inside" / "grind.json")["intervals"].contains("outside_data_region"));
  CHECK(count_of(in_said, "the data do not bound") == 0);  // its range inside the file's
}

TEST_CASE("grind --fit: one test at 0.5 pp is four copies of it at 1 pp", "[grind][interval][held]") {
  // The weights' exact equivalence: 1/noise² counts a test at half the
  // noise as four. η and σ come out the same, and so does the information
  // JᵀWJ / noise². S and s² are in pp² of the first test's noise: S of the
  // four copies, in (1 pp)², is 4 S of the one, in (0.5 pp)²; s² = S / ν
  // counts readings (ν = 4n − 2 against n − 2), so the covariance
  // s² (JᵀWJ)⁻¹ times ν is what agrees, not the covariance itself.
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  TestInMill one{synthetic_test(truth, 0.5, 61), synthetic_spectrum(), kPower_W, kHoldup_kg};
  one.test.noise_pp = 0.5;
  TestInMill copy = one;
  copy.test.noise_pp = 1.0;
  const std::vector<std::string> names = {"efficiency", "sigma"};
  const BatchFit a = fit_batch_tests(start, {one}, names), b = fit_batch_tests(start, {copy, copy, copy, copy}, names);
  std::printf("one test at 0.5 pp against four at 1 pp: eta %.12g / %.12g, sigma %.12g / %.12g, S %.10g / %.10g, "
              "dof %d / %d, var(log eta) x dof %.10g / %.10g\n",
              a.ore.efficiency, b.ore.efficiency, a.ore.fracture.sigma, b.ore.fracture.sigma, a.ssr, b.ssr, a.dof,
              b.dof, a.covariance[0][0] * a.dof, b.covariance[0][0] * b.dof);
  REQUIRE(a.covariance.size() == 2);
  REQUIRE(b.covariance.size() == 2);
  // The two are the same minimum, but each fit stops on its own: when the
  // residuals are within a cosine of 1e-8 of orthogonal to the Jacobian
  // (fit.cpp), so the parameters agree to about 1e-8, not 1e-9 (measured:
  // 3e-9 and 4e-9); S, stationary there, to 1e-9; the covariance, a
  // numerical Jacobian at points 1e-8 apart, to about 1e-8 (measured 8e-9).
  CHECK(b.dof == 4 * (a.dof + 2) - 2);
  CHECK(b.ore.efficiency == Approx(a.ore.efficiency).epsilon(1e-8));
  CHECK(b.ore.fracture.sigma == Approx(a.ore.fracture.sigma).epsilon(1e-8));
  CHECK(b.ssr == Approx(4 * a.ssr).epsilon(1e-9));
  for (std::size_t i = 0; i < 2; ++i)
    for (std::size_t j = 0; j < 2; ++j)
      CHECK(b.covariance[i][j] * b.dof == Approx(a.covariance[i][j] * a.dof).epsilon(1e-7));
}

TEST_CASE("grind intervals: held parameters on a ridge: each profile runs along it, past the conditional range",
          "[grind][interval][held]") {
  // η and E∞ both held, σ free: the two trade against each other (a
  // ridge), so each one's range with the other kept at its best (the
  // conditional range) is short; its profile, the other refitted, runs
  // along the ridge. Every point the search kept lies within the profiles'
  // ranges, and the corner points on the limit: an eighth further is past.
  const Ore truth = known_ore();
  Ore start = truth;
  start.fracture.sigma = 1.0;
  const std::vector<TestInMill> tests = {{synthetic_test(truth, 1.0, 43), synthetic_spectrum(), kPower_W, kHoldup_kg}};
  const std::vector<std::string> free = {"sigma"};
  BatchFit f = fit_batch_tests(start, tests, free);
  for (const char* name : {"efficiency", "e_inf_J_kg"}) {
    FittedParameter h;
    h.name = name;
    h.start = h.value = find_ore_parameter(name)->get(start);
    h.identified = false;
    h.why = "held for the test";
    f.parameters.push_back(h);
  }
  const FitCovariance u = fit_covariance(f, tests);
  REQUIRE(u.held.size() == 2);
  Ore at_best = with_variables(start, u, u.best.free);
  for (std::size_t k = 0; k < 2; ++k) find_ore_parameter(u.held[k].name)->set(at_best, u.best.held[k]);
  const double limit = profile_limit(weighted_ssr(at_best, tests), interval_dof(u));
  int corners = 0, beyond = 0, past_conditional = 0;
  for (const HeldEdge& c : u.edges) {
    Ore o = with_variables(start, u, c.free);
    for (std::size_t k = 0; k < 2; ++k) find_ore_parameter(u.held[k].name)->set(o, c.held[k]);
    CHECK(weighted_ssr(o, tests) <= limit * (1 + 1e-6));
    // Within the ranges, to the accuracy of their ends (a tenth of their
    // distance from the best point, in the logarithm).
    for (std::size_t k = 0; k < 2; ++k) {
      const double lo = std::log(u.held[k].lo), hi = std::log(u.held[k].hi), x = std::log(c.held[k]);
      const double b = std::log(u.best.held[k]);
      beyond += x < lo - 0.1 * (b - lo) - 1e-9 || x > hi + 0.1 * (hi - b) + 1e-9;
    }
    if (c.of >= 0) {
      // A profile's end: the conditional refit there (the other at its best) is past the limit.
      const OreParameter& p = *find_ore_parameter(u.held[static_cast<std::size_t>(c.of)].name);
      Ore conditional = at_best;
      p.set(conditional, c.held[static_cast<std::size_t>(c.of)]);
      past_conditional += refit_ssr(conditional, tests, free) > limit;
      continue;
    }
    bool in_file = true;
    Ore further = at_best;
    for (std::size_t k = 0; k < 2; ++k) {
      const OreParameter& p = *find_ore_parameter(u.held[k].name);  // both scales: their logarithms
      const double v = u.best.held[k] * std::pow(c.held[k] / u.best.held[k], 1.125);
      in_file = in_file && v >= p.lo && v <= p.hi;
      if (in_file) p.set(further, v);
    }
    ++corners;
    if (!in_file) continue;
    const double s_further = refit_ssr(further, tests, free);
    INFO("corner " << c.held[0] << ", " << c.held[1] << ": an eighth further S " << s_further << ", limit " << limit);
    CHECK(s_further > limit * (1 - 1e-6));
  }
  std::printf("held on a ridge: eta [%.4g, %.4g], E_inf [%.4g, %.4g] (profiles); %d corner points, %d ends past "
              "the conditional range, %d coordinates beyond the ranges\n",
              u.held[0].lo, u.held[0].hi, u.held[1].lo, u.held[1].hi, corners, past_conditional, beyond);
  CHECK(corners >= 2);
  CHECK(past_conditional >= 2);  // the profiles reach past the conditional ranges
  CHECK(beyond == 0);            // and hold every point of the region the search found
}

TEST_CASE("grind intervals: the held parameters' reach against a brute-force grid over them",
          "[grind][interval][held]") {
  // η and E∞ held on a ridge, σ free (the case above). A grid over the
  // logarithms of the two, σ refitted at each point: the extreme of each
  // product over the points within the limit, against the reach
  // sensitivities() takes from the kept points (the profiles' ends and the
  // corner points). The region is a thin ridge, so the grid is a band
  // along it: 41 columns across η's range (a tenth wider), in each 21
  // points of E∞ about the ridge (through η's profile: its ends and the
  // best point), a band wide enough that its edge rows lie past the limit
  // (doubled until they do). And the reach of the profiles' ends alone
  // (down_by_held, up_by_held): without the corner search, the P80 after
  // 20 min falls short of the grid's.
  const auto t0 = std::chrono::steady_clock::now();
  const Ore truth = known_ore();
  Ore start = truth;
  start.fracture.sigma = 1.0;
  const std::vector<TestInMill> tests = {{synthetic_test(truth, 1.0, 43), synthetic_spectrum(), kPower_W, kHoldup_kg}};
  const std::vector<std::string> free = {"sigma"};
  BatchFit f = fit_batch_tests(start, tests, free);
  for (const char* name : {"efficiency", "e_inf_J_kg"}) {
    FittedParameter h;
    h.name = name;
    h.start = h.value = find_ore_parameter(name)->get(start);
    h.identified = false;
    h.why = "held for the test";
    f.parameters.push_back(h);
  }
  const FitCovariance u = fit_covariance(f, tests);
  REQUIRE(u.held.size() == 2);
  Ore at_best = with_variables(start, u, u.best.free);
  for (std::size_t k = 0; k < 2; ++k) find_ore_parameter(u.held[k].name)->set(at_best, u.best.held[k]);
  const double limit = profile_limit(weighted_ssr(at_best, tests), interval_dof(u));
  // Products: a third mill's P80, the first mill's after 20 min, E∞ / η² (a number across the ridge).
  auto products = [](const Ore& o) {
    return std::vector<double>{p80_third_mill(o)[0], p80_at_20_min(o)[0],
                               o.fracture.e_inf_J_kg / (o.efficiency * o.efficiency)};
  };
  const std::vector<Sensitivity> ss = sensitivities(f.ore, u, products);
  const std::size_t np = ss.size();
  const OreParameter &pe = *find_ore_parameter("efficiency"), &pE = *find_ore_parameter("e_inf_J_kg");
  // The ridge through η's profile: log E∞ against log η, piecewise linear
  // through its two ends and the best point.
  std::vector<std::pair<double, double>> ridge = {{std::log(u.best.held[0]), std::log(u.best.held[1])}};
  for (const HeldEdge& e : u.edges)
    if (e.of == 0) ridge.push_back({std::log(e.held[0]), std::log(e.held[1])});
  REQUIRE(ridge.size() == 3);
  std::sort(ridge.begin(), ridge.end());
  auto ridge_at = [&](double x) {
    const std::size_t k = x < ridge[1].first ? 0 : 1;
    const double dx = ridge[k + 1].first - ridge[k].first;
    return dx > 0 ? ridge[k].second + (x - ridge[k].first) / dx * (ridge[k + 1].second - ridge[k].second)
                  : ridge[k].second;
  };
  const double a = std::log(u.held[0].lo), b = std::log(u.held[0].hi);
  const double x_lo = std::max(a - 0.1 * (b - a), std::log(pe.lo)), x_hi = std::min(b + 0.1 * (b - a), std::log(pe.hi));
  const int nx = 41, ny = 21;
  std::vector<double> grid_up(np, 0), grid_down(np, 0);
  int inside = 0, fits = 0;
  double band = 0.05;  // half-width in log E∞
  for (int tries = 0; tries < 4; ++tries, band *= 2) {
    std::fill(grid_up.begin(), grid_up.end(), 0.0);
    std::fill(grid_down.begin(), grid_down.end(), 0.0);
    inside = 0;
    bool edge_inside = false;
    for (int i = 0; i < nx; ++i) {
      const double x = x_lo + (x_hi - x_lo) * i / (nx - 1);
      for (int j = 0; j < ny; ++j) {
        const double y = ridge_at(x) + band * (2.0 * j / (ny - 1) - 1);
        if (y < std::log(pE.lo) || y > std::log(pE.hi)) continue;
        Ore o = at_best;
        pe.set(o, std::exp(x));
        pE.set(o, std::exp(y));
        BatchFit g;
        ++fits;
        try {
          g = fit_batch_tests(o, tests, free, 300, false);
        } catch (const std::exception&) {
          continue;
        }
        if (g.ssr > limit) continue;
        ++inside;
        edge_inside = edge_inside || j == 0 || j == ny - 1;
        const std::vector<double> v = products(g.ore);
        for (std::size_t m = 0; m < np; ++m) {
          grid_up[m] = std::max(grid_up[m], std::log(v[m]) - ss[m].center);
          grid_down[m] = std::min(grid_down[m], std::log(v[m]) - ss[m].center);
        }
      }
    }
    if (!edge_inside) break;
  }
  // The held point counts as a point of the reach (the products are made there).
  for (std::size_t m = 0; m < np; ++m) {
    const double at_held = std::log(ss[m].value) - ss[m].center;
    grid_up[m] = std::max(grid_up[m], at_held);
    grid_down[m] = std::min(grid_down[m], at_held);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("held reach against a grid of %d x %d along the ridge (band +-%.2f in log E_inf; %d points within the "
              "limit, %d fits), in logarithms below / above the centre; %.1f s\n",
              nx, ny, band, inside, fits, seconds);
  int ends_short = 0;
  for (std::size_t m = 0; m < np; ++m) {
    REQUIRE(ss[m].ok);
    REQUIRE(ss[m].log);
    double ends_down = 0, ends_up = 0;
    for (std::size_t k = 0; k < 2; ++k) {
      ends_down = std::min(ends_down, ss[m].down_by_held[k]);
      ends_up = std::max(ends_up, ss[m].up_by_held[k]);
    }
    std::printf("  product %zu: search %.4f / %.4f, grid %.4f / %.4f, profiles' ends alone %.4f / %.4f\n", m,
                ss[m].down, ss[m].up, grid_down[m], grid_up[m], ends_down, ends_up);
    // Within 12 % of the grid's reach (and 0.001, a tenth of a per cent
    // of the product, for a reach near 0). Measured with the profiles'
    // ends to 2 % (2026-12-07): short by 0.8 to 12.7 % of the grid's
    // reach, none past; beyond the 0.001 the most any side needs is 9.2 %
    // (the P80 after 20 min, below), so 12 % leaves
    // about 3 points. What remains is the rays' directions (a linear
    // number's extreme to cos 22.5°) and the grid's own spacing (its
    // columns 0.04 apart in log η, which moves E∞ / η² by 0.08).
    auto close = [](double reach, double grid) { return std::fabs(reach - grid) <= 0.12 * std::fabs(grid) + 1e-3; };
    INFO("product " << m);
    CHECK(close(ss[m].down, grid_down[m]));
    CHECK(close(ss[m].up, grid_up[m]));
    ends_short += !close(ends_down, grid_down[m]);
    ends_short += !close(ends_up, grid_up[m]);
  }
  // Without the rays beyond the profiles' ends the reach misses the grid's
  // on three sides of the six (measured: the third mill's P80 below, 84 %
  // short; the P80 after 20 min 46 and 55 % short on both sides).
  CHECK(ends_short >= 3);
}
