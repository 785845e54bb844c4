// What this build of millcharge is: its version and the commit it was
// built from, so that every result can be traced to its code (summary.json,
// grind.json, the sweep table, the GPU kit).
#pragma once

#include <string>

namespace mc {

const char* version();       // "0.1.0"
const char* build_commit();  // `git describe --always --dirty` at build time, or "unknown"
std::string version_line();  // "millcharge 0.1.0 (commit 1a2b3c4)"

}  // namespace mc
