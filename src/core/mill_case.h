// A mill case in SI units, as a case file describes it (src/io/case_file.cpp
// reads it; assets/cases/*.toml document every key), and the values derived
// from it in one place: speeds, volumes, the charge's size classes and counts,
// contact times and the time step. No OpenCL, no file reading here.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/clump.h"
#include "core/lifters.h"
#include "core/morrell.h"
#include "core/scene.h"
#include "core/wall_mesh.h"

namespace mc {

struct SizeClass {
  double diameter_min = 0;  // m; equal to diameter_max for one size
  double diameter_max = 0;  // m; within a range diameters are uniform by number
  std::string material;
  double fraction = 1.0;    // of the charge's mass or number (MillCase::number_fractions)
  // "" or "sphere": balls. Otherwise a clump (core/clump.h) of a library
  // shape or of a [[charge.shape]] the case defines: a rigid body of
  // spheres whose volume-equivalent diameter is the class's diameter.
  std::string shape;
};

struct PairOverride {
  std::string a, b;         // material names
  Interaction interaction;  // complete: the case's defaults with this pair's keys applied
};

// One [[walls.mesh]]: a wall of triangles from an STL file (io reads it:
// the triangles here are in metres, as the file gives them times the units,
// not yet placed).
struct MeshSpec {
  std::string file;          // as the case gives it
  std::string path;          // the file found: relative paths from the case file's folder
  std::string units = "m";   // "m" or "mm"
  std::string material;      // "" : the liner's (mill.liner)
  bool turning = true;       // false: it stands still (a chute, a trommel)
  MeshPart part = MeshPart::lifters;
  Vec3 offset;               // m, added after the turn
  double angle_deg = 0;      // turned about the mill axis (+z), counter-clockwise
  bool flip = false;         // the charge is on the other side of every triangle
  std::vector<Triangle> triangles;
};

struct MillCase {
  std::string name;          // the case file's stem
  std::string title;
  // [mill]
  double diameter = 0;       // m, inside the liners
  double length = 0;         // m, between the end plates (or of the slice)
  // mill.ends = "periodic": a slice of `length` with no end plates, standing
  // for the middle of a long mill (cl/periodic.h); "plates" (the default):
  // a whole mill closed by its end plates.
  bool periodic = false;
  double speed_fraction = 0; // of critical; 0 when the case gives rpm
  double speed_rpm = 0;      // 0 when the case gives the fraction
  std::string liner;         // material of shell, end plates and lifters
  // [lifters]
  int lifter_rows = 0;
  std::vector<LifterProfile> lifter_pattern;  // row k has pattern[k % size]
  // [[walls.mesh]]: walls of triangles besides the shell, plates and lifters
  std::vector<MeshSpec> meshes;
  // mill.ends = "cones" (cone_angle, trunnion_diameter) and [end_lifters]: the ends, built
  // as meshes (core/wall_mesh.h)
  EndsSpec ends;
  // [liner]: how the liner is cut into elements for impact and wear sums
  LinerGrid liner_grid;
  // [liner] plate_depth_mm: worn end plates, each plate's (z = 0, then z =
  // length) depth per ring, m (core/plate_wear.h: the face across the
  // ring's middle half); empty: flat.
  std::array<std::vector<double>, 2> plate_depth;
  double lifter_first_angle_deg = 0;
  // [charge]
  double filling = 0;        // J: bulk charge volume / free mill volume
  double porosity = 0.4;     // of the bulk charge
  bool number_fractions = false;
  std::vector<SizeClass> sizes;
  std::vector<ClumpShape> shapes;  // [[charge.shape]]: the case's own clump shapes
  std::uint32_t seed = 1;
  // [materials]
  std::vector<Material> materials;
  // [contact]
  ContactLaw law = ContactLaw::linear;
  Interaction contact;       // defaults for every pair
  std::vector<PairOverride> pairs;
  // [run]
  double duration = 0;       // s of the turning mill, after settling; with
                             // duration_auto 0 (derive() gives the cap)
  bool duration_auto = false; // "auto": turn until the power's mean converges
  double tolerance = 0.01;   // an auto run stops at this standard error of the
                             // power's mean, relative to it
  double max_duration = -1;  // s, the cap of an auto run; < 0: the warm-up
                             // and kAutoRevolutions revolutions
  double warmup = 0;         // s excluded from the averages
  double settle = -1;        // s before the mill turns; < 0: until the charge is at rest
  double settle_damping = 0;  // 1/s, viscous damping of the balls while they
                              // settle; < 0: "auto" (kSettleDamping sqrt(g/D));
                              // 0, the default: none (it did not settle the
                              // shipped mills sooner: docs/performance.md)
  double dt = 0;             // s; 0: auto
  double steps_per_contact = 25;  // auto dt = shortest contact time / this
  double output_interval = 0.01;  // s between timeseries rows
  double snapshot_interval = 0;   // s between .vtp snapshots; 0: none
  double checkpoint_interval = 0.5;  // simulated s between checkpoints; 0: only on a signal and at the end
  Precision precision = Precision::single;
};

// Everything derived from a case, computed in one place.
struct MillDerived {
  double largest_ball_diameter = 0;  // m
  double shortest_slice = 0;         // m, the shortest periodic slice allowed
                                     // (kSliceDiameters largest balls)
  double critical_rpm = 0;           // 42.3 / sqrt(D − d), d the largest ball
  double speed_rpm = 0;
  double speed_fraction = 0;
  double omega = 0;                  // rad/s
  double revolution_s = 0;
  double tip_speed = 0;              // m/s at the shell
  double mill_volume = 0;            // m³ inside the shell, lifters excluded
  double lifter_volume = 0;          // m³
  double charge_solid_volume = 0;    // m³ the filling asks for
  std::vector<long> class_counts;    // balls per size class
  long n_balls = 0;
  double charge_mass = 0;            // kg of the balls the counts give
  double filling_from_counts = 0;    // J the integer counts give
  double contact_time = 0;           // s, shortest ball–ball contact
  double dt = 0;                     // s, used
  bool dt_auto = true;
  double turn_limit_s = 0;           // the case's duration, or an auto run's cap
  double settle_damping = 0;         // 1/s while settling
};

// Revolutions after the warm-up an automatic run turns at most by default.
inline constexpr double kAutoRevolutions = 40;
// Damping of the balls while they settle, in units of sqrt(g/D): the charge
// falls and slumps over times of order sqrt(D/g), and damps out over a fifth
// of that.
inline constexpr double kSettleDamping = 5;
// The shortest periodic slice, in largest-ball diameters: the neighbour
// grid needs 3 cells of 2 r_max + skin along the axis (3.3 diameters at
// most), and a shorter slice would let a ball meet its own image's
// neighbours across both seams at once.
inline constexpr double kSliceDiameters = 4.0;

// Checks what the case reader cannot check key by key (cross-key rules) and
// derives the values; throws std::invalid_argument naming the key.
MillDerived derive(const MillCase& c);

// The scene without its charge: materials, pair table, walls, numerics and
// the case's speed. build_scene adds the packed charge; the viewer keeps the
// balls it has when the case changes.
Scene build_walls(const MillCase& c, const MillDerived& d);

// The shape a size class names: a [[charge.shape]] of the case, else one
// of the library's; throws std::invalid_argument naming `key` otherwise.
ClumpShape size_class_shape(const MillCase& c, const std::string& name, const std::string& key);

// The solver's scene: materials, pair table, walls and the charge placed
// without overlaps in the lower part of the mill, at rest (not yet settled).
// The mill turns at the case's speed (the run may hold it still to settle).
// Throws std::invalid_argument when the charge does not fit.
Scene build_scene(const MillCase& c, const MillDerived& d);

// The case's mesh walls placed in the mill (turned, offset, flipped; in a
// periodic slice the caps on its seams dropped) with their materials and
// interactions. Throws std::invalid_argument naming the key
// ("walls.mesh[0].material: ...") or the file and the triangle.
std::vector<WallMesh> place_meshes(const MillCase& c);

// A [[walls.mesh]]'s triangles placed in the mill frame (flipped, turned
// about the axis, offset), every one of them in the file's order.
std::vector<Triangle> placed_mesh_triangles(const MeshSpec& spec);

// Whether a placed triangle lies on a periodic slice's seam (all its
// corners at z = 0 or at z = length): place_meshes drops those caps, which
// are inside the repeating slice.
bool on_periodic_seam(const Triangle& t, const MillCase& c);

// The index of a material name in c.materials, or −1.
int material_index(const MillCase& c, const std::string& name);

// The filling a settled charge reaches, from the level of its free surface:
// the circular segment below the level (lifters excluded) over the mill's
// free cross-section. Balls are (x, y, radius) in the lab frame.
double settled_filling(const Scene& scene, const std::vector<Vec3>& xyr);

// Morrell's C-model inputs for the case: the filling of the whole ball counts
// and the bulk density of that charge.
MorrellInput morrell_input(const MillCase& c, const MillDerived& d);

}  // namespace mc
