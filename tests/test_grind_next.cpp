// Which batch test to run next (src/grind/next_test.h, `grind --next-test`):
// the expected width of a product's interval after a candidate test,
// against the widths that fits of simulated candidate tests give, and
// with held parameters against the definitions computed by hand; the
// ranking through the command (two different mills), its files, and bad
// candidates refused.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/grind.h"
#include "app/grind_next.h"
#include "bond_run.h"
#include "grind/bond.h"
#include "grind/circuit.h"
#include "grind/fit.h"
#include "grind/interval.h"
#include "grind/next_test.h"
#include "grind_synthetic.h"
#include "small_matrix.h"
#include "io/batch_test_file.h"
#include "io/ore_file.h"
#include "io/run_folder.h"

using namespace mc::grind;
using namespace mc::test;
namespace fs = std::filesystem;

namespace {

struct Candidate {
  std::string name;
  std::vector<SpectrumBin> spectrum;
  std::vector<double> times;
};

fs::path temp(const std::string& name) {
  return fs::temp_directory_path() / ("millcharge_test_next_" + std::to_string(::getpid()) + "_" + name);
}

std::string run_binary(const std::string& args, int& status) {
  FILE* p = popen((std::string(MC_BINARY) + " " + args + " 2>&1").c_str(), "r");
  std::string out;
  char buf[512];
  while (p && fgets(buf, sizeof buf, p)) out += buf;
  const int rc = p ? pclose(p) : -1;
  status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  return out;
}

}  // namespace

TEST_CASE("grind next test: the expected width against refits of simulated tests", "[grind][next]") {
  // One test in the first mill, η and σ fitted; the candidates: that mill
  // or the harder one, short or long times. The product: a third mill's
  // P80. The recommended and the worst candidate are simulated from the
  // truth with seeded ±1 pp scatter and fitted with the first test: the
  // mean width of their intervals against the predicted.
  const auto t0 = std::chrono::steady_clock::now();
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const std::vector<std::string> names = {"efficiency", "sigma"};
  const TestInMill first{synthetic_test(truth, 1.0, 51), synthetic_spectrum(), kPower_W, kHoldup_kg};
  const BatchFit f = fit_batch_tests(start, {first}, names);
  const FitCovariance u = fit_covariance(f, {first});
  REQUIRE(u.held.empty());
  const Sensitivity s = sensitivities(f.ore, u, p80_third_mill, true).front();
  const Interval now = propagate(f.ore, u, p80_third_mill)[0];
  const std::vector<Candidate> candidates = {{"first mill, 0.5 to 8 min", synthetic_spectrum(), {0.5, 1, 2, 4, 8}},
                                             {"first mill, 2 to 32 min", synthetic_spectrum(), {2, 4, 8, 16, 32}},
                                             {"harder mill, 0.5 to 8 min", harder_spectrum(), {0.5, 1, 2, 4, 8}},
                                             {"harder mill, 2 to 32 min", harder_spectrum(), {2, 4, 8, 16, 32}}};
  std::vector<double> predicted;
  for (const Candidate& c : candidates) {
    const NextTestWidth w = expected_after(
        f.ore, u, s, {candidate_test(f.ore, c.times), c.spectrum, kPower_W, kHoldup_kg});
    REQUIRE(w.expected.valid());
    predicted.push_back(w.width);
  }
  const std::size_t best = std::min_element(predicted.begin(), predicted.end()) - predicted.begin();
  const std::size_t worst = std::max_element(predicted.begin(), predicted.end()) - predicted.begin();
  REQUIRE(best != worst);
  // The realised widths: the candidate made from the truth, fitted with
  // the first test, seed after seed.
  auto realised = [&](const Candidate& c) {
    const int n = 20;
    double sum = 0;
    for (int seed = 0; seed < n; ++seed) {
      const TestInMill next{synthetic_test(truth, 1.0, 900 + seed, c.spectrum, c.times), c.spectrum, kPower_W,
                            kHoldup_kg};
      const BatchFit fj = fit_batch_tests(start, {first, next}, names);
      const Interval i = propagate(fj.ore, fit_covariance(fj, {first, next}), p80_third_mill)[0];
      REQUIRE(i.valid());
      sum += (i.hi - i.lo) / n;
    }
    return sum;
  };
  const double real_best = realised(candidates[best]), real_worst = realised(candidates[worst]);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("next test: third mill's P80 interval now %.1f um wide; predicted after each candidate:", now.hi - now.lo);
  for (std::size_t k = 0; k < candidates.size(); ++k)
    std::printf(" %s %.1f%s", candidates[k].name.c_str(), predicted[k], k + 1 < candidates.size() ? "," : "\n");
  std::printf("next test: recommended (%s) predicted %.1f, realised %.1f (mean of 20 refits); worst (%s) predicted "
              "%.1f, realised %.1f; %.1f s\n",
              candidates[best].name.c_str(), predicted[best], real_best, candidates[worst].name.c_str(),
              predicted[worst], real_worst, seconds);
  CHECK(predicted[best] < now.hi - now.lo);  // one more test narrows it
  CHECK(real_best == Approx(predicted[best]).epsilon(0.25));
  CHECK(real_worst == Approx(predicted[worst]).epsilon(0.25));
  CHECK(real_best < real_worst);
}

