// The sweep on a real Slurm cluster (label `slurm`): scripts/slurm_local.sh
// starts a one-machine cluster from Debian's packages, `millcharge sweep run
// --slurm` submits a 2 x 2 sweep of small lab mills as a job array, one
// task is cancelled mid-run with scancel, the rerun submits only that case
// and it resumes from its checkpoint; `sweep collect` then has a full table.
// Then a sweep of two life studies, one cancelled mid-stage and resumed.
// Without root or the packages the cluster does not start and the test
// fails, saying why; it never passes without Slurm.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <thread>

#include "io/checkpoint.h"

#include "text_file.h"

namespace fs = std::filesystem;
using namespace mc;

namespace {

struct Outcome {
  int status = -1;
  std::string out;  // stdout and stderr
};

Outcome shell(const std::string& cmd, const fs::path& work) {
  const fs::path out = work / "output.txt";
  const int st = std::system((cmd + " > '" + out.string() + "' 2>&1").c_str());
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, read_text(out)};
}

// A scratch folder removed when the test ends (after the cluster in it).
struct Scratch {
  fs::path dir;
  explicit Scratch(const std::string& name)
      : dir(fs::temp_directory_path() / ("millcharge_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
};

// The cluster for one test: started in the constructor, stopped (its jobs
// cancelled, its daemons ended) in the destructor, whatever happened.
class Cluster {
 public:
  Cluster(const fs::path& dir, const fs::path& work) : dir_(dir), work_(work) {
    const Outcome o = shell("bash '" MC_SCRIPT_DIR "/slurm_local.sh' start '" + dir.string() + "'", work);
    started_ = o.status == 0;
    log_ = o.out;
    if (started_) ::setenv("SLURM_CONF", (dir / "slurm.conf").c_str(), 1);
  }
  ~Cluster() {
    shell("bash '" MC_SCRIPT_DIR "/slurm_local.sh' stop '" + dir_.string() + "'", work_);
    ::unsetenv("SLURM_CONF");
  }
  bool started() const { return started_; }
  const std::string& log() const { return log_; }

 private:
  fs::path dir_, work_;
  bool started_ = false;
  std::string log_;
};

bool wait_until(double seconds, const std::function<bool()>& done) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
  }
  return done();
}

// Slurm no longer holds any task of the job.
bool job_gone(const std::string& job, const fs::path& work) {
  const Outcome o = shell("squeue --noheader --array --jobs=" + job + " --format=%i", work);
  return o.status != 0 || o.out.find_first_not_of(" \n") == std::string::npos;
}

std::string job_of(const std::string& out) {
  std::smatch m;
  return std::regex_search(out, m, std::regex("submitted job ([0-9]+):")) ? m[1].str() : "";
}

std::vector<double> column_of(const fs::path& csv, std::size_t col) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  std::vector<double> v;
  while (std::getline(in, line)) {
    std::istringstream cells(line);
    std::string cell;
    for (std::size_t i = 0; i <= col && std::getline(cells, cell, ','); ++i) {
    }
    v.push_back(std::strtod(cell.c_str(), nullptr));
  }
  return v;
}

}  // namespace

