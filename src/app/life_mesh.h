// A life study's mesh liners (docs/liner-life.md "Mesh liners"): the
// case's [[walls.mesh]] of part "lifters" or "shell" that turn with the
// mill wear by what their triangles booked in each stage's run
// (life/mesh_wear.h moves them); each worn stage runs on the meshes the
// study wrote for it, stage-NN/liner.stl (liner-K.stl, K the [[walls.mesh]]
// index, where the case has several), and life_meshes.csv follows them.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "app/life_state.h"
#include "core/mill_case.h"

namespace mc::app::life {

// The [[walls.mesh]] indices a study wears: those of part "lifters" or
// "shell" that turn with the mill (an "ends" mesh, or one that stands
// still, is left as it is). std::invalid_argument naming the key where a
// worn mesh's material wears otherwise than the liner (the study's wear
// coefficients and calibration are the liner's).
std::vector<int> worn_meshes(const MillCase& c);

// A stage's mesh as placed in the mill frame, every triangle (a periodic
// slice's seam caps too): the case's own at stage 0, else the STL the study
// wrote (relative to `out`).
std::vector<Triangle> stage_mesh_triangles(const std::filesystem::path& out, const MillCase& c, const StageMesh& m);

// Refused by name before a study starts: a worn mesh whose STL corners are
// not welded (more than half its triangles alone), and with
// `axial_segments` a triangle (not an end cap) longer along the mill than
// a segment.
void check_worn_meshes(const MillCase& c, const std::vector<int>& worn, int axial_segments);

// The share of the shell's area that the worn meshes of part "lifters"
// stand on, where the case has no [lifters] bars: each bar's (connected
// part's) vertices within a millimetre of the shell span an arc and a
// length, the bar's footprint. The run books the shell's wear over the
// whole cylinder (it does not know the mesh covers it); the shell's mean
// depth rate is its wear over the rest, the rate over the whole divided by
// (1 - this share).
double shell_share_covered(const MillCase& c, const std::vector<int>& worn);

// A stage's shell depth rates (and their parts, and the halves') times f.
void scale_shell_rates(StageResult& r, double f);

// The case's [[walls.mesh]] entries for stage s: each worn mesh from the
// STL the study wrote for it (placed already: offset 0, angle 0, no flip),
// or from `worn` (in s.meshes' order) where given.
void put_stage_meshes(MillCase& c, const std::filesystem::path& out, const Stage& s,
                      const std::vector<std::vector<Triangle>>* worn = nullptr);

// The wear of stage s's `span_case_hours` (at the case's wear coefficient;
// volumes at `mix`) on its meshes: the worn meshes (in s.meshes' order),
// next.meshes named and s.meshes' step figures set; the booked wear spread
// by `smoothing` first. Writes nothing: write_stage_meshes does, once the
// next stage's case is known to be valid. `next_R`: the worn
// shell's radius, which no vertex may pass. std::invalid_argument from
// the mesh move (life/mesh_wear.h) naming walls.mesh[K] and the stage.
// Each bar, in each of `axial_segments` spans of the mill where that is
// more than 1, removes what it was asked (life/mesh_collapse.h wear_kept_fit).
// How far the booked wear is spread before the mesh moves (m; life/mesh_wear.h smooth_wear).
struct MeshSmoothing {
  double across_m = 0, along_m = 0;
};
std::vector<std::vector<Triangle>> wear_meshes(const std::filesystem::path& out, const MillCase& c, Stage& s,
                                               Stage& next, const WearMix& mix, double span_case_hours, double next_R,
                                               const MeshSmoothing& smoothing, int axial_segments = 1);
void write_stage_meshes(const std::filesystem::path& out, const Stage& next,
                        const std::vector<std::vector<Triangle>>& worn);

// life_meshes.csv: per stage and worn mesh, its triangles, its parts (bars)
// measured across at mid-length and a tenth of the length from each end
// (life/mesh_section.h: height and face angles, the mean over the bars and
// its standard error from their spread), what it wears per hour at the
// study's mix and calibration, and the step's booked and removed volume,
// depth scale and deepest move.
struct MeshTableBasis {
  double factor = 1;  // calibrated hours = case hours / factor
  std::string basis;  // life.csv's wear_basis
  WearMix mix;
  double density = 0;
  MeshSmoothing smoothing;
};
void write_mesh_table(const std::filesystem::path& out, const MillCase& c, const std::vector<Stage>& stages,
                      const MeshTableBasis& b);

// life_segments.csv: per stage, worn mesh and axial segment (the mill's
// length cut into `segments` equal spans): its bars cut across at the
// segment's middle (mean height and face angles over the bars, each with
// its standard error from their spread), the shell's wear rate there (the
// area-weighted mean of its elements, each element's area shared over the
// spans it covers by the length in each, at the study's mix and
// calibration: the shell itself moves by its mean), and for each stage but
// the last the volume the segment's triangles booked, what the move was
// asked to remove there (spread by the smoothing, less the collapse's
// share: life/mesh_collapse.h), and the volume the move removed.
void write_segment_table(const std::filesystem::path& out, const MillCase& c, const std::vector<Stage>& stages,
                         const MeshTableBasis& b, int segments);

// The stages as life.png draws them where the bars are a mesh: each ran
// stage's outline the mean of the first worn mesh's bars cut across at
// mid-length (life/mesh_section.h mean_outline), without standard errors.
std::vector<Stage> stages_drawn(const std::filesystem::path& out, const MillCase& c, const std::vector<Stage>& stages);

}  // namespace mc::app::life
