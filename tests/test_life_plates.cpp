// The end plates over a life study: each ring's wear rate and its standard
// error from its sectors, against sums by hand; a step removes what it
// booked; a short lab study's plates deepen by what its stage-0 run booked
// (read back from that run's wear.csv here), the next stage's case holds
// them, a rerun resumes them, --hold-plates holds them, a study begun
// before the plates wore resumes with them held, and a damaged state is
// refused by name.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/commands.h"
#include "app/life_options.h"
#include "app/prepare.h"
#include "core/plate_wear.h"
#include "io/case_file.h"
#include "life/plates.h"
#include "life_cli.h"
#include "text_file.h"

namespace fs = std::filesystem;
using namespace life_cli;
using mc::life::PlateBooks;

TEST_CASE("a plate ring's wear rate and its error come from its sectors", "[life][plates]") {
  PlateBooks b;
  const int rings = 3, sectors = 4;
  for (int p = 0; p < 2; ++p)
    for (int j = 0; j < rings; ++j) {
      b.sliding_m3_s[p].push_back({});
      b.strike_W[p].push_back({});
      for (int s = 0; s < sectors; ++s) {
        b.sliding_m3_s[p][j].push_back(1e-12 * (1 + j + s + p));
        b.strike_W[p][j].push_back(0.01 * (s + 1));
      }
    }
  const double R = 0.3, sliding = 2.0, impact = 3e-12;
  const mc::life::PlateRates r = mc::life::plate_rates(b, sliding, impact, R);
  for (int p = 0; p < 2; ++p)
    for (int j = 0; j < rings; ++j) {
      // By hand: each sector's depth rate over its share of the ring's area.
      const double ring_area = M_PI * R * R * ((j + 1) * (j + 1) - j * j) / (rings * rings);
      std::vector<double> v;
      for (int s = 0; s < sectors; ++s)
        v.push_back((sliding * 1e-12 * (1 + j + s + p) + impact * 0.01 * (s + 1)) * 3600 / (ring_area / sectors));
      double mean = 0, var = 0;
      for (double x : v) mean += x / sectors;
      for (double x : v) var += (x - mean) * (x - mean) / (sectors - 1);
      CHECK(r.m_per_h[p][j] == Approx(mean).epsilon(1e-12));
      CHECK(r.se_m_per_h[p][j] == Approx(std::sqrt(var / sectors)).epsilon(1e-9));
    }
  // A step of 500 h: the depths, and booked = removed where no node is held.
  const std::array<std::vector<double>, 2> before{std::vector<double>{1e-3, 1.2e-3, 1.5e-3},
                                                  std::vector<double>{0, 0, 0}};
  const mc::life::PlateStep st = mc::life::wear_plates(before, r, 500, R);
  for (int p = 0; p < 2; ++p) {
    double booked = 0;
    for (int j = 0; j < rings; ++j) {
      const double ring_area = M_PI * R * R * ((j + 1) * (j + 1) - j * j) / (rings * rings);
      // The face's ring mean moves by the booked depth (none is held here).
      CHECK(st.depth[p][j] >= before[p][j]);
      CHECK(mc::plate_ring_means(st.depth[p], R / rings)[j] - mc::plate_ring_means(before[p], R / rings)[j] ==
            Approx(500 * r.m_per_h[p][j]).epsilon(1e-9));
      CHECK(st.booked_m3[p][j] == Approx(500 * r.m_per_h[p][j] * ring_area).epsilon(1e-12));
      CHECK(st.removed_m3[p][j] == Approx(st.booked_m3[p][j]).epsilon(1e-9));
      booked += st.booked_m3[p][j];
    }
    CHECK(mc::plate_worn_volume(st.depth[p], R) - mc::plate_worn_volume(before[p], R) == Approx(booked).epsilon(1e-12));
  }
}

