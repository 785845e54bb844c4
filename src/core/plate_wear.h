// Worn end plates (the life study, docs/liner-life.md#the-end-plates). The
// plate turns with the mill and every sector of a ring passes under the
// charge alike, so a worn plate is a dish, the same all round, cut in rings
// of equal width from the axis to the shell as the books cut them ([liner]
// plate_rings). Its face lies `depth` behind the plate's plane: flat at
// each ring's own depth across the ring's middle half, and straight from
// one ring's depth to the next over the quarter-rings either side of their
// common edge (flat inside the first ring and out past the shell). The
// force kernels find a ball's nearest point on that face (cl/walls.h
// plate_overlap). No OpenCL.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/vec.h"

namespace mc {

// Rings a worn plate may have (cl/layout.h MC_PLATE_NODES).
inline constexpr int kMaxWornPlateRings = 16;

// The face's depth (m) at rho (m) from the axis, its rings' depths `depth`
// (m) on rings of `width` (m); and its slope d depth / d rho.
double plate_surface_depth(const std::vector<double>& depth, double width, double rho, double* slope = nullptr);

// The radii where a dish of `rings` rings of `width` (m) bends: the ends of
// the ramps across each edge between two rings ((k ∓ 1/4) width), outward.
std::vector<double> plate_bend_radii(std::size_t rings, double width);

// A plate's face for drawing: the plate at z = 0 facing +z, its face at
// z = -depth(rho) (rings of R / depth.size(); empty: flat), as triangles
// in rings between the radii where it bends (the ramps' ends) and
// `segments` sectors round, each counter-clockwise seen from +z.
std::vector<Triangle> plate_face_triangles(const std::vector<double>& depth, double R, int segments);

// Each ring's area-weighted mean depth of that face (closed form): the
// metal the ring has lost over its area. A ring beside a deeper one loses a
// little more than its own depth at its edge, the deeper one a little less.
std::vector<double> plate_ring_means(const std::vector<double>& depth, double width);

// The volume (m³) a plate of radius R has lost with its rings at `depth`.
double plate_worn_volume(const std::vector<double>& depth, double R);

// How far each ring's depth moves (m, never back: each >= 0) for the rings
// to lose `booked` (m over each ring's area) more: each ring whose depth
// moves loses exactly its booked depth; a ring that booked little beside
// one that booked much, which would have to rise for that, stays where it
// is and loses a little more than it booked, the neighbour's metal at their
// edge (the rings' means as a complementarity problem: increments >= 0,
// each ring losing at least its booking, exactly where it moves).
std::vector<double> plate_increment(const std::vector<double>& booked);

// How far worn plates' faces lie behind their planes at the shell, both
// ends together (m; 0 for flat plates): the shell and the bars reach that
// much farther along the mill, into the dishes.
double plate_depth_at_shell(const std::array<std::vector<double>, 2>& depth);

// What is wrong with worn plates' depths (m, each plate's per ring) for
// `rings` rings on plates of radius R in a mill of `length` (0: a mill
// without flat end plates): "" when nothing, else the fault after the key,
// as "[1][2]: must be >= 0 ..." or ": ...".
std::string check_plate_depths(const std::array<std::vector<double>, 2>& depth, int rings, double R, double length);

}  // namespace mc