TEST_CASE("grind next test: the same test again divides the standard deviation by the square root of 2",
          "[grind][next]") {
  // The information now is exactly the candidate's own (J_cᵀ J_c / s²):
  // the same test run again doubles it, so the product's log standard
  // deviation after over now is 1/√2, exactly for the linear model.
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const TestInMill first{synthetic_test(truth, 1.0, 51), synthetic_spectrum(), kPower_W, kHoldup_kg};
  const BatchFit f = fit_batch_tests(start, {first}, {"efficiency", "sigma"});
  FitCovariance u = fit_covariance(f, {first});
  REQUIRE(u.held.empty());
  const Sensitivity s = sensitivities(f.ore, u, p80_third_mill, true).front();
  REQUIRE(s.log);
  const TestInMill again{candidate_test(f.ore, {1, 2, 4, 8}), synthetic_spectrum(), kPower_W, kHoldup_kg};
  // The fit's own information against the candidate's: the two estimates of the test.
  const NextTestWidth real = expected_after(f.ore, u, s, again);
  REQUIRE(real.added.size() == 2);
  u.information = real.added;
  const NextTestWidth twice = expected_after(f.ore, u, s, again);
  const auto& I = real.added;
  const double det = I[0][0] * I[1][1] - I[0][1] * I[1][0];
  const double var_now = (s.g[0] * s.g[0] * I[1][1] - 2 * s.g[0] * s.g[1] * I[0][1] + s.g[1] * s.g[1] * I[0][0]) / det;
  const double ratio = twice.sd / std::sqrt(var_now);
  double var_fit = 0;
  for (std::size_t a = 0; a < 2; ++a)
    for (std::size_t b = 0; b < 2; ++b) var_fit += s.g[a] * u.matrix[a][b] * s.g[b];
  std::printf("next test, the same test again: log sd after/now %.9f (1/sqrt 2 = %.9f); the fit's covariance gives "
              "sd %.6g now, the candidate's information %.6g; after the candidate on the fit's information %.6g\n",
              ratio, 1 / std::sqrt(2.0), std::sqrt(var_fit), std::sqrt(var_now), real.sd);
  CHECK(ratio == Approx(1 / std::sqrt(2.0)).epsilon(1e-6));
}

