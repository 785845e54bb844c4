// Life studies side by side (docs/sweeps.md, "Life studies side by side"):
// a sweep file of command = "life", its [life] options and life.* axes, the
// hours to a relining height against a hand computation, and a small sweep
// of two studies run here and collected, its table read against each
// study's own life.csv; a changed sweep refused before it runs.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "app/slurm.h"
#include "app/sweep_life.h"
#include "io/csv_read.h"
#include "io/sweep_file.h"
#include "life_cli.h"
#include "text_file.h"

namespace fs = std::filesystem;
using namespace mc;

namespace {

io::Sweep parse(const std::string& text) { return io::parse_sweep(text, fs::path(MC_TEST_DATA) / "sweep.toml"); }

std::string sweep_error(const std::string& text) {
  try {
    parse(text);
  } catch (const io::SweepError& e) {
    return e.what();
  }
  return "(no error)";
}

struct Outcome {
  int status = -1;
  std::string out, err;
};

Outcome run_binary(const std::string& args, const fs::path& work) {
  const fs::path out = work / "stdout.txt", err = work / "stderr.txt";
  const std::string cmd = std::string(MC_BINARY) + " " + args + " > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  Outcome o;
  o.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  o.out = read_text(out);
  o.err = read_text(err);
  return o;
}

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

// The study's last stage row of profile 0 in its own life.csv.
std::map<std::string, std::string> last_stage(const fs::path& study) {
  const auto rows = life_cli::read_csv(study / "life.csv");
  std::map<std::string, std::string> last;
  for (const auto& r : rows)
    if (r.at("profile") == "0") last = r;
  REQUIRE(!last.empty());
  return last;
}

}  // namespace

TEST_CASE("life sweep file: [life] options and life.* axes become each study's options", "[sweep][life]") {
  const io::Sweep s = parse(R"(
case = "lab.toml"
command = "life"
[set]
run.duration = 0.5
[life]
stages = 4
calibrate_consumption = 4
hours = 8000
[axes]
lifters.profile.0.face_angle = [10, 30]
"life.impact-share" = [0.25, 0.75]
)");
  REQUIRE(s.is_life());
  REQUIRE(s.life.size() == 3);
  CHECK(s.life[1].key == "calibrate-consumption");  // underscores read as the option's dashes
  CHECK(s.life[1].line == 8);
  const auto cases = io::expand(s);
  REQUIRE(cases.size() == 4);
  // Case keys go to --set; life options to the study, in the file's order.
  CHECK(cases[1].overrides == std::vector<std::string>{"run.duration=0.5", "lifters.profile.0.face_angle=10"});
  CHECK(cases[1].life_args ==
        std::vector<std::string>{"--stages=4", "--calibrate-consumption=4", "--hours=8000", "--impact-share=0.75"});
  CHECK(cases[1].dir == "face_angle=10,impact-share=0.75");
  // The job script runs `millcharge life` with them, no --force (a study resumes itself).
  const app::JobScript js = app::job_script_for(s, cases, "/scratch/s", "/opt/millcharge");
  const std::string text = app::job_script_text(js);
  CHECK_THAT(text, Catch::Contains("life=('--stages=4' '--calibrate-consumption=4' '--hours=8000' '--impact-share=0.75')"));
  CHECK_THAT(text, Catch::Contains(R"(run=("$millcharge" life "$base" --out "$dir" "${common[@]}" "${axes[@]}" "${life[@]}")"));
  CHECK_THAT(text, Catch::Contains(R"(grep -q '"stopped"' "$dir/life.json")"));
  CHECK_THAT(text, !Catch::Contains("run --resume"));

  // A sweep of runs: no [life], no life axes.
  CHECK_THAT(sweep_error("case = \"lab.toml\"\n[life]\nstages = 2\n[axes]\nmill.speed_fraction = [0.7]\n"),
             Catch::Contains("sweep.toml:2: life: [life] holds a life study's options: give command = \"life\" too"));
  CHECK_THAT(sweep_error("case = \"lab.toml\"\n[axes]\n\"life.stages\" = [1, 2]\n"),
             Catch::Contains("sweep.toml:3: axes.life.stages: a life option varies in a sweep of life studies only"));
  CHECK_THAT(sweep_error("case = \"lab.toml\"\ncommand = \"life\"\n[axes]\nmill.speed_fraction = [0.7]\n"),
             Catch::Contains("life: command = \"life\" needs a table [life]"));
  CHECK_THAT(sweep_error("case = \"lab.toml\"\ncommand = \"bench\"\n[axes]\nmill.speed_fraction = [0.7]\n"),
             Catch::Contains("sweep.toml:2: command: \"bench\" is not one of \"run\""));
  CHECK_THAT(sweep_error("case = \"lab.toml\"\ncommand = \"life\"\n[life]\nstages = 2\nhours = 10\n[axes]\n"
                         "\"life.hours\" = [1, 2]\n"),
             Catch::Contains("axes.life.hours: is also in [life]; give it in one place"));
}