TEST_CASE("sweep on Slurm: a 2x2 job array and two life studies, a task cancelled mid-run resumes", "[slurm]") {
  const Scratch scratch("slurm");
  const fs::path& work = scratch.dir;
  Cluster cluster(work / "cluster", work);  // stopped before the scratch folder goes
  INFO("scripts/slurm_local.sh start said:\n" << cluster.log());
  REQUIRE(cluster.started());

  // Four small lab mills; one second of turning each (about 50,000 steps of
  // 900 balls), a checkpoint every 0.05 s of simulated time.
  const fs::path file = work / "lab2x2.toml";
  std::ofstream(file) << R"(
name = "lab2x2"
case = "lab.toml"
[set]
mill.length = 0.05
run.duration = 1.0
run.settle = 0.05
run.warmup = 0.2
run.output_interval = 0.02
run.snapshot_interval = 0
run.checkpoint_interval = 0.05
[axes]
mill.speed_fraction = [0.6, 0.8]
lifters.profile.0.face_angle = [10, 30]
)";
  const fs::path out = work / "sweep";
  const std::string run = std::string(MC_BINARY) + " sweep run '" + file.string() + "' --slurm --out '" +
                          out.string() + "' --time 15 --signal-grace 30";
  const fs::path case0 = out / "cases" / "speed_fraction=0.6,face_angle=10";

  const Outcome first = shell(run, work);
  INFO(first.out);
  REQUIRE(first.status == 0);
  CHECK_THAT(first.out, Catch::Contains("0 finished, 0 queued or running, 0 failed; 4 to run"));
  const std::string job1 = job_of(first.out);
  REQUIRE(!job1.empty());
  CHECK_THAT(read_text(out / "sweep.sh"), Catch::Contains("#SBATCH --array=0-3\n"));

  // scancel task 0 once its mill turns (its checkpoint says so).
  io::Checkpoint at_cancel;
  const bool turning = wait_until(240, [&] {
    try {
      at_cancel = io::read_checkpoint(case0 / io::kCheckpointFile);
      return at_cancel.run.phase == 2 && at_cancel.run.turn_step > 0;
    } catch (const std::exception&) {
      return false;
    }
  });
  REQUIRE(turning);
  REQUIRE(shell("scancel " + job1 + "_0", work).status == 0);
  REQUIRE(wait_until(300, [&] { return job_gone(job1, work); }));

  // Stopped by SIGTERM with a checkpoint part way; the other three finished.
  CHECK(read_text(case0 / "exit_status") == "143\n");
  CHECK_FALSE(fs::exists(case0 / "summary.json"));
  const std::string log1 = read_text(case0 / "run.log");
  CHECK_THAT(log1, Catch::Contains("millcharge: stopped by SIGTERM at t = "));
  const io::Checkpoint stopped = io::read_checkpoint(case0 / io::kCheckpointFile);
  CHECK(stopped.run.phase == 2);
  const double t_stop = stopped.solver.time_s;
  INFO("stopped at solver time " << t_stop << " s");
  CHECK(t_stop < 0.05 + 1.0 - 0.02);  // mid-run, before the end
  const Outcome mid = shell(std::string(MC_BINARY) + " sweep collect '" + out.string() + "'", work);
  REQUIRE(mid.status == 0);
  CHECK_THAT(mid.out, Catch::Contains("3 of 4 cases finished"));
  const nlohmann::json t1 = nlohmann::json::parse(read_text(out / "sweep.json"));
  CHECK(t1["cases"][0]["status"] == "stopped");
  CHECK(t1["cases"][0]["exit_status"] == 143);

  // The rerun submits case 0 alone; it resumes from the checkpoint.
  const Outcome second = shell(run, work);
  INFO(second.out);
  REQUIRE(second.status == 0);
  CHECK_THAT(second.out, Catch::Contains("3 finished, 0 queued or running, 0 failed; 1 to run (1 resume from a checkpoint)"));
  const std::string job2 = job_of(second.out);
  REQUIRE(!job2.empty());
  CHECK(job2 != job1);
  CHECK_THAT(read_text(out / "sweep.sh"), Catch::Contains("#SBATCH --array=0\n"));
  REQUIRE(wait_until(300, [&] { return job_gone(job2, work); }));

  const std::string log2 = read_text(case0 / "run.log");
  CHECK_THAT(log2, Catch::Contains("== case 0 (speed_fraction=0.6,face_angle=10) on "));
  CHECK_THAT(log2, Catch::Contains("Slurm job " + job2 + "_0"));
  char resumed[96];
  std::snprintf(resumed, sizeof resumed, "millcharge: resuming at t = %.4f s", t_stop);
  CHECK_THAT(log2, Catch::Contains(resumed));
  CHECK(read_text(case0 / "exit_status") == "0\n");
  REQUIRE(fs::exists(case0 / "summary.json"));
  // The resumed run's rows at the times of an unbroken run of the same
  // length and dt (case 1's): none lost or written twice; as many steps.
  const std::vector<double> times = column_of(case0 / "timeseries.csv", 0);
  const std::vector<double> unbroken =
      column_of(out / "cases" / "speed_fraction=0.6,face_angle=30" / "timeseries.csv", 0);
  CHECK(times.size() >= 50);
  REQUIRE(times.size() == unbroken.size());
  for (std::size_t i = 0; i < times.size(); ++i) CHECK(times[i] == Approx(unbroken[i]).margin(1e-6));
  const nlohmann::json s0 = nlohmann::json::parse(read_text(case0 / "summary.json"));
  const nlohmann::json s1 =
      nlohmann::json::parse(read_text(out / "cases" / "speed_fraction=0.6,face_angle=30" / "summary.json"));
  CHECK(s0["steps"] == s1["steps"]);

  // The full table.
  const Outcome last = shell(std::string(MC_BINARY) + " sweep collect '" + out.string() + "'", work);
  REQUIRE(last.status == 0);
  CHECK_THAT(last.out, Catch::Contains("4 of 4 cases finished"));
  const nlohmann::json t2 = nlohmann::json::parse(read_text(out / "sweep.json"));
  REQUIRE(t2["cases"].size() == 4);
  for (const auto& row : t2["cases"]) {
    INFO(row.dump());
    CHECK(row["status"] == "done");
    CHECK(row["exit_status"] == 0);
    for (const char* c : {"power_W.torque", "power_W.dissipation", "power_per_metre_W.torque", "toe_deg",
                          "shoulder_deg", "morrell.power_W"})
      REQUIRE(row[c].is_number());
    // A revolution or less after the warm-up: a wide band around Morrell.
    const double p = row["power_W.torque"].get<double>(), m = row["morrell.power_W"].get<double>();
    CHECK(p > 0.3 * m);
    CHECK(p < 1.5 * m);
    CHECK(row["toe_deg"].get<double>() > 150);
    CHECK(row["toe_deg"].get<double>() < 270);
  }
  CHECK(fs::file_size(out / "sweep.png") > 1000);

  // Nothing left to run: no job is submitted.
  const Outcome third = shell(run, work);
  CHECK(third.status == 0);
  CHECK_THAT(third.out, Catch::Contains("nothing to run"));
  CHECK(job_of(third.out).empty());
  CHECK(nlohmann::json::parse(read_text(out / "jobs.json")).size() == 2);

  // A sweep of life studies on the same cluster: two studies of one worn
  // stage; study 0, cancelled while its new liner's run turns, goes on
  // from its life.json (and that run from its checkpoint) when the sweep
  // is run again.
  const fs::path life_file = work / "life2.toml";
  std::ofstream(life_file) << R"(
