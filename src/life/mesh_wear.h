// A mesh liner worn by its booked wear: each triangle's booked volume is a
// depth over its area; each vertex (welded where triangles share its
// coordinates) moves into the liner by the least-squares offset that
// takes each triangle around it its own depth along its normal (over the
// directions in which their normals differ by more than a crease: a flat
// patch moves along its mean normal, an edge moves each face by its own
// depth), so that to first order the volume removed is the volume booked;
// a depth scale then makes the swept volume equal the booked one exactly
// (as core/liner_wear.h does for a bar's outline). Where the booked depths
// are noisy, passes of smoothing average each triangle's depth with its
// neighbours' first (the booked volume kept by the scale). Where the move
// would turn a triangle over or crush it (a worn corner past the first row
// of vertices below it), the vertices within three edges of it slide along
// the surface toward their neighbours' centroid (tangential relaxation;
// sharp edges and corners held, and the mesh's rim but where it lies in an
// end plane) and the scale is found again. The worn mesh
// is checked: no triangle turned over or shrunk to nothing, no vertex
// beyond the shell or the mill's ends. No OpenCL: the unit tests reach it.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "core/vec.h"

namespace mc::life {

// Where a worn mesh must stay: inside the shell (radius at most
// shell_radius + 1 µm; 0: not checked) and between z0 and z1 (not
// checked where z1 <= z0; a vertex within 2 µm of either end stays at its
// z: a bar that stands on an end plate stays on it).
struct MeshBounds {
  double shell_radius = 0;
  double z0 = 0, z1 = 0;
  double on_end = 2e-6;  // a vertex this near z0 or z1 is on the end plane (stays on it)
};

// The refusal of a move that would spoil the mesh (turn a triangle over,
// crush one, or find no move that removes the volume booked), which a
// coarser mesh may pass (mesh_collapse.h); a vertex beyond the shell or the
// ends is a plain std::invalid_argument.
struct MeshSpoiled : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};
// A move that takes a vertex beyond the shell or the mill's ends.
struct MeshOutside : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

struct MeshWear {
  std::vector<Triangle> triangles;  // the worn mesh, the same triangles in the same order
  double booked_m3 = 0;             // the volume the triangles booked
  double removed_m3 = 0;            // the volume between the mesh and the worn one
  double scale = 1;                 // the depth scale that makes them equal
  int smoothing = 0;                // passes of depth smoothing done
  double deepest_m = 0;             // the largest vertex move
  int relaxed = 0;                  // vertices slid along the surface to keep the mesh valid (0: none needed)
};

// The welded vertices of a mesh: each triangle's corners as indices into
// `points` (corners with equal coordinates are one vertex).
struct WeldedMesh {
  std::vector<Vec3> points;
  std::vector<std::array<int, 3>> corners;
};
WeldedMesh weld(const std::vector<Triangle>& triangles);

// The volume swept between a mesh and the same mesh with its vertices
// moved (corner for corner): positive where they moved against the
// triangles' normals. For a closed mesh it is the enclosed volume lost.
double swept_volume(const std::vector<Triangle>& before, const std::vector<Triangle>& after);
// The same per triangle: the prism between each triangle and its moved self
// (its sides cut as swept_volume cuts them, so that the sum is the whole's
// and any set of triangles has its own part of it).
std::vector<double> swept_volumes(const std::vector<Triangle>& before, const std::vector<Triangle>& after);

// The connected parts of a mesh (triangles that share a welded vertex):
// each part's triangles, ascending, the parts in the order of their first
// triangle. A mesh of lifter bars has a part per bar.
std::vector<std::vector<int>> connected_parts(const std::vector<Triangle>& triangles);

// The booked volumes spread over the surface around each triangle: each
// triangle's volume shared out over the triangles of its own part whose
// normals lie within 30° of its own, in proportion to their areas times a
// Gaussian of the distance between their centroids, `across` (m, its
// standard deviation across the mill's axis) and `along` (m, along it). A
// short run books its wear on a few of a fine mesh's triangles; this
// spreads it over the surface that wears alike (wear varies slowly along a
// mill, fast round a bar's edge), keeping creases sharp. Each triangle's
// volume is kept, so each part's and each face's sum is the one booked.
// across <= 0: the volumes unchanged. A negative volume (a difference of
// two) is spread alike; a non-finite one is left out.
std::vector<double> smooth_wear(const std::vector<Triangle>& triangles, const std::vector<double>& volume_m3,
                                double across, double along);

// The mesh worn by `volume_m3` per triangle (>= 0, as many as triangles),
// with `smoothing` passes over the depths. Throws std::invalid_argument
// naming `name` and the triangle (from 1) where the wear would turn a
// triangle over or shrink it below a thousandth of its area, or take a
// vertex beyond `bounds` (the shell within a micrometre), and naming `name`
// where no move removes the volume booked; std::invalid_argument for a negative or
// non-finite volume, or a count that is not the triangles'.
// `relax` false: no tangential relaxation (the unit tests' comparison).
MeshWear wear_mesh(const std::vector<Triangle>& triangles, const std::vector<double>& volume_m3,
                   const MeshBounds& bounds, int smoothing = 0, const std::string& name = "mesh", bool relax = true);

}  // namespace mc::life
