// The Slurm backend of `millcharge sweep run`: a job-array script whose
// task SLURM_ARRAY_TASK_ID runs case number SLURM_ARRAY_TASK_ID (a normal
// `millcharge run`, or `millcharge run --resume` when the case's folder
// holds a checkpoint; in a sweep of life studies `millcharge life`, which
// resumes a study by itself), sbatch to submit it, squeue to see what is queued.
// No scheduler of our own: Slurm queues, places and signals the runs.
#pragma once

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "io/sweep_file.h"

namespace mc::app {

struct JobScript {
  std::string name;                   // the job's name
  std::filesystem::path millcharge;   // the program, absolute
  std::filesystem::path sweep_dir;    // absolute
  std::filesystem::path base_case;    // absolute
  std::string device;                 // --device for every run; empty: millcharge's default
  std::vector<std::string> common;    // the sweep's [set] as KEY=VALUE
  std::string command = "run";        // "run", or "life": each case a life study
  struct Case {
    int index = 0;
    std::string dir;                  // folder name under cases/
    std::string label;                // "key=value, ..." for the script's comments
    std::vector<std::string> axes;    // the axes' KEY=VALUE
    std::vector<std::string> life;    // a life study's options, --KEY=VALUE
  };
  std::vector<Case> cases;            // every case of the sweep
  std::vector<int> array;             // the tasks to submit (#SBATCH --array)
  io::SlurmSettings slurm;
};

JobScript job_script_for(const io::Sweep& s, const std::vector<io::SweepCase>& cases,
                         const std::filesystem::path& sweep_dir, const std::filesystem::path& millcharge);

// The bash script; also runs without Slurm as `bash sweep.sh INDEX`.
std::string job_script_text(const JobScript& j);

// "0-3,5,7-9" (with "%N" for a throttle).
std::string array_spec(const std::vector<int>& indexes, int max_running = 0);

// Quoted for bash: 'text' with ' written as '\''.
std::string shell_quote(const std::string& s);

// sbatch --parsable SCRIPT; returns the job id. Throws std::runtime_error
// with sbatch's own message when it fails.
std::string submit(const std::filesystem::path& script);

// Array tasks of these jobs that Slurm still holds (pending or running), as
// job id -> task ids, from squeue. Throws std::runtime_error when squeue fails.
std::map<std::string, std::set<int>> queued_tasks(const std::set<std::string>& job_ids);

// Is `program` on PATH?
bool on_path(const std::string& program);

}  // namespace mc::app
