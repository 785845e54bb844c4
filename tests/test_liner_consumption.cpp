// The liner's consumption in g/kWh (summary.json, the run's console) and
// life --calibrate-consumption: each figure against one computed here from
// what the outputs report (the worn volume, the liner's density, the power).
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/scene.h"
#include "io/csv_read.h"
#include "text_file.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("millcharge-consumption-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(p);
  return p;
}

// The command's exit status; its stdout and stderr in *log.
int millcharge(const std::string& args, std::string* log) {
  const fs::path f = scratch("log.txt");
  const int st = std::system((std::string(MC_BINARY) + " " + args + " > '" + f.string() + "' 2>&1").c_str());
  *log = read_text(f);
  fs::remove(f);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

// A short lab run: 60 mm of the lab mill's length, 0.3 s turned.
const std::string kShortRun =
    " --set mill.length=0.06 --set run.settle=0.05 --set run.warmup=0.1 --set run.duration=0.3"
    " --set run.snapshot_interval=0";

// Grams per kWh by hand from wear.csv: each element's worn volume per hour
// (its depth rate, mm per 1000 h, times its area), times the liner's
// density, over the power drawn (kW), for the elements of `parts`.
double g_per_kWh_by_hand(const fs::path& run, const std::string& parts, double density, double power_W) {
  const mc::io::CsvTable t = mc::io::read_csv_strict(run / "wear.csv");
  const int c_part = t.column("part"), c_area = t.column("area_m2"), c_depth = t.column("wear_mm_per_1000h");
  double m3_per_h = 0;
  for (std::size_t k = 0; k < t.rows.size(); ++k)
    if (parts.find("," + t.rows[k][c_part] + ",") != std::string::npos)
      m3_per_h += t.number(k, c_depth) * 1e-3 / 1000 * t.number(k, c_area);  // mm per 1000 h to m per h
  const double g_per_h = m3_per_h * density * 1000;
  return g_per_h / (power_W / 1000);
}

double shell_and_lifters_kg_h(const json& summary) {
  double kg_h = 0;
  for (const json& p : summary.at("liner").at("parts")) {
    const std::string name = p.at("part");
    if (name == "shell" || name.rfind("lifter", 0) == 0) kg_h += p.at("wear_kg_per_h").get<double>();
  }
  return kg_h;
}

}  // namespace

TEST_CASE("a run's liner consumption in g/kWh is its worn steel over the energy drawn, by part, and says if relative",
          "[outputs][wear][cli]") {
  const fs::path out = scratch("run"), doubled = scratch("run-2k");
  std::string log;
  REQUIRE(millcharge("run" + kShortRun + " --out '" + out.string() + "'", &log) == 0);
  INFO(log);
  const json j = json::parse(read_text(out / "summary.json"));
  const double P = j.at("power_W").at("torque").get<double>();
  REQUIRE(P > 0);
  const json& use = j.at("liner").at("consumption_g_per_kWh");
  // wear.csv prints depth and area to 6 digits: 1e-5 on a product, 2e-5 with margin.
  const double shell_lifters = g_per_kWh_by_hand(out, ",shell,lifter,", 7800.0, P);
  const double plates = g_per_kWh_by_hand(out, ",plate,", 7800.0, P);
  REQUIRE(shell_lifters > 0);
  CHECK(use.at("shell_and_lifters").get<double>() == Approx(shell_lifters).epsilon(2e-5));
  CHECK(use.at("end_plates").get<double>() == Approx(plates).epsilon(2e-5));
  CHECK(use.at("all").get<double>() == Approx(shell_lifters + plates).epsilon(2e-5));
  CHECK(use.at("power_W").get<double>() == P);
  // The total kg/h (console and summary) is all the parts; the shell and
  // lifters' share alone is what a life study's table gives.
  CHECK(j.at("liner").at("wear_kg_per_h").get<double>() * 1e6 / P == Approx(shell_lifters + plates).epsilon(2e-5));
  // The default wear coefficient: relative, and said so.
  CHECK(j.at("liner").at("wear_coefficient_m3_per_N_m").get<double>() == mc::kDefaultWearCoefficient);
  CHECK(use.at("relative").get<bool>());
  CHECK_THAT(j.at("liner").at("wear_rates").get<std::string>(),
             Catch::StartsWith("relative: wear coefficient not calibrated"));
  // The console: the same figures, named.
  CHECK_THAT(log, Catch::Contains(" kg/h (shell, lifters, end plates), worst "));
  const std::size_t at = log.find("consumption     shell and lifters ");
  REQUIRE(at != std::string::npos);
  CHECK(std::strtod(log.c_str() + at + 34, nullptr) == Approx(shell_lifters).epsilon(5e-3));  // %.3g
  const std::size_t plate_at = log.find(", end plates ", at);
  REQUIRE(plate_at != std::string::npos);
  CHECK(std::strtod(log.c_str() + plate_at + 13, nullptr) == Approx(plates).epsilon(5e-3));
  CHECK_THAT(log, Catch::Contains("the wear figures are relative: wear coefficient not calibrated"));

  // Twice the wear coefficient (not the default): Archard's volume is
  // linear in k, so every g/kWh doubles; the figures are no longer relative.
  char k2[32];
  std::snprintf(k2, sizeof k2, "%.17g", 2 * mc::kDefaultWearCoefficient);
  REQUIRE(millcharge("run" + kShortRun + " --set materials.liner.wear_coefficient=" + std::string(k2) + " --out '" +
                         doubled.string() + "'",
                     &log) == 0);
  const json j2 = json::parse(read_text(doubled / "summary.json"));
  const json& use2 = j2.at("liner").at("consumption_g_per_kWh");
  // The same run bit for bit but for the wear's scale: float books, 1e-5.
  CHECK(j2.at("power_W").at("torque").get<double>() == P);
  CHECK(use2.at("shell_and_lifters").get<double>() == Approx(2 * use.at("shell_and_lifters").get<double>()).epsilon(1e-5));
  CHECK(use2.at("end_plates").get<double>() == Approx(2 * use.at("end_plates").get<double>()).epsilon(1e-5));
  CHECK_FALSE(use2.at("relative").get<bool>());
  CHECK(j2.at("liner").at("wear_rates") == "at the case's wear coefficient");
  CHECK_THAT(log, !Catch::Contains("relative"));
  fs::remove_all(out);
  fs::remove_all(doubled);
}