namespace {

double quad(const std::vector<double>& g, const std::vector<std::vector<double>>& m) {
  double v = 0;
  for (std::size_t a = 0; a < g.size(); ++a)
    for (std::size_t b = 0; b < g.size(); ++b) v += g[a] * m[a][b] * g[b];
  return v;
}

// The expected interval after a candidate, computed here from the
// definitions (docs/grinding-next-test.md, "How the refits work"), not through
// expected_after: the candidate's readings (pp) at its informative sieves
// differenced by hand (central steps of 10⁻³ in each variable, every
// variable a logarithm here), its information J_cᵀJ_c / s² with
// s² = S_min / (dof − held), the fit's information rescaled to that s²,
// the sum inverted by Gauss–Jordan; the free part t √(gᵀ L_ff⁻¹ g), the
// held reach each side the lesser of the reach now and
// t √(cᵀ L⁻¹ c − gᵀ L_ff⁻¹ g); around the centre now.
struct ByHand {
  double lo = 0, hi = 0, linear = 0, linear_now = 0, ratio = 0;
  int data = 0;
};
ByHand expected_by_hand(const Ore& ore, const FitCovariance& u, const Sensitivity& s, TestInMill c) {
  std::vector<std::string> vars = u.names;
  for (const HeldParameter& h : u.held) vars.push_back(h.name);
  const std::size_t nv = vars.size(), np = u.names.size(), nh = u.held.size();
  c.test.passing = batch_test_products(ore, c.spectrum, c.power_W, c.holdup_kg, c.test);
  const std::vector<std::size_t> sieves = informative_sieves(c.test);
  auto readings = [&](const Ore& o) {
    const auto pred = batch_test_products(o, c.spectrum, c.power_W, c.holdup_kg, c.test);
    std::vector<double> r;
    for (const auto& row : pred)
      for (std::size_t k : sieves) r.push_back(100 * row[k]);
    return r;
  };
  std::vector<std::vector<double>> J;  // [variable][reading]
  for (const std::string& name : vars) {
    const OreParameter& p = *find_ore_parameter(name);
    REQUIRE(p.log);
    Ore up = ore, down = ore;
    p.set(up, p.get(ore) * std::exp(1e-3));
    p.set(down, p.get(ore) * std::exp(-1e-3));
    const std::vector<double> a = readings(up), b = readings(down);
    std::vector<double> col;
    for (std::size_t i = 0; i < a.size(); ++i) col.push_back((a[i] - b[i]) / 2e-3);
    J.push_back(col);
  }
  ByHand out;
  out.data = static_cast<int>(J[0].size());
  const int nu = u.dof - static_cast<int>(nh);
  const double s2 = nh ? u.ssr_best / nu : u.residual_variance_pp2;  // S_min over ν
  std::vector<std::vector<double>> L(nv, std::vector<double>(nv));
  for (std::size_t a = 0; a < nv; ++a)
    for (std::size_t b = 0; b < nv; ++b) {
      double v = 0;
      for (std::size_t i = 0; i < J[a].size(); ++i) v += J[a][i] * J[b][i];
      L[a][b] = u.information[a][b] * u.residual_variance_pp2 / s2 + v / s2;
    }
  std::vector<double> all = s.g;
  all.insert(all.end(), s.g_held.begin(), s.g_held.end());
  std::vector<std::vector<double>> Lff(np, std::vector<double>(np));
  for (std::size_t a = 0; a < np; ++a)
    for (std::size_t b = 0; b < np; ++b) Lff[a][b] = L[a][b];
  const double var_all = quad(all, inverse(L)), var_free = quad(s.g, inverse(Lff));
  const double t = t_quantile(0.975, nu + out.data);
  out.linear = t * std::sqrt(var_all - var_free);
  // The same from the tests' information alone (t at their ν): the held
  // reach now scaled by the linear reach's fall, never grown.
  std::vector<std::vector<double>> L0(nv, std::vector<double>(nv)), L0ff(np, std::vector<double>(np));
  for (std::size_t a = 0; a < nv; ++a)
    for (std::size_t b = 0; b < nv; ++b) L0[a][b] = u.information[a][b] * u.residual_variance_pp2 / s2;
  for (std::size_t a = 0; a < np; ++a)
    for (std::size_t b = 0; b < np; ++b) L0ff[a][b] = L0[a][b];
  out.linear_now = t_quantile(0.975, nu) * std::sqrt(quad(all, inverse(L0)) - quad(s.g, inverse(L0ff)));
  out.ratio = std::min(1.0, out.linear / out.linear_now);
  const double below = std::hypot(t * std::sqrt(var_free), -s.down * out.ratio);
  const double above = std::hypot(t * std::sqrt(var_free), s.up * out.ratio);
  out.lo = std::exp(s.center - below);
  out.hi = std::exp(s.center + above);
  return out;
}

}  // namespace

