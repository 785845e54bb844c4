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

// The ore's [sizes], [breakage] and [rates] tables (and its energy basis)
// as ore_toml writes them, each hashed (FNV-1a, 64 bits): "sizes HEX
// breakage HEX rates HEX", kept in [fitted] as tables_fnv1a when the ore is
// fitted. changed_tables: "" when `kept` is "" or the ore's tables hash to
// it; else the tables that differ ("[breakage]", "[sizes] and [rates]").
std::string ore_tables_hash(const grind::Ore& ore);
std::string changed_tables(const grind::Ore& ore, const std::string& kept);

}  // namespace mc::io
