// The benchmark command, as a smoke run: one JSON line with the figures the
// issue names, consistent with each other. Speeds are not asserted here:
// performance is measured with the benchmark itself, on a quiet machine.
#include <catch2/catch.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

using Catch::Matchers::WithinAbs;
using Catch::Matchers::WithinRel;

namespace {

std::string run_capture(const std::string& cmd, int& status) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  REQUIRE(p != nullptr);
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  status = pclose(p);
  return out;
}

}  // namespace

TEST_CASE("bench prints one JSON line with consistent figures on the lab mill", "[bench]") {
  int status = -1;
  const std::string out = run_capture(std::string(MC_BINARY) + " bench " + MC_ASSET_DIR +
                                          "/cases/lab.toml --steps 200 --warmup 0.05 --quiet",
                                      status);
  REQUIRE(status == 0);
  REQUIRE(out.find('\n') == out.size() - 1);  // exactly one line
  const auto j = nlohmann::json::parse(out);
  const long n = j.at("n_particles");
  CHECK(n == 2714);
  CHECK(j.at("steps").get<long>() == 200);
  const double wall = j.at("wall_s");
  REQUIRE(wall > 0);
  CHECK_THAT(j.at("particle_updates_per_s").get<double>(), WithinRel(n * 200.0 / wall, 1e-9));
  CHECK_THAT(j.at("bytes_per_ball").get<double>(), WithinRel(j.at("device_bytes").get<double>() / n, 1e-9));
  CHECK(j.at("bytes_per_ball").get<double>() < 1000);
  // Ten timed parts of 20 steps: the total rate lies within their spread.
  CHECK(j.at("parts").get<int>() == 10);
  const auto& parts = j.at("part_updates_per_s");
  const double slowest = parts.at("min"), typical = parts.at("median"), best = parts.at("max");
  CHECK(slowest > 0);
  CHECK(slowest <= typical);
  CHECK(typical <= best);
  CHECK(j.at("particle_updates_per_s").get<double>() >= slowest * (1 - 1e-9));
  CHECK(j.at("particle_updates_per_s").get<double>() <= best * (1 + 1e-9));
  // The charge has fallen onto itself after 0.05 s: contacts exist, and
  // the lists hold every contact plus the skin's near misses.
  const double contacts = j.at("contacts_per_ball");
  CHECK(contacts > 0.1);
  CHECK(contacts < 12);
  CHECK(j.at("list_entries_per_ball").get<double>() >= contacts);
  CHECK(j.at("precision") == "float");
  double sum = 0;
  for (const char* stage : {"binning", "contacts", "forces", "motion", "reductions"}) {
    const double share = j.at("stages").at(stage);
    CHECK(share >= 0);
    sum += share;
  }
  CHECK_THAT(sum, WithinAbs(1.0, 1e-9));
  CHECK(j.at("stages").at("forces").get<double>() > 0.2);  // the forces dominate a DEM step
  // The same steps without the energy books, timed in turn: a rate of their
  // own, the same memory (but for the record pool's slack), and the books'
  // cost from the two.
  CHECK(j.at("energy_books") == "on");
  const auto& off = j.at("books_off");
  CHECK(off.at("particle_updates_per_s").get<double>() > 0);
  CHECK(off.at("bytes_per_ball").get<double>() == Approx(j.at("bytes_per_ball").get<double>()).epsilon(0.03));
  CHECK_THAT(j.at("books_cost").at("total").get<double>(),
             WithinRel(j.at("wall_s").get<double>() / (n * 200.0 / off.at("particle_updates_per_s").get<double>()) - 1,
                       1e-6));
  // One way only: no comparison.
  const std::string one = run_capture(std::string(MC_BINARY) + " bench " + MC_ASSET_DIR +
                                          "/cases/lab.toml --steps 20 --warmup 0 --books off --quiet",
                                      status);
  REQUIRE(status == 0);
  const auto k = nlohmann::json::parse(one);
  CHECK(k.at("energy_books") == "off");
  CHECK(k.at("books_off").is_null());
}

TEST_CASE("bench refuses a bad case with status 2 and a message", "[bench]") {
  int status = -1;
  const std::string out = run_capture(std::string(MC_BINARY) + " bench " + MC_ASSET_DIR +
                                          "/cases/lab.toml --set mill.diameter=-1 --quiet 2>&1",
                                      status);
  CHECK(WEXITSTATUS(status) == 2);
  CHECK(out.find("mill.diameter") != std::string::npos);
}

