// Case files: TOML (toml++) to a validated MillCase. Every error names the
// file, the line and the dotted key, e.g.
//   lab.toml:7: mill.diameter: must be > 0 m (got -0.9)
// Unknown keys are errors (with the nearest known key suggested), so a typo
// never silently falls back to a default. assets/cases/lab.toml documents
// every key.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/mill_case.h"

namespace mc::io {

// A bad case: the message is complete ("file:line: key: what").
struct CaseError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// Reads and validates a case file; `overrides` are "dotted.key=value" strings
// (`--set`), applied before validation. Array elements are addressed as
// "charge.size.0.fraction" or "charge.size[0].fraction". A value that is not
// valid TOML is taken as a string (`--set contact.law=hertz`).
MillCase read_case(const std::filesystem::path& file, const std::vector<std::string>& overrides = {});

// The same from text in memory; `source` names it in messages.
MillCase parse_case(std::string_view text, const std::string& source,
                    const std::vector<std::string>& overrides = {});

// The case written back as TOML (all keys, resolved), for run folders.
std::string case_to_toml(const MillCase& c);

// assets/cases (MILLCHARGE_ASSET_DIR overrides the built-in path).
std::filesystem::path case_dir();
// The default laboratory mill, assets/cases/lab.toml.
std::filesystem::path default_case();

}  // namespace mc::io
