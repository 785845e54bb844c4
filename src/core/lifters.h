// Lifter bars from their profile: a trapezoid on the shell, extruded along
// the mill (DESIGN.md, "World").
#pragma once

#include <vector>

#include "core/vec.h"

namespace mc {

struct LifterProfile {
  double height = 0.05;      // radial, m
  double top_width = 0.05;   // m
  double face_angle_deg = 0; // of both faces from the radial line
};

// The counter-clockwise cross-section of one bar centred at `angle` (rad) on a
// shell of inside radius `shell_radius`. The base lies just outside the shell
// so that no gap opens between bar and shell.
std::vector<Vec2> lifter_polygon(double shell_radius, const LifterProfile& p, double angle);

// `rows` bars evenly spaced from angle `first`, row k taking
// pattern[k % pattern.size()] (high/low alternation).
std::vector<std::vector<Vec2>> lifter_rows(double shell_radius, int rows,
                                           const std::vector<LifterProfile>& pattern,
                                           double first = 0.0);

// The bars of lifter_rows as closed triangle meshes from z = 0 to `length`:
// each bar's faces (its polygon's edges extruded) and its two end caps, every
// triangle facing out of the bar. What a CAD tool would export for the same
// liner (an STL of the parametric lifters).
std::vector<Triangle> lifter_triangles(const std::vector<std::vector<Vec2>>& bars, double length);

// The bars cut where they enter the shell of radius R (the part behind the
// shell dropped; a chord closes each): the cross-sections a CAD model of
// lifters bolted to the shell has, for lifter_triangles.
std::vector<std::vector<Vec2>> bars_on_shell(const std::vector<std::vector<Vec2>>& bars, double R);

// Signed distance from (x, y) to a convex counter-clockwise polygon: negative
// inside. For packing and checks on the host (the kernels use cl/walls.h).
double polygon_signed_distance(const std::vector<Vec2>& poly, double x, double y);

}  // namespace mc
