/* forces.cl — forces and torques on every ball (ball_forces.h): each pair
 * once, then the partners' sides added (reactions). */
#include "mc_shim.h"
#include "layout.h"
#include "contact_law.h"
#include "walls.h"
#include "books.h"
#include "periodic.h"
#include "mesh.h"
#include "ball_forces.h"

/* The books' arguments of both force kernels, and the struct they fill. */
#define MC_BOOK_ARGS                                                                                      \
  __global real4 *records, __global int *rec_state, int rec_capacity, int rec_mark, __global uint *spectra, \
      __global uint *liner, __global uint *impact_profile, __global const BookParams *bp
#define MC_BOOKS_INIT(b)          \
  Books b;                        \
  b.records = records;            \
  b.rec_state = rec_state;        \
  b.capacity = rec_capacity;      \
  b.mark = rec_mark;              \
  b.spectra = spectra;            \
  b.liner = liner;                \
  b.impact_profile = impact_profile; \
  b.bp = bp;                      \
  b.status = status

/* The mesh walls' arguments of both force kernels (mesh.h Meshes). */
#define MC_MESH_ARGS                                                                                  \
  __global const MeshGrid *mesh_grid, __global const MeshTriangle *mesh_tris,                         \
      __global const int2 *mesh_feature, __global const int *mesh_adj,                               \
      __global const int *mesh_cell_start,                                                           \
      __global const int *mesh_cell_tris, __global const PairParams *mesh_pairs
#define MC_MESHES_INIT(m)            \
  Meshes m;                          \
  m.grid = mesh_grid;                \
  m.tris = mesh_tris;                \
  m.feature = mesh_feature;          \
  m.adj = mesh_adj;                  \
  m.cell_start = mesh_cell_start;    \
  m.cell_tris = mesh_cell_tris;      \
  m.pairs = mesh_pairs

__kernel void forces(__global const SimParams* sp,
                     __global const PairParams* pairs,
                     __global const LifterPolygon* lifters, real mill_cos,
                     real mill_sin, real mill_omega, __global const real4* pos,
                     __global const real4* vel, __global const real4* omega,
                     __global const int2* info, __global const int* neigh_start,
                     __global const int* neigh_count,
                     __global int* neigh_index,
                     __global int* neigh_rec, __global const int* neigh_rev,
                     __global real* pair_out,
                     __global int* wall_key,
                     __global int* wall_rec, __global real4* force,
                     __global real4* torque, __global real4* accum,
                     __global int* status, MC_BOOK_ARGS, MC_MESH_ARGS) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  MillState mill;
  mill.cos_angle = mill_cos;
  mill.sin_angle = mill_sin;
  mill.omega = mill_omega;
  MC_BOOKS_INIT(books);
  MC_MESHES_INIT(meshes);
  ball_forces(i, sp, pairs, lifters, mill, pos, vel, omega, info, neigh_start,
              neigh_count, neigh_index, neigh_rec, neigh_rev, pair_out, wall_key, wall_rec, force,
              torque, accum, &books, &meshes);
}

__kernel void reactions(int n, __global const int* in_start,
                        __global const real* pair_out, __global real4* force,
                        __global real4* torque, __global real4* accum) {
  const int j = get_global_id(0);
  if (j >= n) return;
  ball_reactions(j, in_start, pair_out, force,
                 torque, accum);
}

/* ------------------------------------------------------------------------
 * forces_grouped: the same forces, with the law of the touching pairs run
 * side by side. A work-group of MC_FG_WG balls walks its lists one ball per
 * work-item (the touch test, the contacts that open), queues its touching
 * pairs in local memory, then runs the law on the group's first
 * MC_FG_ROUNDS·MC_FG_ROUND queued pairs, one per work-item a round, with no
 * vector values, no loop and no branch, so that PoCL puts the pairs in SIMD
 * lanes (on a CPU the per-ball loop runs the law one pair at a time). Each
 * ball then adds its pairs' results in list order, running any pair past
 * those itself, and does its walls: its sums are the per-ball kernel's, bit
 * for bit. A ball with more than MC_FG_QUEUE touching pairs in its list
 * (only among balls of very different sizes) runs the rest in the walk and
 * adds them after its queued ones. */