TEST_CASE("the hours to a relining height: linear between stages, the height's error over its slope", "[sweep][life]") {
  const std::vector<double> hours = {0, 2000, 4000}, height = {25, 22, 19}, se = {0, 0.3, 0.5};
  // By hand: 20 mm lies 2/3 of the way from 22 to 19; the error there as
  // life-compare carries it, sqrt(0.3² + (2/3)² (0.5² − 0.3²)) = 0.40139 mm,
  // over the fall of 3 mm per 2000 h.
  const app::Crossing x = app::hours_to_height(hours, height, se, 20);
  CHECK(x.hours == Approx(2000 + 2000 * 2.0 / 3).epsilon(1e-12));
  CHECK(x.se == Approx(std::sqrt(0.09 + 4.0 / 9 * (0.25 - 0.09)) / (3.0 / 2000)).epsilon(1e-9));
  CHECK(x.se == Approx(267.6).epsilon(1e-3));
  // On a stage: the crossing's own error over the fall into it, by hand
  // 0.3 mm over 3 mm per 2000 h.
  const app::Crossing on = app::hours_to_height(hours, height, se, 22);
  CHECK(on.hours == Approx(2000).epsilon(1e-12));
  CHECK(on.se == Approx(200).epsilon(1e-9));
  // A study stopped by its own --until-height 20 ends within 0.05 mm above
  // it: there, with the tolerance; not reached without.
  const std::vector<double> stopped = {25, 22, 20.03};
  CHECK(app::hours_to_height(hours, stopped, se, 20, 0.05).hours == Approx(4000).epsilon(1e-12));
  CHECK(std::isnan(app::hours_to_height(hours, stopped, se, 20).hours));
  // Not reached, reached at the start, and a path without errors.
  CHECK(std::isnan(app::hours_to_height(hours, height, se, 18).hours));
  CHECK(app::hours_to_height(hours, height, se, 26).hours == 0);
  const app::Crossing bare = app::hours_to_height(hours, height, {}, 23.5);
  CHECK(bare.hours == Approx(1000).epsilon(1e-12));
  CHECK(std::isnan(bare.se));
}

namespace {

// A sweep of life studies of a 60 mm slice of the lab mill in short runs,
// up to its [life] table's first line.
std::string short_lab_life(const std::string& name) {
  return "name = \"" + name + R"("
case = "lab.toml"
command = "life"
[set]
mill.length = 0.06
run.duration = 0.3
run.settle = 0.05
run.warmup = 0.1
run.checkpoint_interval = 0.05
run.snapshot_interval = 0
[life]
)";
}

}  // namespace

