// A life study's state (docs/liner-life.md): its stages as life.json holds
// them, what each stage's run reported, and the strict reading of both.
// life.json is read and checked whole (types, keys, list lengths against
// the case's profiles and the wear stations, outlines by the case reader's
// own check) before a resumed study writes anything: a damaged state is
// refused in one line naming the file, the stage and the key.
#pragma once

#include <array>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/vec.h"
#include "life/plates.h"

namespace mc::app::life {

// 2: the calibration says what the hours stand on and the wear coefficients.
inline constexpr const char* kFormat = "millcharge life 2";

// What a stage's run reported (its summary.json and lifter_wear.csv).
// What a stage's wear is made of: sliding wear at the case's coefficient,
// and the strike energy (J/s) the impact wear reads.
struct WearParts {
  double liner_sliding_kg_h = 0, liner_strike_W = 0;  // shell and lifters
  double shell_sliding_kg_h = 0, shell_strike_W = 0;  // the shell's part of them
  double shell_sliding_mm_per_1000h = 0, shell_strike_W_m2 = 0;
  std::vector<std::vector<double>> station_sliding_m3_s, station_strike_W;  // per profile, per station
};

// The wear figures are the sum of sliding and impact wear at the study's
// coefficients (WearMix); the raw parts they are made of are kept beside
// them, so that a study given an impact share mixes them again.
struct StageResult {
  double power_W = 0, power_sem_W = 0, toe_deg = NAN, shoulder_deg = NAN, impact_deg = NAN, bare_share = NAN;
  double liner_kg_h = 0;          // shell and lifters (not the end plates), at the study's coefficients
  double shell_mm_per_1000h = 0;  // the shell's mean depth rate, likewise
  std::vector<std::vector<double>> station_m3_s;  // per profile, per station: one row's volume rate
  WearParts parts;
  // The parts over each half of the run's averaging window (none where the
  // run has no halves): how far the stage's wear can be trusted.
  std::vector<WearParts> halves;
  // Per worn mesh (Stage::meshes), what its triangles booked: sliding wear
  // at the case's coefficient (m³/s) and strike energy (J/s); part of
  // `parts`' liner figures.
  std::vector<double> mesh_sliding_m3_s, mesh_strike_W;
  // What the end plates booked, where the study wears them (life/plates.h).
  mc::life::PlateBooks plates;
};

// How a study mixes the two wears: volume = sliding · (Archard's volume at
// the case's coefficient) + impact · (strike energy), impact in m³/J. The
// case's own: sliding 1, impact its impact_wear_coefficient. Given an impact
// share S of the new liner's shell and lifter wear (--impact-share), both
// are set so that the new liner wears as much as at the case's own, S of it
// by impact.
// `shell` (--shell-wear-ratio) is the shell plates' coefficients over the
// bars' (both wears): the bars keep theirs, the shell's wear is so many
// times what the runs booked at the case's.
struct WearMix {
  double sliding = 1, impact = 0;
  double shell = 1;
  double share = NAN;  // the share asked for; NaN: the case's own mix
};

// The mix for share S (NaN: the case's own mix) and shell ratio `shell`
// from the new liner's result `s0` (liner density `density`, kg/m³; the
// case's impact coefficient `case_impact`, m³/J): the new liner's shell
// and lifters wear as much as at the case's coefficients, S of it by
// impact; std::invalid_argument naming --impact-share where that cannot be
// had.
WearMix mix_for_share(const StageResult& s0, double share, double case_impact, double density, double shell = 1);

// Wear figures at a mix, from their parts.
struct MixedWear {
  double liner_kg_h = 0, shell_mm_per_1000h = 0;
  std::vector<std::vector<double>> station_m3_s;
};
MixedWear mixed(const WearParts& p, const WearMix& mix, double density);

// The share of a stage's shell and lifter wear that impact does at a mix.
double impact_share(const StageResult& r, const WearMix& mix, double density);

// The stage's wear figures at that mix, from their parts.
void apply_mix(StageResult& r, const WearMix& mix, double density);

// A worn mesh liner at a stage: a [[walls.mesh]] of part "lifters" or
// "shell" that turns with the mill.
struct StageMesh {
  int walls_mesh = 0;  // its index in the case's [[walls.mesh]]
  std::string file;    // the STL the stage ran on, relative to the study's folder; "": the case's own
  // The wear carried to the next stage (none for the last): the volume its
  // triangles booked, the volume removed (the collapse's and the move's
  // together: the booked), the move's depth scale, the largest vertex
  // move, the vertices slid along the surface to keep the mesh valid
  // (life/mesh_wear.h).
  double booked_m3 = 0, removed_m3 = 0, scale = 1, deepest_m = 0;
  int relaxed = 0, collapsed = 0;  // and the short edges collapsed first (life/mesh_collapse.h),
  double collapse_share = 0;       // those shorter than this share of the median edge (0: none)
  double collapse_m3 = 0;          // the volume the collapse took (the move removed booked less this)
  int local_passes = -1;           // the move's local corrections (life/mesh_collapse.h wear_kept_fit; -1: not known,
  double local_misfit = 0;         // a move of a study begun before), the largest |removed / asked − 1| of a stretch
  int stretch_segments = 0;        // after them, and the spans along the mill its stretches were cut in (0: not known)
  // The steps the wear was moved in (0: not known, a move of a study begun
  // before; more than 1 where one move would spoil the mesh), and per span
  // of stretch_segments what the moves were asked and swept (m³; empty
  // where not known: the segment table works them out from the meshes).
  int steps = 0;
  std::vector<double> span_asked_m3, span_removed_m3;
};

struct Stage {
  int index = 0;
  double case_hours = 0;  // at its start, at the case's wear coefficient
  double diameter = 0, filling = 0, shell_wear_m = 0;  // shell_wear_m: since the new liner
  std::vector<std::vector<Vec2>> outlines;              // per profile, the bar's frame
  std::vector<StageMesh> meshes;                        // the worn mesh liners
  bool ran = false;
  StageResult r;
  // The wear carried to the next stage (none for the last).
  double span_case_hours = 0, shell_depth_m = 0;
  std::vector<double> booked_mm2, removed_mm2, scale;
  std::vector<int> spread;
  // Per profile, how far this stage's step can be trusted: half the
  // difference between the bar worn by the first and by the second half
  // of the window's wear (height mm, leading and trailing face deg); empty
  // where the run has no halves.
  std::vector<double> se_height_mm, se_leading_deg, se_trailing_deg;
  // Where the study wears the end plates: their depth per ring at the
  // stage's start (m; z = 0, then z = length), and per ring what the step
  // booked and the worn surface lost (m³, life/plates.h wear_plates).
  std::array<std::vector<double>, 2> plate_depth_m;
  std::array<std::vector<double>, 2> plate_booked_m3, plate_removed_m3;
};

// Each stage's standard errors of its bars' height (mm) and face angles
// (deg), per profile: the steps before it (Stage::se_*) added in
// quadrature, each stage's window being a run of its own; NaN from the
// first stage whose run had no halves on.
struct StageSe {
  std::vector<double> height_mm, leading_deg, trailing_deg;
};
std::vector<StageSe> cumulative_se(const std::vector<Stage>& stages);

// What a study's state must fit: its case's lifter profiles and the room a
// bar must leave for a ball (the largest ball's diameter).
struct StateShape {
  std::size_t profiles = 0;
  double largest_ball_m = 0;
  std::vector<int> meshes;  // the worn meshes' indices in [[walls.mesh]]
  int plate_rings = 0, plate_sectors = 0;  // the worn end plates' (0: the study holds them)
  std::array<std::vector<double>, 2> plate_start;  // their depths in the case (m), stage 0's
};

struct LifeState {
  nlohmann::json request;  // the request the study was started with
  std::vector<Stage> stages;
  std::string stopped;  // why it stopped, when it has
};

// life.json read and checked whole; std::invalid_argument naming the file,
// the stage and the key otherwise.
LifeState read_life_state(const std::filesystem::path& file, const StateShape& shape);

// How the request in life.json differs from this one, in words ("stages:
// 2 there, 3 asked"); "" when they are the same.
std::string request_difference(const nlohmann::json& there, const nlohmann::json& asked);

// A study begun before the end plates wore (its request `there` without
// end_plates) resumes with them held: `asked` then loses its end_plates,
// and the answer is true.
bool begun_before_plates(const nlohmann::json& there, nlohmann::json& asked);

// How a study's hours were set: calibrated hours = case hours / factor.
struct Calibration {
  double factor = 1;
  WearMix mix;
  std::string how;
  // "calibrated" (by a measured figure), "relative" (the default wear
  // coefficient: hours and wear rates are relative), "case_coefficient".
  std::string basis;
  double case_wear_coefficient = 0;  // m³/(N·m), the case's
};

// Writes life.json (atomically).
void save_life_state(const std::filesystem::path& out, const nlohmann::json& request, const std::vector<Stage>& stages,
                     const Calibration& calibration, const std::string& stopped);

// A stage's run folder: its summary.json and lifter_wear.csv, checked; and
// where the study wears meshes (their [[walls.mesh]] indices), what their
// triangles booked in its wear.csv, added to the liner's parts.
// (density: the liner's, kg/m³, for the meshes' sliding wear in kg/h).
// Where it wears the end plates (rings > 0), what they booked too.
StageResult read_stage_result(const std::filesystem::path& dir, int profiles, const std::vector<int>& meshes = {},
                              double density = 0, int plate_rings = 0, int plate_sectors = 0);

// What each triangle of mesh `mesh` ([[walls.mesh]] index) booked in a
// run's wear.csv: sliding wear at the case's coefficient (m³/s) and strike
// energy (J/s), in the order of the mesh's triangles in the run (a periodic
// slice's seam caps left out). std::invalid_argument naming the file and
// the row where a row is damaged, or where the mesh's triangles are not
// `triangles` in number.
struct TriangleWear {
  std::vector<double> sliding_m3_s, strike_W;
};
TriangleWear read_triangle_wear(const std::filesystem::path& wear_csv, int mesh, std::size_t triangles);

}  // namespace mc::app::life
