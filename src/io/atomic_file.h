// Files that are either complete or absent: written to a temporary file in the
// same folder, flushed to disk (fsync), then renamed over the target, and the
// folder synced. A crash at any moment leaves the old file or the new one.
#pragma once

#include <filesystem>
#include <string_view>

namespace mc::io {

// Throws std::runtime_error naming the path and the system error.
void write_file_atomic(const std::filesystem::path& path, std::string_view data);

}  // namespace mc::io
