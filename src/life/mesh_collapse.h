// Keeping a worn mesh fit to wear again: over a liner's life the wear at a
// bar's corner draws the row of vertices on the top and the row on the
// face below it together, until a strip of triangles a millimetre wide
// runs along the corner, which the next move turns over (its two rows
// move along different normals). Before a stage's wear moves the mesh,
// each edge much shorter than the mesh's own (a quarter of its median
// edge) is collapsed to a point: the two triangles on it go, their booked
// wear goes to the triangles round the point (by area), and the point
// stays on an end plane where one of the two vertices was on it. An edge
// is left where collapsing it would fold a neighbour (turn its normal by
// more than 60°) or join two parts of the surface that only touch (the
// link condition). No OpenCL: the unit tests reach it.
#pragma once

#include <vector>

#include "core/vec.h"

namespace mc::life {

struct Collapsed {
  std::vector<Triangle> triangles;  // the mesh without the collapsed edges' triangles, in their order
  std::vector<double> volume_m3;    // the booked volumes carried with them (the same sum)
  int edges = 0;                    // edges collapsed
};

// `z0`, `z1`: the mill's end planes (a vertex within 2 µm of one stays on
// it); not held where z1 <= z0. `share`: an edge shorter than this share
// of the median edge length is collapsed.
Collapsed collapse_short_edges(const std::vector<Triangle>& triangles, const std::vector<double>& volume_m3,
                               double z0, double z1, double share = 0.25);

}  // namespace mc::life
