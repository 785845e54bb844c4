// What every command that reads a case shares: the case (from its file and
// the command line, or from a run's checkpoint) validated and built into a
// scene, and the small formats their messages use.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "core/mill_case.h"
#include "core/scene.h"
#include "io/case_file.h"
#include "io/checkpoint.h"

namespace mc::app {

struct Prepared {
  std::filesystem::path path;
  MillCase c;
  MillDerived d;
  Scene scene;
};

// --set, --duration and --precision as overrides of the case's keys.
std::vector<std::string> case_overrides(const CaseOptions& o);

// The case of CASE (or `default_path`) with --set, --duration and
// --precision applied, derived and built; bad input throws naming the key.
Prepared prepare(const CaseOptions& o, const std::filesystem::path& default_path = io::default_case());

// The case of the run in `dir`, from its checkpoint (read into `cp`; the
// last one written whole, should the run be going on). A bad checkpoint is
// bad input: its message, then `consequence`. What run --resume, bench
// --from and view --from read.
Prepared prepare_from_checkpoint(const std::filesystem::path& dir, io::Checkpoint& cp, const std::string& consequence);

std::string thousands(long v);        // 1234567 -> "1,234,567"
// A power or a mass in the unit a reader expects at its size, to 4 figures:
// 874.4 W, 1.234 kW, 4.491 MW; 15.6 kg, 195.5 t.
std::string watts(double w);
std::string kilograms(double kg);
std::string duration_text(double s);  // "42s", "3m05s", "2h10m"
nlohmann::json number_or_null(double v);

}  // namespace mc::app
