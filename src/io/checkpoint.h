// Checkpoints: everything a run needs to continue bit for bit: the resolved
// case, where the run stands (RunState) and the solver's whole state. One
// binary file, written atomically; a length and a checksum guard it, so a
// truncated or damaged file is refused with a message rather than read.
//
// Layout: the magic line "millcharge checkpoint\n", a u32 format version, a
// u64 payload length, the payload, and a u64 FNV-1a hash of the payload. The
// payload is a list of records: u32 name length, name, u64 length, bytes.
// Scalars are text ("key=value" lines, doubles with 17 digits); arrays are the
// device's bytes. Integers are little-endian (the only byte order in use).
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

#include "sim/mill_run.h"
#include "sim/solver.h"

namespace mc::io {

class CheckpointError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Checkpoint {
  std::string case_name;  // the case's name (its file's stem)
  std::string case_toml;  // the resolved case (case_to_toml)
  RunState run;
  SolverState solver;
};

inline constexpr const char* kCheckpointFile = "checkpoint.bin";

// Throws std::runtime_error naming the path on a write failure.
void write_checkpoint(const std::filesystem::path& path, const Checkpoint& cp);
// Throws CheckpointError naming the path and what is wrong with the file.
Checkpoint read_checkpoint(const std::filesystem::path& path);

// The checkpoint at `path` as it was last written whole, for a run that
// another process may still be writing. write_checkpoint replaces the file
// by a rename, so a reader sees the old file or the new one, never a part;
// a file that fails its checks while it changes under the reader (a copy
// under way, a writer that writes in place) is read again once it holds
// still, for up to `wait_s`. A file that fails them and holds still is
// refused at once, as read_checkpoint refuses it.
Checkpoint read_complete_checkpoint(const std::filesystem::path& path, double wait_s = 5.0);

}  // namespace mc::io