name = "life2"
case = "lab.toml"
command = "life"
[set]
mill.length = 0.05
run.duration = 0.5
run.settle = 0.05
run.warmup = 0.1
run.snapshot_interval = 0
run.checkpoint_interval = 0.05
[life]
stages = 1
hours = 4000
[axes]
lifters.profile.0.face_angle = [10, 30]
)";
  const fs::path life_out = work / "life-sweep";
  const std::string life_run = std::string(MC_BINARY) + " sweep run '" + life_file.string() + "' --slurm --out '" +
                               life_out.string() + "' --time 15 --signal-grace 30";
  const fs::path study0 = life_out / "cases" / "face_angle=10";
  const Outcome l1 = shell(life_run, work);
  INFO(l1.out);
  REQUIRE(l1.status == 0);
  CHECK_THAT(l1.out, Catch::Contains("0 finished, 0 queued or running, 0 failed; 2 to run (0 resume from their life.json)"));
  const std::string ljob1 = job_of(l1.out);
  REQUIRE(!ljob1.empty());
  const bool stage_turning = wait_until(240, [&] {
    try {
      const io::Checkpoint c = io::read_checkpoint(study0 / "stage-00" / io::kCheckpointFile);
      return c.run.phase == 2 && c.run.turn_step > 0;
    } catch (const std::exception&) {
      return false;
    }
  });
  REQUIRE(stage_turning);
  REQUIRE(shell("scancel " + ljob1 + "_0", work).status == 0);
  REQUIRE(wait_until(300, [&] { return job_gone(ljob1, work); }));
  CHECK(read_text(study0 / "exit_status") == "143\n");
  CHECK_THAT(read_text(study0 / "life.json"), !Catch::Contains("\"stopped\""));
  const Outcome lmid = shell(std::string(MC_BINARY) + " sweep collect '" + life_out.string() + "'", work);
  REQUIRE(lmid.status == 0);
  CHECK_THAT(lmid.out, Catch::Contains("1 of 2 studies ended"));

  const Outcome l2 = shell(life_run, work);
  INFO(l2.out);
  REQUIRE(l2.status == 0);
  CHECK_THAT(l2.out, Catch::Contains("1 finished, 0 queued or running, 0 failed; 1 to run (1 resume from their life.json)"));
  const std::string ljob2 = job_of(l2.out);
  REQUIRE(!ljob2.empty());
  REQUIRE(wait_until(300, [&] { return job_gone(ljob2, work); }));
  const std::string study_log = read_text(study0 / "run.log");
  CHECK_THAT(study_log, Catch::Contains("life            resuming"));
  CHECK_THAT(study_log, Catch::Contains("millcharge: resuming at t = "));
  CHECK(read_text(study0 / "exit_status") == "0\n");
  const Outcome lend = shell(std::string(MC_BINARY) + " sweep collect '" + life_out.string() + "'", work);
  REQUIRE(lend.status == 0);
  CHECK_THAT(lend.out, Catch::Contains("2 of 2 studies ended"));
  const nlohmann::json lt = nlohmann::json::parse(read_text(life_out / "sweep.json"));
  REQUIRE(lt["cases"].size() == 2);
  for (const auto& row : lt["cases"]) {
    INFO(row.dump());
    CHECK(row["status"] == "done");
    CHECK(row["hours.end"].get<double>() == Approx(4000));
    CHECK(row["stages"].get<double>() == 1);
  }
}
