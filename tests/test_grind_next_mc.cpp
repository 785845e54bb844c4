// Which batch test to run next, by refits (src/grind/next_refit.h): the
// refitted expected width against widths realised by simulating candidate
// tests at drawn truths and fitting them here, where the linear prediction
// is off (a curved valley) and where it is not; reproducible with its
// seed; the options refused.
#include <catch2/catch.hpp>

#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "grind/fit.h"
#include "grind/interval.h"
#include "grind/next_refit.h"
#include "grind/next_test.h"
#include "grind_synthetic.h"

using namespace mc::grind;
using namespace mc::test;

namespace {

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / v.size();
}
// The standard error of a median, from the interquartile range (that of
// a normal bulk: 1.2533 σ / √n, σ = IQR / 1.349): a few draws far out,
// which the widths have (a truth where the candidate leaves a parameter
// held), move it no more than any other draw above it.
double median_error(const std::vector<double>& v) {
  return 1.2533 * (quantile(v, 0.75) - quantile(v, 0.25)) / 1.349 / std::sqrt(static_cast<double>(v.size()));
}

double number(const Ore& o) { return p80_third_mill(o)[0]; }

// Truths drawn from what the real tests leave open without
// plausible_truths, by the test's own generator: the held parameters'
// logarithms uniform over a box 1.6 times their edge points' span (within
// the ore file's ranges), each kept with probability exp(-(S - S_best) /
// 2s²), S with the free ones refitted there (the normal posterior of the
// held ones, flat in their logarithms, uncut); the free ones then moved by
// their covariance given the held ones. `missed`: proposals in the box's
// outer 5 % kept with probability over 0.05 (the box too small).
std::vector<Ore> posterior_truths(const Ore& fitted, const RealTests& real, int n, std::uint64_t seed, int& missed) {
  const FitCovariance& u = fitted.fitted_under.covariance;
  const std::size_t nh = u.held.size(), np = u.names.size();
  const Ore best = best_point(fitted, u);
  const double s2 = interval_variance(u), s_best = weighted_ssr(best, real.tests);
  std::vector<const OreParameter*> held;
  std::vector<double> lo(nh, 1e300), hi(nh, -1e300);
  for (std::size_t j = 0; j < nh; ++j) {
    held.push_back(find_ore_parameter(u.held[j].name));
    REQUIRE(held[j]->log);  // a scale: its logarithm
    for (const HeldEdge& e : u.edges) {
      lo[j] = std::min(lo[j], std::log(e.held[j]));
      hi[j] = std::max(hi[j], std::log(e.held[j]));
    }
    const double c = (lo[j] + hi[j]) / 2, h = 0.8 * (hi[j] - lo[j]);
    lo[j] = std::max(c - h, std::log(held[j]->lo)), hi[j] = std::min(c + h, std::log(held[j]->hi));
  }
  const std::vector<std::vector<double>> C = interval_covariance(u);
  std::vector<std::vector<double>> L(np, std::vector<double>(np, 0.0));  // Cholesky
  for (std::size_t j = 0; j < np; ++j)
    for (std::size_t i = j; i < np; ++i) {
      double v = C[i][j];
      for (std::size_t k = 0; k < j; ++k) v -= L[i][k] * L[j][k];
      L[i][j] = i == j ? std::sqrt(v) : v / L[j][j];
    }
  Scatter g(seed);
  auto uniform = [&] { return std::max(0.5 * (g.next() + 1), 1e-12); };
  std::vector<Ore> out;
  missed = 0;
  for (int tries = 0; static_cast<int>(out.size()) < n && tries < 100 * n; ++tries) {
    Ore o = best;
    bool outer = false;
    for (std::size_t j = 0; j < nh; ++j) {
      const double f = uniform();
      outer = outer || f < 0.05 || f > 0.95;
      held[j]->set(o, std::exp(lo[j] + f * (hi[j] - lo[j])));
    }
    const BatchFit f = fit_batch_tests(o, real.tests, u.names, 300, false);
    const double keep = std::exp(-(weighted_ssr(f.ore, real.tests) - s_best) / (2 * s2));
    missed += outer && keep > 0.05;
    if (!(uniform() < keep)) continue;
    std::vector<double> x, z;
    for (const std::string& name : u.names) {
      const OreParameter& p = *find_ore_parameter(name);
      x.push_back(p.log ? std::log(p.get(f.ore)) : p.get(f.ore));
      const double a = uniform(), b = uniform();  // Box–Muller
      z.push_back(std::sqrt(-2 * std::log(a)) * std::cos(2 * M_PI * b));
    }
    for (std::size_t i = 0; i < np; ++i)
      for (std::size_t j = 0; j <= i; ++j) x[i] += L[i][j] * z[j];
    out.push_back(with_variables(f.ore, u, x));
  }
  return out;
}

