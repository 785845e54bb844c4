// The subcommands of `millcharge` (DESIGN.md, "Command line"). Each returns
// the process's exit status: 0 done, 2 bad input (nothing written), 1 other
// failures. They throw; main() turns exceptions into messages and statuses.
#pragma once

#include <string>
#include <vector>

namespace mc::app {

struct CaseOptions {
  std::string case_path;              // empty: the default lab mill
  std::vector<std::string> overrides; // --set KEY=VALUE
  std::string device;                 // --device
  std::string precision;              // --precision, empty: the case's
  double duration = 0;                // --duration, 0: the case's
  bool duration_auto = false;         // --duration auto
  std::string write_lifters;          // check --write-lifters FILE: the lifter bars as STL
  double lifter_mesh_mm = 0;          // check --lifter-mesh MM: their triangles at most MM across (0: one per face)
};

struct RunOptions {
  CaseOptions c;
  std::string out;     // --out; empty: runs/<case>-<time>
  bool force = false;  // --force: replace an earlier run in --out
  bool quiet = false;  // --quiet: no progress lines
  std::string resume;  // --resume DIR: continue the run in DIR from its checkpoint
  double poison_at_s = -1;  // fault injection for tests: NaN in a ball at this time
};

struct BenchOptions {
  CaseOptions c;       // empty case_path: the 100,000-ball benchmark mill
  long steps = 0;      // timed steps; 0: about 10 wall seconds' worth
  double warmup = -1;  // simulated s of the turning mill before the timing;
                       // < 0: 0.25 s from a packed charge (it collapses into
                       // a dense bed), 0 from a checkpoint
  std::string from;    // --from DIR: start from the checkpoint of a run in DIR
  int tile = 0;        // --tile N (with --from): the checkpoint's charge laid
                       // anew N times end to end along the axis, in a mill N
                       // times as long; 0: not given (the checkpoint's state)
  bool quiet = false;  // no progress lines on stderr
  // --books both|on|off: time with the energy books (collision spectra,
  // liner sums) on, off, or both in turn from the same state (the default).
  std::string books = "both";
};

struct ViewOptions {
  CaseOptions c;
  int frames = 0;              // --frames: draw this many, then exit
  std::string screenshot;      // --screenshot FILE.png after the last frame
  int steps_per_frame = 0;     // --steps-per-frame; 0: default (adaptive; 40 with --frames), −1: adaptive
  std::string camera = "end";  // --camera end|iso
  std::string colour = "speed";  // --colour speed|size|material|impact
  std::string liner = "plain";   // --liner plain|impact|wear
  int width = 1280, height = 800;  // --size WxH
  bool no_panel = false;       // --no-panel
  std::vector<std::string> edits;  // --edit FRAME:KEY=VALUE
  std::string from;                // --from RUN: open on the run's checkpoint
  std::string save_state;          // --save-state DIR: the state after the last frame
};

struct LifeOptions {
  CaseOptions c;
  std::string out;              // --out; empty: runs/<case>-life
  int stages = 0;               // --stages N: worn stages after the new liner
  double hours = 0;             // --hours H: operating hours the study covers
  double until_height_mm = 0;   // --until-height MM: until the lifters are this high
  double calibrate_loss_mm = 0; // --calibrate-loss MM with --calibrate-hours H: the
  double calibrate_hours = 0;   //   lifters lost MM of height in H operating hours
  double calibrate_rate_kg_h = 0;  // --calibrate-rate KG/H: the new shell liner's wear rate
  double calibrate_consumption_g_kWh = 0;  // --calibrate-consumption G_PER_KWH: the new shell and lifters' g/kWh
  double shell_wear_ratio = 1;  // --shell-wear-ratio R: the shell's wear coefficients over the bars'
  double impact_share = -1;     // --impact-share S: the share of the new liner's wear that impact does (< 0: the case's)
  double mesh_smoothing_mm = 0; // --mesh-smoothing MM: a mesh liner's wear averaged over MM across the axis (0: the largest ball's radius)
  int axial_segments = 0;       // --axial-segments N: a mesh liner measured in N spans along the mill (0: none)
  double lifter_mesh_mm = 0;    // --lifter-mesh MM: with --axial-segments, the bars of [lifters] as a mesh of MM triangles (0: default)
  double mesh_smoothing_along_mm = 0;  // --mesh-smoothing-along MM: and along it (0: four times across)
  bool hold_plates = false;     // --hold-plates: the end plates stay as they are (they wear by default)
  bool force = false;           // --force: start again in an --out that holds another study
  bool quiet = false;
};

// life-compare: life studies side by side (app/life_compare.h).
struct LifeCompareOptions {
  std::vector<std::string> studies;   // the studies' folders (their --out)
  std::vector<std::string> labels;    // --label, one per study; empty: the folders' names
  std::vector<double> at;             // --at H,...: the hours tabled; empty: 4 to the shortest study's end
  std::vector<std::string> measured;  // --measured COLUMN@HOURS=VALUE
  int profile = 0;                    // --profile K: the lifter profile followed
  std::string out;                    // --out; empty: runs/life-compare
  bool quiet = false;
};

int cmd_devices();
int cmd_check(const CaseOptions& o);
int cmd_run(const RunOptions& o);
int cmd_bench(const BenchOptions& o);
int cmd_view(const ViewOptions& o);
int cmd_life(const LifeOptions& o);
int cmd_life_compare(const LifeCompareOptions& o);

}  // namespace mc::app
