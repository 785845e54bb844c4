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
  // A charge of rigid bodies (clumps): each point's body (-1: a free ball)
  // and that body's orientation, a unit quaternion (x, y, z, w) taking the
  // body frame to the lab frame; both empty without bodies (and then not
  // written).
  std::vector<int> body;
  std::vector<std::array<float, 4>> orientation;
  std::size_t size() const { return position.size(); }
};

// Writes one snapshot atomically (io/atomic_file.h). Throws std::runtime_error.
void write_vtp(const std::filesystem::path& path, const Snapshot& s);

// A surface of polygons with values per cell (the liner and its sums).
struct PolyMesh {
  double time_s = 0;
  std::vector<std::array<float, 3>> points;  // m
  std::vector<std::vector<int>> polygons;    // point indices, each at least 3
  std::vector<std::pair<std::string, std::vector<float>>> cell_floats;  // one value per polygon
  std::vector<std::pair<std::string, std::vector<int>>> cell_ints;
};

// Writes the mesh atomically as VTK XML PolyData. Throws std::invalid_argument
// for a polygon or cell array that does not fit, std::runtime_error when the
// file cannot be written.
void write_mesh_vtp(const std::filesystem::path& path, const PolyMesh& m);

// Reads a file written by write_vtp back. Throws std::runtime_error naming
// the path and what is wrong when the file is not such a file.
Snapshot read_vtp(const std::filesystem::path& path);

// The charge.pvd index of a run folder; each add() rewrites it atomically
// with every snapshot so far (file names relative to the .pvd's folder).
class PvdIndex {
 public:
  explicit PvdIndex(std::filesystem::path pvd_path);
  // `part` tells datasets of the same time apart (0 the balls, 1 the liner):
  // ParaView shows the parts of a time together.
  void add(double time_s, const std::string& relative_file, int part = 0);
  // Takes the first `count` entries of the index file already at the path
  // (for a resumed run); throws std::runtime_error if it holds fewer.
  void keep_existing(std::size_t count);
  const std::filesystem::path& path() const { return path_; }
  std::vector<double> times(int part = 0) const;  // of the datasets of a part, in order

 private:
  std::filesystem::path path_;
  struct Entry {
    double time_s;
    std::string file;
    int part;
  };
  std::vector<Entry> entries_;
};

}  // namespace mc::io
