// `millcharge sweep collect`: the run folders of a sweep joined into one
// table (sweep.csv, sweep.json) and plots (sweep.png, plots/*.png). A row per
// case: the axis values, the status (and why a failed case failed), then the
// figures its summary.json has. Blocks that other parts of millcharge add to
// summary.json (`spectra.total`, `liner`) come in as they are: every numeric
// scalar there becomes a column, so new fields need no change here.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace mc::app {

struct SweepTable {
  std::string name;                  // the sweep's
  std::vector<std::string> axes;     // axis keys, the first columns
  std::vector<std::string> columns;  // every column, axes first
  std::vector<nlohmann::ordered_json> rows;  // column -> number, string or null
  int finished = 0;
};

// Reads SWEEP/cases.json and every case's folder. A case that failed or never
// ran is a row with its status; it never stops the others. Throws
// std::invalid_argument when SWEEP is not a sweep folder.
SweepTable collect_table(const std::filesystem::path& sweep_dir);

std::string table_csv(const SweepTable& t);
nlohmann::ordered_json table_json(const SweepTable& t);

// sweep.png (power against the first axis, a line per value of the other
// axes, Morrell's C-model dashed beside them) and plots/COLUMN.png for the
// other figures. Returns the files written.
std::vector<std::filesystem::path> write_sweep_plots(const SweepTable& t, const std::filesystem::path& sweep_dir);

}  // namespace mc::app
