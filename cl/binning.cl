/* binning.cl — the cell of each ball, a counting sort by cell, and the
 * reorder of the ball arrays into cell order (so that neighbours in space are
 * neighbours in memory). Order inside a cell is by ball id, which makes the
 * whole step independent of thread scheduling. */
#include "mc_shim.h"
#include "layout.h"
#include "grid.h"

__kernel void bin_clear(__global int* cell_count, int n_cells) {
  const int c = get_global_id(0);
  if (c < n_cells) cell_count[c] = 0;
}

__kernel void bin_count(__global const SimParams* sp, __global const real4* pos,
                        __global int* cell_count, __global int* ball_cell,
                        __global int* ball_rank) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  const int c = grid_cell_of(sp, xyz_of(pos[i])).w;
  ball_cell[i] = c;
  ball_rank[i] = atomic_inc(&cell_count[c]);
}

__kernel void bin_scatter(int n, __global const int* ball_cell,
                          __global const int* ball_rank,
                          __global const int* cell_start,
                          __global int* sorted_index) {
  const int i = get_global_id(0);
  if (i >= n) return;
  sorted_index[cell_start[ball_cell[i]] + ball_rank[i]] = i;
}

/* Insertion sort of each cell's few entries by ball id. */
__kernel void bin_sort_cells(int n_cells, __global const int* cell_start,
                             __global int* sorted_index,
                             __global const int2* info) {
  const int c = get_global_id(0);
  if (c >= n_cells) return;
  const int b = cell_start[c];
  const int m = cell_start[c + 1] - b;
  for (int a = b + 1; a < b + m; ++a) {
    const int idx = sorted_index[a];
    const int key = info[idx].x;
    int k = a - 1;
    while (k >= b && info[sorted_index[k]].x > key) {
      sorted_index[k + 1] = sorted_index[k];
      --k;
    }
    sorted_index[k + 1] = idx;
  }
}

/* dst[i] = src[perm[i]]: the gathers that put the ball arrays in cell order. */
__kernel void gather_real4(int n, __global const int* perm,
                           __global const real4* src, __global real4* dst) {
  const int i = get_global_id(0);
  if (i < n) dst[i] = src[perm[i]];
}

__kernel void gather_int2(int n, __global const int* perm,
                          __global const int2* src, __global int2* dst) {
  const int i = get_global_id(0);
  if (i < n) dst[i] = src[perm[i]];
}

/* Wall slots are stored slot-major (slot s of ball i at s·n + i): a key
 * and a record each. One slot at a time goes through scratch arrays of one
 * entry per ball, then back: no second copy of all slots. */
__kernel void gather_wall_slot(int n, int slot, __global const int* perm,
                               __global const int* key, __global const int* rec,
                               __global int* tmp_key, __global int* tmp_rec) {
  const int i = get_global_id(0);
  if (i >= n) return;
  const int from = slot * n + perm[i];
  tmp_key[i] = key[from];
  tmp_rec[i] = rec[from];
}

__kernel void put_wall_slot(int n, int slot, __global const int* tmp_key,
                            __global const int* tmp_rec, __global int* key,
                            __global int* rec) {
  const int i = get_global_id(0);
  if (i >= n) return;
  key[slot * n + i] = tmp_key[i];
  rec[slot * n + i] = tmp_rec[i];
}
