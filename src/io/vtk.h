// ParaView files of the charge: one VTK XML PolyData file (.vtp) per snapshot,
// each ball a vertex with its radius, velocity, speed, material and id, and a
// charge.pvd collection that indexes the snapshots by simulated time.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace mc::io {

struct Snapshot {
  double time_s = 0;
  std::vector<std::array<float, 3>> position;  // m, lab frame
  std::vector<std::array<float, 3>> velocity;  // m/s
  std::vector<float> radius;                   // m
  std::vector<int> material;
  std::vector<int> id;
  std::size_t size() const { return position.size(); }
};

// Writes one snapshot atomically (io/atomic_file.h). Throws std::runtime_error.
void write_vtp(const std::filesystem::path& path, const Snapshot& s);

// Reads a file written by write_vtp back. Throws std::runtime_error naming
// the path and what is wrong when the file is not such a file.
Snapshot read_vtp(const std::filesystem::path& path);

// The charge.pvd index of a run folder; each add() rewrites it atomically
// with every snapshot so far (file names relative to the .pvd's folder).
class PvdIndex {
 public:
  explicit PvdIndex(std::filesystem::path pvd_path);
  void add(double time_s, const std::string& relative_file);
  // Takes the first `count` entries of the index file already at the path
  // (for a resumed run); throws std::runtime_error if it holds fewer.
  void keep_existing(std::size_t count);
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::vector<std::pair<double, std::string>> entries_;
};

}  // namespace mc::io