TEST_CASE("grind --next-test: an ore edited after its fit is refused, in a fitted key or any other",
          "[grind][next][failures]") {
  // The same staleness check as the intervals': a fitted value moved, or
  // another key of the ore's tables (breakage.beta) edited, which the
  // tables' hash kept by --fit catches.
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  const std::vector<TestInMill> tests = {{synthetic_test(truth, 1.0, 5), synthetic_spectrum(), kPower_W, kHoldup_kg}};
  const BatchFit f = fit_batch_tests(start, tests, {"efficiency", "sigma"});
  Ore fitted = f.ore;
  fitted.fitted_under.covariance = fit_covariance(f, tests);
  fitted.fitted_under.covariance.tables_hash = mc::io::ore_tables_hash(fitted);
  REQUIRE(fitted.fitted_under.covariance.information.size() == 2);
  mc::app::GrindOptions o;
  o.ore = "fitted.toml";
  o.next_tests = {"no-such-run"};
  auto refused = [&](const Ore& ore) {
    try {
      (void)mc::app::plan_next(o, ore);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // As fitted: past the staleness check, to the candidate (not a run folder).
  CHECK(refused(fitted).find("not a run folder") != std::string::npos);
  Ore moved = fitted;
  moved.efficiency *= 1.1;
  CHECK(refused(moved).find("rates.efficiency") != std::string::npos);
  Ore beta = fitted;
  beta.breakage.beta += 0.3;
  const std::string said = refused(beta);
  INFO(said);
  CHECK(said.find("[breakage] differ from the tables the ore was fitted with ([fitted] tables_fnv1a)") !=
        std::string::npos);
  CHECK(said.find("the ore was changed after its fit") != std::string::npos);
}

TEST_CASE("grind next test: a held parameter the candidate informs, its reach against the definitions",
          "[grind][next]") {
  // E∞ and d₀ held wrong, η and σ fitted. Two candidates: a long test in
  // the harder mill, which informs both held ones, and a short one in the
  // first mill, which hardly does. Each expected interval against the one
  // computed by hand from the definitions; the reach of the held ones
  // falls to the linear reach where the candidate informs them, and stays
  // as now on the side where it does not.
  const Ore truth = known_ore();
  Ore start = truth;
  start.efficiency = 0.6;
  start.fracture.sigma = 1.0;
  start.fracture.e_inf_J_kg = 40;
  start.fracture.d0_m = 2.8e-3;
  const std::vector<TestInMill> tests = {{synthetic_test(truth, 1.0, 41), synthetic_spectrum(), kPower_W, kHoldup_kg}};
  BatchFit f = fit_batch_tests(start, tests, {"efficiency", "sigma"});
  for (const char* name : {"e_inf_J_kg", "d0_mm"}) {
    FittedParameter h;
    h.name = name;
    h.start = h.value = find_ore_parameter(name)->get(start);
    h.identified = false;
    h.why = "held for the test";
    f.parameters.push_back(h);
  }
  const FitCovariance u = fit_covariance(f, tests);
  REQUIRE(u.held.size() == 2);
  REQUIRE(u.information.size() == 4);
  const Sensitivity s = sensitivities(f.ore, u, p80_third_mill, true).front();
  REQUIRE(s.log);
  const Interval now = propagate(f.ore, u, p80_third_mill)[0];
  const double width_now = now.hi - now.lo;
  struct Case {
    const char* name;
    TestInMill c;
  };
  const std::vector<Case> cases = {
      {"harder mill, 2 to 32 min",
       {candidate_test(f.ore, {2, 4, 8, 16, 32}), harder_spectrum(), kPower_W, kHoldup_kg}},
      {"first mill, 0.5 to 8 min", {candidate_test(f.ore, {0.5, 1, 2, 4, 8}), synthetic_spectrum(), kPower_W, kHoldup_kg}}};
  std::printf("next test with two held (E_inf, d0): interval now [%.2f, %.2f], width %.2f um; reach now %.4f / %.4f\n",
              now.lo, now.hi, width_now, s.down, s.up);
  std::vector<NextTestWidth> ws;
  for (const Case& k : cases) {
    const NextTestWidth w = expected_after(f.ore, u, s, k.c);
    const ByHand h = expected_by_hand(best_point(f.ore, u), u, s, k.c);
    REQUIRE(w.expected.valid());
    std::printf("  %s: expected [%.3f, %.3f] width %.3f (by hand [%.3f, %.3f]); held reach %.4f / %.4f, linear "
                "%.4f; fixes %zu\n",
                k.name, w.expected.lo, w.expected.hi, w.width, h.lo, h.hi, w.reach_down, w.reach_up, h.linear,
                w.fixes.size());
    CHECK(w.data == h.data);
    CHECK(w.expected.lo == Approx(h.lo).epsilon(1e-4));
    CHECK(w.expected.hi == Approx(h.hi).epsilon(1e-4));
    // By how much the width shrinks, against the hand's.
    CHECK(width_now - w.width == Approx(width_now - (h.hi - h.lo)).epsilon(1e-3));
    ws.push_back(w);
  }
  // The harder mill's long test informs E∞ and d₀: their reach now falls,
  // each side, by the linear reach's ratio (after over now), computed by hand.
  const ByHand hard = expected_by_hand(best_point(f.ore, u), u, s, cases[0].c);
  std::printf("  harder mill's linear reach %.5f after, %.5f now: ratio %.4f\n", hard.linear, hard.linear_now, hard.ratio);
  CHECK(hard.ratio < 0.5);
  CHECK(ws[0].reach_down == Approx(-s.down * hard.ratio).epsilon(1e-4));
  CHECK(ws[0].reach_up == Approx(s.up * hard.ratio).epsilon(1e-4));
  // A candidate that adds nothing (ground for 10⁻⁷ min): the reach stays
  // as now, and the whole interval with it, but for t (the candidate's
  // readings add to ν): each side's half-width in logarithms scaled by
  // t after over t now.
  const TestInMill useless{candidate_test(f.ore, {1e-7}), synthetic_spectrum(), kPower_W, kHoldup_kg};
  const NextTestWidth z = expected_after(f.ore, u, s, useless);
  REQUIRE(z.expected.valid());
  const double t_now = t_quantile(0.975, interval_dof(u)), t_after = t_quantile(0.975, interval_dof(u) + z.data);
  std::printf("  a candidate without information: expected [%.3f, %.3f] against now [%.3f, %.3f]; reach %.4f / %.4f "
              "(now %.4f / %.4f); t %.5f now, %.5f after\n",
              z.expected.lo, z.expected.hi, now.lo, now.hi, z.reach_down, z.reach_up, -s.down, s.up, t_now, t_after);
  CHECK(z.reach_down == Approx(-s.down * t_after / t_now).epsilon(1e-3));
  CHECK(z.reach_up == Approx(s.up * t_after / t_now).epsilon(1e-3));
  CHECK(std::log(z.expected.hi) - s.center == Approx((std::log(now.hi) - s.center) * t_after / t_now).epsilon(1e-3));
  CHECK(s.center - std::log(z.expected.lo) == Approx((s.center - std::log(now.lo)) * t_after / t_now).epsilon(1e-3));
  for (const NextTestWidth& w : ws) CHECK(w.width < width_now);
}

TEST_CASE("grind --next-test: candidates ranked, next_test.csv and grind.json, bad candidates refused",
          "[grind][next][outputs][failures]") {
  const fs::path run_dir = short_bond_run();
  const Ore truth = known_ore();
  const TempDir dir{temp("command")};
  fs::create_directories(dir.path);
  // A second candidate mill, another: the Bond mill at 55 rpm instead of
  // 70 (a short run, as short_bond_run's); a copy without its spectrum.
  {
    mc::app::RunOptions ro;
    ro.c.case_path = std::string(MC_ASSET_DIR) + "/cases/bond.toml";
    ro.c.overrides = {"run.settle=0.05", "run.warmup=0.1", "run.output_interval=0.01", "run.snapshot_interval=0",
                      "run.checkpoint_interval=0", "mill.speed_rpm=55"};
    ro.c.duration = 0.4;
    ro.out = (dir.path / "mill2").string();
    ro.quiet = true;
    REQUIRE(mc::app::cmd_run(ro) == 0);
  }
  fs::copy(run_dir, dir.path / "nospectrum", fs::copy_options::recursive);
  fs::remove(dir.path / "nospectrum" / "spectra.csv");
  const std::string fitted = fit_synthetic_in_bond_run(truth, 13, dir.path).string();
  const std::string grind = "grind " + run_dir.string() + " --ore " + fitted + " --bond 106 ";
  int status = 0;
  const std::string shown = run_binary(grind + "--next-test " + run_dir.string() + " --next-test " +
                                           (dir.path / "mill2").string() + " --next-refit 2 --next-draws 3 --out " +
                                           (dir.path / "next").string(),
                                       status);
  INFO(shown);
  REQUIRE(status == 0);
  CHECK(shown.find("which test next, for the Bond Wi (kWh/t)") != std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir.path / "next" / "grind.json"));
  const nlohmann::json& nt = j["next_test"];
  REQUIRE(nt["candidates"].size() == 6);  // two mills x the three default sets of times
  const auto wi_95 = j["bond"]["work_index_kWh_t_95"].get<std::vector<double>>();
  CHECK(nt["width_now"].get<double>() == Approx(wi_95[1] - wi_95[0]).epsilon(1e-9));
  // The first two of the linear order refitted (3 draws each) and ranked
  // first, narrowest refitted width first; the other four after them, by
  // their linear width.
  CHECK(nt["refitted"].get<int>() == 2);
  CHECK(nt["draws"].get<int>() == 3);
  double last = 0, last_linear = 0, worst_refitted_linear = 0;
  for (std::size_t k = 0; k < nt["candidates"].size(); ++k) {
    const auto& c = nt["candidates"][k];
    const double linear = c["linear_width"].get<double>();
    CHECK(linear < nt["width_now"].get<double>());
    if (k < 2) {
      REQUIRE(c["draws"].get<int>() == 3);
      // A draw with no width counts as infinitely wide: "inf" in the JSON.
      auto width = [](const nlohmann::json& v) {
        if (v.is_string()) {
          CHECK(v.get<std::string>() == "inf");
          return HUGE_VAL;
        }
        return v.get<double>();
      };
      const double w = width(c["median_width"]);
      const double lo = width(c["width_10_90"][0]), hi = width(c["width_10_90"][1]);
      CHECK(w >= last);  // narrowest median first
      CHECK(lo <= w);
      CHECK(w <= hi);
      const double wide = c["wide_share"].get<double>();
      CHECK(wide >= (3 - c["draws_converged"].get<int>()) / 3.0 - 1e-12);  // a draw with no width is wide
      CHECK(wide <= 1);
      last = w;
      worst_refitted_linear = std::max(worst_refitted_linear, linear);
    } else {
      CHECK(c["median_width"].is_null());
      CHECK(c["wide_share"].is_null());
      CHECK(c["draws"].is_null());
      CHECK(linear >= last_linear);
      CHECK(linear >= worst_refitted_linear);  // the linear ranking chose the two refitted
      last_linear = linear;
    }
  }
  // Each row's expected width against the one computed here from the
  // definitions (expected_by_hand), the product Bond's Wi in the first
  // run's mill as run_bond makes it, each candidate the usual test in its
  // mill at the ore's hold-up there; the ranking the same. The two mills
  // differ: their best candidates' widths by more than 1 %.
  const Ore fo = mc::io::read_ore(fitted);
  const FitCovariance& fu = fo.fitted_under.covariance;
  const mc::io::Run bond_mill = mc::io::read_run(run_dir, true, fo.energy_basis);
  auto wi = [&](const Ore& o) {
    Ore b = o;
    put_sieve_on_class_top(b, 106e-6);
    const double charge = bond_charge_kg(b);
    const MillRates r = mill_rates(b, bond_mill.spectrum, bond_mill.power_W, charge);
    return std::vector<double>{bond_test(b.sizes, b.feed, r.S_per_min, appearance_matrix(b, bond_mill.spectrum),
                                         bond_mill.speed_rpm, charge, 106e-6)
                                   .wi_kWh_t};
  };
  const Sensitivity fs_wi = sensitivities(fo, fu, wi, true).front();
  CHECK(fs_wi.value == Approx(j["bond"]["work_index_kWh_t"].get<double>()).epsilon(1e-9));
  std::vector<double> by_hand;
  double best_of[2] = {HUGE_VAL, HUGE_VAL};
  for (const auto& c : nt["candidates"]) {
    const std::string run = c["run"].get<std::string>();
    const mc::io::Run r = mc::io::read_run(run, true, fo.energy_basis);
    const TestInMill cand{candidate_test(fo, c["times_min"].get<std::vector<double>>()), r.spectrum, r.power_W,
                          mill_holdup_kg(fo, r.porosity, r.filling, r.mill_volume)};
    const ByHand h = expected_by_hand(best_point(fo, fu), fu, fs_wi, cand);
    INFO(run << " " << c["times_min"].dump());
    CHECK(c["linear_width"].get<double>() == Approx(h.hi - h.lo).epsilon(1e-3));
    by_hand.push_back(h.hi - h.lo);
    double& b = best_of[run == run_dir.string() ? 0 : 1];
    b = std::min(b, h.hi - h.lo);
  }
  REQUIRE(by_hand.size() == 6);
  CHECK(std::is_sorted(by_hand.begin() + 2, by_hand.end()));
  std::printf("next test through the command: Bond Wi width now %.4g; the narrowest expected %.4g in the 70 rpm mill, "
              "%.4g at 55 rpm\n",
              nt["width_now"].get<double>(), best_of[0], best_of[1]);
  CHECK(std::fabs(best_of[0] / best_of[1] - 1) > 0.01);
  // The same rows in next_test.csv: a header and six.
  std::ifstream csv(dir.path / "next" / "next_test.csv");
  std::string line;
  std::getline(csv, line);
  CHECK(line ==
        "rank,run,times_min,median_width,width_p10,width_p90,wide_share,mean_width_finite,draws_converged,draws,"
        "linear_lo,linear_hi,linear_width,width_now,fixes_held");
  int rows = 0;
  while (std::getline(csv, line)) ++rows;
  CHECK(rows == 6);
  // Bad input: one message naming the option or the file, exit 2, nothing written.
  auto refused = [&](const std::string& args, const std::string& message) {
    const fs::path out = dir.path / "refused";
    const std::string said = run_binary(args + " --out " + out.string(), status);
    INFO(said);
    CHECK(status == 2);
    CHECK(said.find(message) != std::string::npos);
    CHECK_FALSE(fs::exists(out));
  };
  refused(grind + "--next-test " + (dir.path / "nowhere").string(),
          "--next-test " + (dir.path / "nowhere").string() + ": not a run folder");
  refused(grind + "--next-test " + (dir.path / "nospectrum").string(),
          "--next-test " + (dir.path / "nospectrum").string() + ": ");
  refused(grind + "--next-test " + run_dir.string() + " --next-times 1,-2", "--next-times 1,-2: expected minutes > 0");
  refused(grind + "--next-test " + run_dir.string() + " --next-times 2,1", "--next-times 2,1: 1 does not follow 2");
  refused(grind + "--next-times 1,2", "--next-times: the times of a next test; give --next-test RUN");
  refused("grind " + run_dir.string() + " --ore " + (fs::path(MC_ASSET_DIR) / "ores" / "example_spectrum.toml").string() + " --bond 106 --next-test " + run_dir.string(),
          "keeps no covariance");
  refused(grind + "--next-test " + run_dir.string() + " --next-for throughput", "--next-for throughput: ");
  // The test the ore was fitted to changed since its fit: no refits, and
  // the console and grind.json say why; the linear ranking still made.
  {
    mc::io::BatchTestFile tf;
    tf.title = "synthetic, changed";
    tf.test = synthetic_test(truth, 1.0, 99, mc::io::read_run(run_dir, true).spectrum, {1, 2, 4, 8, 16}, true);
    std::ofstream(dir.path / "test.toml") << mc::io::batch_test_toml(tf);
    const std::string said = run_binary(grind + "--next-test " + run_dir.string() + " --next-refit 1 --next-draws 2 " +
                                            "--out " + (dir.path / "changed").string(),
                                        status);
    INFO(said);
    REQUIRE(status == 0);
    CHECK(said.find("note: no refits: the tests the ore was fitted to") != std::string::npos);
    const nlohmann::json jc = nlohmann::json::parse(std::ifstream(dir.path / "changed" / "grind.json"));
    CHECK(jc["next_test"]["refitted"].get<int>() == 0);
    CHECK(jc["next_test"]["no_refits"].get<std::string>().find("a test or a run changed since") != std::string::npos);
    CHECK(jc["next_test"]["candidates"].size() == 3);
  }
}
