// millcharge life-compare: studies' figures at the same hours, and the
// refusals, on life.csv files written here (no study is run).
#include <catch2/catch.hpp>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "app/life_compare.h"
#include "io/csv_read.h"

namespace fs = std::filesystem;
using namespace mc::app::life;

namespace {

const char* kHeader =
    "stage,hours,case_hours,profile,height_mm,top_width_mm,leading_angle_deg,trailing_angle_deg,area_mm2,"
    "worn_area_mm2,shell_wear_mm,diameter_m,power_W,power_sem_W,toe_deg,shoulder_deg,impact_point_deg,"
    "bare_liner_impact_share,shell_lifters_wear_kg_per_h,shell_lifters_g_per_kWh,top_wear_mm_per_1000h,stage_hours,"
    "booked_mm2,removed_mm2,wear_basis,impact_wear_share,height_mm_se,leading_angle_deg_se,trailing_angle_deg_se\n";

// A study of two profiles whose figures are straight lines in the hours
// (so that any interpolation between stages is exact), profile 1 offset.
fs::path write_study(const fs::path& dir, double hours_per_stage, int stages, bool with_se, double slope = 0.01) {
  fs::create_directories(dir);
  std::ofstream f(dir / "life.csv");
  f << kHeader;
  for (int s = 0; s <= stages; ++s)
    for (int k = 0; k < 2; ++k) {
      const double h = s * hours_per_stage;
      // life writes 0 for the new liner's error.
      const std::string se = with_se ? std::to_string(0.1 * s) : "";
      f << s << "," << h << "," << h << "," << k << "," << 150 - 0.02 * h << ",100," << 14 + slope * h + 5 * k << ","
        << 14 + 0.002 * h << ",1,0," << 0.01 * h << ",8.26,387000,1500,240,45," << 230 + 0.001 * h
        << ",0.8,2,5,30,,,," << "calibrated,0.1," << se << "," << se << "," << se << "\n";
    }
  return dir;
}

int cli(const std::string& args, const fs::path& log) {
  const int st = std::system((std::string(MC_BINARY) + " life-compare " + args + " >'" + log.string() + "' 2>&1").c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

}  // namespace

TEST_CASE("life-compare: a study's figures between its stages are interpolated in the hours", "[life][compare]") {
  const fs::path dir = fs::temp_directory_path() / "mc_compare_interp";
  fs::remove_all(dir);
  const StudyPath a = read_study_path(write_study(dir / "a", 700, 6, true), "a", 0);
  REQUIRE(a.hours.size() == 7);
  // 14 + 0.01 h on stages 700 h apart: at 1000 h (between 700 and 1400) 24.
  CHECK(a.at(0, 1000) == Approx(24.0).margin(1e-9));
  CHECK(a.at(1, 2500) == Approx(150 - 50.0).margin(1e-9));
  CHECK(a.at(3, 4200) == Approx(42.0).margin(1e-9));  // the last stage exactly
  // The standard errors: 0.1 s at stage s; 1000 h is t = 300/700 of the way from 0.1 to 0.2, the stage's own
  // error (its variance 0.03 at the end) grown in proportion to t.
  const double t = 300.0 / 700;
  CHECK(a.at(0, 1000, true) == Approx(std::sqrt(0.01 + t * t * 0.03)).margin(1e-9));
  CHECK(a.at(0, 350, true) == Approx(0.5 * 0.1).margin(1e-9));  // up from the new liner's 0: in proportion
  const StudyPath none = read_study_path(write_study(dir / "b", 700, 6, false), "b", 0);
  CHECK(std::isnan(none.at(0, 1000, true)));  // a study without errors has none between its stages
  CHECK(std::isnan(a.at(0, 4300)));       // beyond the study
  // Profile 1 is profile 0 five degrees on.
  const StudyPath b = read_study_path(dir / "a", "a", 1);
  CHECK(b.at(0, 1000) == Approx(29.0).margin(1e-9));

  const Measured m = parse_measured("leading_angle_deg@4000=47.1");
  CHECK(m.figure == 0);
  CHECK(m.hours == 4000);
  const Against x = against(a, m);
  CHECK(x.value == Approx(54.0).margin(1e-9));
  CHECK(x.difference == Approx(6.9).margin(1e-9));
  const double se4000 = std::sqrt(0.25 + (0.36 - 0.25) * (500.0 / 700) * (500.0 / 700));
  CHECK(x.se == Approx(se4000).margin(1e-9));
  CHECK(x.in_se == Approx(6.9 / se4000).margin(1e-9));
  fs::remove_all(dir);
}

TEST_CASE("life-compare: compare.csv holds each study at the hours asked", "[life][compare]") {
  const fs::path dir = fs::temp_directory_path() / "mc_compare_cli";
  fs::remove_all(dir);
  write_study(dir / "slow", 500, 8, false, 0.005);
  write_study(dir / "fast", 1000, 5, true, 0.01);
  REQUIRE(cli("'" + (dir / "slow").string() + "' '" + (dir / "fast").string() +
                  "' --label slow --label fast --at 1000,3000 --measured leading_angle_deg@4000=47.2 --out '" +
                  (dir / "cmp").string() + "'",
              dir / "log.txt") == 0);
  const mc::io::CsvTable t = mc::io::read_csv_strict(dir / "cmp" / "compare.csv");
  REQUIRE(t.rows.size() == 4);
  const int lead = t.column("leading_angle_deg"), se = t.column("leading_angle_deg_se");
  CHECK(t.rows[0][0] == "slow");
  CHECK(t.number(0, lead) == Approx(19.0).margin(1e-4));  // 14 + 0.005 x 1000
  CHECK(t.number(3, lead) == Approx(44.0).margin(1e-4));  // 14 + 0.01 x 3000
  CHECK(t.rows[1][se].empty());                            // the slow study has no errors
  CHECK(t.number(3, se) == Approx(0.3).margin(1e-4));
  CHECK(fs::file_size(dir / "cmp" / "compare.png") > 10000);
  std::string log = slurp(dir / "log.txt");
  CHECK(log.find("different grounds") == std::string::npos);
  CHECK(log.find("leading_angle_deg at 4000 h, fast: 54.0 ± 0.4 against 47.2 measured (+6.8, 17.0 standard errors)") !=
        std::string::npos);
  // A study whose hours are relative beside a calibrated one: compared, with a note.
  {
    std::string text = slurp(dir / "slow" / "life.csv");
    for (std::size_t at; (at = text.find(",calibrated,")) != std::string::npos;) text.replace(at, 12, ",relative,");
    std::ofstream(dir / "slow" / "life.csv") << text;
  }
  REQUIRE(cli("'" + (dir / "slow").string() + "' '" + (dir / "fast").string() + "' --out '" + (dir / "cmp2").string() + "'",
              dir / "log.txt") == 0);
  log = slurp(dir / "log.txt");
  CHECK(log.find("the studies' hours stand on different grounds (slow relative, fast calibrated)") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("life-compare: bad input is named and nothing is written", "[life][compare]") {
  const fs::path dir = fs::temp_directory_path() / "mc_compare_bad";
  fs::remove_all(dir);
  write_study(dir / "a", 500, 4, true);  // to 2000 h
  const std::string a = "'" + (dir / "a").string() + "'";
  const std::string out = " --out '" + (dir / "cmp").string() + "'";
  const fs::path log = dir / "log.txt";
  struct Case {
    std::string args, says;
  };
  const Case cases[] = {
      {a + " --at 2500", "--at 2500: study a"},
      {a + " --measured face@100=3", "--measured face@100=3: the column is one of leading_angle_deg"},
      {a + " --measured power_W@100=3", "the column is one of"},
      {a + " --measured leading_angle_deg@x=3", "the hours are not a number"},
      {a + " --label one --label two", "--label: given 2 times for 1 studies"},
      {a + " " + a, "two studies have this label"},
      {a + " --profile 2", "--profile 2: the study has lifter profiles 0 to 1"},
      {"'" + (dir / "none").string() + "'", "not a folder"},
      {"'" + dir.string() + "'", "life.csv"},
  };
  for (const Case& c : cases) {
    INFO(c.args);
    CHECK(cli(c.args + out, log) == 2);
    CHECK(slurp(log).find(c.says) != std::string::npos);
    CHECK_FALSE(fs::exists(dir / "cmp"));
  }
  // A measured point beyond a study's end is drawn, not compared.
  CHECK(cli(a + " --measured leading_angle_deg@3000=40" + out, log) == 0);
  CHECK(slurp(log).find("leading_angle_deg at 3000 h, a: the study ends at 2000 h") != std::string::npos);
  fs::remove_all(dir / "cmp");
  // A study whose hours go back.
  {
    std::ofstream f(dir / "a" / "life.csv", std::ios::app);
    f << "5,100,100,0,100,100,30,20,1,0,1,8.26,387000,1500,240,45,230,0.8,2,5,30,,,,calibrated,0.1,,,\n";
  }
  CHECK(cli(a + out, log) == 2);
  CHECK(slurp(log).find("hours do not go back") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "cmp"));
  fs::remove_all(dir);
}
