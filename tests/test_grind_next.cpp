// Which batch test to run next (src/grind/next_test.h, `grind --next-test`):
// the expected width of a product's interval after a candidate test,
// against the widths that fits of simulated candidate tests give; the
// ranking through the command, its files, and bad candidates refused.
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

#include "app/grind.h"
#include "bond_run.h"
#include "grind/fit.h"
#include "grind/interval.h"
#include "grind/next_test.h"
#include "grind_synthetic.h"
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

TEST_CASE("grind next test: Student's t counts every parameter, held ones included", "[grind][next]") {
  // E∞ and d₀ held wrong, η and σ fitted; a long test in the harder mill
  // fixes both: the expected half-width is Student's t with the intervals'
  // degrees of freedom (the fit's less the two held), plus the
  // candidate's readings.
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
  const Sensitivity s = sensitivities(f.ore, u, p80_third_mill, true).front();
  const NextTestWidth w =
      expected_after(f.ore, u, s, {candidate_test(f.ore, {2, 4, 8, 16, 32}), harder_spectrum(), kPower_W, kHoldup_kg});
  REQUIRE(w.expected.valid());
  REQUIRE(w.fixes.size() == 2);
  REQUIRE(s.log);
  const int nu = interval_dof(u) + w.data;  // u.dof less the two held, plus the candidate's readings
  const double half = std::log(w.expected.hi) - std::log(s.value);  // centred on the value where all are fixed
  std::printf("next test, both held fixed: dof %d - 2 held + %d readings = %d; half-width %.9g against t %.9g x sd "
              "%.9g\n",
              u.dof, w.data, nu, half, t_quantile(0.975, nu), w.sd);
  CHECK(half == Approx(t_quantile(0.975, nu) * w.sd).epsilon(1e-9));
}

TEST_CASE("grind --next-test: candidates ranked, next_test.csv and grind.json, bad candidates refused",
          "[grind][next][outputs][failures]") {
  const fs::path run_dir = short_bond_run();
  const Ore truth = known_ore();
  const TempDir dir{temp("command")};
  fs::create_directories(dir.path);
  // A second candidate mill (a copy of the run), one without its spectrum.
  fs::copy(run_dir, dir.path / "mill2", fs::copy_options::recursive);
  fs::copy(run_dir, dir.path / "nospectrum", fs::copy_options::recursive);
  fs::remove(dir.path / "nospectrum" / "spectra.csv");
  const std::string fitted = fit_synthetic_in_bond_run(truth, 13, dir.path).string();
  const std::string grind = "grind " + run_dir.string() + " --ore " + fitted + " --bond 106 ";
  int status = 0;
  const std::string shown = run_binary(grind + "--next-test " + run_dir.string() + " --next-test " +
                                           (dir.path / "mill2").string() + " --out " + (dir.path / "next").string(),
                                       status);
  INFO(shown);
  REQUIRE(status == 0);
  CHECK(shown.find("which test next, for the Bond Wi (kWh/t)") != std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir.path / "next" / "grind.json"));
  const nlohmann::json& nt = j["next_test"];
  REQUIRE(nt["candidates"].size() == 6);  // two mills x the three default sets of times
  const auto wi_95 = j["bond"]["work_index_kWh_t_95"].get<std::vector<double>>();
  CHECK(nt["width_now"].get<double>() == Approx(wi_95[1] - wi_95[0]).epsilon(1e-9));
  double last = 0;
  for (const auto& c : nt["candidates"]) {
    const double w = c["expected_width"].get<double>();
    CHECK(w >= last);  // narrowest first
    CHECK(w < nt["width_now"].get<double>());
    last = w;
  }
  // The same rows in next_test.csv: a header and six.
  std::ifstream csv(dir.path / "next" / "next_test.csv");
  std::string line;
  std::getline(csv, line);
  CHECK(line == "rank,run,times_min,expected_lo,expected_hi,expected_width,width_now,fixes_held");
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
}
