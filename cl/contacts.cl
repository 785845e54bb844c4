/* contacts.cl — the neighbour lists (the "collision links"): each pair of
 * balls within r_i + r_j + skin once, in the list of the ball with the lower
 * index (half lists), stored compactly (CSR: a start and a count per ball).
 * Cell c holds the balls cell_start[c] .. cell_start[c + 1]. Built in two
 * passes, count then fill, after binning has put the balls in cell order.
 * The fill pass carries each persisting contact's record (its spring and
 * losses, layout.h) over from the previous list, which was written in the
 * previous ball order: `perm` maps a new index to the old one. Only pairs in
 * contact (MC_LINK_TOUCHING) have records: before the new lists are built
 * their partners and records are copied out of the old lists into a
 * compact carry list (carry_count, a scan, carry_fill), so that the old
 * lists need no second buffer while the new ones are written. A spring is
 * seen from the ball that lists the pair; when the new order hands the pair
 * to the other ball, the spring changes sign.
 *
 * Then the records of the open contacts are packed to the front of the
 * pool in ball order (records_count, a scan, records_pack), so that the
 * pool holds no records of contacts that ended.
 *
 * Each ball's incoming slots (one per entry k of a lower ball's list that
 * holds it) are indexed too, for the reactions: in_count, a scan,
 * in_scatter, then in_sort puts each ball's entries in ascending order, so
 * that its forces are summed in an order that does not depend on the
 * threads, and tells each entry its slot (neigh_rev). */
#include "mc_shim.h"
#include "layout.h"
#include "grid.h"
#include "periodic.h"

/* Whether a and b are within r_a + r_b + skin (the minimum image along a
 * periodic axis). */
MC_FN int is_neighbour(__global const SimParams* sp, real4 a, real4 b) {
  real3 d = xyz_of(a) - xyz_of(b);
  d.z = image_dz(sp, d.z);
  const real cut = a.w + b.w + sp->skin;
  return dot(d, d) < cut * cut;
}

/* Two components of one rigid body are never a pair (cl/body.h): body_of
 * gives each component's body, by id − first_component. */
MC_FN int same_body(__global const SimParams* sp, __global const int2* info,
                    __global const int* body_of, int id_i, int j) {
  if (!MC_IS_COMPONENT(sp, id_i)) return 0;
  const int id_j = info[j].x;
  return MC_IS_COMPONENT(sp, id_j) &&
         body_of[id_i - sp->first_component] == body_of[id_j - sp->first_component];
}

__kernel void contacts_count(__global const SimParams* sp,
                             __global const real4* pos,
                             __global const int* cell_start,
                             __global int* neigh_count,
                             __global const int2* info, __global const int* body_of) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  const real4 pi = pos[i];
  const int id_i = info[i].x;
  const int4 c = grid_cell_of(sp, xyz_of(pi));
  int count = 0;
  const int periodic = sp->period > R(0.0);
  const int z_lo = periodic ? c.z - 1 : max(c.z - 1, 0);
  const int z_hi = periodic ? c.z + 1 : min(c.z + 1, sp->grid_nz - 1);
  for (int zs = z_lo; zs <= z_hi; ++zs) {
    const int z = periodic ? grid_wrap(zs, sp->grid_nz) : zs;
    for (int y = max(c.y - 1, 0); y <= min(c.y + 1, sp->grid_ny - 1); ++y)
      for (int x = max(c.x - 1, 0); x <= min(c.x + 1, sp->grid_nx - 1); ++x) {
        const int cell = (z * sp->grid_ny + y) * sp->grid_nx + x;
        const int b = cell_start[cell];
        const int e = cell_start[cell + 1];
        for (int j = max(b, i + 1); j < e; ++j)
          if (is_neighbour(sp, pi, pos[j]) && !same_body(sp, info, body_of, id_i, j)) ++count;
      }
  }
  neigh_count[i] = count;
}

/* Whether the pair (old indices a < b) was carried; if so its record goes
 * to *rec. */
