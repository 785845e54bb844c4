/* forces.cl — forces and torques on every ball (ball_forces.h): each pair
 * once, then the partners' sides added (reactions). */
#include "mc_shim.h"
#include "layout.h"
#include "contact_law.h"
#include "walls.h"
#include "ball_forces.h"

__kernel void forces(__global const SimParams* sp,
                     __global const PairParams* pairs,
                     __global const LifterPolygon* lifters, real mill_cos,
                     real mill_sin, real mill_omega, __global const real4* pos,
                     __global const real4* vel, __global const real4* omega,
                     __global const int2* info, __global const int* neigh_start,
                     __global const int* neigh_count,
                     __global int* neigh_index,
                     __global real* neigh_hist, __global const int* neigh_rev,
                     __global real* pair_out,
                     __global int* wall_key,
                     __global real* wall_hist, __global real4* force,
                     __global real4* torque, __global real4* accum,
                     __global int* status) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  MillState mill;
  mill.cos_angle = mill_cos;
  mill.sin_angle = mill_sin;
  mill.omega = mill_omega;
  ball_forces(i, sp, pairs, lifters, mill, pos, vel, omega, info, neigh_start,
              neigh_count, neigh_index, neigh_hist, neigh_rev, pair_out, wall_key, wall_hist, force,
              torque, accum, status);
}

__kernel void reactions(int n, __global const int* in_start,
                        __global const real* pair_out, __global real4* force,
                        __global real4* torque, __global real4* accum) {
  const int j = get_global_id(0);
  if (j >= n) return;
  ball_reactions(j, in_start, pair_out, force,
                 torque, accum);
}