// The realised widths: at each truth, the candidate made by the suite's
// own synthetic test (uniform scatter of the same variance, s² = h²/3, its
// own seeds), fitted with the real tests from the fitted ore as --fit
// fits them, its interval as grind takes it.
std::vector<double> realised(const Ore& fitted, const RealTests& real, const std::vector<Ore>& truths,
                             const std::vector<SpectrumBin>& spectrum, const std::vector<double>& times) {
  const double half_pp = std::sqrt(3 * interval_variance(fitted.fitted_under.covariance));
  std::vector<double> widths;
  for (std::size_t k = 0; k < truths.size(); ++k) {
    TestInMill next{synthetic_test(truths[k], half_pp, 700 + k, spectrum, times), spectrum, kPower_W, kHoldup_kg};
    next.test.noise_pp = real.tests.front().test.noise_pp;
    std::vector<TestInMill> all = real.tests;
    all.push_back(next);
    const BatchFit f = fit_batch_tests(fitted, all, real.names);
    const Interval i = propagate(f.ore, fit_covariance(f, all), p80_third_mill)[0];
    REQUIRE(i.valid());
    widths.push_back(i.hi - i.lo);
  }
  return widths;
}

// One test in the first mill, fitted for `free`; `held` appended as held
// where the start has them (unidentified), their profiles and rays made.
Ore fitted_ore(const Ore& start, const RealTests& real, const std::vector<std::string>& free,
               const std::vector<std::string>& held) {
  BatchFit f = fit_batch_tests(start, real.tests, free);
  for (const std::string& name : held) {
    FittedParameter h;
    h.name = name;
    h.start = h.value = find_ore_parameter(name)->get(start);
    h.identified = false;
    h.why = "held for the test";
    f.parameters.push_back(h);
  }
  Ore o = f.ore;
  o.fitted_under.covariance = fit_covariance(f, real.tests);
  return o;
}

}  // namespace