MC_FN int find_carried(int a, int b, __global const int* carry_start,
                        __global const int* carry_count,
                        __global const int* carry_index,
                        __global const int* carry_rec, int* rec) {
  const int q0 = carry_start[a];
  for (int q = q0; q < q0 + carry_count[a]; ++q)
    if (carry_index[q] == b) { *rec = carry_rec[q]; return 1; }
  return 0;
}

__kernel void contacts_fill(__global const SimParams* sp,
                            __global const real4* pos,
                            __global const int* cell_start,
                            __global const int* neigh_start,
                            __global int* neigh_index,
                            __global int* neigh_rec,
                            __global const int* perm,
                            __global const int* carry_start,
                            __global const int* carry_count,
                            __global const int* carry_index,
                            __global const int* carry_rec,
                            __global real4* records,
                            __global const int2* info, __global const int* body_of) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  const real4 pi = pos[i];
  const int id_i = info[i].x;
  const int4 c = grid_cell_of(sp, xyz_of(pi));
  const int oi = perm[i];
  int k = neigh_start[i];
  const int periodic = sp->period > R(0.0);
  const int z_lo = periodic ? c.z - 1 : max(c.z - 1, 0);
  const int z_hi = periodic ? c.z + 1 : min(c.z + 1, sp->grid_nz - 1);
  for (int zs = z_lo; zs <= z_hi; ++zs) {
    const int z = periodic ? grid_wrap(zs, sp->grid_nz) : zs;
    for (int y = max(c.y - 1, 0); y <= min(c.y + 1, sp->grid_ny - 1); ++y)
      for (int x = max(c.x - 1, 0); x <= min(c.x + 1, sp->grid_nx - 1); ++x) {
        const int cell = (z * sp->grid_ny + y) * sp->grid_nx + x;
        const int b = cell_start[cell];
        const int e = cell_start[cell + 1];
        for (int j = max(b, i + 1); j < e; ++j) {
          if (!is_neighbour(sp, pi, pos[j]) || same_body(sp, info, body_of, id_i, j)) continue;
          const int oj = perm[j];
          int rec = MC_NO_RECORD;
          /* The old list of the lower old index held the pair. */
          const int found = oi < oj
              ? find_carried(oi, oj, carry_start, carry_count, carry_index, carry_rec, &rec)
              : find_carried(oj, oi, carry_start, carry_count, carry_index, carry_rec, &rec);
          if (found && oi > oj && rec >= 0) { /* now seen from the other ball */
            const real4 h = records[2 * rec];
            records[2 * rec] = (real4)(-h.x, -h.y, -h.z, h.w);
          }
          neigh_index[k] = found ? MC_LINK_TOUCHED(j) : j;
          neigh_rec[k] = found ? rec : MC_NO_RECORD;
          ++k;
        }
      }
  }
}

/* Records to carry over (pairs touching at the last evaluation), per ball,
 * in the old order. A touching pair without a record (the pool was full)
 * is carried too, and starts afresh. */
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
                         __global const int* neigh_rec,
                         __global const int* carry_start,
                         __global int* carry_index, __global int* carry_rec) {
  const int i = get_global_id(0);
  if (i >= n) return;
  int q = carry_start[i];
  const int b = neigh_start[i];
  for (int k = b; k < b + neigh_count[i]; ++k) {
    const int link = neigh_index[k];
    if (MC_LINK_TOUCHING(link)) {
      carry_index[q] = MC_LINK_PARTNER(link);
      carry_rec[q] = neigh_rec[k];
      ++q;
    }
  }
}

/* Incoming slots per ball, counted into in_start (zeroed first; scanned in
 * place after). */
__kernel void in_count(int n, __global const int* neigh_start,
                       __global const int* neigh_count,
                       __global const int* neigh_index,
                       __global int* in_start) {
  const int i = get_global_id(0);
  if (i >= n) return;
  const int b = neigh_start[i];
  for (int k = b; k < b + neigh_count[i]; ++k)
    atomic_inc(&in_start[MC_LINK_PARTNER(neigh_index[k])]);
}

