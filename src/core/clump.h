// Clumps: rigid bodies of overlapping spheres, the shape of the rock in
// autogenous and semi-autogenous mills (DEM-Engine and LIGGGHTS build
// non-spherical particles the same way). Host side only: a shape's volume,
// centroid and inertia from the union of its spheres (overlaps counted
// once, not summed), the shape scaled to a volume-equivalent diameter and
// turned to its principal axes, and the library of shapes a case will name.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/vec.h"

namespace mc {

struct ClumpSphere {
  Vec3 centre;        // in the shape's frame, m (or any unit: shapes scale)
  double radius = 0;
};

struct ClumpShape {
  std::string name;
  std::vector<ClumpSphere> spheres;
};

using Mat3 = std::array<std::array<double, 3>, 3>;

struct ClumpMassProperties {
  double volume = 0;   // of the union
  Vec3 centroid;       // of the union, in the shape's frame
  Mat3 inertia{};      // about the centroid, per unit density (volume × length²)
  Vec3 principal;      // the principal moments, ascending, per unit density
  Mat3 axes{};         // the principal axes, as columns, in the order of `principal`
  double equivalent_diameter() const;  // (6 V / π)^(1/3)
};

// Integrates over the union of the spheres: the shape's extent in x and y is
// cut into n × n columns, and in each column the spheres' chords along z are
// merged into intervals and integrated exactly (volume, first and second
// moments). The error is that of the midpoint rule across the columns,
// falling as 1/n² for smooth parts (the tests hold a sphere's volume and
// inertia to 2·10⁻⁵ at n = 512).
ClumpMassProperties clump_mass_properties(const ClumpShape& s, int n = 512);

// The shape scaled to the volume-equivalent diameter d_eq, its centroid
// moved to the origin and its principal axes turned onto x, y, z (least
// moment along x), so that the body frame of a clump is its principal frame.
ClumpShape normalised_shape(const ClumpShape& s, double d_eq, int n = 512);

// Refuses a shape that cannot be a body: no spheres, a radius not > 0, a
// coordinate or radius that is not finite, a sphere farther from the others
// than 100 times the largest radius. The message names `key` (a case key
// such as "shapes.rock.spheres") and the sphere.
void check_shape(const ClumpShape& s, const std::string& key);

// The library: "sphere"; "peanut" (two spheres of one radius, centres one
// radius apart); "flat4" (four in a square, centres one radius from the
// middle, in one plane); "rod5" (five in a row, centres 0.8 radius apart);
// "rock" (12 spheres filling an ellipsoid of axes 1 : 0.8 : 0.6). Throws
// std::invalid_argument listing the names for any other.
ClumpShape library_shape(const std::string& name);
std::vector<std::string> library_shape_names();

// n spheres (2..64) filling the ellipsoid of semi-axes 1, b, c (1 >= b >= c
// > 0.2): a greedy cover, each sphere the largest one inscribed at a
// candidate centre (candidates drawn from `seed`) that covers the most of
// the inside not yet covered. The union stays inside the ellipsoid (to the
// sampling of its surface) and touches it where its spheres are largest.
ClumpShape rock_shape(int n_spheres, double b, double c, unsigned seed = 1);

}  // namespace mc
