// The run folders of a sweep (docs/sweeps.md, "The sweep folder"):
//   SWEEP/cases.json        the cases: axes, values, overrides, folder names
//   SWEEP/sweep.sh          the job script: one case per array task
//   SWEEP/cases/NAME/       a normal `millcharge run` folder, plus run.log
//                           (every attempt's output) and exit_status (the
//                           last attempt's, written by sweep.sh)
// What state a case is in follows from its folder alone, so a rerun and
// `sweep collect` need no other bookkeeping.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "io/sweep_file.h"

namespace mc::app {

enum class CaseStatus {
  not_started,  // no folder
  incomplete,   // a folder and no exit status: running, or killed (SIGKILL, a lost node)
  stopped,      // stopped by a signal (scancel, the time limit, Ctrl-C): resumes from its checkpoint
  failed,       // exited with an error (a blow-up, a device failure)
  done          // summary.json is there
};

const char* status_name(CaseStatus s);

struct CaseState {
  CaseStatus status = CaseStatus::not_started;
  int exit_status = -1;      // of the last attempt; −1: none recorded
  bool checkpoint = false;   // checkpoint.bin is there
  std::string last_line;     // the last line of run.log the run wrote (its error, for a failed case)
};

// The first file in `dir` that sweep.sh did not write there (its log and
// exit status, app/slurm.cpp); "" where there is none (or no folder): a
// case folder before its run or study began. A folder that cannot be
// listed holds what cannot be listed.
std::string file_not_of_a_sweep(const std::filesystem::path& dir);

// A life study's life.json (an empty object where there is none or it
// does not read), and where it says the study stopped ("" while it goes
// on).
nlohmann::json life_study_state(const std::filesystem::path& case_dir);
std::string life_study_stopped(const nlohmann::json& state);

// A life study's case (a sweep of command = "life") is done when its
// life.json says where the study stopped, and resumes from its life.json.
CaseState case_state(const std::filesystem::path& case_dir, bool life = false);

// The last line of a run log that the run wrote (not sweep.sh's "== " lines).
std::string last_log_line(const std::filesystem::path& log);

// cases.json: the sweep as expanded, for reruns and `sweep collect`.
nlohmann::ordered_json cases_json(const io::Sweep& s, const std::vector<io::SweepCase>& cases);

// "cases/NAME" of each case in cases.json, and the sweep folder's path to it.
std::filesystem::path case_path(const std::filesystem::path& sweep_dir, const std::string& dir);

// Runs the job script for `indexes` on this machine, `parallel` at a time
// (`bash sweep.sh INDEX`, as a Slurm task would). SIGINT or SIGTERM stops
// the runs (each writes its checkpoint) and launches no more. Prints a line
// per case as it ends. Returns the exit status of `sweep run --local`: 0 all
// finished, 1 some failed, 128 + the signal when stopped.
int run_local(const std::filesystem::path& script, const std::filesystem::path& sweep_dir,
              const std::vector<io::SweepCase>& cases, const std::vector<int>& indexes, int parallel,
              const io::Sweep& s);

}  // namespace mc::app