/* Each entry k into one of its partner's incoming slots, in any order (fill
 * zeroed first). */
__kernel void in_scatter(int n, __global const int* neigh_start,
                         __global const int* neigh_count,
                         __global const int* neigh_index,
                         __global const int* in_start, __global int* fill,
                         __global int* in_slot) {
  const int i = get_global_id(0);
  if (i >= n) return;
  const int b = neigh_start[i];
  for (int k = b; k < b + neigh_count[i]; ++k) {
    const int j = MC_LINK_PARTNER(neigh_index[k]);
    in_slot[in_start[j] + atomic_inc(&fill[j])] = k;
  }
}

/* Insertion sort of each ball's few incoming entries; then each entry learns
 * its slot (neigh_rev). */
__kernel void in_sort(int n, __global const int* in_start,
                      __global int* in_slot, __global int* neigh_rev) {
  const int j = get_global_id(0);
  if (j >= n) return;
  const int b = in_start[j];
  const int e = in_start[j + 1];
  for (int a = b + 1; a < e; ++a) {
    const int v = in_slot[a];
    int q = a - 1;
    while (q >= b && in_slot[q] > v) {
      in_slot[q + 1] = in_slot[q];
      --q;
    }
    in_slot[q + 1] = v;
  }
  for (int q = b; q < e; ++q) neigh_rev[in_slot[q]] = q;
}

/* The pool packed: each ball's live records (its touching entries', then
 * its wall slots') counted, then (after a scan into `first`) copied in that
 * order into `packed` and renumbered. `pending` counts, per ball, the pairs
 * that overlap now but hold no record yet (a charge laid anew), so that the
 * host can size the pool before the next force evaluation takes them. */
__kernel void records_count(__global const SimParams* sp, __global const real4* pos,
                            __global const int* neigh_start, __global const int* neigh_count,
                            __global const int* neigh_index, __global const int* neigh_rec,
                            __global const int* wall_key, __global const int* wall_rec,
                            __global int* live, __global int* pending) {
  const int i = get_global_id(0);
  const int n = sp->n_balls;
  if (i >= n) return;
  int c = 0, p = 0;
  const real4 pi = pos[i];
  const int b = neigh_start[i];
  for (int k = b; k < b + neigh_count[i]; ++k) {
    const int link = neigh_index[k];
    if (MC_LINK_TOUCHING(link)) {
      c += neigh_rec[k] >= 0;
    } else {
      const real4 pj = pos[link];
      real3 d = xyz_of(pi) - xyz_of(pj);
      d.z = image_dz(sp, d.z);
      const real r = pi.w + pj.w;
      p += dot(d, d) < r * r;
    }
  }
  for (int s = 0; s < MC_MAX_WALL_CONTACTS; ++s)
    c += wall_key[s * n + i] != MC_WALL_NONE && wall_rec[s * n + i] >= 0;
  live[i] = c;
  pending[i] = p;
}

__kernel void records_pack(int n, __global const int* neigh_start, __global const int* neigh_count,
                           __global const int* neigh_index, __global int* neigh_rec,
                           __global const int* wall_key, __global int* wall_rec,
                           __global const int* first, __global const real4* records,
                           __global real4* packed) {
  const int i = get_global_id(0);
  if (i >= n) return;
  int q = first[i];
  const int b = neigh_start[i];
  for (int k = b; k < b + neigh_count[i]; ++k) {
    const int r = neigh_rec[k];
    if (!MC_LINK_TOUCHING(neigh_index[k]) || r < 0) continue;
    packed[2 * q] = records[2 * r];
    packed[2 * q + 1] = records[2 * r + 1];
    neigh_rec[k] = q++;
  }
  for (int s = 0; s < MC_MAX_WALL_CONTACTS; ++s) {
    const int r = wall_rec[s * n + i];
    if (wall_key[s * n + i] == MC_WALL_NONE || r < 0) continue;
    packed[2 * q] = records[2 * r];
    packed[2 * q + 1] = records[2 * r + 1];
    wall_rec[s * n + i] = q++;
  }
}
