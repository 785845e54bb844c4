// Ore files for `millcharge grind` (TOML, assets/ores/*.toml documents the
// keys): read and validated to a grind::Ore. Every error names the file,
// the line and the dotted key, e.g.
//   ore.toml:12: rates.zeta1: 60 is out of range: -5 to 5
// and unknown keys are errors.
#pragma once

#include <filesystem>
#include <string>

#include "grind/ore.h"

namespace mc::io {

grind::Ore read_ore(const std::filesystem::path& path);

// The ore as an ore file that read_ore takes back: every key of its rate
// model to 10 significant digits, and the [fitted] table when the ore was
// fitted (the contact it holds under). `header`: comment lines put first.
std::string ore_toml(const grind::Ore& ore, const std::string& header);

}  // namespace mc::io
