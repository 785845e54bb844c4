/* law_probe.cl — the contact law alone, one listed pair per work-item, for
 * tools/law_probe.cpp: how much a contact costs when the law runs in SIMD
 * lanes, against the same law run one pair at a time. The pair's geometry
 * and law are the solver's (pair_geometry, contact_force).
 *
 * PoCL puts work-items in SIMD lanes only when the kernel holds no vector
 * values: with MC_PROBE_LANES the balls' state is read a real at a time,
 * without it as real4, which keeps each work-item scalar. */
#include "mc_shim.h"
#include "layout.h"
#include "contact_law.h"
#include "walls.h"
#include "books.h"
#include "periodic.h"
#include "mesh.h"
#include "ball_forces.h"

#ifdef MC_PROBE_LANES
#define PROBE_LOAD(a, b, k) \
  (b)[0] = ((__global const real*)(a))[4 * (k)];     \
  (b)[1] = ((__global const real*)(a))[4 * (k) + 1]; \
  (b)[2] = ((__global const real*)(a))[4 * (k) + 2]; \
  (b)[3] = ((__global const real*)(a))[4 * (k) + 3]
#else
#define PROBE_LOAD(a, b, k) \
  { const real4 v_ = (a)[k]; (b)[0] = v_.x; (b)[1] = v_.y; (b)[2] = v_.z; (b)[3] = v_.w; }
#endif

__kernel void law_probe(__global const PairParams* pairs, __global const int* ball_i,
                        __global const int* ball_j, __global const real4* pos,
                        __global const real4* vel, __global const real4* omega,
                        __global const real* spring, __global real* out, int n, real dt) {
  const int c = get_global_id(0);
  if (c >= n) return;
  const int i = ball_i[c], j = ball_j[c];
  real pi[4], pj[4], vi[4], vj[4], wi[4], wj[4];
  PROBE_LOAD(pos, pi, i);
  PROBE_LOAD(pos, pj, j);
  PROBE_LOAD(vel, vi, i);
  PROBE_LOAD(vel, vj, j);
  PROBE_LOAD(omega, wi, i);
  PROBE_LOAD(omega, wj, j);
  const v3 p_i = v3_make(pi[0], pi[1], pi[2]), p_j = v3_make(pj[0], pj[1], pj[2]);
  const ContactGeom g =
      pair_geometry(p_i, pi[3], v3_make(vi[0], vi[1], vi[2]), v3_make(wi[0], wi[1], wi[2]), vi[3], wi[3], p_j,
                    pj[3], v3_make(vj[0], vj[1], vj[2]), v3_make(wj[0], wj[1], wj[2]), vj[3], wj[3]);
  const v3 s0 = v3_make(spring[c], spring[n + c], spring[2 * n + c]);
  const ContactOut o = contact_force(pairs[0], g, s0, dt, MC_LAW_HERTZ);
  out[c] = o.force.x;
  out[n + c] = o.force.y;
  out[2 * n + c] = o.force.z;
  out[3 * n + c] = o.torque.x;
  out[4 * n + c] = o.torque.y;
  out[5 * n + c] = o.torque.z;
  out[6 * n + c] = o.spring.x;
  out[7 * n + c] = o.spring.y;
  out[8 * n + c] = o.spring.z;
  out[9 * n + c] = o.dissipated;
}