TEST_CASE("grind next test by refits: a curved valley, where the linear width is off", "[grind][next]") {
  // E∞ and d₀ held wrong (40 J/kg, 2.8 mm; the truth 60 and 2), η and σ
  // fitted to a test in the first mill: the data fit best far from where
  // they are held, along a curved valley. The candidate: the harder mill,
  // 2 to 32 min, which fixes both. 24 truths drawn from the posterior
  // without plausible_truths (posterior_truths: another sampler, the
  // test's own generator), the candidate made at each and fitted here.
  // Tolerance: three standard errors of the difference of the two means
  // (over 12 and 24 draws), and no wider than a third of the
  // realised: the refitted width must fall within it, the linear must not.
  const auto t0 = std::chrono::steady_clock::now();
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  start.fracture.e_inf_J_kg = 40;
  start.fracture.d0_m = 2.8e-3;
  const RealTests real{{{synthetic_test(truth, 1.0, 41), synthetic_spectrum(), kPower_W, kHoldup_kg}},
                       {"efficiency", "sigma", "e_inf_J_kg", "d0_mm"}};
  const Ore fitted = fitted_ore(start, real, {"efficiency", "sigma"}, {"e_inf_J_kg", "d0_mm"});
  const FitCovariance& u = fitted.fitted_under.covariance;
  REQUIRE(u.held.size() == 2);
  const TestInMill candidate{candidate_test(fitted, {2, 4, 8, 16, 32}), harder_spectrum(), kPower_W, kHoldup_kg};
  const Sensitivity s = sensitivities(fitted, u, p80_third_mill, true).front();
  const double linear = expected_after(fitted, u, s, candidate).width;
  const int n = 12;
  const RefitWidth refit = refitted_width(fitted, real, plausible_truths(fitted, real, n, 1), candidate, number,
                                          std::sqrt(interval_variance(u)), 1);
  REQUIRE(refit.converged == n);
  int missed = 0;
  const std::vector<Ore> truths = posterior_truths(fitted, real, 2 * n, 2, missed);
  REQUIRE(truths.size() == static_cast<std::size_t>(2 * n));
  CHECK(missed == 0);
  const std::vector<double> real_widths = realised(fitted, real, truths, harder_spectrum(), {2, 4, 8, 16, 32});
  const double real_mean = mean(real_widths), real_median = quantile(real_widths, 0.5);
  const std::size_t widest = std::max_element(real_widths.begin(), real_widths.end()) - real_widths.begin();
  const double tolerance = 3 * std::hypot(median_error(refit.widths), median_error(real_widths));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("next test by refits, curved valley: linear %.2f, refitted median %.2f (mean %.2f) [%.2f, %.2f], "
              "realised median %.2f (mean %.2f, widest %.1f at E_inf %.1f J/kg, d0 %.2f mm, sigma %.2f) um "
              "(tolerance %.2f); %.1f s\n",
              linear, quantile(refit.widths, 0.5), refit.mean, refit.p10, refit.p90, real_median, real_mean,
              real_widths[widest], truths[widest].fracture.e_inf_J_kg, truths[widest].fracture.d0_m * 1e3,
              truths[widest].fracture.sigma, tolerance, seconds);
  CHECK(tolerance < real_median / 3);
  CHECK(std::fabs(quantile(refit.widths, 0.5) - real_median) < tolerance);
  CHECK(std::fabs(linear - real_median) > tolerance);  // the linear prediction fails the same check
}

TEST_CASE("grind next test by refits: nearly linear, the refitted and the linear width agree", "[grind][next]") {
  // η and σ fitted to one test, nothing held: the products are nearly
  // linear in them over their region, and the refitted width agrees with
  // the linear one within 10 % for a long test in the harder mill and a
  // short one in the first (the rest: the refits' own scatter, 12 draws,
  // and t's and s²'s spread, which the linear width takes as known).
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const RealTests real{{{synthetic_test(truth, 1.0, 51), synthetic_spectrum(), kPower_W, kHoldup_kg}},
                       {"efficiency", "sigma"}};
  const Ore fitted = fitted_ore(start, real, {"efficiency", "sigma"}, {});
  const FitCovariance& u = fitted.fitted_under.covariance;
  REQUIRE(u.held.empty());
  const Sensitivity s = sensitivities(fitted, u, p80_third_mill, true).front();
  const std::vector<PlausibleTruth> truths = plausible_truths(fitted, real, 12, 3);
  for (const auto& [spectrum, times] :
       {std::make_pair(harder_spectrum(), std::vector<double>{2, 4, 8, 16, 32}),
        std::make_pair(synthetic_spectrum(), std::vector<double>{0.5, 1, 2, 4, 8})}) {
    const TestInMill candidate{candidate_test(fitted, times), spectrum, kPower_W, kHoldup_kg};
    const double linear = expected_after(fitted, u, s, candidate).width;
    const RefitWidth refit = refitted_width(fitted, real, truths, candidate, number, std::sqrt(interval_variance(u)), 3);
    std::printf("next test by refits, nearly linear (%g to %g min): linear %.3f, refitted %.3f [%.3f, %.3f] um, "
                "%d/%d\n",
                times.front(), times.back(), linear, refit.mean, refit.p10, refit.p90, refit.converged, refit.draws);
    CHECK(refit.converged == 12);
    CHECK(refit.mean == Approx(linear).epsilon(0.10));
  }
}