#ifndef MC_FG_WG
#define MC_FG_WG 64
#endif
#ifndef MC_FG_ROUNDS
#define MC_FG_ROUNDS 2
#endif
#ifndef MC_FG_QUEUE
#define MC_FG_QUEUE 16
#endif
#ifndef MC_FG_ROUND
#define MC_FG_ROUND MC_FG_WG /* queued pairs per round; the tests set fewer */
#endif
#define MC_FG_PAIRS (MC_FG_ROUNDS * MC_FG_ROUND)
#define MC_FG_OWN 8 /* reals of a ball's own side: F, T, half the loss, the stored energy */

/* A real4 array read a real at a time: a vector value would keep PoCL
 * from putting the work-items in lanes. */
#define FG_AT(a, k, c) (((__global const real*)(a))[4 * (k) + (c)])

/* The law on queued pair q of the group. Only q < total stores its
 * results: a work-item past the end redoes the last pair, or with no pair
 * entry 0 (whose partner is clamped, as the list may be empty), and its
 * results are dropped. These take local reads that PoCL vectorises at 8
 * lanes: padding the queue with dummies or a branch around the law made
 * it choose 4. */
MC_FN void fg_pair_law(int q, int total, int group_first, __global const SimParams* sp,
                       __global const PairParams* pairs, __global const real4* pos,
                       __global const real4* vel, __global const real4* omega,
                       __global const int2* info, __global int* neigh_index,
                       __global int* neigh_rec, __global const int* neigh_rev,
                       __global real* pair_out, __local const int* pair_entry,
                       __local const int* pair_ball,
                       __local real* own, Books* books, int law) {
  const int qc = min(q, max(total - 1, 0));
  /* With no pair queued nothing is read that no kernel wrote: the queue's
   * local slots, the list and the records may all be unwritten (a GPU does
   * not zero its memory); the lane runs ball group_first against ball 0. */
  const int any = total > 0;
  const int k = any ? pair_entry[qc] : 0;
  const int link = any ? neigh_index[k] : 0;
  const int a = group_first + (any ? pair_ball[qc] : 0);
  const int touched = any && MC_LINK_TOUCHING(link);
  const int b = clamp(MC_LINK_PARTNER(link), 0, sp->n_balls - 1);
  const real z_b = image_z(sp, FG_AT(pos, b, 2), FG_AT(pos, a, 2)); /* nearest image, periodic.h */
  const ContactGeom g = pair_geometry(
      v3_make(FG_AT(pos, a, 0), FG_AT(pos, a, 1), FG_AT(pos, a, 2)), FG_AT(pos, a, 3),
      v3_make(FG_AT(vel, a, 0), FG_AT(vel, a, 1), FG_AT(vel, a, 2)),
      v3_make(FG_AT(omega, a, 0), FG_AT(omega, a, 1), FG_AT(omega, a, 2)), FG_AT(vel, a, 3),
      FG_AT(omega, a, 3), v3_make(FG_AT(pos, b, 0), FG_AT(pos, b, 1), z_b), FG_AT(pos, b, 3),
      v3_make(FG_AT(vel, b, 0), FG_AT(vel, b, 1), FG_AT(vel, b, 2)),
      v3_make(FG_AT(omega, b, 0), FG_AT(omega, b, 1), FG_AT(omega, b, 2)), FG_AT(vel, b, 3),
      FG_AT(omega, b, 3));
  __global const int* mat = (__global const int*)info;
  const PairParams pp = pairs[MC_PAIR_INDEX(sp, mat[2 * a + 1], mat[2 * b + 1])];
  /* A pair that begins to touch takes its record after the law (only the
   * stored pairs take one), with no spring. */
  const int rec = touched ? neigh_rec[k] : MC_NO_RECORD;
  const ContactOut c = contact_force(pp, g, record_spring(books, rec), sp->dt, law);
  if (q < total) {
    store_partner_side(pair_out + MC_SLOT_REALS * neigh_rev[k], g, c, FG_AT(pos, b, 3));
    const int fresh = rec < 0;
    const int r = fresh ? record_take(books) : rec;
    record_step(books, r, fresh, v3_dot(g.v_rel, g.normal), c);
    if (fresh) {
      neigh_index[k] = MC_LINK_TOUCHED(b);
      neigh_rec[k] = r;
    }
    own[MC_FG_OWN * q + 0] = c.force.x;
    own[MC_FG_OWN * q + 1] = c.force.y;
    own[MC_FG_OWN * q + 2] = c.force.z;
    own[MC_FG_OWN * q + 3] = c.torque.x;
    own[MC_FG_OWN * q + 4] = c.torque.y;
    own[MC_FG_OWN * q + 5] = c.torque.z;
    own[MC_FG_OWN * q + 6] = R(0.5) * c.dissipated;
    own[MC_FG_OWN * q + 7] = c.elastic;
  }
}

