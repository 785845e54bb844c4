// `millcharge sweep check|run|collect` (docs/sweeps.md). A sweep file
// expands into cases; each case is a normal `millcharge run` into its own
// folder, run here N at a time (--local) or as a Slurm job array (--slurm,
// --print); `collect` joins the finished runs into a table and plots.
#pragma once

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace mc::app {

struct SweepCheckOptions {
  std::string file;
  double throughput = 0;  // --throughput particle-updates/s; 0: the file's, else the default
};

struct SweepRunOptions {
  std::string file;
  std::string out;          // --out; empty: runs/NAME
  int local = 0;            // --local N: N cases at a time here; 0: not local
  bool slurm = false;       // --slurm: write the script and sbatch it
  bool print = false;       // --print: write the script only
  bool retry_failed = false;
  std::string device;       // --device for every run (overrides the file's)
  // Slurm settings from the command line; unset ones keep the file's.
  std::string partition, time;
  int gpus_per_task = -1, cpus_per_task = -1, max_running = -1, signal_grace = -1;
  std::vector<std::string> sbatch_args;
};

struct SweepCollectOptions {
  std::string dir;
  double relining_height_mm = 0;  // --relining-height MM: a life sweep's hours to it (0: [life] until-height)
};

// `millcharge sweep` and its three subcommands on the CLI11 app; after
// parsing, run_sweep() runs the one given (returns false when `sweep` was not).
struct SweepCli {
  CLI::App* sweep = nullptr;
  CLI::App* check = nullptr;
  CLI::App* run = nullptr;
  CLI::App* collect = nullptr;
  SweepCheckOptions check_options;
  SweepRunOptions run_options;
  std::string local;  // --local's value, as given
  SweepCollectOptions collect_options;
};
void add_sweep_commands(CLI::App& app, SweepCli& cli);
bool run_sweep(SweepCli& cli, int& status);

int cmd_sweep_check(const SweepCheckOptions& o);
int cmd_sweep_run(const SweepRunOptions& o);
int cmd_sweep_collect(const SweepCollectOptions& o);

}  // namespace mc::app