TEST_CASE("grind next test by refits: the same seed, the same widths", "[grind][next]") {
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const RealTests real{{{synthetic_test(truth, 1.0, 51), synthetic_spectrum(), kPower_W, kHoldup_kg}},
                       {"efficiency", "sigma"}};
  const Ore fitted = fitted_ore(start, real, {"efficiency", "sigma"}, {});
  const double scatter = std::sqrt(interval_variance(fitted.fitted_under.covariance));
  const TestInMill candidate{candidate_test(fitted, {0.5, 1, 2, 4, 8}), synthetic_spectrum(), kPower_W, kHoldup_kg};
  auto widths = [&](std::uint64_t seed) {
    return refitted_width(fitted, real, plausible_truths(fitted, real, 4, seed), candidate, number, scatter, seed).widths;
  };
  const std::vector<double> a = widths(5), b = widths(5), c = widths(6);
  REQUIRE(a.size() == 4);
  CHECK(a == b);  // bit for bit
  CHECK(a != c);
  // Refitted beside another candidate (their draws shared out over the
  // threads together), the same widths: each draw has its own seed.
  const TestInMill other{candidate_test(fitted, {2, 4, 8, 16, 32}), harder_spectrum(), kPower_W, kHoldup_kg};
  const std::vector<RefitWidth> both =
      refitted_widths(fitted, real, plausible_truths(fitted, real, 4, 5), {other, candidate}, number, scatter, 5);
  REQUIRE(both.size() == 2);
  CHECK(both[1].widths == a);
  CHECK(both[0].widths != a);
  // On one thread and on five (more than the draws' half), the same widths.
  for (unsigned threads : {1u, 5u}) {
    const std::vector<RefitWidth> on = refitted_widths(fitted, real, plausible_truths(fitted, real, 4, 5),
                                                       {other, candidate}, number, scatter, 5, threads);
    CHECK(on[0].widths == both[0].widths);
    CHECK(on[1].widths == both[1].widths);
  }
  // The normal deviates: mean 0, variance 1 (20000 draws: 4 standard errors).
  SeededNormal g(9);
  double s1 = 0, s2 = 0;
  for (int k = 0; k < 20000; ++k) {
    const double z = g.next();
    s1 += z, s2 += z * z;
  }
  CHECK(std::fabs(s1 / 20000) < 4 / std::sqrt(20000.0));
  CHECK(std::fabs(s2 / 20000 - 1) < 4 * std::sqrt(2 / 20000.0));
}

TEST_CASE("grind --next-draws, --next-seed, --next-refit: bad values refused, the option named", "[grind][next][failures]") {
  // Refused before any file is read: exit 2, one message naming the option.
  auto run = [](const std::string& args, int& status) {
    FILE* p = popen((std::string(MC_BINARY) + " grind no-run --ore no-ore.toml --next-test no-run " + args + " 2>&1")
                        .c_str(),
                    "r");
    std::string out;
    char buf[512];
    while (p && fgets(buf, sizeof buf, p)) out += buf;
    const int rc = p ? pclose(p) : -1;
    status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
    return out;
  };
  for (const char* bad : {"--next-draws 0", "--next-draws -3", "--next-draws 2.5", "--next-draws many",
                          "--next-seed -1", "--next-refit x", "--next-seed 99999999999",
                          "--next-draws 99999999999999999999"}) {
    int status = 0;
    const std::string said = run(bad, status);
    INFO(bad << ": " << said);
    CHECK(status == 2);
    const std::string option = std::string(bad).substr(0, std::string(bad).find(' '));
    CHECK(said.find(option + " ") != std::string::npos);
    CHECK(said.find("expected a whole number") != std::string::npos);
    CHECK((said.find("at most 1000000000") != std::string::npos) == (std::string(bad).size() > 20));
  }
  int status = 0;
  FILE* p = popen((std::string(MC_BINARY) + " grind no-run --ore no-ore.toml --next-draws 4 2>&1").c_str(), "r");
  std::string said;
  char buf[512];
  while (p && fgets(buf, sizeof buf, p)) said += buf;
  status = WEXITSTATUS(pclose(p));
  CHECK(status == 2);
  CHECK(said.find("--next-draws: the refits of a next test; give --next-test RUN") != std::string::npos);
}