__kernel __attribute__((reqd_work_group_size(MC_FG_WG, 1, 1)))
void forces_grouped(__global const SimParams* sp,
                    __global const PairParams* pairs,
                    __global const LifterPolygon* lifters, real mill_cos,
                    real mill_sin, real mill_omega, __global const real4* pos,
                    __global const real4* vel, __global const real4* omega,
                    __global const int2* info, __global const int* neigh_start,
                    __global const int* neigh_count,
                    __global int* neigh_index,
                    __global int* neigh_rec, __global const int* neigh_rev,
                    __global real* pair_out,
                    __global int* wall_key,
                    __global int* wall_rec, __global real4* force,
                    __global real4* torque, __global real4* accum,
                    __global int* status, MC_BOOK_ARGS, MC_MESH_ARGS) {
  __local int queue[MC_FG_WG * MC_FG_QUEUE]; /* list entries, per ball */
  __local int queued[MC_FG_WG];
  __local int first[MC_FG_WG + 1];            /* each ball's first queued pair */
  __local int pair_entry[MC_FG_PAIRS];        /* the group's queue, in ball order */
  __local int pair_ball[MC_FG_PAIRS];
  __local real own[MC_FG_OWN * MC_FG_PAIRS];

  const int lid = get_local_id(0);
  const int i = get_global_id(0);
  const int group_first = i - lid;
  const int active = i < sp->n_balls;
  const int law = MC_RUN_LAW(sp);
  MC_BOOKS_INIT(books);

  /* 1. The walk: which listed pairs touch. */
  BallSums extra = ball_sums_zero(); /* pairs past the ball's queue, run here */
  int nq = 0, n_extra = 0;
  if (active) {
    const real4 pi4 = pos[i];
    const v3 p = v3_of(xyz_of(pi4));
    const int start = neigh_start[i];
    const int count = neigh_count[i];
    for (int k = start; k < start + count; ++k) {
      int link;
      real4 pj4;
      if (!entry_touches(k, p, pi4.w, vel[i].w, info[i].y, sp, pos, vel, info, neigh_index, neigh_rec, neigh_rev,
                         pair_out, &books, &link, &pj4))
        continue;
      if (nq < MC_FG_QUEUE) {
        queue[lid * MC_FG_QUEUE + nq++] = k;
      } else {
        pair_contact(pi4, vel[i], omega[i], info[i].y, k, link, pj4, sp, pairs, vel, omega, info,
                     neigh_index, neigh_rec, neigh_rev, pair_out, &books, law, &extra);
        ++n_extra;
      }
    }
  }
  queued[lid] = nq;
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid == 0) {
    int s = 0;
    for (int w = 0; w < MC_FG_WG; ++w) {
      first[w] = s;
      s += queued[w];
    }
    first[MC_FG_WG] = s;
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  const int total = first[MC_FG_WG];
  const int in_rounds = min(total, MC_FG_PAIRS); /* the rest run in step 3 */
  {
    const int f0 = first[lid];
    for (int q = 0; q < nq && f0 + q < MC_FG_PAIRS; ++q) {
      const int k = queue[lid * MC_FG_QUEUE + q];
      pair_entry[f0 + q] = k;
      pair_ball[f0 + q] = lid;
    }
    if (lid == 0 && total == 0) { /* the dummy of a group with no pair */
      pair_entry[0] = 0;
      pair_ball[0] = 0;
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);

  /* 2. The law, a queued pair per work-item in each of MC_FG_ROUNDS rounds. */
#define FG_LAW(r)                                                                                    \
  fg_pair_law((r) * MC_FG_ROUND + lid, lid < MC_FG_ROUND ? in_rounds : 0, group_first, sp, pairs, pos, \
              vel, omega, info, neigh_index, neigh_rec, neigh_rev, pair_out, pair_entry, pair_ball, own, &books, law)
  FG_LAW(0);
#if MC_FG_ROUNDS > 1
  barrier(CLK_LOCAL_MEM_FENCE); /* a region per round, so each is one law wide */
  FG_LAW(1);
#endif
#if MC_FG_ROUNDS > 2
  barrier(CLK_LOCAL_MEM_FENCE);
  FG_LAW(2);
#endif
#if MC_FG_ROUNDS > 3
#error "MC_FG_ROUNDS: at most 3"
#endif
#undef FG_LAW
  barrier(CLK_LOCAL_MEM_FENCE);

  /* 3. Each ball's sums, in list order: gravity, its queued pairs (those
   * past the group's MC_FG_PAIRS run here), the rest, the walls. */
  if (active) {
    const real4 pi4 = pos[i];
    const real4 vi = vel[i];
    const real4 wi = omega[i];
    const int2 info_i = info[i];
    const int mat_i = info_i.y;
    BallSums s = ball_sums_start(sp, vi, info_i.x);
    const int f0 = first[lid];
    for (int q = 0; q < nq; ++q) {
      const int fq = f0 + q;
      if (fq < MC_FG_PAIRS) {
        s.f += make_real3(own[MC_FG_OWN * fq + 0], own[MC_FG_OWN * fq + 1], own[MC_FG_OWN * fq + 2]);
        s.t += make_real3(own[MC_FG_OWN * fq + 3], own[MC_FG_OWN * fq + 4], own[MC_FG_OWN * fq + 5]);
        s.dissipated += own[MC_FG_OWN * fq + 6];
        s.elastic += own[MC_FG_OWN * fq + 7];
      } else {
        const int k = queue[lid * MC_FG_QUEUE + q];
        const int link = neigh_index[k];
        pair_contact(pi4, vi, wi, mat_i, k, link, image_of(sp, pos[MC_LINK_PARTNER(link)], pi4.z), sp, pairs, vel,
                     omega, info,
                     neigh_index, neigh_rec, neigh_rev, pair_out, &books, law, &s);
      }
    }
    if (n_extra > 0) {
      s.f += extra.f;
      s.t += extra.t;
      s.dissipated += extra.dissipated;
      s.elastic += extra.elastic;
    }
    MillState mill;
    mill.cos_angle = mill_cos;
    mill.sin_angle = mill_sin;
    mill.omega = mill_omega;
    MC_MESHES_INIT(meshes);
    ball_walls(i, pi4, vi, wi, mat_i, sp, pairs, lifters, &meshes, mill, wall_key, wall_rec, &books, law, &s);
    ball_store(i, s, mill, sp->dt, force, torque, accum);
  }
}
