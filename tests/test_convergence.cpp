// Runs that stop when converged: the batch-means standard error on series
// with a known answer, the stop rule, and short runs with run.duration =
// "auto" (they stop on a whole revolution, converged or at the cap, write
// the standard errors, and resume bit for bit).
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "core/mill_case.h"
#include "io/case_file.h"
#include "io/checkpoint.h"
#include "sim/batch_means.h"

namespace fs = std::filesystem;
using namespace mc;

namespace {

std::vector<double> iid(int n, std::uint64_t seed, double mean = 100.0, double sd = 1.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(mean, sd);
  std::vector<double> v(n);
  for (double& x : v) x = g(rng);
  return v;
}

// x_t = phi x_(t-1) + e_t, started from the stationary distribution.
std::vector<double> ar1(int n, double phi, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<double> v(n);
  double x = g(rng) / std::sqrt(1 - phi * phi);
  for (double& y : v) {
    x = phi * x + g(rng);
    y = x;
  }
  return v;
}

// The exact standard error of the mean of n values of that AR(1) process:
// Var = sigma^2/n (1 + 2 sum_k (1 - k/n) phi^k), sigma^2 = 1/(1 - phi^2).
double ar1_true_sem(int n, double phi) {
  double s = 1;
  for (int k = 1; k < n; ++k) s += 2 * (1.0 - static_cast<double>(k) / n) * std::pow(phi, k);
  return std::sqrt(s / (1 - phi * phi) / n);
}

}  // namespace

TEST_CASE("batch means of independent values: the error is sd/sqrt(n)", "[convergence]") {
  // One series: uncorrelated, so nothing is merged and the error is exactly
  // the naive one.
  const std::vector<double> v = iid(400, 7);
  const BatchMeans b = batch_means(v);
  CHECK(b.values == 400);
  CHECK(b.batch_length == 1);
  CHECK_FALSE(b.correlated);
  CHECK(b.sem == Approx(naive_sem(v)).epsilon(1e-12));
  CHECK(b.sem == Approx(1.0 / std::sqrt(400.0)).epsilon(0.1));
  // Over many series the error is unbiased against the true 1/sqrt(n).
  double ratio = 0;
  const int series = 200;
  for (int k = 0; k < series; ++k) ratio += batch_means(iid(40, 1000 + k)).sem * std::sqrt(40.0) / series;
  CHECK(ratio == Approx(1.0).epsilon(0.05));  // E[s] = c4 sigma, c4(40) = 0.994
}

TEST_CASE("batch means of an AR(1) series: merged batches correct the naive error", "[convergence]") {
  const int n = 2000;
  const double phi = 0.8;  // integrated autocorrelation time (1 + phi)/(1 - phi) = 9
  const double truth = ar1_true_sem(n, phi);
  double mean_ratio = 0;
  const int series = 20;
  for (int k = 0; k < series; ++k) {
    const std::vector<double> v = ar1(n, phi, 50 + k);
    const BatchMeans b = batch_means(v);
    INFO("series " << k << ": naive " << naive_sem(v) << ", batch means " << b.sem << " (" << b.batches
                   << " batches of " << b.batch_length << ", lag-1 " << b.lag1 << "), true " << truth);
    CHECK(naive_sem(v) < 0.5 * truth);  // sqrt(1/9) of it
    CHECK(b.batch_length >= 8);
    CHECK_FALSE(b.correlated);
    CHECK(b.sem == Approx(truth).epsilon(0.3));
    mean_ratio += b.sem / truth / series;
  }
  CHECK(mean_ratio == Approx(1.0).epsilon(0.15));
}

TEST_CASE("a drift is caught as correlation, and few batches are not trusted", "[convergence]") {
  // A steady rise (a charge still warming up): strongly correlated means.
  std::vector<double> rise;
  for (int k = 0; k < 8; ++k) rise.push_back(100.0 + k + 0.1 * ((k * 7) % 3));
  const BatchMeans r = batch_means(rise);
  CHECK(r.batch_length >= 2);  // merged: fewer batches than a run may stop on
  CHECK(r.batches < kMinBatches);
  CHECK_FALSE(converged(r, 0.5));
  // Fewer than eight batches never stop a run, however small the error.
  REQUIRE(kMinBatches == 8);
  const BatchMeans seven = batch_means({100.0, 100.1, 99.9, 100.0, 100.2, 99.8, 100.1});
  CHECK(seven.sem < 0.001 * 100);
  CHECK_FALSE(seven.correlated);
  CHECK_FALSE(converged(seven, 0.01));
  // Eight independent ones with a small error do.
  const BatchMeans eight = batch_means({100.0, 100.2, 99.9, 100.1, 99.8, 100.1, 99.9, 100.2});
  CHECK_FALSE(eight.correlated);
  CHECK(converged(eight, 0.01));
  CHECK_FALSE(converged(eight, 0.0005));
  // NaNs (revolutions without a toe) are left out.
  const BatchMeans gaps = batch_means({100.0, std::nan(""), 100.2, 99.9});
  CHECK(gaps.values == 3);
  CHECK(gaps.mean == Approx(100.033333));
  CHECK(lag1_limit(4) == 0.5);
  CHECK(lag1_limit(100) == Approx(0.2));
}

