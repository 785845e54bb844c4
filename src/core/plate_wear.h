// Worn end plates (the life study, docs/liner-life.md#the-end-plates): each
// plate's wear as a depth per ring, the rings of equal width from the axis
// to the shell as the books cut them ([liner] plate_rings). The plate turns
// with the mill and every sector of a ring passes under the charge alike,
// so a worn plate is a dish, the same all round: its surface lies `depth`
// behind the plate's plane at distance rho from the axis, linear between
// node depths at the rings' centres and flat inside the first centre and
// outside the last. The nodes are chosen so that each ring's area-weighted
// mean depth is the ring's depth: the metal the surface has lost in a ring
// is its depth times its area. The force kernels read the nodes
// (cl/walls.h plate_depth). No OpenCL.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace mc {

// Rings a worn plate may have (cl/layout.h MC_PLATE_NODES).
inline constexpr int kMaxWornPlateRings = 16;

// The node depths (m) whose surface gives each ring (of equal width from
// the axis out) the mean depth `ring_depth` (m): the tridiagonal system of
// the rings' means solved exactly. A node that would stand proud of the
// plate's plane (a shallow ring beside deep ones) is held at 0, the rest
// solved again and scaled so that the plate loses its rings' volume in all:
// each ring's mean then misses its depth by a little (plate_ring_means
// shows how much), the plate's total does not.
std::vector<double> plate_surface_nodes(const std::vector<double>& ring_depth);

// The surface's depth (m) at rho (m) from the axis, nodes as above on rings
// of `width` (m), and its slope d depth / d rho.
double plate_surface_depth(const std::vector<double>& nodes, double width, double rho, double* slope = nullptr);

// Each ring's area-weighted mean depth of that surface (closed form).
std::vector<double> plate_ring_means(const std::vector<double>& nodes, double width);

// The volume (m³) a plate of radius R has lost at those ring depths: each
// ring's depth times its area.
double plate_worn_volume(const std::vector<double>& ring_depth, double R);

// What is wrong with worn plates' depths (m, each plate's per ring) for
// `rings` rings on plates of radius R in a mill of `length` (0: a mill
// without flat end plates): "" when nothing, else the fault after the key,
// as "[1][2]: must be >= 0 ..." or ": ...". A depth must be less than
// the mill's length, and the surface between two rings' centres slope by
// at most 45° (the kernels take it as its tangent plane under a ball).
std::string check_plate_depths(const std::array<std::vector<double>, 2>& depth, int rings, double R, double length);

}  // namespace mc
