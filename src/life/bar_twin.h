// The bars of [lifters] as a mesh liner, for a life study that follows the
// wear along the mill (`life --axial-segments N` on a mill of parametric
// bars): each bar's faces cut into triangles, so that every part of a bar
// wears by its own wear, where [lifters] bars wear alike along the axis.
// The twin is the mesh `check --write-lifters FILE --lifter-mesh MM` writes,
// cut at the shell. No OpenCL, no files.
#pragma once

#include <string>
#include <vector>

#include "core/vec.h"
#include "core/mill_case.h"

namespace mc::life {

// The triangle size a twin is cut to by default: the largest ball's radius
// (a bar's corner rounds over about a ball's contact), at most half a
// segment of `segments` along the mill's `length` (the wear is told to a
// segment by its triangles).
double default_twin_edge(double largest_ball_diameter, double length, int segments);

// The bars of case c (derived d) cut at the shell as triangles at most
// `max_edge_m` across, in metres in the mill frame at t = 0, each
// coordinate rounded to a 32-bit float as a binary STL holds it.
std::vector<Triangle> bar_twin_triangles(const MillCase& c, const MillDerived& d, double max_edge_m);

// About how many triangles bar_twin_triangles makes at `max_edge_m`
// (without making them): the faces' rows and columns, twice.
double twin_triangle_estimate(const MillCase& c, const MillDerived& d, double max_edge_m);

// Case c with its bars as that mesh: lifters.rows = 0 and one more
// [[walls.mesh]] of part "lifters" turning with the mill, of the liner's
// material, its file `file` (which the caller writes before a run reads
// the case).
MillCase with_bar_twin(const MillCase& c, std::vector<Triangle> twin, const std::string& file);

}  // namespace mc::life