TEST_CASE("the stop rule on a series of revolutions: the first revolution whose error is small enough", "[convergence]") {
  // Revolutions with 3 % noise and a 1 % tolerance: about ten revolutions.
  const std::vector<double> revs = iid(60, 11, 800.0, 24.0);
  int stop = -1;
  for (int n = 1; n <= 60 && stop < 0; ++n) {
    const std::vector<double> so_far(revs.begin(), revs.begin() + n);
    if (converged(batch_means(so_far), 0.01)) stop = n;
  }
  INFO("stopped after " << stop << " revolutions");
  REQUIRE(stop >= kMinBatches);
  CHECK(stop <= 40);
  const BatchMeans b = batch_means(std::vector<double>(revs.begin(), revs.begin() + stop));
  CHECK(b.sem <= 0.01 * b.mean);
  // The revolution before did not satisfy the rule.
  CHECK_FALSE(converged(batch_means(std::vector<double>(revs.begin(), revs.begin() + stop - 1)), 0.01));
}

TEST_CASE("run.duration, run.tolerance and run.max_duration are read, checked and written back", "[convergence][case]") {
  const fs::path lab = io::default_case();
  const MillCase a = io::read_case(lab, {"run.duration=auto", "run.tolerance=0.02", "run.max_duration=30"});
  CHECK(a.duration_auto);
  CHECK(a.tolerance == 0.02);
  const MillDerived da = derive(a);
  CHECK(da.turn_limit_s == 30);
  const MillCase b = io::parse_case(io::case_to_toml(a), "case.toml");
  CHECK(b.duration_auto);
  CHECK(b.tolerance == 0.02);
  CHECK(b.max_duration == 30);
  // The default cap: the warm-up and 40 revolutions.
  const MillCase c = io::read_case(lab, {"run.duration=\"auto\""});
  const MillDerived dc = derive(c);
  CHECK(dc.turn_limit_s == Approx(c.warmup + kAutoRevolutions * dc.revolution_s));
  // A number stays a number.
  const MillCase f = io::read_case(lab, {"run.duration=5"});
  CHECK_FALSE(f.duration_auto);
  CHECK(derive(f).turn_limit_s == 5);
  auto error_of = [&](const std::vector<std::string>& sets) {
    try {
      io::read_case(lab, sets);
    } catch (const io::CaseError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(error_of({"run.duration=forever"}),
             Catch::Contains("--set run.duration=forever: run.duration: expected a number of seconds or \"auto\""));
  CHECK_THAT(error_of({"run.duration=auto", "run.tolerance=0"}), Catch::Contains("run.tolerance: must be in (0, 1)"));
  CHECK_THAT(error_of({"run.tolerance=1"}), Catch::Contains("run.tolerance: must be in (0, 1)"));
  CHECK_THAT(error_of({"run.tolerance=auto"}), Catch::Contains("run.tolerance: expected a number"));
  CHECK_THAT(error_of({"run.duration=auto", "run.max_duration=1"}),
             Catch::Contains("run.max_duration: must leave at least one revolution"));
  CHECK_THAT(error_of({"run.settle_damping=-1"}), Catch::Contains("run.settle_damping: must be >= 0 or \"auto\""));
}

namespace {

// A small, soft mill that turns a revolution in about a second of about 8,000
// steps: 85 balls in a 0.3 m mill.
const std::string kSmall =
    " --quiet --set mill.diameter=0.3 --set mill.length=0.05 --set contact.stiffness=1e5"
    " --set run.steps_per_contact=10 --set run.warmup=1.0 --set run.snapshot_interval=0"
    " --set run.output_interval=0.02 --set run.checkpoint_interval=0.5";

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("millcharge-conv-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(p);
  return p;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

int run_cmd(const std::string& args, const fs::path& out_log) {
  const int st = std::system((std::string(MC_BINARY) + " " + args + " >'" + out_log.string() + "' 2>&1").c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

nlohmann::json summary(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in);
}

// The turning time is the warm-up and a whole number of revolutions.
void check_whole_revolutions(const nlohmann::json& j, double warmup, double revolution_s, double dt) {
  const double turned = j["turning_s"].get<double>();
  const double revs = (turned - warmup) / revolution_s;
  INFO("turned " << turned << " s = warm-up + " << revs << " revolutions");
  CHECK(std::fabs(revs - std::round(revs)) * revolution_s < 2 * dt);
  CHECK(j["average"]["from_s"].get<double>() == Approx(warmup).margin(dt));
  CHECK(j["average"]["revolutions"].get<double>() == Approx(std::round(revs)).margin(0.01));
}

}  // namespace

TEST_CASE("duration auto stops on a whole revolution once converged, with the standard errors", "[convergence][run]") {
  const fs::path dir = scratch("auto"), log = scratch("auto.txt");
  const std::string args = "run" + kSmall + " --set run.duration=auto --set run.tolerance=0.1 --set run.max_duration=16";
  REQUIRE(run_cmd(args + " --out '" + dir.string() + "'", log) == 0);
  const std::string console = slurp(log);
  INFO(console);
  const MillCase c = io::read_case(io::default_case(), {"mill.diameter=0.3", "mill.length=0.05",
                                                        "contact.stiffness=1e5", "run.steps_per_contact=10",
                                                        "run.warmup=1.0", "run.duration=auto", "run.tolerance=0.1",
                                                        "run.max_duration=16"});
  const MillDerived d = derive(c);
  const nlohmann::json j = summary(dir);
  const auto& conv = j["convergence"];
  CHECK(conv["duration"] == "auto");
  CHECK(conv["converged"] == true);
  CHECK(conv["stopped_at_cap"] == false);
  // Eighths of a revolution as batches: at least one revolution, and
  // never fewer than kMinBatches batches.
  const int revs = conv["revolutions"].get<int>();
  CHECK(conv["batches_per_revolution"] == kBatchesPerRevolution);
  CHECK(revs >= 1);
  CHECK(revs < 15);
  CHECK(conv["batches"].get<int>() >= kMinBatches);
  CHECK(conv["batches"].get<int>() * conv["revolutions_per_batch"].get<double>() == Approx(revs));
  check_whole_revolutions(j, 1.0, d.revolution_s, d.dt);
  const double p = j["power_W"]["torque"].get<double>(), sem = j["power_W"]["torque_sem"].get<double>();
  CHECK(sem > 0);
  CHECK(sem <= 0.1 * p);
  CHECK(conv["power_relative_sem"].get<double>() == Approx(sem / p).epsilon(0.05));
  for (const char* k : {"torque_Nm_sem", "com_angle_deg_sem"}) {
    INFO(k);
    CHECK(j[k].is_number());
  }
  CHECK(j.contains("toe_deg_sem"));  // null in a revolution without a toe
  CHECK(j.contains("shoulder_deg_sem"));
  for (const char* k : {"dissipation_sem", "torque_arm_sem"}) CHECK(j["power_W"][k].is_number());
  CHECK(j["spectra"]["total"]["power_W_sem"].is_number());
  CHECK(j["liner"]["impact_power_W_sem"].is_number());
  CHECK(j["liner"]["wear_kg_per_h_sem"].is_number());
  // The console gives the means with their errors and says why it stopped.
  CHECK_THAT(console, Catch::Contains("\u00b1"));
  CHECK_THAT(console, Catch::Contains("converged after " + std::to_string(revs) + " revolution"));
  CHECK_THAT(console, Catch::Contains("batch means of "));
  // The last row of timeseries.csv is the end of the run.
  std::ifstream ts(dir / "timeseries.csv");
  std::string line, last;
  while (std::getline(ts, line)) last = line;
  CHECK(std::stod(last) == Approx(j["turning_s"].get<double>()).margin(1e-5));
  fs::remove_all(dir);
  fs::remove(log);
}

TEST_CASE("duration auto stops at the cap on a whole revolution and says it did not converge", "[convergence][run]") {
  const fs::path dir = scratch("cap"), log = scratch("cap.txt");
  // 1 s of warm-up and 2.5 revolutions of cap: two whole revolutions.
  const MillCase c = io::read_case(io::default_case(), {"mill.diameter=0.3", "run.warmup=1.0"});
  const MillDerived d0 = derive(c);
  std::ostringstream cap;
  cap.precision(10);
  cap << 1.0 + 2.5 * d0.revolution_s;
  REQUIRE(run_cmd("run" + kSmall + " --set run.duration=auto --set run.tolerance=1e-6 --set run.max_duration=" +
                      cap.str() + " --out '" + dir.string() + "'",
                  log) == 0);
  const std::string console = slurp(log);
  INFO(console);
  const nlohmann::json j = summary(dir);
  CHECK(j["convergence"]["converged"] == false);
  CHECK(j["convergence"]["stopped_at_cap"] == true);
  CHECK(j["convergence"]["revolutions"] == 2);
  const MillDerived d = derive(io::read_case(io::default_case(), {"mill.diameter=0.3", "contact.stiffness=1e5",
                                                                  "run.steps_per_contact=10"}));
  check_whole_revolutions(j, 1.0, d.revolution_s, d.dt);
  CHECK(j["turning_s"].get<double>() <= std::stod(cap.str()));
  CHECK_THAT(console, Catch::Contains("NOT converged: stopped at the cap"));
  fs::remove_all(dir);
  fs::remove(log);
}

TEST_CASE("an auto run killed while turning resumes to the same stop, bit for bit", "[convergence][checkpoint]") {
  const fs::path a = scratch("unbroken"), b = scratch("killed"), log = scratch("resume.txt");
  const std::string args = "run" + kSmall + " --set run.duration=auto --set run.tolerance=0.1 --set run.max_duration=16";
  REQUIRE(run_cmd(args + " --out '" + a.string() + "'", log) == 0);

  // The unbroken run's stop: the kill must come before it.
  const io::Checkpoint ca = io::read_checkpoint(a / io::kCheckpointFile);
  REQUIRE(ca.run.stop_step > 0);
  // A checkpoint of the turning (phase 2) that holds a batch or more and
  // lies before the stop.
  auto mid_turning = [&](const fs::path& dir) {
    try {
      const io::Checkpoint cp = io::read_checkpoint(dir / io::kCheckpointFile);
      return cp.run.phase == 2 && !cp.run.batches.empty() && cp.run.turn_step < ca.run.stop_step;
    } catch (const std::exception&) {
      return false;
    }
  };
  // Kill the same run once such a checkpoint is written. On a loaded
  // machine the poll can miss the window and the run end first: then try
  // again, polling faster; a kill that never lands mid-run fails the test,
  // which would otherwise resume nothing.
  bool killed_mid = false;
  for (int attempt = 0; attempt < 3 && !killed_mid; ++attempt) {
    fs::remove_all(b);
    const pid_t pid = ::fork();
    if (pid == 0) {
      const std::string cmd =
          "exec " + std::string(MC_BINARY) + " " + args + " --out '" + b.string() + "' >/dev/null 2>&1";
      ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(300);
    while (!mid_turning(b) && !fs::exists(b / "summary.json") && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(std::chrono::milliseconds(20 >> (2 * attempt)));
    ::kill(pid, SIGKILL);
    int st = 0;
    ::waitpid(pid, &st, 0);
    // What the resume starts from: a checkpoint mid-turning, no summary.
    killed_mid = !fs::exists(b / "summary.json") && mid_turning(b);
    if (!killed_mid) WARN("attempt " << attempt + 1 << ": the run ended before it was killed; trying again");
  }
  REQUIRE(killed_mid);
  REQUIRE(run_cmd("run --quiet --resume '" + b.string() + "'", log) == 0);
  const io::Checkpoint cb = io::read_checkpoint(b / io::kCheckpointFile);
  CHECK(ca.solver.steps == cb.solver.steps);
  CHECK(ca.run.stop_step == cb.run.stop_step);
  REQUIRE(ca.run.batches.size() == cb.run.batches.size());
  for (std::size_t k = 0; k < ca.run.batches.size(); ++k)
    CHECK(ca.run.batches[k].torque_power_W == cb.run.batches[k].torque_power_W);
  CHECK(slurp(a / "timeseries.csv") == slurp(b / "timeseries.csv"));
  CHECK(summary(a)["power_W"]["torque_sem"] == summary(b)["power_W"]["torque_sem"]);
  fs::remove_all(a);
  fs::remove_all(b);
  fs::remove(log);
}