TEST_CASE("a life study wears the lab mill's end plates by what its runs booked", "[life][plates][cli]") {
  const fs::path a = scratch("plates"), held = scratch("plates-held");
  const std::string study = " --stages 1 --hours 3000" + kShort;
  std::string err;
  REQUIRE(life(study + " --out '" + a.string() + "'", &err) == 0);
  INFO(err);
  // Stage 0's booking by hand from its run's wear.csv: per plate and ring,
  // the sliding wear (mm per 1000 h over each sector's area) and the
  // strike energy at the case's impact coefficient, over the ring's area.
  const mc::MillCase c = mc::io::read_case(a / "cases" / "stage-01.toml");
  double k_impact = -1;
  for (const mc::Material& m : c.materials)
    if (m.name == c.liner) k_impact = m.impact_wear_coefficient;
  REQUIRE(k_impact >= 0);
  const auto wear = read_csv(a / "stage-00" / "wear.csv");
  double vol[2][4] = {}, area[2][4] = {};
  int plate_rows = 0;
  for (const auto& row : wear) {
    if (row.at("part") != "plate") continue;
    ++plate_rows;
    const int p = static_cast<int>(num(row, "row")), j = static_cast<int>(num(row, "face_or_bin"));
    REQUIRE(j < 4);
    const double ar = num(row, "area_m2");
    vol[p][j] += num(row, "sliding_wear_mm_per_1000h") * 1e-6 * ar + k_impact * num(row, "strike_W") * 3600;  // m³ per h
    area[p][j] += ar;
  }
  CHECK(plate_rows == 2 * 4 * 12);  // two plates, 4 rings, a sector per lifter row
  const auto rows = read_csv(a / "life_plates.csv");
  REQUIRE(rows.size() == 2 * 2 * 4);  // stages 0 and 1, two plates, four rings
  REQUIRE(c.plate_depth[0].size() == 4);
  double deepest = 0;
  for (const auto& row : rows) {
    const int p = static_cast<int>(num(row, "plate")), j = static_cast<int>(num(row, "ring"));
    const double rate = vol[p][j] / area[p][j];  // m per h
    if (num(row, "stage") == 0) {
      INFO("plate " << p << " ring " << j);
      CHECK(num(row, "depth_mm") == 0);
      CHECK(num(row, "wear_mm_per_1000h") == Approx(rate * 1e6).epsilon(1e-4).margin(1e-9));
      CHECK(num(row, "step_booked_cm3") == Approx(rate * 3000 * area[p][j] * 1e6).epsilon(1e-4).margin(1e-9));
    } else {
      // Each ring's face lost what it booked (its mean depth), but the
      // centre, whose step is held where it booked little beside a worn ring.
      if (j > 0) CHECK(num(row, "mean_depth_mm") == Approx(rate * 3000 * 1e3).epsilon(2e-4).margin(1e-9));
      // The next stage ran on that face: its case holds it.
      CHECK(c.plate_depth[p][j] * 1e3 == Approx(num(row, "depth_mm")).epsilon(1e-4).margin(1e-9));
      deepest = std::max(deepest, num(row, "depth_mm"));
    }
  }
  CHECK(deepest > 0.3);  // the plates do wear in 3,000 h at the default coefficient
  // Removed against booked per plate: within 1 %.
  for (int p = 0; p < 2; ++p) {
    double booked = 0, removed = 0;
    for (const auto& row : rows)
      if (num(row, "stage") == 0 && num(row, "plate") == p)
        booked += num(row, "step_booked_cm3"), removed += num(row, "step_removed_cm3");
    CHECK(removed == Approx(booked).epsilon(0.01));
  }
  CHECK(fs::file_size(a / "life_plates.png") > 10000);
  // Resumed as it stands: nothing runs, the same table.
  const std::string table = read_text(a / "life_plates.csv");
  REQUIRE(life(study + " --out '" + a.string() + "'") == 0);
  CHECK(read_text(a / "life_plates.csv") == table);
  // A damaged state: a worn plate that grew back.
  nlohmann::json j = nlohmann::json::parse(read_text(a / "life.json"));
  const nlohmann::json good = j;
  j["stages"][1]["plate_depth_mm"][0][2] = -0.5;
  std::ofstream(a / "life.json") << j.dump(1);
  std::string why;
  CHECK(life(study + " --out '" + a.string() + "'", &why) == 2);
  CHECK(why.find("stage 1: plate_depth_mm[0][2]: below 0") != std::string::npos);
  j = good;
  j["stages"][1]["plate_depth_mm"][1][2] = 1.01 * j["stages"][1]["plate_depth_mm"][1][2].get<double>();
  std::ofstream(a / "life.json") << j.dump(1);
  CHECK(life(study + " --out '" + a.string() + "'", &why) == 2);
  CHECK(why.find("stage 1: plate_depth_mm[1][") != std::string::npos);  // ring 2 or a neighbour whose face it shares
  CHECK(why.find("where the step removed") != std::string::npos);
  j = good;
  j["stages"][0]["plate_depth_mm"][0][1] = 0.5;  // the case's plates are new
  std::ofstream(a / "life.json") << j.dump(1);
  CHECK(life(study + " --out '" + a.string() + "'", &why) == 2);
  CHECK(why.find("stage 0: plate_depth_mm[0][1]") != std::string::npos);
  // A study begun before the plates wore (no end_plates in its request, no
  // plate keys): it resumes with them held.
  j = good;
  j["request"].erase("end_plates");
  for (auto& s : j["stages"]) {
    s.erase("plate_depth_mm");
    if (s.contains("result")) s["result"].erase("plate_sliding_wear_m3_per_s"), s["result"].erase("plate_strike_W");
    if (s.contains("wear")) s["wear"].erase("plate_booked_m3"), s["wear"].erase("plate_removed_m3");
  }
  // Part-way: its last stage's run read again, and the study ended anew.
  j.erase("stopped");
  j["stages"][1]["ran"] = false;
  j["stages"][1].erase("result");
  std::ofstream(a / "life.json") << j.dump(1);
  CHECK(life(study + " --out '" + a.string() + "'", &why) == 0);
  CHECK(why.empty());
  const nlohmann::json resumed = nlohmann::json::parse(read_text(a / "life.json"));
  CHECK(resumed["stages"][1]["ran"] == true);
  CHECK(resumed.contains("stopped"));
  CHECK(!resumed["request"].contains("end_plates"));
  CHECK(!resumed["stages"][1].contains("plate_depth_mm"));
  CHECK(!resumed["stages"][1]["result"].contains("plate_strike_W"));

  // --hold-plates: the plates stay; the request says so.
  REQUIRE(life(study + " --hold-plates --out '" + held.string() + "'") == 0);
  CHECK(!fs::exists(held / "life_plates.csv"));
  CHECK(mc::io::read_case(held / "cases" / "stage-01.toml").plate_depth[0].empty());
  CHECK(nlohmann::json::parse(read_text(held / "life.json"))["request"]["end_plates"] == "held");
  // The same folder without it is another study.
  CHECK(life(study + " --out '" + held.string() + "'", &why) == 2);
  CHECK(why.find("end_plates") != std::string::npos);
  fs::remove_all(a);
  fs::remove_all(held);
}

