// Life studies side by side (docs/sweeps.md, "Life studies side by side"):
// a sweep file of command = "life" runs one `millcharge life` study per case
// (a candidate liner), here or on Slurm, and `sweep collect` tables each
// study's end state beside its new liner's: the lifters' height and faces,
// the shell's wear, power and impact point, and the hours to the relining
// height, each with its standard error where the study has one; sweep.png
// draws their paths against hours.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "app/sweep_table.h"

namespace mc::app {

// How the study in `case_dir` (its life.json's request) differs from the
// request the sweep's case makes, in words; "" where the folder holds no
// study yet or the same one.
std::string life_study_difference(const std::filesystem::path& case_dir, const nlohmann::json& request);

// The hours at which a path of heights falls to `relining_mm` (linear
// between stages; a height within `tolerance_mm` above it counts as
// there: a study stopped by its own --until-height ends that close) and
// their standard error, the height's error there over the path's fall
// per hour. NaN where the path stays above it. `se` may be empty.
struct Crossing {
  double hours = NAN, se = NAN;
};
Crossing hours_to_height(const std::vector<double>& hours, const std::vector<double>& height,
                         const std::vector<double>& se, double relining_mm, double tolerance_mm = 0);

// The table of a life sweep: a row per case with its axes, status, and its
// study's figures at the new liner (`.new`) and at the study's end
// (`.end`, `.end_se`); the hours to `relining_mm` (0: the studies'
// --until-height where [life] gives it, else none). Paths for the picture
// come back in `paths` (per row; empty for a case without life.csv).
struct LifeSweep {
  SweepTable table;
  double relining_mm = 0;
  std::string relining_source;  // "--relining-height", "[life] until-height" or ""
  struct Path {
    std::string label;
    std::vector<double> hours, height, leading, power, impact;
  };
  std::vector<Path> paths;
};
LifeSweep collect_life_table(const std::filesystem::path& sweep_dir, const nlohmann::json& cases, double relining_mm);

// sweep.png: height, leading face, power and impact point against hours, a
// line per study (the relining height dashed). Returns whether it was drawn.
bool write_life_sweep_plot(const LifeSweep& s, const std::filesystem::path& file);

// `sweep collect` of a life sweep: sweep.csv, sweep.json, sweep.png and the
// table on the console. Returns the exit status.
int collect_life_sweep(const std::filesystem::path& sweep_dir, const nlohmann::json& cases, double relining_mm);

}  // namespace mc::app