TEST_CASE("life --calibrate-consumption sets the new liner's g/kWh to the plant's and says what it covers",
          "[life][wear][cli]") {
  const fs::path out = scratch("life");
  constexpr double kTarget = 3.7;  // g/kWh
  std::string log;
  // Hours the default would wear through in one stage were it not scaled:
  // calibrated, 3.7 g/kWh against the default's few g/kWh.
  REQUIRE(millcharge("life --stages 1 --hours 500 --calibrate-consumption 3.7 --set mill.length=0.06 --set "
                     "run.duration=0.15 --set run.settle=0.05 --set run.warmup=0.05 --set run.snapshot_interval=0 "
                     "--out '" + out.string() + "'",
                     &log) == 0);
  INFO(log);
  const json life = json::parse(read_text(out / "life.json"));
  const json& cal = life.at("calibration");
  const double factor = cal.at("factor").get<double>();
  CHECK(cal.at("hours_and_wear_rates") == "calibrated");
  CHECK_THAT(cal.at("how").get<std::string>(), Catch::Contains("3.7 g/kWh measured"));
  // The first stage's run, by hand: its shell and lifters' kg/h times the
  // factor, over its power, is the plant's figure.
  const json s0 = json::parse(read_text(out / "stage-00" / "summary.json"));
  const double P = s0.at("power_W").at("torque").get<double>();
  const double g0 = shell_and_lifters_kg_h(s0) * 1e6 / P;
  REQUIRE(g0 > 0);
  CHECK(std::fabs(g0 * factor - kTarget) <= 1e-6 * kTarget);
  // The run's own figure is the one life calibrates (one definition of
  // what plants weigh as shell liners).
  CHECK(s0.at("liner").at("consumption_g_per_kWh").at("shell_and_lifters").get<double>() ==
        Approx(g0).epsilon(1e-9));
  // The calibration scales the wear applied: the stage's 500 h are 500 x
  // factor hours at the case's coefficient.
  const mc::io::CsvTable tc = mc::io::read_csv_strict(out / "life.csv");
  CHECK(tc.number(1, tc.column("case_hours")) == Approx(500 * factor).epsilon(1e-5));
  // The wear coefficient it implies: the case's times the factor.
  CHECK(cal.at("wear_coefficient_m3_per_N_m").get<double>() ==
        Approx(mc::kDefaultWearCoefficient * factor).epsilon(1e-12));
  // life.csv's row of stage 0 (6 digits).
  const mc::io::CsvTable t = mc::io::read_csv_strict(out / "life.csv");
  CHECK(t.number(0, t.column("shell_lifters_g_per_kWh")) == Approx(kTarget).epsilon(1e-5));
  CHECK(t.number(0, t.column("shell_lifters_wear_kg_per_h")) ==
        Approx(shell_and_lifters_kg_h(s0) * factor).epsilon(1e-5));
  CHECK(t.rows[0][t.column("wear_basis")] == "calibrated");
  CHECK(t.number(1, t.column("hours")) == Approx(500).epsilon(1e-6));
  CHECK_THAT(log, Catch::Contains("calibrated on the new shell and lifters' consumption"));
  // The study's own lines (not its stages' runs, which report at the case's
  // coefficient) call nothing relative.
  for (std::size_t at = log.find("\nlife "); at != std::string::npos; at = log.find("\nlife ", at + 1))
    CHECK(log.substr(at, log.find('\n', at + 1) - at).find("relative") == std::string::npos);
  fs::remove_all(out);
}
