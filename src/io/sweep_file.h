// Sweep files: one TOML file that expands into many cases (docs/sweeps.md).
// A base case, keys every case gets, and axes: case keys with a list of
// values or a range, crossed (every combination) or zipped (the i-th values
// together). Each case is the base case with `--set` overrides, so a case of
// a sweep is exactly what `millcharge run CASE --set ...` would run.
//
//   case = "lab.toml"                  # relative to this file, or in assets/cases
//   [set]                              # every case
//   "run.duration" = 4.0
//   [axes]                             # in this order: the first is the plots' x
//   mill.speed_fraction = {from = 0.5, to = 1.0, step = 0.1}
//   lifters.profile.0.face_angle = [10, 30]
//
// Errors name the file, the line and the key, like the case reader's.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace mc::io {

struct SweepError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// One value of an axis: as `--set` takes it (TOML: 0.5, 10, "hertz") and as
// people read it (0.5, 10, hertz).
struct SweepValue {
  std::string toml;
  std::string text;
  bool numeric = false;
  double number = 0;  // when numeric
};

struct SweepAxis {
  std::string key;  // dotted case key, e.g. lifters.profile.0.face_angle
  std::vector<SweepValue> values;
  int group = 0;    // axes of one group move together (zipped); groups are crossed
};

// Settings of the Slurm backend; the command line overrides each.
struct SlurmSettings {
  std::string partition;        // empty: the cluster's default
  std::string time;             // time limit as sbatch takes it, e.g. 04:00:00; empty: the partition's
  int gpus_per_task = 0;        // 0: none asked for
  int cpus_per_task = 0;        // 0: the cluster's default
  int max_running = 0;          // array throttle (%N); 0: no limit
  int signal_grace_s = 120;     // SIGTERM this long before the time limit (--signal=B:TERM@S)
  std::vector<std::string> sbatch_args;  // more sbatch options, e.g. "--qos=long"
};

// A life option of `[life]` (command = "life"): as `millcharge life` takes
// it, `--KEY=VALUE`. The key as written, underscores made dashes.
struct SweepLifeOption {
  std::string key;   // e.g. calibrate-consumption
  SweepValue value;
  int line = 0;      // in the sweep file
};

// Axes whose key starts with this vary a life option, not a case key.
inline constexpr const char* kLifeAxisPrefix = "life.";

struct Sweep {
  std::filesystem::path file;   // the sweep file
  std::string name;             // `name`, default the file's stem
  std::filesystem::path base_case;  // resolved path of `case`
  std::vector<std::string> set;     // "key=value" for every case
  std::vector<SweepAxis> axes;      // in the file's order
  bool zipped = false;              // combine = "zip": all axes one group
  std::string device;               // `device`, empty: millcharge's default
  double throughput = 0;            // particle-updates/s for estimates; 0: not given
  SlurmSettings slurm;
  // `command`: "run" (default), each case a `millcharge run`; or "life",
  // each case a life study (`millcharge life`) with `[life]`'s options.
  std::string command = "run";
  std::vector<SweepLifeOption> life;
  bool is_life() const { return command == "life"; }
};

struct SweepCase {
  int index = 0;                     // 0-based, the array task id
  std::vector<int> value_index;      // per axis, the index into its values
  std::string dir;                   // folder name under cases/, from the values
  std::vector<std::string> overrides;  // the sweep's `set`, then the axes' "key=value" (not life.* axes)
  // A life sweep's options for `millcharge life`: `[life]`'s, then the
  // life.* axes', each "--key=value".
  std::vector<std::string> life_args;
};

// Reads and checks a sweep file (not yet its cases: expand and read_case do).
Sweep read_sweep(const std::filesystem::path& file);
Sweep parse_sweep(const std::string& text, const std::filesystem::path& file);

// The cases in order: crossed groups with the first axis changing slowest
// (the plots' lines follow the second axis), zipped axes together.
std::vector<SweepCase> expand(const Sweep& s);

// "key=value, key=value" of a case, for messages and tables.
std::string case_label(const Sweep& s, const SweepCase& c);

// Whether `t` is a time limit in one of sbatch's forms: MM, MM:SS, HH:MM:SS,
// D-HH, D-HH:MM or D-HH:MM:SS (digits only; minutes and seconds after the
// first field below 60, hours after D- below 24).
bool slurm_time_valid(const std::string& t);
inline constexpr const char* kSlurmTimeForms = "MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS, e.g. 90, 04:00:00 or 1-12:00:00";

// The key's last part, or the whole key where two axes share a last part.
std::vector<std::string> short_axis_names(const Sweep& s);

}  // namespace mc::io