TEST_CASE("the plates wear at the study's mix and calibration, and end lifters hold them", "[life][plates][cli]") {
  const fs::path a = scratch("plates-mix");
  const std::string study = " --stages 1 --hours 3000 --impact-share 0.5 --calibrate-consumption 10" + kShort;
  std::string err;
  REQUIRE(life(study + " --out '" + a.string() + "'", &err) == 0);
  INFO(err);
  // The study's coefficients as life.json states them: the sliding wear
  // booked at the case's coefficient times their ratio, and the strike
  // energy times the impact coefficient, both on calibrated hours.
  const nlohmann::json cal = nlohmann::json::parse(read_text(a / "life.json"))["calibration"];
  const double ks = cal["wear_coefficient_m3_per_N_m"].get<double>() / cal["case_wear_coefficient_m3_per_N_m"].get<double>();
  const double ki = cal["impact_wear_coefficient_m3_per_J"].get<double>();
  CHECK(ki > 0);
  CHECK(cal["factor"].get<double>() != Approx(1.0));
  double vol[2][4] = {}, area[2][4] = {};
  for (const auto& row : read_csv(a / "stage-00" / "wear.csv")) {
    if (row.at("part") != "plate") continue;
    const int p = static_cast<int>(num(row, "row")), j = static_cast<int>(num(row, "face_or_bin"));
    const double ar = num(row, "area_m2");
    vol[p][j] += ks * num(row, "sliding_wear_mm_per_1000h") * 1e-6 * ar + ki * num(row, "strike_W") * 3600;
    area[p][j] += ar;
  }
  int checked = 0;
  for (const auto& row : read_csv(a / "life_plates.csv"))
    if (num(row, "stage") == 0) {
      const int p = static_cast<int>(num(row, "plate")), j = static_cast<int>(num(row, "ring"));
      INFO("plate " << p << " ring " << j);
      CHECK(num(row, "wear_mm_per_1000h") == Approx(vol[p][j] / area[p][j] * 1e6).epsilon(1e-4).margin(1e-9));
      CHECK(row.at("wear_basis") == "calibrated");
      ++checked;
    }
  CHECK(checked == 8);
  fs::remove_all(a);

  // End lifters stand on the plates: a study holds them, and says why.
  mc::app::LifeOptions o;
  o.stages = 1;
  o.hours = 1000;
  o.c.overrides = {"end_lifters.rows=12", "end_lifters.height=0.02", "end_lifters.width=0.02"};
  const mc::app::Prepared with = mc::app::prepare(o.c);
  CHECK(mc::app::life_request(o, with, 0)["end_plates"] == "held");
  o.c.overrides.clear();
  CHECK(mc::app::life_request(o, mc::app::prepare(o.c), 0)["end_plates"] == "worn");
  o.hold_plates = true;
  CHECK(mc::app::life_request(o, mc::app::prepare(o.c), 0)["end_plates"] == "held");
}