TEST_CASE("sweep run --local of life studies: each a study, collected against its own life.csv, a changed sweep "
          "is refused", "[sweep][life][cli]") {
  const fs::path work = life_cli::scratch("sweep");
  fs::create_directories(work);
  const std::string head = short_lab_life("two_faces") + "stages = 2\n";
  const std::string axes = "[axes]\nlifters.profile.0.face_angle = [10, 30]\n";
  write_text(work / "life.toml", head + "hours = 8000\n" + axes);
  const fs::path dir = work / "out";

  // A life option out of range: refused by the life command's own check,
  // case by case, and nothing written.
  write_text(work / "bad.toml", head + "hours = 8000\n" + axes + "\"life.impact-share\" = [0.5, 1.5]\n");
  const Outcome bad = run_binary("sweep run '" + (work / "bad.toml").string() + "' --local --out '" + dir.string() + "'", work);
  CHECK(bad.status == 2);
  CHECK_THAT(bad.err, Catch::Contains("case 1 (lifters.profile.0.face_angle=10, life.impact-share=1.5): life: "
                                      "--impact-share: must be from 0 to 1, got 1.5"));
  CHECK_THAT(bad.err, Catch::Contains("2 of 4 cases are not valid; nothing was run or written"));
  CHECK(!fs::exists(dir));

  const Outcome run = run_binary("sweep run '" + (work / "life.toml").string() + "' --local --out '" + dir.string() + "'", work);
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  CHECK_THAT(run.out, Catch::Contains("case 0 (lifters.profile.0.face_angle=10): done in"));
  CHECK_THAT(run.out, Catch::Contains("case 1 (lifters.profile.0.face_angle=30): done in"));

  // Each study is what `millcharge life` wrote: two worn stages, 8000 hours.
  const fs::path s10 = dir / "cases" / "face_angle=10", s30 = dir / "cases" / "face_angle=30";
  const auto end10 = last_stage(s10), end30 = last_stage(s30);
  CHECK(life_cli::num(end10, "hours") == Approx(8000));
  CHECK(life_cli::num(end10, "leading_angle_deg") > 10);  // the new face is 10 deg; wear opens it

  // A relining height the 10 deg bar's path falls through: its hours by
  // hand from its life.csv (linear between the stages it falls between).
  std::vector<double> H, h;
  for (const auto& r : life_cli::read_csv(s10 / "life.csv"))
    if (r.at("profile") == "0") H.push_back(life_cli::num(r, "hours")), h.push_back(life_cli::num(r, "height_mm"));
  REQUIRE(h.size() == 3);
  const double top = std::max({h[0], h[1]});
  REQUIRE(h[2] < top - 0.05);  // the worn bar ends lower than it was
  const double relining = 0.5 * (top + h[2]);
  double by_hand = NAN;
  for (std::size_t i = 1; i < h.size() && std::isnan(by_hand); ++i)
    if (h[i] <= relining) by_hand = H[i - 1] + (h[i - 1] - relining) / (h[i - 1] - h[i]) * (H[i] - H[i - 1]);
  const Outcome col = run_binary("sweep collect '" + dir.string() + "' --relining-height " + std::to_string(relining), work);
  INFO(col.out << col.err);
  REQUIRE(col.status == 0);
  CHECK_THAT(col.out, Catch::Contains("2 of 2 studies ended"));
  const auto rows = life_cli::read_csv(dir / "sweep.csv");
  REQUIRE(rows.size() == 2);
  CHECK(rows[0].at("status") == "done");
  CHECK(life_cli::num(rows[0], "lifters.profile.0.face_angle") == 10);
  CHECK(life_cli::num(rows[0], "stages") == 2);
  CHECK(life_cli::num(rows[0], "hours.end") == Approx(8000));
  CHECK(life_cli::num(rows[0], "height_mm.new") == Approx(h[0]).margin(1e-4));
  CHECK(life_cli::num(rows[0], "height_mm.end") == Approx(h[2]).margin(1e-4));
  CHECK(life_cli::num(rows[1], "height_mm.end") == Approx(life_cli::num(end30, "height_mm")).margin(1e-4));
  CHECK(life_cli::num(rows[1], "leading_angle_deg.end") == Approx(life_cli::num(end30, "leading_angle_deg")).margin(1e-3));
  CHECK(life_cli::num(rows[1], "power_W.end") == Approx(life_cli::num(end30, "power_W")).margin(1e-2));
  CHECK(life_cli::num(rows[0], "power_W.new") == Approx(life_cli::num(life_cli::read_csv(s10 / "life.csv")[0], "power_W")).margin(1e-2));
  CHECK(life_cli::num(rows[0], "hours_to_relining") == Approx(by_hand).epsilon(1e-6));
  // The studies wear their end plates: the deepest ring at the last stage,
  // by hand from the study's life_plates.csv.
  double deepest = 0;
  for (const auto& r : life_cli::read_csv(s10 / "life_plates.csv"))
    if (life_cli::num(r, "stage") == 2) deepest = std::max(deepest, life_cli::num(r, "depth_mm"));
  CHECK(deepest > 0.1);
  CHECK(life_cli::num(rows[0], "plate_depth_mm.end") == Approx(deepest).margin(1e-4));
  CHECK_THAT(col.out, Catch::Contains("plate_mm end"));
  CHECK(fs::exists(dir / "sweep.png"));
  const nlohmann::json j = nlohmann::json::parse(read_text(dir / "sweep.json"));
  CHECK(j["command"] == "life");
  CHECK(j["relining_height_mm"].get<double>() == Approx(relining));

  // Run again: both ended, none to run; the job script says so for a task.
  const Outcome again = run_binary("sweep run '" + (work / "life.toml").string() + "' --local --out '" + dir.string() + "'", work);
  CHECK(again.status == 0);
  CHECK_THAT(again.out, Catch::Contains("2 finished, 0 queued or running, 0 failed; 0 to run"));
  CHECK(std::system(("bash '" + (dir / "sweep.sh").string() + "' 1 > '" + (work / "task.txt").string() + "'").c_str()) == 0);
  CHECK_THAT(read_text(work / "task.txt"), Catch::Contains("case 1 (face_angle=30) has finished"));

  // The sweep file changed (hours): the studies there are of other
  // options; refused by name before anything runs, the studies kept.
  const std::string before = read_text(s10 / "life.json");
  write_text(work / "life.toml", head + "hours = 9000\n" + axes);
  const Outcome changed = run_binary("sweep run '" + (work / "life.toml").string() + "' --local --out '" + dir.string() + "'", work);
  CHECK(changed.status == 2);
  CHECK_THAT(changed.err, Catch::Contains("face_angle=10: not the study of the sweep's case 0 "
                                          "(lifters.profile.0.face_angle=10): hours"));
  CHECK_THAT(changed.err, Catch::Contains("2 case folders hold other studies"));
  CHECK(read_text(s10 / "life.json") == before);

  // A case folder that holds something else (a run's summary) and no
  // study: refused before anything runs.
  write_text(work / "life.toml", head + "hours = 8000\n" + axes);
  fs::remove_all(s30);
  fs::create_directories(s30);
  write_text(s30 / "summary.json", "{}");
  const Outcome stale = run_binary("sweep run '" + (work / "life.toml").string() + "' --local --out '" + dir.string() + "'", work);
  CHECK(stale.status == 2);
  CHECK_THAT(stale.err, Catch::Contains("face_angle=30: not the study of the sweep's case 1 "
                                        "(lifters.profile.0.face_angle=30): it holds summary.json and no life study"));
  CHECK(!fs::exists(s30 / "life.json"));

  // The relining height is a life sweep's.
  fs::create_directories(work / "runs_sweep");
  write_text(work / "runs_sweep" / "cases.json", R"({"sweep": "x", "axes": [], "cases": []})");
  const Outcome wrong = run_binary("sweep collect '" + (work / "runs_sweep").string() + "' --relining-height 10", work);
  CHECK(wrong.status == 2);
  CHECK_THAT(wrong.err, Catch::Contains("--relining-height: " + (work / "runs_sweep").string() + " is a sweep of runs"));
  fs::remove_all(work);
}

