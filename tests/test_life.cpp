// millcharge life end to end on a short lab mill: the volume each stage
// removes against what its run booked, the stations against the liner
// elements, a killed study resumed to the same table, and the refusals.
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/lifters.h"
#include "core/liner_wear.h"
#include "io/case_file.h"
#include "io/csv_read.h"
#include "life_cli.h"
#include "text_file.h"

namespace fs = std::filesystem;
using namespace life_cli;


TEST_CASE("a life study of the lab mill removes what its runs booked and resumes after a kill", "[life][cli]") {
  const fs::path a = scratch("unbroken"), b = scratch("killed");
  // Stages of 2,000 h at the default wear coefficient (5e-12: the bars
  // lose a few mm a stage).
  const std::string study = " --stages 2 --hours 4000" + kShort;
  std::string err;
  const int first = life(study + " --out '" + a.string() + "'", &err);
  INFO(err);
  REQUIRE(first == 0);

  // The table: three stages of the one profile, the lifter's top lower and
  // the mill wider each stage, the removed area the booked one within 1 %.
  const auto rows = read_csv(a / "life.csv");
  REQUIRE(rows.size() == 3);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    INFO("stage " << i);
    CHECK(num(rows[i], "stage") == i);
    CHECK(num(rows[i], "hours") == Approx(2000.0 * i));
    if (i + 1 < rows.size()) {
      CHECK(num(rows[i], "stage_hours") == Approx(2000.0));
      CHECK(num(rows[i], "booked_mm2") > 1.0);
      CHECK(num(rows[i], "removed_mm2") == Approx(num(rows[i], "booked_mm2")).epsilon(2e-5));  // 6 digits
      // The top wears back (its height above the new shell's line falls);
      // the shell wears too, so its height above the worn shell may not.
      CHECK(num(rows[i + 1], "height_mm") - num(rows[i + 1], "shell_wear_mm") <
            num(rows[i], "height_mm") - num(rows[i], "shell_wear_mm"));
      CHECK(num(rows[i + 1], "diameter_m") > num(rows[i], "diameter_m"));
      CHECK(num(rows[i + 1], "worn_area_mm2") ==
            Approx(num(rows[i], "worn_area_mm2") + num(rows[i], "removed_mm2")).epsilon(1e-3));
    }
    CHECK(num(rows[i], "power_W") > 500);
    // The shell and lifters' wear (not the end plates'): the stage run's
    // parts of that name, and its g/kWh over the run's power; uncalibrated
    // at the default coefficient, so relative.
    const nlohmann::json summary =
        nlohmann::json::parse(read_text(a / ("stage-0" + std::to_string(i)) / "summary.json"));
    double kg_h = 0, plates = 0;
    for (const auto& part : summary.at("liner").at("parts")) {
      const std::string name = part.at("part");
      if (name == "shell" || name.rfind("lifter", 0) == 0) kg_h += part.at("wear_kg_per_h").get<double>();
      if (name == "end plates") plates += part.at("wear_kg_per_h").get<double>();
    }
    REQUIRE(kg_h > 0);
    CHECK(plates > 0);
    CHECK(num(rows[i], "shell_lifters_wear_kg_per_h") == Approx(kg_h).epsilon(1e-5));  // 6 digits
    CHECK(summary.at("liner").at("wear_kg_per_h").get<double>() == Approx(kg_h + plates).epsilon(1e-9));
    const double watts = summary.at("power_W").at("torque").get<double>();
    CHECK(num(rows[i], "shell_lifters_g_per_kWh") == Approx(kg_h * 1e6 / watts).epsilon(1e-5));
    CHECK(rows[i].at("wear_basis") == "relative");
  }
  CHECK(num(rows[0], "height_mm") == Approx(25.0).epsilon(1e-6));
  CHECK(num(rows[0], "diameter_m") == Approx(0.9).epsilon(1e-9));
  CHECK(num(rows[2], "shell_wear_mm") ==
        Approx(500 * (num(rows[2], "diameter_m") - num(rows[0], "diameter_m"))).epsilon(1e-3));

  // Removed = booked to 1e-6 (life.json's full precision), and the booked
  // area is each stage run's own station volumes (lifter_wear.csv, nine
  // digits) times the stage's hours over the mill's length; the shell moved
  // by its run's mean rate (summary.json) times those hours.
  {
    const nlohmann::json life_json = nlohmann::json::parse(read_text(a / "life.json"));
    for (int i = 0; i < 2; ++i) {
      INFO("stage " << i);
      // The bars' length: the mill's, and the worn end plates' dish at the
      // shell on either end, from the stage's own case.
      const mc::MillCase sc = mc::io::read_case(a / "cases" / ("stage-0" + std::to_string(i) + ".toml"));
      double length = sc.length;
      for (const auto& d : sc.plate_depth)
        if (!d.empty()) length += d.back();
      if (i == 1) CHECK(length > sc.length + 1e-4);  // the plates have worn
      const nlohmann::json& w = life_json.at("stages").at(i).at("wear");
      const double booked = w.at("booked_mm2").at(0).get<double>(), removed = w.at("removed_mm2").at(0).get<double>();
      CHECK(std::fabs(removed - booked) <= 1e-6 * booked);
      const fs::path stage = a / ("stage-0" + std::to_string(i));
      double m3_s = 0;
      for (const auto& r : read_csv(stage / "lifter_wear.csv"))
        if (r.at("profile") == "0") m3_s += num(r, "wear_m3_per_s");
      const double hours = num(rows[i], "stage_hours");
      CHECK(booked == Approx(m3_s * hours * 3600 / length * 1e6).epsilon(1e-6));
      const nlohmann::json summary = nlohmann::json::parse(read_text(stage / "summary.json"));
      double shell_mm_per_1000h = -1;
      for (const auto& part : summary.at("liner").at("parts"))
        if (part.at("part") == "shell") shell_mm_per_1000h = part.at("mean_wear_mm_per_1000h").get<double>();
      const double shell_m = life_json.at("stages").at(i + 1).at("shell_wear_m").get<double>() -
                             life_json.at("stages").at(i).at("shell_wear_m").get<double>();
      CHECK(shell_m * 1000 == Approx(shell_mm_per_1000h * hours / 1000).epsilon(1e-9));
    }
  }

  // The stations of the first stage's run hold what its lifter elements
  // hold: each row's mean, times the rows.
  {
    double station_W = 0, station_m3_s = 0, element_W = 0, element_kg_h = 0;
    for (const auto& r : read_csv(a / "stage-00" / "lifter_wear.csv"))
      station_W += num(r, "impact_W"), station_m3_s += num(r, "wear_m3_per_s");
    for (const auto& r : read_csv(a / "stage-00" / "wear.csv"))
      if (r.at("part") == "lifter") element_W += num(r, "impact_W"), element_kg_h += num(r, "wear_kg_per_h");
    REQUIRE(element_W > 0);
    const mc::MillCase c = mc::io::read_case(a / "cases" / "stage-00.toml");
    const int rows_of_bars = c.lifter_rows;
    CHECK(station_W * rows_of_bars == Approx(element_W).epsilon(1e-3));
    CHECK(station_m3_s * rows_of_bars * 7800.0 * 3600 == Approx(element_kg_h).epsilon(1e-3));
  }

  // The worn stages' cases hold the worn outline as points, and read back.
  const mc::MillCase worn = mc::io::read_case(a / "cases" / "stage-02.toml");
  REQUIRE(worn.lifter_pattern.size() == 1);
  CHECK(worn.lifter_pattern[0].points.size() >= 4);
  CHECK(worn.diameter == Approx(num(rows[2], "diameter_m")).epsilon(1e-5));
  const nlohmann::json j = nlohmann::json::parse(read_text(a / "life.json"));
  CHECK(j.at("stopped").get<std::string>().find("4000 hours (relative: wear coefficient not calibrated) reached") !=
        std::string::npos);
  CHECK(j.at("calibration").at("hours_and_wear_rates") == "relative");
  CHECK(fs::exists(a / "life.png"));
  CHECK(fs::exists(a / "stage-02" / "liner.vtp"));
  const std::string pvd = read_text(a / "life.pvd");
  CHECK(pvd.find("stage-02/liner.vtp") != std::string::npos);

  // Killed in its second stage's run, then the same command: the same table.
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd =
        "exec " + std::string(MC_BINARY) + " life" + study + " --out '" + b.string() + "' >/dev/null 2>&1";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(300);
  while (!fs::exists(b / "stage-01" / "checkpoint.bin") && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, SIGKILL);
  int st = 0;
  ::waitpid(pid, &st, 0);
  REQUIRE(WIFSIGNALED(st));
  CHECK_FALSE(fs::exists(b / "stage-02"));
  const int resumed = life(study + " --out '" + b.string() + "'", &err);
  INFO(err);
  REQUIRE(resumed == 0);
  CHECK(read_text(b / "life.csv") == read_text(a / "life.csv"));

  // The same folder with another request is refused, and left as it was.
  const std::string table = read_text(a / "life.csv");
  CHECK(life(" --stages 2 --hours 6000" + kShort + " --out '" + a.string() + "'", &err) == 2);
  CHECK(err.find("holds a life study of another case or options") != std::string::npos);
  CHECK(read_text(a / "life.csv") == table);
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST_CASE("a stage that wears the lifters away stops the study by name and keeps what was written", "[life][cli]") {
  const fs::path dir = scratch("worn-away");
  std::string err;
  CHECK(life(" --stages 1 --hours 1e10" + kShort + " --out '" + dir.string() + "'", &err) == 2);
  CHECK(err.find("millcharge: lifters.profile[0]: stage 1 wears the lifter away") != std::string::npos);
  CHECK(std::count(err.begin(), err.end(), '\n') == 1);
  const auto rows = read_csv(dir / "life.csv");
  REQUIRE(rows.size() == 1);
  CHECK(num(rows[0], "height_mm") == Approx(25.0).epsilon(1e-6));
  CHECK(fs::exists(dir / "stage-00" / "summary.json"));
  CHECK_FALSE(fs::exists(dir / "stage-01"));
  const nlohmann::json j = nlohmann::json::parse(read_text(dir / "life.json"));
  CHECK(j.at("stopped").get<std::string>().find("wears the lifter away") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("bad life study requests are refused by name, status 2 and nothing written", "[life][cli]") {
  const fs::path out = scratch("bad");
  const std::string o = " --out '" + out.string() + "'";
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--stages 0 --hours 10", "--stages: must be a whole number from 1 to 100, got 0"},
      {"--stages 101 --hours 10", "--stages: must be a whole number from 1 to 100, got 101"},
      {"--stages 2", "give one of --hours H (operating hours the study covers) and --until-height MM"},
      {"--stages 2 --hours 0", "--hours: must be > 0 h, got 0"},
      {"--stages 2 --hours -5", "--hours: must be > 0 h, got -5"},
      {"--stages 2 --hours 10 --until-height 5", "give one of --hours H"},
      {"--stages 2 --until-height 0", "--until-height: must be > 0 mm, got 0"},
      {"--stages 2 --until-height 30", "--until-height 30: the new lifters are 25 mm high"},
      {"--stages 2 --hours 10 --set materials.liner.wear_coefficient=0",
       "materials.liner.wear_coefficient is 0: a life study needs the liner's wear coefficient > 0"},
      {"--stages 2 --hours 10 --calibrate-loss 10", "--calibrate-loss MM goes with --calibrate-hours H"},
      {"--stages 2 --hours 10 --calibrate-loss 30 --calibrate-hours 100",
       "--calibrate-loss 30: more than the new lifters' height"},
      {"--stages 2 --hours 10 --calibrate-loss 10 --calibrate-hours 100 --calibrate-rate 1",
       "--calibrate-rate and --calibrate-loss: give one measured figure"},
      {"--stages 2 --hours 10 --calibrate-consumption 0", "--calibrate-consumption: must be > 0 g/kWh, got 0"},
      {"--stages 2 --hours 10 --calibrate-consumption -2", "--calibrate-consumption: must be > 0 g/kWh, got -2"},
      {"--stages 2 --hours 10 --calibrate-consumption nan",
       "--calibrate-consumption: must be a number > 0 g/kWh, got \"nan\""},
      {"--stages 2 --hours 10 --calibrate-consumption inf",
       "--calibrate-consumption: must be a number > 0 g/kWh, got \"inf\""},
      {"--stages 2 --hours 10 --calibrate-consumption 4 --calibrate-rate 1",
       "--calibrate-consumption and --calibrate-rate: give one measured figure"},
      {"--stages 2 --hours 10 --calibrate-consumption 4 --calibrate-loss 10 --calibrate-hours 100",
       "--calibrate-consumption and --calibrate-loss: give one measured figure"},
      {"--stages 2 --hours 10 --set lifters.rows=0", "lifters.rows = 0: a life study wears lifter bars"},
      {"--stages 2 --hours 10 --impact-share 1.5", "--impact-share: must be from 0 to 1, got 1.5"},
      {"--stages 2 --hours 10 --shell-wear-ratio 0", "--shell-wear-ratio: must be from 0.01 to 100, got 0"},
      {"--stages 2 --hours 10 --impact-share 0.5 --set charge.size.0.shape=peanut",
       "--impact-share 0.5: charge.size[0] is a class of clumps"},
      {"--stages 2 --hours 10 --set charge.size.0.shape=peanut --set materials.liner.impact_wear_coefficient=1e-11",
       "materials.liner.impact_wear_coefficient: impact wear with a charge of clumps"},
      {"--stages 2 --hours 10 --impact-share -0.1", "--impact-share: must be from 0 to 1, got -0.1"},
      {"--stages 2 --hours 10 --impact-share nan", "--impact-share: must be a number from 0 to 1, got \"nan\""},
      {"--stages 2 --hours 10 --impact-share inf", "--impact-share: must be a number from 0 to 1, got \"inf\""},
      {"--stages 2 --hours 10 --set materials.liner.impact_wear_coefficient=-1e-12",
       "materials.liner.impact_wear_coefficient"},
      {"--stages 2 --hours 10 --set materials.liner.impact_wear_coefficient=nan",
       "materials.liner.impact_wear_coefficient"},
      {"--stages 2 --hours 10 --set materials.liner.impact_wear_coefficient=inf",
       "materials.liner.impact_wear_coefficient"},
      {"--stages 2 --hours 10 --set materials.liner.impact_wear_threshold_speed=-1",
       "materials.liner.impact_wear_threshold_speed"},
      {"--stages 2 --hours 10 --set lifters.profile.0.height=0.5", "lifters.profile[0].height"},
      {std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 2 --until-height 5",
       "--until-height: lifters.rows = 0: the lifters' height is followed on the bars of [lifters]"},
      {std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 2 --hours 10 --calibrate-loss 5 --calibrate-hours 9",
       "--calibrate-loss: lifters.rows = 0"},
      {std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 2 --hours 10 --shell-wear-ratio 2",
       "--shell-wear-ratio 2: walls.mesh[0] is worn as a liner of its own"},
      {std::string(MC_ASSET_DIR) +
           "/cases/lab_stl.toml --stages 2 --hours 10 --set walls.mesh.0.material=steel --set "
           "materials.steel.wear_coefficient=1e-12",
       "walls.mesh[0].material = \"steel\": a life study wears its meshes at the liner's"},
      {std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 2 --hours 10 --mesh-smoothing 0",
       "--mesh-smoothing"},
      // Bars of [lifters] with --axial-segments wear as their mesh twin:
      // what the twin cannot do.
      {"--stages 2 --hours 10 --axial-segments 3 --set mill.ends=periodic",
       "--axial-segments 3: the bars of [lifters] then wear as a mesh (their twin, triangle by triangle), and "
       "mill.ends = \"periodic\" makes a slice"},
      {"--stages 2 --calibrate-loss 5 --calibrate-hours 9 --axial-segments 3",
       "--calibrate-loss: --axial-segments 3: the bars of [lifters] then wear as a mesh"},
      {"--stages 2 --until-height 20 --axial-segments 3", "--until-height: --axial-segments 3"},
      {"--stages 2 --hours 10 --axial-segments 3 --shell-wear-ratio 2", "--shell-wear-ratio 2: --axial-segments 3"},
      {"--stages 2 --hours 10 --lifter-mesh 10", "--lifter-mesh: only with --axial-segments on a mill of [lifters]"},
      {"--stages 2 --hours 10 --axial-segments 3 --set mill.ends=cones --set mill.cone_angle=20 "
       "--set mill.trunnion_diameter=0.3",
       "cut at the end planes; this mill's ends are cones (mill.ends = \"cones\"), not planes"},
      {"--stages 2 --hours 10 --axial-segments 3 --set liner.plate_depth_mm=[[1,2,3,4],[1,2,3,4]]",
       "this mill's end plates are worn ([liner] plate_depth_mm), and its bars reach into their dish"},
      {"--stages 2 --hours 10 --axial-segments 3 --lifter-mesh 0.5 --set mill.length=4",
       "--lifter-mesh 0.5: the bars' twin would have about 5e+07 triangles (at most 2e+07)"},
      {std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 2 --hours 10 --axial-segments 2 --lifter-mesh 10",
       "--lifter-mesh: only with --axial-segments on a mill of [lifters]"},
      {"--stages 2 --hours 10 --axial-segments 3 --lifter-mesh 60",
       "--lifter-mesh 60: triangles up to 60 mm along the mill, longer than a segment (50 mm of --axial-segments 3)"},
      {std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 2 --hours 10 --axial-segments 7",
       "--axial-segments 7: segments of 0.02143 m, shorter than the largest ball (0.0254 m); give at most 5"},
      {std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 2 --hours 10 --axial-segments 0", "--axial-segments"},
      {std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 2 --hours 10 --set mill.ends=periodic",
       "mill.ends = \"periodic\": walls.mesh[0] would wear unevenly along the slice"},
      // A scanned liner that lies outside the shell or beyond the end plates.
      {std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 2 --hours 10 --set walls.mesh.0.offset=[0.01,0,0]",
       "walls.mesh[0]: ../meshes/lab_lifters.stl: triangle 1 lies outside the mill: a vertex at 0.46 m from the axis"},
      {std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 2 --hours 10 --set walls.mesh.0.offset=[0,0,0.01]",
       "the end plates are at z = 0 and 0.15 m"},
  };
  for (const auto& [args, expect] : bad) {
    std::string err;
    INFO(args << " -> " << err);
    CHECK(life(args + o, &err) == 2);
    CHECK(err.find(expect) != std::string::npos);
    CHECK_FALSE(fs::exists(out));
  }
  // A folder that holds something else is not taken over.
  fs::create_directories(out);
  std::ofstream(out / "notes.txt") << "mine\n";
  std::string err;
  CHECK(life("--stages 2 --hours 10" + o, &err) == 2);
  CHECK(err.find("exists and holds no life study") != std::string::npos);
  CHECK(read_text(out / "notes.txt") == "mine\n");
  fs::remove_all(out);
}

TEST_CASE("a lab run with its bars given as points is the h x w x theta run bit for bit", "[life][cli]") {
  // The lab bar, 25 mm x 30 mm with 20 degree faces, written as its outline
  // in the bar's frame, the base as profile_outline computes it.
  std::string lab = read_text(mc::io::default_case());
  const std::string bar = "height = 0.025";
  const std::size_t at = lab.find(bar);
  REQUIRE(at != std::string::npos);
  const std::size_t end = lab.find("face_angle = 20.0", at);
  REQUIRE(end != std::string::npos);
  const double half_top = 0.5 * 0.03, half_base = half_top + 0.025 * std::tan(20.0 * M_PI / 180.0);
  char points[256];
  std::snprintf(points, sizeof points, "points = [[%.17g, 0.0], [%.17g, 0.025], [%.17g, 0.025], [%.17g, 0.0]]",
                half_base, half_top, -half_top, -half_base);
  const std::string polygon = lab.substr(0, at) + points + lab.substr(lab.find('\n', end));
  const fs::path dir = scratch("polygon");
  fs::create_directories(dir);
  std::ofstream(dir / "polygon.toml") << polygon;
  const std::string shortrun =
      " --quiet --set run.duration=0.1 --set run.settle=0.05 --set run.warmup=0.05 --set run.snapshot_interval=0";
  auto run = [&](const std::string& c, const std::string& out) {
    const std::string cmd = std::string(MC_BINARY) + " run " + c + shortrun + " --out '" + (dir / out).string() +
                            "' > /dev/null 2>&1";
    return std::system(cmd.c_str());
  };
  REQUIRE(run("", "trapezoid") == 0);
  REQUIRE(run("'" + (dir / "polygon.toml").string() + "'", "polygon") == 0);
  const mc::MillCase c = mc::io::read_case(dir / "polygon" / "case.toml");
  REQUIRE(c.lifter_pattern.size() == 1);
  CHECK(c.lifter_pattern[0].points.size() == 4);
  const std::string a = read_text(dir / "trapezoid" / "timeseries.csv"), b = read_text(dir / "polygon" / "timeseries.csv");
  REQUIRE(a.size() > 1000);
  CHECK(a == b);
  CHECK(read_text(dir / "trapezoid" / "wear.csv") == read_text(dir / "polygon" / "wear.csv"));
  CHECK(read_text(dir / "trapezoid" / "lifter_wear.csv") == read_text(dir / "polygon" / "lifter_wear.csv"));
  fs::remove_all(dir);
}

TEST_CASE("an impact share of 0 is the sliding study, and a share of 1 wears by impact alone", "[life][cli][impact_wear]") {
  // The new liner's wear is the same whatever the share (only how it is
  // split); the shapes it wears to differ.
  const fs::path none = scratch("share-none"), zero = scratch("share-0"), one = scratch("share-1");
  // Long enough a window for two batches: its halves.
  const std::string study = " --stages 1 --hours 4000" + kShort + " --set run.duration=0.6";
  REQUIRE(life(study + " --out '" + none.string() + "'") == 0);
  REQUIRE(life(study + " --impact-share 0 --out '" + zero.string() + "'") == 0);
  REQUIRE(life(study + " --impact-share 1 --out '" + one.string() + "'") == 0);
  // The same runs, the same table: bit for bit.
  CHECK(read_text(none / "life.csv") == read_text(zero / "life.csv"));
  const auto a = read_csv(zero / "life.csv"), b = read_csv(one / "life.csv");
  REQUIRE(a.size() == 2);
  REQUIRE(b.size() == 2);
  CHECK(num(a[0], "impact_wear_share") == 0);
  CHECK(num(b[0], "impact_wear_share") == Approx(1).epsilon(1e-4));
  // Stage 0 ran the same case: the same wear in kg/h at either share.
  CHECK(num(b[0], "shell_lifters_wear_kg_per_h") ==
        Approx(num(a[0], "shell_lifters_wear_kg_per_h")).epsilon(1e-5));
  // The calibration block says what each coefficient came out at.
  const nlohmann::json j = nlohmann::json::parse(read_text(one / "life.json"));
  CHECK(j["calibration"]["impact_share"] == 1.0);
  CHECK(j["calibration"]["wear_coefficient_m3_per_N_m"] == 0.0);
  CHECK(j["calibration"]["impact_wear_coefficient_m3_per_J"].get<double>() > 0);
  // Impact wear moves the liner otherwise: the worn bar differs.
  CHECK(num(b[1], "leading_angle_deg") != num(a[1], "leading_angle_deg"));
  // The halves of the window add up to the whole: each station's sliding
  // wear and strike energy, rate times seconds.
  const nlohmann::json sj = nlohmann::json::parse(read_text(zero / "stage-00" / "summary.json"));
  REQUIRE(sj["liner"].contains("halves"));
  const double t1 = sj["liner"]["halves"][0]["window_s"], t2 = sj["liner"]["halves"][1]["window_s"];
  CHECK(t1 + t2 == Approx(sj["liner"]["window_s"].get<double>()).epsilon(1e-9));
  // The middle batch: within a batch of half the window (a batch is an
  // eighth of a revolution here, the window shorter than one).
  const double rev_s = 60.0 / sj["speed_rpm"].get<double>();
  CHECK(std::fabs(t1 - 0.5 * (t1 + t2)) <= rev_s / 8 + 1e-9);
  double whole = 0, halves = 0, strike = 0, strike_halves = 0;
  for (const auto& r : read_csv(zero / "stage-00" / "lifter_wear.csv")) {
    whole += num(r, "sliding_wear_m3_per_s") * (t1 + t2);
    halves += num(r, "first_half_sliding_wear_m3_per_s") * t1 + num(r, "second_half_sliding_wear_m3_per_s") * t2;
    strike += num(r, "strike_W") * (t1 + t2);
    strike_halves += num(r, "first_half_strike_W") * t1 + num(r, "second_half_strike_W") * t2;
  }
  CHECK(whole > 0);
  CHECK(halves == Approx(whole).epsilon(1e-6));
  // Each half booked its own part: neither is empty nor all of it.
  double first = 0;
  for (const auto& r : read_csv(zero / "stage-00" / "lifter_wear.csv"))
    first += num(r, "first_half_sliding_wear_m3_per_s") * t1;
  CHECK(first > 0.1 * whole);
  CHECK(first < 0.9 * whole);
  CHECK(strike_halves == Approx(strike).epsilon(1e-6));
  // The new liner is known exactly; the worn one carries the stage's noise.
  CHECK(num(a[0], "height_mm_se") == 0);
  CHECK(num(a[1], "leading_angle_deg_se") > 0);
  CHECK(num(a[1], "leading_angle_deg_se") < 2);
  // Again from the files: the new bar (life.json) worn for the stage's
  // hours by each half's station rates (lifter_wear.csv) and shell rate
  // (summary.json); half the difference of the two bars is the step's
  // error, which stage 1's row gives.
  {
    const nlohmann::json lj = nlohmann::json::parse(read_text(zero / "life.json"));
    const nlohmann::json& s0 = lj["stages"][0];
    std::vector<mc::Vec2> bar;
    for (const auto& pt : s0["profiles"][0]) bar.push_back({pt[0].get<double>(), pt[1].get<double>()});
    const double R = 0.5 * s0["diameter_m"].get<double>(), span = s0["wear"]["span_case_hours"].get<double>();
    std::vector<double> rate[2] = {std::vector<double>(mc::kWearStations, 0.0), std::vector<double>(mc::kWearStations, 0.0)};
    for (const auto& r : read_csv(zero / "stage-00" / "lifter_wear.csv"))
      if (num(r, "profile") == 0) {
        rate[0][static_cast<int>(num(r, "station"))] = num(r, "first_half_sliding_wear_m3_per_s");
        rate[1][static_cast<int>(num(r, "station"))] = num(r, "second_half_sliding_wear_m3_per_s");
      }
    mc::ProfileMeasures m[2];
    for (int h = 0; h < 2; ++h) {
      const double shell = sj["liner"]["halves"][h]["shell_sliding_wear_mm_per_1000h"].get<double>() * 1e-6;
      const mc::WornLifter w = mc::wear_for_hours(bar, R, mc::BarWearRates{rate[h], sj["length_m"].get<double>(), shell}, span);
      REQUIRE_FALSE(w.worn_away);
      m[h] = mc::measure_profile(w.outline);
    }
    const double se_h = 0.5 * std::fabs(m[0].height - m[1].height) * 1000,
                 se_lead = 0.5 * std::fabs(m[0].leading_angle_deg - m[1].leading_angle_deg);
    CHECK(num(a[1], "height_mm_se") == Approx(se_h).margin(1e-4));
    CHECK(num(a[1], "leading_angle_deg_se") == Approx(se_lead).margin(1e-4));
    CHECK(s0["wear"]["step_se"]["leading_angle_deg"][0].get<double>() == Approx(se_lead).epsilon(1e-9));
  }
  for (const fs::path& p : {none, zero, one}) fs::remove_all(p);
}
