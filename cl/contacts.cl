/* contacts.cl — the neighbour lists (the "collision links"): for each ball,
 * the balls within r_i + r_j + skin, stored compactly (CSR: a start and a
 * count per ball). Cell c holds the balls cell_start[c] .. cell_start[c + 1].
 * Built in two passes, count then fill, after binning has
 * put the balls in cell order. The fill pass carries each persisting pair's
 * tangential spring over from the previous list, which was written in the
 * previous ball order: `perm` maps a new index to the old one. Only the
 * springs of pairs in contact (MC_LINK_TOUCHING) are carried: before the new
 * lists are built they are copied out of the old lists into a compact carry
 * list (carry_count, a scan, carry_fill), so that the old lists need no
 * second buffer while the new ones are written. */
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
        const int e = cell_start[cell + 1];
        for (int j = b; j < e; ++j)
          if (j != i && is_neighbour(sp, pi, pos[j])) ++count;
      }
  neigh_count[i] = count;
}

__kernel void contacts_fill(__global const SimParams* sp,
                            __global const real4* pos,
                            __global const int* cell_start,
                            __global const int* neigh_start,
                            __global int* neigh_index,
                            __global real* neigh_hist,
                            __global const int* perm,
                            __global const int* old_start,
                            __global const int* old_count,
                            __global const int* old_index,
                            __global const real* old_hist) {
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
        const int e = cell_start[cell + 1];
        for (int j = b; j < e; ++j) {
          if (j == i || !is_neighbour(sp, pi, pos[j])) continue;
          const int oj = perm[j];
          real3 h = (real3)(0, 0, 0);
          int link = j;
          for (int q = ob; q < oe; ++q)
            if (old_index[q] == oj) { h = load_hist(old_hist, q); link = MC_LINK_TOUCHED(j); break; }
          neigh_index[k] = link;
          store_hist(h, neigh_hist, k);
          ++k;
        }
      }
}

/* Springs to carry over (pairs touching at the last evaluation), per ball,
 * in the old order. */
__kernel void carry_count(int n, __global const int* neigh_start,
                          __global const int* neigh_count,
                          __global const int* neigh_index,
                          __global int* carry_count) {
  const int i = get_global_id(0);
  if (i >= n) return;
  int c = 0;
  const int b = neigh_start[i];
  for (int k = b; k < b + neigh_count[i]; ++k)
    if (MC_LINK_TOUCHING(neigh_index[k])) ++c;
  carry_count[i] = c;
}

__kernel void carry_fill(int n, __global const int* neigh_start,
                         __global const int* neigh_count,
                         __global const int* neigh_index,
                         __global const real* neigh_hist,
                         __global const int* carry_start,
                         __global int* carry_index, __global real* carry_hist) {
  const int i = get_global_id(0);
  if (i >= n) return;
  int q = carry_start[i];
  const int b = neigh_start[i];
  for (int k = b; k < b + neigh_count[i]; ++k) {
    const int link = neigh_index[k];
    if (MC_LINK_TOUCHING(link)) {
      carry_index[q] = MC_LINK_PARTNER(link);
      store_hist(load_hist(neigh_hist, k), carry_hist, q);
      ++q;
    }
  }
}
