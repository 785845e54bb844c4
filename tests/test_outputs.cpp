// A short run through the command's own code path: every output file is
// there and says what it should.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/commands.h"
#include "core/mill_case.h"
#include "core/version.h"
#include "io/case_file.h"
#include "io/vtk.h"

namespace fs = std::filesystem;

namespace {

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

}  // namespace

TEST_CASE("run writes summary.json, timeseries.csv, snapshots with charge.pvd and pictures", "[outputs]") {
  const fs::path out = fs::temp_directory_path() / ("millcharge_test_outputs_" + std::to_string(::getpid()));
  fs::remove_all(out);
  mc::app::RunOptions o;
  o.c.overrides = {"mill.length=0.06",        "run.settle=0.05",          "run.warmup=0.1",
                   "run.output_interval=0.01", "run.snapshot_interval=0.1"};
  o.c.duration = 0.3;
  o.out = out.string();
  o.quiet = true;
  REQUIRE(mc::app::cmd_run(o) == 0);

  std::ifstream js(out / "summary.json");
  const nlohmann::json j = nlohmann::json::parse(js);
  for (const char* k : {"n_particles", "speed_rpm", "critical_speed_rpm", "speed_fraction", "filling", "dt_s", "steps",
                        "simulated_s", "revolutions", "power_W", "torque_Nm", "toe_deg", "shoulder_deg",
                        "com_angle_deg", "wall_s", "particle_updates_per_s", "device", "precision"}) {
    INFO(k);
    CHECK(j.contains(k));
  }
  for (const char* k : {"torque", "dissipation", "imbalance"}) CHECK(j["power_W"].contains(k));
  const mc::MillCase c = mc::io::read_case(mc::io::default_case(), o.c.overrides);
  const mc::MillDerived d = mc::derive(c);
  CHECK(j["n_particles"].get<long>() == d.n_balls);
  CHECK(j["critical_speed_rpm"].get<double>() == Approx(d.critical_rpm));
  CHECK(j["speed_fraction"].get<double>() == Approx(0.75));
  CHECK(j["dt_s"].get<double>() == Approx(d.dt));
  CHECK(j["precision"] == "float");
  // The code that made it: this build's version and commit.
  CHECK(j["build"]["version"] == mc::version());
  CHECK(j["build"]["commit"] == mc::build_commit());
  CHECK(std::string(mc::build_commit()).size() >= 7);
  CHECK(j["revolutions"].get<double>() == Approx(0.3 / d.revolution_s).epsilon(0.01));
  CHECK(j["simulated_s"].get<double>() == Approx(0.35).epsilon(0.01));
  CHECK(j["steps"].get<long>() == std::lround(0.05 / d.dt) + std::lround(0.3 / d.dt));
  CHECK(j["power_W"]["torque"].get<double>() > 0);
  CHECK(j["particle_updates_per_s"].get<double>() > 0);

  // timeseries: a header, one row per output interval (rows align on the
  // averaging window's start, so a short row may come before it and at the
  // end), times increasing.
  const auto rows = lines_of(out / "timeseries.csv");
  REQUIRE(rows.size() >= 2);
  CHECK(rows[0].rfind("time_s,revolutions,torque_Nm,torque_power_W,dissipation_power_W", 0) == 0);
  CHECK(rows.size() - 1 >= 30);
  CHECK(rows.size() - 1 <= 32);
  double last = -1;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const double t = std::stod(rows[i]);
    CHECK(t > last);
    last = t;
  }
  CHECK(last == Approx(0.3).margin(d.dt));

  // Snapshots at 0, 0.1, 0.2, 0.3 s, listed in charge.pvd (part 0) with the
  // liner turned to the mill's angle then (part 1), read back whole.
  const auto pvd = lines_of(out / "charge.pvd");
  int listed = 0, liners = 0;
  for (const auto& l : pvd) {
    listed += l.find("<DataSet") != std::string::npos && l.find("part=\"0\"") != std::string::npos;
    liners += l.find("<DataSet") != std::string::npos && l.find("part=\"1\"") != std::string::npos &&
              l.find("snapshots/liner_") != std::string::npos;
  }
  CHECK(listed == 4);
  CHECK(liners == 4);
  const mc::io::Snapshot last_snap = mc::io::read_vtp(out / "snapshots" / "charge_000003.vtp");
  CHECK(last_snap.time_s == Approx(0.3).margin(d.dt));
  REQUIRE(static_cast<long>(last_snap.size()) == d.n_balls);
  for (std::size_t i = 0; i < last_snap.size(); ++i) {
    CHECK(last_snap.radius[i] >= 0.010f * 0.999999f);
    CHECK(last_snap.radius[i] <= 0.0127f * 1.000001f);
    const auto& p = last_snap.position[i];
    CHECK(std::hypot(p[0], p[1]) < 0.45);
  }

  for (const char* f : {"power.png", "charge.png", "case.toml", "liner.vtp", "spectra.png", "liner.png"}) {
    INFO(f);
    CHECK(fs::file_size(out / f) > 1000);
  }

  // Where the energy went: the spectra's books against the dissipation, a
  // row per pair type and bin, a row per liner element.
  const nlohmann::json& sp = j["spectra"];
  CHECK(sp["total"]["collisions_per_s"].get<double>() > 0);
  CHECK(sp["total"]["power_W"].get<double>() > 0);
  CHECK(sp["by_pair"].size() == 4);  // steel-steel, steel-shell, steel-lifter, steel-end plate
  CHECK(sp["books"]["spectra_W"].get<double>() ==
        Approx(j["power_W"]["dissipation"].get<double>()).epsilon(0.01));
  const nlohmann::json& ln = j["liner"];
  for (const char* k : {"wear_kg_per_h", "worst_wear_mm_per_1000h", "impact_power_W", "shear_power_W",
                        "bare_liner_impact_power_W", "bare_liner_impact_share", "impact_point_deg"}) {
    INFO(k);
    CHECK(ln.contains(k));
  }
  CHECK(ln["impact_power_W"].get<double>() > 0);
  CHECK(ln["wear_kg_per_h"].get<double>() > 0);
  // Along the mill: the axial bins' spans tile the length, their impact
  // power sums to the profile's.
  const nlohmann::json& along = ln["impact_point_along"];
  REQUIRE(along.size() >= 1);
  CHECK(along.back()["z1_m"].get<double>() == Approx(0.06));  // the mill's length, its plates new
  double along_W = 0, profile_W = 0;
  for (std::size_t k = 0; k < along.size(); ++k) {
    CHECK(along[k]["z0_m"].get<double>() == Approx(k == 0 ? 0.0 : along[k - 1]["z1_m"].get<double>()));
    along_W += along[k]["impact_power_W"].get<double>();
  }
  for (const auto& w : ln["impact_W_by_5deg"]) profile_W += w.get<double>();
  CHECK(along_W == Approx(profile_W).epsilon(1e-9));
  CHECK(lines_of(out / "spectra.csv").size() == 1 + 4 * 122);
  CHECK(static_cast<long>(lines_of(out / "wear.csv").size()) == 1 + ln["elements"].get<long>());
  // The folder holds a run now: a second run there is refused unless forced.
  CHECK_THROWS_WITH(mc::app::cmd_run(o), Catch::Contains("already holds a run"));
  fs::remove_all(out);
}

