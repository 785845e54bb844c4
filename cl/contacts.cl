/* contacts.cl — the neighbour lists (the "collision links"): for each ball,
 * the balls within r_i + r_j + skin, stored compactly (CSR: a start and a
 * count per ball). Built in two passes, count then fill, after binning has
 * put the balls in cell order. The fill pass carries each persisting pair's
 * tangential spring over from the previous list, which was written in the
 * previous ball order: `perm` maps a new index to the old one. */
#include "mc_shim.h"
#include "layout.h"
#include "grid.h"

inline int is_neighbour(__global const SimParams* sp, real4 a, real4 b) {
  const real3 d = xyz_of(a) - xyz_of(b);
  const real cut = a.w + b.w + sp->skin;
  return dot(d, d) < cut * cut;
}

__kernel void contacts_count(__global const SimParams* sp,
                             __global const real4* pos,
                             __global const int* cell_start,
                             __global const int* cell_count,
                             __global int* neigh_count) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  const real4 pi = pos[i];
  const int4 c = grid_cell_of(sp, xyz_of(pi));
  int count = 0;
  for (int z = max(c.z - 1, 0); z <= min(c.z + 1, sp->grid_nz - 1); ++z)
    for (int y = max(c.y - 1, 0); y <= min(c.y + 1, sp->grid_ny - 1); ++y)
      for (int x = max(c.x - 1, 0); x <= min(c.x + 1, sp->grid_nx - 1); ++x) {
        const int cell = (z * sp->grid_ny + y) * sp->grid_nx + x;
        const int b = cell_start[cell];
        const int e = b + cell_count[cell];
        for (int j = b; j < e; ++j)
          if (j != i && is_neighbour(sp, pi, pos[j])) ++count;
      }
  neigh_count[i] = count;
}

__kernel void contacts_fill(__global const SimParams* sp,
                            __global const real4* pos,
                            __global const int* cell_start,
                            __global const int* cell_count,
                            __global const int* neigh_start,
                            __global int* neigh_index,
                            __global real4* neigh_hist,
                            __global const int* perm,
                            __global const int* old_start,
                            __global const int* old_count,
                            __global const int* old_index,
                            __global const real4* old_hist) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  const real4 pi = pos[i];
  const int4 c = grid_cell_of(sp, xyz_of(pi));
  const int oi = perm[i];
  const int ob = old_start[oi];
  const int oe = ob + old_count[oi];
  int k = neigh_start[i];
  for (int z = max(c.z - 1, 0); z <= min(c.z + 1, sp->grid_nz - 1); ++z)
    for (int y = max(c.y - 1, 0); y <= min(c.y + 1, sp->grid_ny - 1); ++y)
      for (int x = max(c.x - 1, 0); x <= min(c.x + 1, sp->grid_nx - 1); ++x) {
        const int cell = (z * sp->grid_ny + y) * sp->grid_nx + x;
        const int b = cell_start[cell];
        const int e = b + cell_count[cell];
        for (int j = b; j < e; ++j) {
          if (j == i || !is_neighbour(sp, pi, pos[j])) continue;
          const int oj = perm[j];
          real4 h = (real4)(0, 0, 0, 0);
          for (int q = ob; q < oe; ++q)
            if (old_index[q] == oj) { h = old_hist[q]; break; }
          neigh_index[k] = j;
          neigh_hist[k] = h;
          ++k;
        }
      }
}
