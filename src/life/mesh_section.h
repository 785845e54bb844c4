// Lifter bars of a mesh liner measured as a plant measures a bar: each
// connected part of the mesh (a bar) cut across at a z, its outline in the
// frame core/lifters.h gives a parametric bar (x along the shell's tangent
// at the bar's centre, positive on the leading side, counter-clockwise;
// y the height above that tangent), so that core/lifters.h measure_profile
// reads its height and face angles as it reads a parametric bar's. No
// OpenCL: the unit tests reach it.
#pragma once

#include <vector>

#include "core/vec.h"

namespace mc::life {

// The angle (rad, counter-clockwise from +x) of a part's centre: the
// direction of the mean of its vertices (each once) across the axis.
double part_angle(const std::vector<Triangle>& triangles, const std::vector<int>& part);

// The part cut by the plane z: its outline in the frame of a bar centred
// at `angle` on a shell of radius R, from the leading foot (the point of
// largest x) over the top to the trailing foot (the least x), each foot
// carried down its face's lowest edge to the tangent (y = 0) as a
// parametric outline's feet are; empty where
// the plane misses the part or its cut is not one loop or one chain.
std::vector<Vec2> bar_section(const std::vector<Triangle>& triangles, const std::vector<int>& part, double z,
                              double angle, double R);

// The mean of outlines (each from its leading foot to its trailing foot),
// point by point at `samples` equal steps of each one's length along it: a
// mesh's bars drawn as one. Empty where `outlines` is.
std::vector<Vec2> mean_outline(const std::vector<std::vector<Vec2>>& outlines, int samples = 64);

// Each bar of a mesh cut across at z, in the frames of `angles` (the
// parts' order; those the plane misses left out, and those whose cut is
// wider or higher than half the shell's radius: not a bar).
std::vector<std::vector<Vec2>> bar_sections(const std::vector<Triangle>& triangles, const std::vector<double>& angles,
                                            double z, double R);

// A mesh's bars measured at z: each part's height (m), leading and
// trailing face angles (deg) from its section, the parts the plane misses
// left out.
struct BarMeasures {
  std::vector<double> height, leading_deg, trailing_deg;
};
BarMeasures measure_bars(const std::vector<Triangle>& triangles, const std::vector<double>& angles, double z,
                         double R);

}  // namespace mc::life