TEST_CASE("bench starts from a run's checkpoint with --from, and repeats its charge with --tile", "[bench]") {
  const std::string dir = "/tmp/millcharge-test-bench-from-" + std::to_string(::getpid());
  int status = -1;
  run_capture(std::string(MC_BINARY) + " run --quiet --force --set run.duration=0.02 --set run.settle=0.2 --set run.warmup=0 --out " +
                  dir + " >/dev/null 2>&1",
              status);
  REQUIRE(status == 0);
  const std::string out = run_capture(std::string(MC_BINARY) + " bench --from " + dir + " --steps 100 --quiet", status);
  REQUIRE(status == 0);
  const auto j = nlohmann::json::parse(out);
  CHECK(j.at("n_particles").get<long>() == 2714);
  CHECK(j.at("warmup_steps").get<long>() == 0);
  CHECK(j.at("from") == dir);
  // The state is the run's after 0.22 s, not a fresh packing (whose balls
  // all start apart, and would touch nothing 100 steps later).
  CHECK(j.at("contacts_per_ball").get<double>() > 0.2);
  CHECK(j.at("list_entries_per_ball").get<double>() > 4);
  CHECK(j.at("tile").is_null());

  // --tile 3: the same charge three times along a mill three times as long,
  // still as dense (the copies keep their places, so their contacts).
  const std::string tiled =
      run_capture(std::string(MC_BINARY) + " bench --from " + dir + " --tile 3 --steps 50 --quiet", status);
  REQUIRE(status == 0);
  const auto t = nlohmann::json::parse(tiled);
  CHECK(t.at("n_particles").get<long>() == 3 * 2714);
  CHECK(t.at("tile").get<int>() == 3);
  CHECK(t.at("case").get<std::string>().find("x3") != std::string::npos);
  CHECK(t.at("contacts_per_ball").get<double>() > 0.5 * j.at("contacts_per_ball").get<double>());
  CHECK_THAT(t.at("list_entries_per_ball").get<double>(),
             WithinRel(j.at("list_entries_per_ball").get<double>(), 0.2));
  CHECK(t.at("bytes_per_ball").get<double>() < 430);

  // --tile needs a charge to repeat.
  const std::string bad = run_capture(std::string(MC_BINARY) + " bench " + MC_ASSET_DIR +
                                          "/cases/lab.toml --tile 2 --quiet 2>&1",
                                      status);
  CHECK(WEXITSTATUS(status) == 2);
  CHECK(bad.find("--tile") != std::string::npos);
  std::system(("rm -rf " + dir).c_str());
}

TEST_CASE("the law probe runs the law both ways and they agree with Hertz", "[bench]") {
  int status = -1;
  const std::string out = run_capture(std::string(MC_LAW_PROBE) + " --pairs 20000", status);
  REQUIRE(status == 0);
  // Each line: "<form>: <ns> ns per pair (mean |F| <N> N)".
  auto figures = [&](const std::string& form, double& ns, double& force) {
    const auto at = out.find(form + ":");
    REQUIRE(at != std::string::npos);
    REQUIRE(std::sscanf(out.c_str() + at + form.size() + 1, " %lf ns per pair (mean |F| %lf N)", &ns, &force) == 2);
  };
  double ns_one = 0, f_one = 0, ns_lanes = 0, f_lanes = 0;
  figures("one pair at a time", ns_one, f_one);
  figures("in SIMD lanes", ns_lanes, f_lanes);
  CHECK(ns_one > 0);
  CHECK(ns_lanes > 0);
  CHECK_THAT(f_lanes, WithinRel(f_one, 1e-4));
  // 10 mm steel balls overlapping by 0.1 mm: the Hertz force is
  // 4/3 E* sqrt(R*) d^1.5 = 1.036e4 N along an axis; the dashpots and the
  // tangential force of the random speeds add to the sum of |F|'s parts.
  CHECK(f_one > 1.0e4);
  CHECK(f_one < 1.3e4);
  int bad = -1;
  run_capture(std::string(MC_LAW_PROBE) + " --pairs 5", bad);
  CHECK(WIFEXITED(bad));
  CHECK(WEXITSTATUS(bad) == 2);
}