TEST_CASE("a window whose charge is still gaining energy: the console says so, and the books with it counted",
          "[outputs][books][cli]") {
  const fs::path out = fs::temp_directory_path() / ("millcharge_test_transient_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const fs::path log = out.string() + ".log";
  // A charge settled for only 0.1 s and a window from 0.05 s of turning:
  // its energy still changes a lot (it is still falling, and being lifted).
  const std::string cmd = std::string(MC_BINARY) +
                          " run --set mill.length=0.04 --set run.settle=0.1 --set run.warmup=0.05 --set "
                          "run.duration=0.2 --set run.snapshot_interval=0 --out '" +
                          out.string() + "' > '" + log.string() + "' 2>&1";
  REQUIRE(std::system(cmd.c_str()) == 0);
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  std::size_t at = text.find("the charge's energy rose at ");
  if (at == std::string::npos) at = text.find("the charge's energy fell at ");
  INFO(text);
  REQUIRE(at != std::string::npos);
  const std::size_t books = text.find("that rate: ", at);
  REQUIRE(books != std::string::npos);
  const double percent = std::strtod(text.c_str() + books + 11, nullptr);
  std::ifstream js(out / "summary.json");
  const nlohmann::json j = nlohmann::json::parse(js);
  const double torque = j["power_W"]["torque"], diss = j["power_W"]["dissipation"], de = j["power_W"]["energy_change"];
  std::printf("transient window: torque %.4g W, dissipation %.4g W, dE/dt %.4g W, books %+.2f %%\n", torque, diss, de,
              percent);
  CHECK(std::fabs(de) > 0.01 * torque);
  CHECK(std::fabs(j["power_W"]["imbalance"].get<double>()) > 0.02);
  CHECK(std::fabs(percent) < 2.0);
  CHECK(percent == Approx(100 * (torque - diss - de) / torque).margin(0.01));
  fs::remove_all(out);
  fs::remove(log);
}

TEST_CASE("a --duration shorter than the case's warm-up cuts the warm-up to half the run and says so",
          "[outputs][cli]") {
  const fs::path out = fs::temp_directory_path() / ("millcharge_test_short_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const fs::path err = out.string() + ".err";
  // The lab case's warm-up is 1.5 s; the run turns 0.2 s.
  const std::string cmd = std::string(MC_BINARY) + " run --duration 0.2 --set mill.length=0.06 --set run.settle=0.05 "
                          "--out '" + out.string() + "' --quiet > /dev/null 2> '" + err.string() + "'";
  REQUIRE(std::system(cmd.c_str()) == 0);
  std::ifstream e(err);
  const std::string message((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  CHECK_THAT(message, Catch::Contains("the warm-up is cut to 0.1 s, half the run"));
  std::ifstream js(out / "summary.json");
  const nlohmann::json j = nlohmann::json::parse(js);
  CHECK(j["average"]["from_s"].get<double>() == Approx(0.1).margin(2e-4));
  CHECK(j["average"]["to_s"].get<double>() == Approx(0.2).margin(2e-4));
  // The case as run keeps the cut warm-up: it resumes as it ran.
  std::ifstream ct(out / "case.toml");
  const std::string case_text((std::istreambuf_iterator<char>(ct)), std::istreambuf_iterator<char>());
  CHECK_THAT(case_text, Catch::Contains("warmup = 0.1"));
  fs::remove_all(out);
  fs::remove(err);
}

TEST_CASE("check gives a plant mill's power in MW and its charge in tonnes", "[outputs][cli]") {
  // mill_b: Morrell's 4.491e6 W and a 1.955e5 kg charge, as a plant reads them.
  const fs::path log = fs::temp_directory_path() / ("millcharge_test_check_units_" + std::to_string(::getpid()));
  const std::string cmd = std::string(MC_BINARY) + " check '" + (fs::path(MC_TEST_DATA) / ".." / ".." / "assets" /
                          "cases" / "mill_b.toml").string() + "' > '" + log.string() + "' 2>&1";
  REQUIRE(std::system(cmd.c_str()) == 0);
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CHECK_THAT(text, Catch::Contains("morrell c-model power 4.491 MW (k 1.26 x net 3.565 MW)"));
  CHECK_THAT(text, Catch::Contains("94,157 balls, 195.5 t;"));
  CHECK_THAT(text, !Catch::Contains(" W (") && !Catch::Contains("e+05 kg"));
  fs::remove(log);
}

TEST_CASE("a run shorter than a revolution says why it has no standard error, or gives a rough one marked so",
          "[outputs][cli]") {
  // The lab mill turns once in 1.769 s; its batches are eighths (0.221 s).
  struct Case {
    const char* duration;
    const char* kind;
    int batches;
  };
  for (const Case& k : {Case{"0.3", "none", 0}, Case{"1.0", "rough", 4}}) {
    const fs::path out = fs::temp_directory_path() / ("millcharge_test_sem_" + std::to_string(::getpid()));
    fs::remove_all(out);
    const fs::path log = out.string() + ".log";
    const std::string cmd = std::string(MC_BINARY) + " run --quiet --duration " + k.duration +
                            " --set run.warmup=0.1 --set mill.length=0.06 --set run.settle=0.05"
                            " --set run.snapshot_interval=0 --out '" + out.string() + "' > '" + log.string() + "' 2>&1";
    REQUIRE(std::system(cmd.c_str()) == 0);
    std::ifstream in(log);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ifstream js(out / "summary.json");
    const nlohmann::json j = nlohmann::json::parse(js);
    INFO(text);
    const auto& conv = j["convergence"];
    CHECK(conv["standard_errors"] == k.kind);
    CHECK(conv["batches"].get<int>() == k.batches);  // whole eighths in the window after 0.1 s
    CHECK(conv["standard_errors_why"].is_string());
    if (std::string(k.kind) == "none") {
      CHECK(j["power_W"]["torque_sem"].is_null());
      CHECK(j["toe_deg_sem"].is_null());
      // Half a revolution after the warm-up for a rough one, one for a whole one.
      CHECK_THAT(text, Catch::Contains("no standard error: the averaging window (0.2 s after the warm-up of 0.1 s)"));
      CHECK_THAT(text, Catch::Contains("turn at least 0.984 s for a rough error, 1.87 s"));
    } else {
      CHECK(j["power_W"]["torque_sem"].get<double>() > 0);
      CHECK(j["power_W"]["torque_sem"].get<double>() < 0.5 * j["power_W"]["torque"].get<double>());
      CHECK_THAT(text, Catch::Contains("\u00b1 a rough standard error, from 4 batches of 1/8 revolution"));
    }
    fs::remove_all(out);
    fs::remove(log);
  }
}
