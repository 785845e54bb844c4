// Settling: its wall time is recorded, and the optional damping of the
// balls while the mill is at rest settles them to the same bed.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "app/commands.h"

namespace fs = std::filesystem;

namespace {

nlohmann::json settle_only(const std::string& damping, const std::string& name) {
  const fs::path out = fs::temp_directory_path() / ("millcharge_test_settle_" + name + std::to_string(::getpid()));
  fs::remove_all(out);
  mc::app::RunOptions o;
  // 85 balls in a 0.3 m mill; a few turning steps after the settling.
  o.c.overrides = {"mill.diameter=0.3",          "mill.length=0.05",        "contact.stiffness=1e5",
                   "run.steps_per_contact=10",   "run.warmup=0",            "run.snapshot_interval=0",
                   "run.settle_damping=" + damping};
  o.c.duration = 0.01;
  o.out = out.string();
  o.quiet = true;
  REQUIRE(mc::app::cmd_run(o) == 0);
  std::ifstream js(out / "summary.json");
  nlohmann::json j = nlohmann::json::parse(js);
  fs::remove_all(out);
  return j;
}

}  // namespace

TEST_CASE("settling with damping comes to rest in the same bed and records its wall time", "[settle]") {
  const nlohmann::json plain = settle_only("0", "plain"), damped = settle_only("auto", "damped");
  const double t0 = plain["settle_s"].get<double>(), t1 = damped["settle_s"].get<double>();
  INFO("settled in " << t0 << " s without damping, " << t1 << " s with");
  CHECK(plain["settled"] == true);
  CHECK(damped["settled"] == true);
  CHECK(t1 < 2 * t0);
  CHECK(damped["filling_settled"].get<double>() ==
        Approx(plain["filling_settled"].get<double>()).epsilon(0.05));
  for (const nlohmann::json* j : {&plain, &damped}) {
    CHECK((*j)["settle_wall_s"].get<double>() > 0);
    CHECK((*j)["settle_wall_s"].get<double>() <= (*j)["wall_s"].get<double>());
  }
}
