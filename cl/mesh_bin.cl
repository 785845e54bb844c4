/* mesh_bin.cl — the mesh walls' triangles into the cells of their set's grid
 * (layout.h MeshGrid, mesh.h): a triangle goes into every cell whose centre
 * is within reach plus the cell's half-diagonal of it, so a ball centre in
 * a cell finds there every triangle it can touch. Run when the walls are
 * set (triangles do not move in their set's frame): count, scan (scan.cl),
 * fill, then each cell's list sorted, so the lists do not depend on the
 * order of the atomics. */
#include "mc_shim.h"
#include "layout.h"
#include "contact_law.h"
#include "walls.h"
#include "mesh.h"

/* Triangle t's cells: `fill` 0 counts them into cell_count, 1 writes t at
 * each cell's cursor. Triangles [0, n_first) are set 0's, the rest set 1's. */
__kernel void mesh_bin(__global const MeshGrid* grid, __global const MeshTriangle* tris, int n_tris, int n_first,
                       int fill, __global int* cell_count, __global int* cell_tris) {
  const int t = get_global_id(0);
  if (t >= n_tris) return;
  __global const MeshGrid* g = grid + (t < n_first ? 0 : 1);
  __global const MeshTriangle* tr = tris + t;
  const real3 a = tr->a.xyz, b = tr->b.xyz, c = tr->c.xyz;
  const real cell = g->origin.w;
  const real reach = g->reach;
  const real limit = reach + R(0.5) * sqrt(R(3.0)) * cell * R(1.0001);
  const real3 lo = fmin(fmin(a, b), c) - (real3)(reach), hi = fmax(fmax(a, b), c) + (real3)(reach);
  const int x0 = clamp((int)floor((lo.x - g->origin.x) / cell), 0, g->nx - 1);
  const int x1 = clamp((int)floor((hi.x - g->origin.x) / cell), 0, g->nx - 1);
  const int y0 = clamp((int)floor((lo.y - g->origin.y) / cell), 0, g->ny - 1);
  const int y1 = clamp((int)floor((hi.y - g->origin.y) / cell), 0, g->ny - 1);
  const int z0 = clamp((int)floor((lo.z - g->origin.z) / cell), 0, g->nz - 1);
  const int z1 = clamp((int)floor((hi.z - g->origin.z) / cell), 0, g->nz - 1);
  for (int cz = z0; cz <= z1; ++cz)
    for (int cy = y0; cy <= y1; ++cy)
      for (int cx = x0; cx <= x1; ++cx) {
        const real3 centre = (real3)(g->origin.x + ((real)cx + R(0.5)) * cell, g->origin.y + ((real)cy + R(0.5)) * cell,
                                     g->origin.z + ((real)cz + R(0.5)) * cell);
        int region;
        const real3 q = triangle_closest(centre, a, b, c, &region) - centre;
        if (!(dot(q, q) <= limit * limit)) continue;
        const int id = g->first_cell + (cz * g->ny + cy) * g->nx + cx;
        if (fill) cell_tris[atomic_inc(&cell_count[id])] = t;
        else atomic_inc(&cell_count[id]);
      }
}

/* dst[c] = src[c]: the cursors of the fill start at the cells' starts. */
__kernel void mesh_copy(int n, __global const int* src, __global int* dst) {
  const int i = get_global_id(0);
  if (i < n) dst[i] = src[i];
}

/* Each cell's triangles in ascending order (insertion sort: a cell holds a
 * few). */
__kernel void mesh_sort_cells(int n_cells, __global const int* cell_start, __global int* cell_tris) {
  const int c = get_global_id(0);
  if (c >= n_cells) return;
  const int b = cell_start[c], e = cell_start[c + 1];
  for (int a = b + 1; a < e; ++a) {
    const int v = cell_tris[a];
    int k = a - 1;
    while (k >= b && cell_tris[k] > v) {
      cell_tris[k + 1] = cell_tris[k];
      --k;
    }
    cell_tris[k + 1] = v;
  }
}