TEST_CASE("a sweep of life studies along the mill wears bars of [lifters] as their twin, and runs again as ended",
          "[sweep][life][cli]") {
  const fs::path work = life_cli::scratch("sweep-twin");
  fs::create_directories(work);
  const std::string head = short_lab_life("twin") + "stages = 1\nhours = 4000\naxial-segments = 2\n";
  const fs::path dir = work / "out";
  // What the twin cannot do, refused by the sweep's check as by life's.
  const std::string axes = "[axes]\nlifters.profile.0.face_angle = [20]\n";
  write_text(work / "bad.toml", head + "lifter-mesh = 40\n" + axes);
  const Outcome bad = run_binary("sweep run '" + (work / "bad.toml").string() + "' --local --out '" + dir.string() + "'", work);
  CHECK(bad.status == 2);
  CHECK_THAT(bad.err, Catch::Contains("--lifter-mesh 40: triangles up to 40 mm along the mill, longer than a segment"));
  CHECK(!fs::exists(dir));
  write_text(work / "twin.toml", head + "lifter-mesh = 25\n" + axes);
  const Outcome run = run_binary("sweep run '" + (work / "twin.toml").string() + "' --local --out '" + dir.string() + "'", work);
  INFO(run.out << run.err);
  REQUIRE(run.status == 0);
  const fs::path study = dir / "cases";
  bool twin = false;
  for (const auto& e : fs::directory_iterator(study)) twin = twin || fs::exists(e.path() / "new-bars.stl");
  CHECK(twin);
  // The sweep's request is the study's (the twin's size and smoothing in
  // both): run again, it is ended, not another study.
  const Outcome again = run_binary("sweep run '" + (work / "twin.toml").string() + "' --local --out '" + dir.string() + "'", work);
  INFO(again.out << again.err);
  CHECK(again.status == 0);
  CHECK_THAT(again.out, Catch::Contains("1 finished, 0 queued or running, 0 failed; 0 to run"));
  fs::remove_all(work);
}
