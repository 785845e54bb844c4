// Positive tests of how a life study plans its stages: --until-height
// lowers the bars by equal shares of what is left, and a study calibrated
// on a measured loss reaches that loss at the measured hours and covers the
// hours asked (src/app/life.cpp, core/liner_wear.h hours_to_lose).
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "io/csv_read.h"
#include "text_file.h"

namespace fs = std::filesystem;

namespace {

// A 60 mm slice of the lab mill's length (1,089 balls), each stage turned 0.15 s.
const std::string kShort =
    " --quiet --set mill.length=0.06 --set run.duration=0.15 --set run.settle=0.05 --set run.warmup=0.05"
    " --set run.snapshot_interval=0";

struct Row {
  double hours, height;
};

// life.csv's rows of profile 0: hours and height (mm).
std::vector<Row> rows_of(const fs::path& csv) {
  const std::string text = read_text(csv);
  std::vector<Row> out;
  std::size_t at = text.find('\n') + 1;
  while (at < text.size()) {
    const std::size_t end = text.find('\n', at);
    std::vector<std::string> f;
    std::size_t p = at;
    const std::string line = text.substr(at, end - at);
    for (std::size_t c = 0;; c = p + 1) {
      p = line.find(',', c);
      f.push_back(line.substr(c, p == std::string::npos ? std::string::npos : p - c));
      if (p == std::string::npos) break;
    }
    if (f.size() > 4 && f[3] == "0") out.push_back({std::stod(f[1]), std::stod(f[4])});
    at = end == std::string::npos ? text.size() : end + 1;
  }
  return out;
}

int life(const std::string& args, const fs::path& out) {
  const std::string cmd = std::string(MC_BINARY) + " life" + kShort + " " + args + " --out '" + out.string() +
                          "' > '" + out.string() + ".log' 2>&1";
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

}  // namespace

TEST_CASE("life --until-height lowers the bars by equal shares of the height left, stage by stage", "[life][cli]") {
  const fs::path out = fs::temp_directory_path() / ("millcharge-life-plan-height-" + std::to_string(::getpid()));
  fs::remove_all(out);
  // The lab's bars are 25 mm high: two stages to 24 mm, half a millimetre each.
  REQUIRE(life("--stages 2 --until-height 24", out) == 0);
  const std::vector<Row> rows = rows_of(out / "life.csv");
  INFO(read_text(out.string() + ".log"));
  REQUIRE(rows.size() == 3);
  CHECK(rows[0].height == Approx(25.0).margin(1e-4));
  // Half a millimetre, or more where the worn outline sheds a thin ridge at
  // once (its height then falls in a step): never less than planned.
  CHECK(rows[1].height <= 24.5 + 1e-3);
  CHECK(rows[1].height > 24.0 + 1e-3);
  CHECK(rows[2].height == Approx(24.0).margin(1e-3));
  CHECK(rows[2].hours > rows[1].hours);
  CHECK_THAT(read_text(out.string() + ".log"), Catch::Contains("the lifters are down to 24.0 mm"));
  fs::remove_all(out);
  fs::remove(out.string() + ".log");
}

TEST_CASE("a study calibrated on a measured loss reaches it at the measured hours and covers the hours asked",
          "[life][cli]") {
  const fs::path out = fs::temp_directory_path() / ("millcharge-life-plan-cal-" + std::to_string(::getpid()));
  fs::remove_all(out);
  // The bars lost 0.6 mm in 600 h; the study covers 1,000 h in two stages.
  REQUIRE(life("--stages 2 --hours 1000 --calibrate-loss 0.6 --calibrate-hours 600", out) == 0);
  const std::vector<Row> rows = rows_of(out / "life.csv");
  INFO(read_text(out.string() + ".log"));
  REQUIRE(rows.size() >= 3);
  CHECK(rows.front().hours == 0);
  // Covered: the study stops once it is within 5 % of a stage (500 h) of the
  // hours asked, on the calibration as it stands then. (It may end past
  // them: each stage revises an extrapolated calibration, and with it the
  // hours of the stages before.)
  CHECK(rows.back().hours >= 1000 - 0.05 * 500);
  // ... and not by more than a stage: the revision moves the hours of the
  // stages run, not how many there are (two, and at most the third the
  // revision calls for).
  CHECK(rows.back().hours <= 1000 + 500);
  CHECK(rows.size() <= 4);
  // Where the table's height falls past 24.4 mm, interpolated between its rows.
  double at = -1;
  for (std::size_t i = 1; i < rows.size() && at < 0; ++i)
    if (rows[i].height <= 24.4)
      at = rows[i - 1].hours + (rows[i - 1].height - 24.4) / (rows[i - 1].height - rows[i].height) *
                                   (rows[i].hours - rows[i - 1].hours);
  CHECK(at == Approx(600).epsilon(1e-3));
  fs::remove_all(out);
  fs::remove(out.string() + ".log");
}
