// Files that are either complete or absent: written to a temporary file in the
// same folder, flushed to disk (fsync), then renamed over the target, and the
// folder synced. A crash at any moment leaves the old file or the new one.
#pragma once

#include <filesystem>
#include <functional>
#include <string_view>

namespace mc::io {

// Throws std::runtime_error naming the path and the system error.
void write_file_atomic(const std::filesystem::path& path, std::string_view data);

// Writes a file that comes after a run's results (a mesh, a picture's data)
// with `write`; one that cannot be written is a warning on stderr naming the
// file and why, never an end to the command. Returns whether it was written.
// `verb` names what failed ("written", "drawn").
bool write_or_warn(const std::filesystem::path& path, const std::function<void()>& write,
                   const char* verb = "written");

}  // namespace mc::io
