// Keeping a worn mesh fit to wear again: over a liner's life the wear at a
// bar's corner draws the row of vertices on the top and the row on the
// face below it together, until a strip of triangles a millimetre wide
// runs along the corner, which the next move turns over (its two rows
// move along different normals). Before a stage's wear moves the mesh,
// each edge much shorter than the mesh's own (a share of its median edge)
// is collapsed to a point: the two triangles on it go, their booked wear
// goes to the triangles round the point (by area). The point is where an
// end of the edge lies on the mesh's rim (an open edge: never moved), else
// on an end plane, else on a crease (a bar's edge); two crease vertices
// (a corner's strip) or two plain ones meet half-way, as two of one end
// plane do unless one is on a crease there. An edge is left where it
// joins two rim vertices or two end planes, where collapsing it would
// turn a neighbour's normal by more than 60° from the mesh as given, join
// two sheets of the surface that only touch (the link condition), or
// leave no triangle round the point. The volume the collapse takes from
// the solid is measured (the mesh's own enclosed volume, before and
// after: the rim stays, so it is the volume between the two). No OpenCL:
// the unit tests reach it.
#pragma once

#include <string>
#include <vector>

#include "core/vec.h"
#include "life/mesh_wear.h"

namespace mc::life {

struct Collapsed {
  std::vector<Triangle> triangles;  // the mesh without the collapsed edges' triangles, in their order
  std::vector<double> volume_m3;    // the booked volumes carried with them (the same sum)
  int edges = 0;                    // edges collapsed
  double removed_m3 = 0;            // the volume the collapse took from the solid the mesh bounds (< 0: gave)
  // Where it took it: each collapse's own volume (the triangles round its
  // point, before and after) shared by area over the triangles round the
  // point, and carried as their booked wear is; one per triangle of
  // `triangles`, summing to removed_m3. Empty where nothing was collapsed.
  std::vector<double> taken_m3;
};

// The volumes a stage's move is asked to remove, triangle by triangle: the
// booked wear carried through the collapse, less what the collapse itself
// took there (taken_m3), spread by smooth_wear (across, along, m), any
// triangle left below nothing set to nothing, and the whole brought to the
// booked total less removed_m3, so that the collapse and the move together
// remove what each stretch of the mesh booked.
std::vector<double> asked_volumes(const Collapsed& c, double across, double along);

// `z0`, `z1`: the mill's end planes (a vertex within `on_end_m` of one
// stays on it); not held where z1 <= z0. `share`: an edge shorter than this share
// of the median edge length is collapsed.
Collapsed collapse_short_edges(const std::vector<Triangle>& triangles, const std::vector<double>& volume_m3,
                               double z0, double z1, double share = 0.25, double on_end_m = 2e-6);

// The shares of the median edge below which edges are collapsed, tried in
// turn until the move keeps the mesh one: none first (most stages need no
// collapse), then a quarter; no further than 0.55, where a 10 mm mesh's
// corners are already coarser than the mesh was cut to.
inline constexpr double kCollapseShares[] = {0, 0.25, 0.4, 0.55};

// A stage's mesh worn by its booked volumes and kept fit to wear again:
// collapsed at each share in turn, its volumes spread (smooth_wear, across
// and along, m), less what the collapse itself took, and moved (wear_mesh,
// relaxed where needed), the first share whose move does not spoil the
// mesh kept: the collapse and the move together remove the volume booked. The last share's
// MeshSpoiled where none does; any other refusal (a vertex beyond the
// shell or the ends) at once.
// The move's one depth scale makes the whole volume right, but a convex
// stretch (a worn corner) removes less per booked depth than a flat one:
// so each stretch of the mesh (a connected part, a bar, and where
// `segments` > 1 its span of the mill's length between bounds.z0 and z1,
// by the triangles' centroids) has its volumes scaled by the ratio of what
// it was asked to what it removed, and the mesh is moved again, until
// every stretch asked at least a fifth of the mean stretch's removes what it
// was asked within kLocalTolerance (at most kLocalPasses; a corrected
// move that spoils the mesh or leaves the shell or the ends, or that
// misplaces no less volume over all the stretches, is not taken).
// Where no share keeps the mesh one (a corner worn deep in one stage:
// its rounded strip shrinks to nothing as it moves in, as any convex
// corner of a solid worn back does), the stage's wear is moved in
// kMoveSteps equal steps, each collapsed and moved as above on the mesh
// the one before left (its normals and short edges found again): each
// step asked an equal share of what is left, carried through the
// collapses; a stretch's shortfall in one step is added to its share of
// the steps left, and the rest then brought to what the stage has still to
// remove.
inline constexpr int kLocalPasses = 4;
inline constexpr double kLocalTolerance = 0.002;
inline constexpr int kMoveSteps[] = {1, 2, 4, 8};
struct FitWear {
  Collapsed collapsed;  // the first step's collapsed mesh (the stage's, as it was moved), its booked volumes
  MeshWear wear;        // the last step's move; its triangles: the worn mesh
  double share = 0;     // the share the first step was collapsed at
  int local_passes = 0;      // local corrections taken (all steps)
  double local_misfit = 0;   // after them: the largest |removed / asked − 1| of a stretch (of any step)
  int steps = 1;             // the steps the wear was moved in
  int edges = 0;             // edges collapsed (all steps)
  double collapse_m3 = 0;    // the volume the collapses took
  double removed_m3 = 0;     // the volume the collapses and moves removed (the booked)
  double deepest_m = 0;      // the steps' largest vertex moves, added: at most this deep
  int relaxed = 0;           // vertices slid along the surface (all steps)
  // Per span of the mill (`segments` between bounds.z0 and z1, by the
  // triangles' centroids; one where segments <= 1): what the moves were
  // asked (the booked less the collapses' own, spread) and what they swept.
  std::vector<double> span_asked_m3, span_removed_m3;
};
// `most_steps`: no more steps than this (1: one move, refused where it spoils the mesh).
FitWear wear_kept_fit(const std::vector<Triangle>& triangles, const std::vector<double>& booked_m3,
                      const MeshBounds& bounds, double across, double along, const std::string& name,
                      int segments = 1, int most_steps = 8);

}  // namespace mc::life
