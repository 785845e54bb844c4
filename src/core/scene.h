// What the solver simulates, in SI units: materials and their pairs, the
// walls, the balls, and the numerical settings. Built by a case file, a test
// or the viewer; the solver takes it as it is. No OpenCL here.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/restitution.h"
#include "core/vec.h"

namespace mc {

enum class Precision { single, double_ };

// Archard's dimensional wear coefficient of a liner, m³ of liner per N of
// normal force and m slid (k/H). The default is a stand-in chosen from
// plants' liner consumption: with it the lab mill (assets/cases/lab.toml)
// wears about 4.5 g of shell and lifter steel per kWh drawn, within the
// 2.6–5 g/kWh published for SAG shell liners (Orford et al., CMP 2003;
// Burger et al., SAG 2011) and at the bottom of the 5–15 g/kWh that
// Bond's ball-mill liner estimate gives for those duties (two to three
// times them). It is 50 times the 1e-13 of clean three-body abrasion of a
// 350 HB steel (Archard k ≈ 1e-4 to 1e-3 over 3.5 GPa; Rabinowicz,
// Friction and Wear of Materials, 1995, ch. 8): it folds in what the model
// lacks (impact wear, corrosion, the ore between ball and liner). Wear at
// it is relative until calibrated (docs/liner-life.md#the-time-axis).
inline constexpr double kDefaultWearCoefficient = 5.0e-12;

// Wear at the default coefficient is relative: the words every output
// that prints or draws such a wear rate or its hours uses.
inline constexpr const char* kWearRelative = "relative: wear coefficient not calibrated";
// The default before it, 1e-13 (clean steel's three-body abrasion), which
// cases of that time wrote out: a stand-in as much.
inline constexpr double kFormerDefaultWearCoefficient = 1.0e-13;
inline bool wear_coefficient_is_default(double k) {
  return k == kDefaultWearCoefficient || k == kFormerDefaultWearCoefficient;
}

struct Material {
  std::string name;
  double density = 7800.0;        // kg/m³
  double youngs_modulus = 2.0e11;  // Pa
  double poisson_ratio = 0.3;
  double wear_coefficient = kDefaultWearCoefficient;  // m³/(N·m), as a liner
  // Impact wear as a liner (Bitter's deformation wear, docs/liner-life.md):
  // the volume a collision takes off is impact_wear_coefficient · ½ m
  // (vn − K)², vn the ball's approach speed at first touch, K the threshold
  // below which a strike only deforms elastically. 0: no impact wear.
  double impact_wear_coefficient = 0;      // m³/J
  double impact_wear_threshold_speed = 0;  // m/s
};

// How the liner is cut into elements for impact and wear sums
// (src/sim/liner.h): the shell between two lifter rows in shell_bins
// angular bins (a smooth shell in smooth_shell_bins), shell and lifters in
// axial_bins (0: about square shell elements, at most 32), the end plates in
// plate_rings rings and plate_sectors sectors (0: one per lifter row, or 12).
struct LinerGrid {
  int shell_bins = 4;
  int smooth_shell_bins = 36;
  int axial_bins = 0;
  int plate_rings = 4;
  int plate_sectors = 0;
};

// How two materials meet. kn is used by the linear law only.
struct Interaction {
  double restitution = 0.5;
  double mu_slide = 0.3;
  double mu_roll = 0.0;
  double kn = 1.0e6;               // N/m, linear law
  double kt_over_kn = 2.0 / 7.0;   // linear law
};

// Derived coefficients of one material pair (mirrors cl/layout.h PairParams).
struct PairCoefficients {
  double kn, kt_over_kn, e_star, g_star, damping, mu_slide, mu_roll, restitution;
};

struct Ball {
  int id = 0;
  int material = 0;
  double radius = 0.01;
  Vec3 position, velocity, omega;
  // A component sphere of rigid body `body` (Scene::bodies), or -1 for a
  // ball of its own. A component's position is its body's centre plus its
  // offset turned by the body's orientation; its velocity and spin follow
  // from the body's (the solver sets them).
  int body = -1;
  Vec3 offset;  // m, in the body's principal frame
};

// A rigid body of overlapping spheres (a clump, core/clump.h): the rock of
// autogenous and semi-autogenous mills. Its components are the balls with
// ids first .. first + count - 1; the components of all bodies come after
// every free ball (their ids are the highest), body by body.
struct Body {
  int first = 0;
  int count = 0;
  double mass = 0;   // kg, of the union of the spheres
  Vec3 inertia;      // kg·m², the principal moments (the body frame's axes)
  Vec3 position;     // m, the centre of mass
  Vec3 velocity;     // m/s
  Vec3 omega;        // rad/s, the angular velocity in the lab frame
  std::array<double, 4> orientation{0, 0, 0, 1};  // unit quaternion (x, y, z, w), body → lab
};

// q v q* for a unit quaternion (x, y, z, w).
Vec3 rotate(const std::array<double, 4>& q, const Vec3& v);

// What a mesh wall stands for in the books (the spectra's wall types, the
// impact profile): shell liner, lifters, or the ends (cl/layout.h
// MC_WALL_TYPE_*, in the same order).
enum class MeshPart { shell = 0, lifters = 1, ends = 2 };

// A wall of triangles (core/wall_mesh.h): metres, in the mill frame when it
// turns with the mill, in the lab frame when it stands still; each triangle
// faces the charge from the side its vertex order makes counter-clockwise.
struct WallMesh {
  std::string name;                 // the file, or what built it
  std::vector<Triangle> triangles;
  bool turning = true;
  MeshPart part = MeshPart::lifters;
  Material material;
  // How each ball material (Scene::materials order) meets this mesh.
  std::vector<Interaction> interactions;
  // m³ the mesh encloses when it is closed (every edge shared by two
  // triangles), as placed before a slice's caps were dropped; 0 when open.
  double volume = 0;
};

struct Walls {
  double shell_radius = 0.0;  // inside radius of the shell; 0: no shell
  double length = 0.0;        // end plates at z = 0 and z = length; 0: none
  // A periodic slice of `length` (cl/periodic.h): no end plates, z taken
  // modulo the length, contacts across the seam as any other.
  bool periodic = false;
  // false: the ends are meshes (cone heads) instead of flat plates.
  bool end_plates = true;
  bool has_end_plates() const { return length > 0 && !periodic && end_plates; }
  // Lifter cross-sections in the mill frame, counter-clockwise convex
  // polygons, one per row, rows evenly spaced starting at lifter_first_angle.
  std::vector<std::vector<Vec2>> lifters;
  double lifter_first_angle = 0.0;  // rad
  std::vector<WallMesh> meshes;      // in addition to the shell, plates and lifters
  // Worn end plates (core/plate_wear.h): each plate's (z = 0, then z =
  // length) depth per ring (its face across the ring's middle half), m, the
  // rings of equal width from the axis to the shell as
  // LinerGrid::plate_rings cuts them; empty: flat.
  std::array<std::vector<double>, 2> plate_depth;
  bool plates_worn() const { return !plate_depth[0].empty() || !plate_depth[1].empty(); }
};

struct Numerics {
  ContactLaw law = ContactLaw::hertz;
  Precision precision = Precision::single;
  double dt = 1e-5;      // s
  double skin = 0.0;     // m; 0: 0.2 · smallest radius (default_skin)
  Vec3 gravity{0.0, -9.81, 0.0};
  // The energy books (collision spectra, liner sums; cl/books.h). Off only
  // to time what they cost (bench).
  bool energy_books = true;
};

struct Scene {
  std::vector<Material> materials;  // ball materials
  Material wall_material;           // liner
  // (materials + 1)² interactions, row-major, the wall material last;
  // use set_interaction to fill both (a, b) and (b, a).
  std::vector<Interaction> interactions;
  Walls walls;
  LinerGrid liner;
  std::vector<Ball> balls;
  std::vector<Body> bodies;  // empty: every ball is free
  Numerics numerics;
  double mill_omega = 0.0;  // rad/s, counter-clockwise about +z
  double mill_angle = 0.0;  // rad at t = 0

  int wall_index() const { return static_cast<int>(materials.size()); }
  void set_interaction(int a, int b, const Interaction& in);
  // Same interaction for every pair (sizes the table to the materials).
  void set_all_interactions(const Interaction& in);
  const Interaction& interaction(int a, int b) const;
};

// E*, G*, calibrated damping, friction of pair (a, b); b may be the wall.
PairCoefficients pair_coefficients(const Scene& scene, int a, int b);

double ball_mass(const Scene& scene, const Ball& b);

// Checks the scene for what would make the solver fail or lie: throws
// std::invalid_argument naming the field.
void validate(const Scene& scene);

}  // namespace mc
