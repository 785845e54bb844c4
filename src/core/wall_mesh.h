// Mesh walls: liners, lifters and ends as triangles (from STL files, or
// built from the case: cone ends, end lifters), in addition to the shell,
// the end plates and the parametric lifters. The force kernels take them
// as cl/mesh.h describes: a triangle is touched from the side its normal
// faces, the normal from its vertex order (counter-clockwise seen from the
// charge: the outward normals of a solid liner or lifter). This module
// holds them, checks them against the mill, and derives the device's view:
// the order of the triangles, their shared edges and vertices, the smooth
// patches, and each set's grid. No OpenCL.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/scene.h"
#include "core/vec.h"

namespace mc {

// Triangles that share an edge at less than this angle between their normals
// form one smooth surface: a contact that slides from one to the next keeps
// its tangential spring.
inline constexpr double kSmoothDegrees = 20.0;

// The device order of the mesh triangles: the turning meshes' first (set 0),
// then those that stand still (set 1); each mesh's triangles in file order.
struct MeshTriangleRef {
  int mesh = 0;
  int triangle = 0;
};
std::vector<MeshTriangleRef> mesh_device_order(const std::vector<WallMesh>& meshes);

// Shared features of the meshes, in the device order: each triangle's edges
// (ab, bc, ca) and vertices (a, b, c) as indices, vertices welded where
// their coordinates are equal (within a mesh), and the smooth patch of each
// feature (triangles, then edges, then vertices: cl/layout.h), and the
// triangles that share each edge and vertex (cl/mesh.h mesh_in_cone): those
// of feature f are adj_tris[adj_start[f] .. adj_start[f + 1]), in device
// order, none for a triangle.
struct MeshTopology {
  int n_triangles = 0, n_edges = 0, n_vertices = 0;
  std::vector<std::array<int, 3>> edges, vertices;  // per triangle, feature-local
  std::vector<int> patch;                            // per feature
  std::vector<int> adj_start, adj_tris;              // features + 1; the lists
  int n_patches = 0;
  int features() const { return n_triangles + n_edges + n_vertices; }
};
MeshTopology mesh_topology(const std::vector<WallMesh>& meshes);

// The triangle's unit normal from its vertex order (zero when degenerate).
Vec3 triangle_unit_normal(const Triangle& t);

// Where a set's triangles are looked up (cl/layout.h MeshGrid), in double:
// a grid over the set's triangles grown by `reach`, cells of at least
// `reach`, at most kMaxMeshCells of them; the core cylinder no triangle
// comes within reach of.
struct MeshGridSpec {
  Vec3 origin;
  double cell = 0;
  int nx = 0, ny = 0, nz = 0;
  double core_r2 = 0, core_z0 = 0, core_z1 = 0;
  double reach = 0;
  int n_triangles = 0;
  long cells() const { return static_cast<long>(nx) * ny * nz; }
};
inline constexpr long kMaxMeshCells = 1L << 22;
MeshGridSpec mesh_grid_spec(const std::vector<Triangle>& set_triangles, double reach);

// The cells of a set's grid, on the host (the CPU reference, and the tests
// of the device's binning): starts (cells + 1) and each cell's triangles,
// ascending; `first` is added to each triangle index.
void mesh_bin_host(const MeshGridSpec& g, const std::vector<Triangle>& set_triangles, int first,
                   std::vector<int>& starts, std::vector<int>& tris);

// Whether a triangle may be listed in a cell: the distance from the cell's
// centre to it is within reach plus the half-diagonal (and a margin). The
// device's binning (cl/mesh_bin.cl) makes the same test.
bool triangle_near_cell(const Triangle& t, const Vec3& centre, double limit);

// Closest point of triangle t to p (Ericson §5.1.5; cl/mesh.h has the
// device's).
Vec3 closest_on_triangle(const Triangle& t, const Vec3& p);

// The volume a closed mesh encloses (divergence theorem over its
// triangles), 0 for an open one (an edge not shared by exactly two).
double closed_mesh_volume(const std::vector<Triangle>& triangles);

// The ends of a mill as case keys (mill.ends = "cones", [end_lifters]; docs/cases.md): cone heads at
// both ends instead of flat end plates, and radial lifter bars on the ends,
// built as meshes (part "ends", turning with the mill).
struct EndsSpec {
  double cone_angle_deg = 0;         // of the cone heads from the end plane; 0: flat end plates
  double trunnion_diameter = 0;      // m, where the cones end (a flat disc closes the opening)
  int lifter_rows = 0;               // bars on each end
  double lifter_height = 0;          // m, off the end's surface
  double lifter_width = 0;           // m
  double lifter_inner_diameter = 0;  // m, where the bars end towards the axis (0: the trunnion, or D/3)
  double lifter_first_angle_deg = 0; // centre of bar 0 (the shell lifters' first_angle)
  bool cones() const { return cone_angle_deg > 0; }
};

// Axial depth of one cone head: (R − trunnion radius) tan(cone angle).
double cone_depth(const EndsSpec& e, double shell_radius);

// The triangles of the ends (mill frame): each cone from the shell at z = 0
// (z = length) out to the trunnion at z = −depth (length + depth), in
// `segments` facets around and rings along, with the trunnion discs; the end
// lifters as closed boxes standing on the plates or the cones.
std::vector<Triangle> cone_triangles(const EndsSpec& e, double shell_radius, double length, int segments);
std::vector<Triangle> end_lifter_triangles(const EndsSpec& e, double shell_radius, double length);

// Checks the meshes against the mill: every vertex inside the shell (a
// radius at most the shell's plus 0.1 %), between the end plates (or, in a
// periodic slice, within the slice, and then only triangles along the axis:
// a slice's meshes are the same at both ends). Throws std::invalid_argument
// naming the mesh and the triangle (from 1).
void check_meshes(const Walls& walls);

}  // namespace mc
