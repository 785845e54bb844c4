// Design sweeps (docs/sweeps.md): the sweep file and its expansion, bad
// sweeps named by the file, the key and the case's values, the job script,
// `sweep collect` on a hand-written sweep folder (with the energy blocks
// summary.json will have), and a small sweep run here (--local) with a case
// whose checkpoint is damaged, which fails without stopping the other.
// The same sweep on a real Slurm cluster is tests/test_sweep_slurm.cpp.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/slurm.h"
#include "app/sweep_runs.h"
#include "app/sweep_table.h"
#include "core/mill_case.h"
#include "io/case_file.h"
#include "io/sweep_file.h"

#include "text_file.h"

namespace fs = std::filesystem;
using namespace mc;

namespace {

fs::path temp_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("millcharge_sweep_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
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

io::Sweep parse(const std::string& text) { return io::parse_sweep(text, fs::path(MC_TEST_DATA) / "sweep.toml"); }

std::string sweep_error(const std::string& text) {
  try {
    parse(text);
  } catch (const io::SweepError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("sweep file: axes in file order, lists and ranges, crossed", "[sweep]") {
  const io::Sweep s = parse(R"(
case = "lab.toml"
[set]
"mill.length" = 0.1
run.duration = 4.0
[axes]
mill.speed_fraction = {from = 0.5, to = 1.0, step = 0.1}
"lifters.profile.0.face_angle" = [10, 30]
)");
  CHECK(s.name == "sweep");
  CHECK(s.base_case == io::case_dir() / "lab.toml");
  REQUIRE(s.set == std::vector<std::string>{"mill.length=0.1", "run.duration=4.0"});
  REQUIRE(s.axes.size() == 2);
  CHECK(s.axes[0].key == "mill.speed_fraction");  // file order, not toml++'s sorted order
  CHECK(s.axes[1].key == "lifters.profile.0.face_angle");
  REQUIRE(s.axes[0].values.size() == 6);
  const char* speeds[] = {"0.5", "0.6", "0.7", "0.8", "0.9", "1.0"};
  for (int i = 0; i < 6; ++i) {
    CHECK(s.axes[0].values[i].toml == speeds[i]);  // 0.7, not 0.7000000000000001
    CHECK(s.axes[0].values[i].number == Approx(0.5 + 0.1 * i).epsilon(1e-12));
  }
  CHECK(s.axes[1].values[1].toml == "30");  // an integer stays an integer

  const auto cases = io::expand(s);
  REQUIRE(cases.size() == 12);
  // The first axis changes slowest; the overrides are [set] then the axes.
  CHECK(cases[1].overrides == std::vector<std::string>{"mill.length=0.1", "run.duration=4.0",
                                                       "mill.speed_fraction=0.5", "lifters.profile.0.face_angle=30"});
  CHECK(cases[11].dir == "speed_fraction=1,face_angle=30");
  CHECK(io::case_label(s, cases[2]) == "mill.speed_fraction=0.6, lifters.profile.0.face_angle=10");

  // Every case reads as the run would read it.
  const MillCase c = io::read_case(s.base_case, cases[7].overrides);
  CHECK(c.speed_fraction == Approx(0.8));
  CHECK(c.lifter_pattern.at(0).face_angle_deg == Approx(30));
  CHECK(c.length == Approx(0.1));
}

TEST_CASE("sweep file: zipped axes, zip groups and counted ranges", "[sweep]") {
  const io::Sweep z = parse(R"(
case = "lab.toml"
combine = "zip"
[axes]
mill.speed_fraction = [0.7, 0.8, 0.9]
charge.filling = {from = 0.25, to = 0.35, count = 3}
)");
  const auto zc = io::expand(z);
  REQUIRE(zc.size() == 3);
  CHECK(zc[2].overrides == std::vector<std::string>{"mill.speed_fraction=0.9", "charge.filling=0.35"});
  CHECK(z.axes[1].values[1].toml == "0.3");

  const io::Sweep g = parse(R"(
case = "lab.toml"
zip = [["lifters.profile.0.height", "lifters.profile.0.top_width"]]
[axes]
mill.speed_fraction = [0.7, 0.8]
lifters.profile.0.height = [0.02, 0.03, 0.04]
lifters.profile.0.top_width = [0.02, 0.03, 0.04]
)");
  const auto gc = io::expand(g);
  REQUIRE(gc.size() == 6);  // 2 speeds × 3 (height, width) pairs
  for (const auto& c : gc) CHECK(c.value_index[1] == c.value_index[2]);
  CHECK(gc[5].dir == "speed_fraction=0.8,height=0.04,top_width=0.04");
}

TEST_CASE("sweep file: a bad sweep is named by the file, the line and the key", "[sweep]") {
  const std::string head = "case = \"lab.toml\"\n";
  CHECK_THAT(sweep_error(head + "speed = 3\n[axes]\nmill.speed_fraction = [0.5]\n"),
             Catch::Contains("sweep.toml:2: speed: unknown key"));
  CHECK_THAT(sweep_error(head), Catch::Contains("axes: missing"));
  CHECK_THAT(sweep_error(head + "[axes]\nmill.speed_fraction = []\n"),
             Catch::Contains("sweep.toml:3: axes.mill.speed_fraction: an axis needs at least one value"));
  CHECK_THAT(sweep_error(head + "[axes]\nmill.speed_fraction = {from = 0.9, to = 0.5, step = 0.1}\n"),
             Catch::Contains("axes.mill.speed_fraction.step: must be < 0"));
  CHECK_THAT(sweep_error(head + "[axes]\nmill.speed_fraction = {from = 0.5, to = 0.9}\n"),
             Catch::Contains("exactly one of step and count"));
  CHECK_THAT(sweep_error(head + "[axes]\nmill.speed_fraction = [0.5, 0.5]\n"),
             Catch::Contains("axes.mill.speed_fraction: the value 0.5 is listed twice"));
  CHECK_THAT(sweep_error(head + "combine = \"zip\"\n[axes]\nmill.speed_fraction = [0.5, 0.6]\ncharge.filling = [0.3]\n"),
             Catch::Contains("axes.charge.filling: has 1 values but zipped mill.speed_fraction has 2"));
  CHECK_THAT(sweep_error(head + "[set]\nmill.speed_fraction = 0.7\n[axes]\nmill.speed_fraction = [0.5]\n"),
             Catch::Contains("axes.mill.speed_fraction: is also in [set]"));
  CHECK_THAT(sweep_error(head + "[axes]\nmill.speed_fraction = [0.5]\n[slurm]\nqueue = \"gpu\"\n"),
             Catch::Contains("slurm.queue: unknown key"));
  CHECK(sweep_error(head + "[axes]\nmill.speed_fraction = [0.5]\n[slurm]\ntime = \"4 hours\"\n") ==
        (fs::path(MC_TEST_DATA) / "sweep.toml").string() +
            ":5: slurm.time: \"4 hours\" is not a Slurm time limit: expected MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM "
            "or D-HH:MM:SS, e.g. 90, 04:00:00 or 1-12:00:00");
  for (const char* bad : {"04:00:00:00", "1-24", "10:60", "1-", "-4", ":30", "04::00", "1-2-3", ""})
    CHECK_THAT(sweep_error(head + "[axes]\nmill.speed_fraction = [0.5]\n[slurm]\ntime = \"" + bad + "\"\n"),
               Catch::Contains(":5: slurm.time: \"" + std::string(bad) + "\" is not a Slurm time limit"));
  for (const char* good : {"90", "90:30", "04:00:00", "100:00:00", "1-12", "1-12:30", "1-12:30:15"})
    CHECK(io::slurm_time_valid(good));
  CHECK_THAT(sweep_error("case = \"no_such.toml\"\n[axes]\nmill.speed_fraction = [0.5]\n"),
             Catch::Contains("sweep.toml:1: case: \"no_such.toml\": no such case file"));
}

TEST_CASE("sweep check: every bad combination named by its values and key, run writes nothing", "[sweep]") {
  const fs::path work = temp_dir("check");
  write_text(work / "bad.toml", R"(
case = "lab.toml"
[axes]
mill.speed_fraction = [0.7, -0.5]
lifters.profile.0.face_angle = [10, 95]
)");
  const Outcome o = run_binary("sweep check '" + (work / "bad.toml").string() + "'", work);
  CHECK(o.status == 2);
  // Three of four combinations are bad, each on its own line.
  CHECK_THAT(o.err, Catch::Contains("bad.toml: case 1 (mill.speed_fraction=0.7, lifters.profile.0.face_angle=95): "
                                    "--set lifters.profile.0.face_angle=95: lifters.profile[0].face_angle"));
  CHECK_THAT(o.err, Catch::Contains("case 2 (mill.speed_fraction=-0.5, lifters.profile.0.face_angle=10): "
                                    "--set mill.speed_fraction=-0.5: mill.speed_fraction: must be > 0"));
  CHECK_THAT(o.err, Catch::Contains("case 3 (mill.speed_fraction=-0.5, lifters.profile.0.face_angle=95)"));
  CHECK(o.err.find("case 0 (") == std::string::npos);
  CHECK_THAT(o.err, Catch::Contains("3 of 4 cases are not valid"));

  const Outcome r = run_binary("sweep run '" + (work / "bad.toml").string() + "' --local --out '" +
                                   (work / "out").string() + "'", work);
  CHECK(r.status == 2);
  CHECK_FALSE(fs::exists(work / "out"));

  write_text(work / "typo.toml", "case = \"lab.toml\"\n[axes]\nmill.sped = [0.7]\n");
  const Outcome t = run_binary("sweep check '" + (work / "typo.toml").string() + "'", work);
  CHECK(t.status == 2);
  CHECK_THAT(t.err, Catch::Contains("case 0 (mill.sped=0.7): --set mill.sped=0.7: mill.sped: unknown key"));
  fs::remove_all(work);
}

namespace {

// `sweep check` at 2e6 updates/s on the lab mill cut to 0.05 m, 0.5 s of
// settling and 2 s of turning, over the given [axes].
Outcome check_lab_sweep(const fs::path& work, const std::string& axes) {
  write_text(work / "sweep.toml", R"(
case = "lab.toml"
[set]
mill.length = 0.05
run.duration = 2.0
run.settle = 0.5
[axes]
)" + axes + "\n");
  return run_binary("sweep check '" + (work / "sweep.toml").string() + "' --throughput 2e6", work);
}

std::string with_commas(long v) {
  std::string t = std::to_string(v);
  for (int i = static_cast<int>(t.size()) - 3; i > 0; i -= 3) t.insert(i, ",");
  return t;
}

// The total work that the closing line reports (after "steps, ").
double reported_work(const std::string& out) {
  const std::size_t at = out.find("steps, ");
  return at == std::string::npos ? -1 : std::strtod(out.c_str() + at + 7, nullptr);
}

}  // namespace

TEST_CASE("sweep check: the count of cases and their cost, balls x steps", "[sweep]") {
  const fs::path work = temp_dir("cost");
  const Outcome o = check_lab_sweep(work, "mill.speed_fraction = [0.6, 0.8]\ncharge.filling = [0.25, 0.35]");
  REQUIRE(o.status == 0);
  // The totals from the case reader: balls × (settle + duration)/dt per case.
  const io::Sweep s = io::read_sweep(work / "sweep.toml");
  double balls = 0, work_total = 0;
  for (const auto& c : io::expand(s)) {
    const MillCase mc = io::read_case(s.base_case, c.overrides);
    const MillDerived d = derive(mc);
    balls += d.n_balls;
    work_total += d.n_balls * std::round(2.5 / d.dt);
  }
  CHECK_THAT(o.out, Catch::Contains("4 cases, all valid: " + with_commas(static_cast<long>(balls)) + " balls"));
  REQUIRE(reported_work(o.out) >= 0);
  CHECK(reported_work(o.out) == Approx(work_total).epsilon(5e-3));  // printed with 3 digits
  CHECK_THAT(o.out, Catch::Contains("at 2e+06 particle-updates/s (--throughput"));
  fs::remove_all(work);
}

TEST_CASE("sweep check: a charge of clumps costs its spheres", "[sweep][bodies]") {
  const fs::path work = temp_dir("clumps");
  const Outcome o = check_lab_sweep(work, R"(charge.size.0.shape = ["sphere", "peanut", "rock"])");
  REQUIRE(o.status == 0);
  // The same particles in each case; a peanut is 2 spheres, a rock 12.
  const io::Sweep s = io::read_sweep(work / "sweep.toml");
  const auto cases = io::expand(s);
  REQUIRE(cases.size() == 3);
  const MillCase mc = io::read_case(s.base_case, cases[0].overrides);
  const MillDerived d = derive(mc);
  const long n = d.n_balls;
  const double steps = std::round(2.5 / d.dt);
  CHECK_THAT(o.out, Catch::Contains("3 cases, all valid: " + with_commas(3 * n) + " particles (" +
                                    with_commas(15 * n) + " spheres)"));
  REQUIRE(reported_work(o.out) >= 0);
  CHECK(reported_work(o.out) == Approx(15.0 * n * steps).epsilon(5e-3));
  CHECK_THAT(o.out, Catch::Contains("sphere-steps in all"));
  CHECK_THAT(o.out, Catch::Contains("at 2e+06 sphere-updates/s (--throughput"));
  fs::remove_all(work);
}

TEST_CASE("sweep job script: a task per case, Slurm options, resume from the checkpoint", "[sweep]") {
  CHECK(app::array_spec({0, 1, 2, 5, 7, 8}) == "0-2,5,7-8");
  CHECK(app::array_spec({3}, 2) == "3%2");
  CHECK(app::shell_quote("it's") == "'it'\\''s'");

  io::Sweep s = parse(R"(
name = "lifters"
case = "lab.toml"
device = "gpu"
[set]
run.duration = 4.0
[axes]
mill.speed_fraction = [0.7, 0.8]
lifters.profile.0.face_angle = [10, 30]
[slurm]
partition = "gpu"
time = "04:00:00"
gpus_per_task = 1
max_running = 2
sbatch_args = ["--qos=long"]
)");
  const auto cases = io::expand(s);
  app::JobScript j = app::job_script_for(s, cases, "/scratch/sweeps/lifters", "/opt/millcharge/bin/millcharge");
  j.array = {0, 1, 3};
  const std::string text = app::job_script_text(j);
  for (const char* line : {"#SBATCH --job-name=lifters\n", "#SBATCH --array=0-1,3%2\n",
                           "#SBATCH --output=/scratch/sweeps/lifters/slurm/%A_%a.out\n", "#SBATCH --partition=gpu\n",
                           "#SBATCH --time=04:00:00\n", "#SBATCH --gpus-per-task=1\n",
                           "#SBATCH --signal=B:TERM@120\n", "#SBATCH --qos=long\n", "device='gpu'\n",
                           "common=(--set 'run.duration=4.0')\n", "task=${SLURM_ARRAY_TASK_ID:-$1}\n",
                           "    name='speed_fraction=0.8,face_angle=30'\n"
                           "    axes=(--set 'mill.speed_fraction=0.8' --set 'lifters.profile.0.face_angle=30') ;;\n",
                           "run=(\"$millcharge\" run --resume \"$dir\""})
    CHECK_THAT(text, Catch::Contains(line));

  // A task outside the sweep is refused (exit status 2) before it writes.
  const fs::path work = temp_dir("script");
  j.sweep_dir = work;
  write_text(work / "sweep.sh", app::job_script_text(j));
  const int st = std::system(("bash '" + (work / "sweep.sh").string() + "' 9 2>/dev/null").c_str());
  CHECK(WEXITSTATUS(st) == 2);
  CHECK_FALSE(fs::exists(work / "cases"));
  fs::remove_all(work);
}

TEST_CASE("sweep collect: a row per case, status and cause, open spectra and liner blocks", "[sweep]") {
  const fs::path work = temp_dir("collect");
  fs::copy(fs::path(MC_TEST_DATA) / "sweep_collect", work / "s", fs::copy_options::recursive);
  const Outcome o = run_binary("sweep collect '" + (work / "s").string() + "'", work);
  REQUIRE(o.status == 0);
  CHECK_THAT(o.out, Catch::Contains("2 of 6 cases finished"));

  const nlohmann::json j = nlohmann::json::parse(read_text(work / "s" / "sweep.json"));
  REQUIRE(j["cases"].size() == 6);
  CHECK(j["cases_finished"] == 2);
  const auto& c = j["columns"];
  CHECK(c[0] == "mill.speed_fraction");
  CHECK(c[1] == "lifters.profile.0.face_angle");
  CHECK(c[2] == "status");
  auto has = [&](const std::string& name) { return std::find(c.begin(), c.end(), name) != c.end(); };
  for (const char* name : {"spectra.total.collisions_per_s", "spectra.total.power_W", "spectra.total.normal_W",
                           "spectra.total.tangential_W", "spectra.total.rolling_W", "spectra.total.mean_energy_J",
                           "spectra.total.future_figure", "liner.wear_kg_per_h", "liner.worst_wear_mm_per_1000h",
                           "liner.impact_power_W", "liner.shear_power_W", "liner.bare_liner_impact_power_W",
                           "liner.bare_liner_impact_share", "liner.impact_point_deg", "morrell.power_W",
                           "power_per_metre_W.torque", "build", "exit_status", "error"})
    CHECK(has(name));
  CHECK_FALSE(has("liner.surfaces"));     // not a number
  CHECK_FALSE(has("liner.material"));
  CHECK_FALSE(has("spectra.pairs.ball_ball.power_W"));  // only spectra.total's scalars

  const auto& done = j["cases"][0];
  CHECK(done["status"] == "done");
  CHECK(done["mill.speed_fraction"].get<double>() == Approx(0.6));
  CHECK(done["power_W.torque"].get<double>() == Approx(100.0));
  CHECK(done["power_per_metre_W.torque"].get<double>() == Approx(500.0));  // 100 W over 0.2 m
  CHECK(done["power_per_metre_W.dissipation"].get<double>() == Approx(475.0));
  CHECK(done["morrell.power_per_metre_W"].get<double>() == Approx(600.0));
  CHECK(done["spectra.total.power_W"].get<double>() == Approx(94.5));
  CHECK(done["spectra.total.future_figure"].get<double>() == Approx(7.0));
  CHECK(done["liner.wear_kg_per_h"].get<double>() == Approx(0.0021));
  CHECK(done["liner.impact_point_deg"].get<double>() == Approx(215.0));
  CHECK(done["toe_deg"].get<double>() == Approx(225.5));
  CHECK(done["error"].is_null());
  // The case's grind (grind/grind.json): a column per product and figure.
  CHECK(has("grind.batch 4 min.P80_um"));
  CHECK(done["grind.batch 4 min.P80_um"].get<double>() == Approx(267.8));
  CHECK(done["grind.batch 4 min.specific_energy_kWh_t"].get<double>() == Approx(3.19));
  CHECK(done["grind.throughput_at_target_t_h"].get<double>() == Approx(0.0566));
  CHECK(j["cases"][1]["grind.batch 4 min.P80_um"].is_null());

  const auto& own_metre = j["cases"][1];  // the run's own power_per_metre_W wins
  CHECK(own_metre["power_per_metre_W.torque"].get<double>() == Approx(321.0));
  CHECK(own_metre["shoulder_deg"].is_null());
  CHECK(own_metre["spectra.total.power_W"].is_null());

  const auto& failed = j["cases"][2];
  CHECK(failed["status"] == "failed");
  CHECK(failed["exit_status"] == 1);
  CHECK_THAT(failed["error"].get<std::string>(), Catch::StartsWith("millcharge: blow-up at t = 1.2340 s"));
  CHECK(failed["power_W.torque"].is_null());
  CHECK(j["cases"][3]["status"] == "stopped");
  CHECK(j["cases"][3]["exit_status"] == 143);
  CHECK_THAT(j["cases"][3]["error"].get<std::string>(), Catch::StartsWith("millcharge: stopped by SIGTERM"));
  CHECK(j["cases"][4]["status"] == "incomplete");
  CHECK(j["cases"][5]["status"] == "not started");

  // The CSV: the same columns, a line per case; a comma inside a cell quoted.
  const std::string csv = read_text(work / "s" / "sweep.csv");
  std::istringstream lines(csv);
  std::string header, line;
  std::getline(lines, header);
  CHECK(header.rfind("mill.speed_fraction,lifters.profile.0.face_angle,status,", 0) == 0);
  int rows = 0;
  while (std::getline(lines, line)) ++rows;
  CHECK(rows == 6);
  CHECK_THAT(csv, Catch::Contains("\n0.6,10,done,3600,0.6,27.14,0.3,1,100,95,0.05,35.2,225.5,40.25,320,120,"));
  CHECK_THAT(csv, Catch::Contains("\"speed_fraction=0.6,face_angle=10\""));

  // Pictures: sweep.png and a plot per other figure with data.
  for (const char* f : {"sweep.png", "plots/toe_deg.png", "plots/liner.wear_kg_per_h.png",
                        "plots/spectra.total.power_W.png", "plots/power_per_metre_W.torque.png"}) {
    const std::string png = read_text(work / "s" / f);
    INFO(f);
    REQUIRE(png.size() > 1000);
    CHECK(png.substr(1, 3) == "PNG");
  }

  // A finished case's summary.json damaged after its run (a figure turned to
  // text): said in its row, not read as a run without that figure.
  {
    const fs::path summary = work / "s" / "cases" / "speed_fraction=0.6,face_angle=10" / "summary.json";
    nlohmann::json bad = nlohmann::json::parse(read_text(summary));
    bad["toe_deg"] = "225.5";
    write_text(summary, bad.dump(2));
    REQUIRE(run_binary("sweep collect '" + (work / "s").string() + "'", work).status == 0);
    const nlohmann::json again = nlohmann::json::parse(read_text(work / "s" / "sweep.json"));
    CHECK(again["cases"][0]["status"] == "failed");
    CHECK(again["cases"][0]["error"] == "summary.json: toe_deg: expected a number, found string; the file is damaged");
    CHECK(again["cases"][1]["status"] == "done");
  }
  fs::remove_all(work);
}

TEST_CASE("sweep run --local: cases N at a time, a failed case stops no other, a rerun runs none", "[sweep]") {
  const fs::path work = temp_dir("local");
  write_text(work / "small.toml", R"(
name = "small"
case = "lab.toml"
[set]
mill.length = 0.05
run.duration = 0.3
run.settle = 0.05
run.warmup = 0.1
run.output_interval = 0.02
run.snapshot_interval = 0
[axes]
mill.speed_fraction = [0.6, 0.8]
lifters.profile.0.face_angle = [20, 30]
)");
  const fs::path out = work / "out";
  // Case 3's folder holds a damaged checkpoint: its run is refused (status 2).
  fs::create_directories(out / "cases" / "speed_fraction=0.8,face_angle=30");
  write_text(out / "cases" / "speed_fraction=0.8,face_angle=30" / "checkpoint.bin", "not a checkpoint");

  const std::string args = "sweep run '" + (work / "small.toml").string() + "' --out '" + out.string() + "'";
  const Outcome o = run_binary(args + " --local 2", work);
  INFO(o.out << o.err);
  CHECK(o.status == 1);  // one case failed
  CHECK_THAT(o.out, Catch::Contains("4 to run (1 resume from a checkpoint)"));
  CHECK_THAT(o.out, Catch::Contains("case 3 (mill.speed_fraction=0.8, lifters.profile.0.face_angle=30): failed (exit status 2)"));
  CHECK_THAT(o.out, Catch::Contains("3 of 4 cases run here finished, 1 failed"));

  const Outcome c = run_binary("sweep collect '" + out.string() + "'", work);
  REQUIRE(c.status == 0);
  const nlohmann::json j = nlohmann::json::parse(read_text(out / "sweep.json"));
  REQUIRE(j["cases"].size() == 4);
  for (int i = 0; i < 3; ++i) {
    const auto& row = j["cases"][i];
    INFO("case " << i);
    REQUIRE(row["status"] == "done");
    // A fraction of a revolution, so only a wide band: the torque power of
    // the turning charge against Morrell's C-model for the same mill.
    const double p = row["power_W.torque"].get<double>(), m = row["morrell.power_W"].get<double>();
    CHECK(p > 0.3 * m);
    CHECK(p < 1.5 * m);
    CHECK(row["power_per_metre_W.torque"].get<double>() == Approx(p / 0.05));
    CHECK(row["n_particles"].get<double>() > 800);
  }
  CHECK(j["cases"][0]["morrell.power_W"].get<double>() < j["cases"][2]["morrell.power_W"].get<double>());
  const auto& bad = j["cases"][3];
  CHECK(bad["status"] == "failed");
  CHECK(bad["exit_status"] == 2);
  CHECK_THAT(bad["error"].get<std::string>(), Catch::Contains("not a millcharge checkpoint"));

  // Again: the finished cases are not run, nor the failed one unless asked.
  const Outcome again = run_binary(args + " --local", work);
  CHECK(again.status == 0);
  CHECK_THAT(again.out, Catch::Contains("3 finished, 0 queued or running, 1 failed (not run again: --retry-failed); 0 to run"));
  fs::remove_all(work);
}

TEST_CASE("sweep run: a damaged record of submitted jobs is refused, not read as none", "[sweep][failures]") {
  // Read as empty, the cases Slurm still holds would be submitted again.
  const fs::path work = temp_dir("jobs");
  write_text(work / "s.toml", "name = \"t\"\ncase = \"" + (fs::path(MC_ASSET_DIR) / "cases" / "lab.toml").string() +
                                  "\"\n[axes]\nmill.speed_fraction = [0.7, 0.8]\n");
  for (const char* damaged : {"{broken", "{\"job\": \"12\"}", "[{\"job\": \"12\", \"tas", "[{\"job\": 12}]",
                              "[{\"job\": \"12\", \"tasks\": {\"0\": 3}}]"}) {
    INFO(damaged);
    fs::create_directories(work / "out");
    write_text(work / "out" / "jobs.json", damaged);
    const fs::path log = work / "log.txt";
    const int st = std::system((std::string(MC_BINARY) + " sweep run '" + (work / "s.toml").string() +
                                "' --print --out '" + (work / "out").string() + "' > '" + log.string() + "' 2>&1")
                                   .c_str());
    const std::string said = read_text(log);
    INFO(said);
    CHECK(WEXITSTATUS(st) == 2);
    CHECK_THAT(said, Catch::Contains("jobs.json: ") && Catch::Contains("record of submitted jobs is damaged"));
    CHECK(std::count(said.begin(), said.end(), '\n') == 1);
    CHECK(said.find("json.exception") == std::string::npos);
    CHECK_FALSE(fs::exists(work / "out" / "sweep.sh"));
    CHECK_FALSE(fs::exists(work / "out" / "cases.json"));
    fs::remove_all(work / "out");
  }
  fs::remove_all(work);
}
