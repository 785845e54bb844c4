/* motion.cl — leapfrog (kick–drift) integration, translation and rotation:
 * v(n+½) = v(n−½) + dt·F(n)/m, x(n+1) = x(n) + dt·v(n+½), likewise ω with the
 * torque (spheres, isotropic inertia). Gravity is already in F. Raises the
 * rebuild flag when a ball has moved more than half the skin since the
 * neighbour lists were built, and the not-finite flag on NaN or Inf. */
#include "mc_shim.h"
#include "layout.h"
#include "periodic.h"
#include "motion.h"
#include "rigid.h"
#include "body.h"
#include "contact_law.h"
#include "walls.h"
#include "books.h"
#include "mesh.h"
#include "ball_forces.h"

/* The free balls; a body's components move with their body (body_move). */
__kernel void motion(__global const SimParams* sp, __global real4* pos,
                     __global real4* vel, __global real4* omega,
                     __global const real4* force, __global const real4* torque,
                     __global const real4* pos_at_build, __global int* status,
                     __global const int2* info) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  if (sp->first_component < sp->n_balls && MC_IS_COMPONENT(sp, info[i].x)) return;
  const int flags = integrate_ball(i, sp, pos, vel, omega, force, torque, pos_at_build);
  if (flags) MC_ATOMIC_OR(status, flags);
}

/* The partners' sides of the last force evaluation added (ball_reactions,
 * as the reactions kernel adds them), then the step: one launch instead of
 * two, the same sums in the same order, so the same bits. For charges of
 * balls only: a body needs its components' whole forces summed first. */
__kernel void react_motion(__global const SimParams* sp, __global real4* pos,
                           __global real4* vel, __global real4* omega,
                           __global real4* force, __global real4* torque, __global real4* accum,
                           __global const int* in_start, __global const real* pair_out,
                           __global const real4* pos_at_build, __global int* status) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  ball_reactions(i, in_start, pair_out, force, torque, accum);
  const int flags = integrate_ball(i, sp, pos, vel, omega, force, torque, pos_at_build);
  if (flags) MC_ATOMIC_OR(status, flags);
}

/* Rigid bodies (body.h): where each component lies now, after the balls
 * were put in cell order; the forces summed to each body; a step of each. */
__kernel void body_slots(__global const SimParams* sp, __global const int2* info, __global int* slot_of) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  const int id = info[i].x;
  if (MC_IS_COMPONENT(sp, id)) slot_of[id - sp->first_component] = i;
}

__kernel void body_sums(__global const SimParams* sp, __global const real4* pos, __global const real4* force,
                        __global const real4* torque, __global const int* slot_of,
                        __global const int2* body_comp, __global const real4* body_pos,
                        __global real4* body_force, __global real4* body_torque) {
  const int b = get_global_id(0);
  if (b >= sp->n_bodies) return;
  body_sum(b, sp, pos, force, torque, slot_of, body_comp, body_pos, body_force, body_torque);
}

__kernel void body_motion(__global const SimParams* sp, __global real4* pos, __global real4* vel,
                          __global real4* omega, __global const real4* pos_at_build,
                          __global const int* slot_of, __global const int2* body_comp,
                          __global const real4* comp_offset, __global real4* body_pos,
                          __global real4* body_vel, __global real4* body_quat, __global real4* body_angmom,
                          __global const real4* body_inv_inertia, __global const real4* body_force,
                          __global const real4* body_torque, __global int* status) {
  const int b = get_global_id(0);
  if (b >= sp->n_bodies) return;
  const int flags = body_move(b, sp, pos, vel, omega, pos_at_build, slot_of, body_comp, comp_offset, body_pos,
                              body_vel, body_quat, body_angmom, body_inv_inertia, body_force, body_torque);
  if (flags) MC_ATOMIC_OR(status, flags);
}

/* Clears status bits once the host has acted on them. */
__kernel void clear_status_flag(__global int* status, int bits) {
  if (get_global_id(0) == 0) atomic_and(status, ~bits);
}

/* Reports the device's struct sizes so the host can check its mirrors. */
__kernel void layout_sizes(__global int* out) {
  out[0] = (int)sizeof(SimParams);
  out[1] = (int)sizeof(PairParams);
  out[2] = (int)sizeof(LifterPolygon);
  out[3] = (int)sizeof(real4);
  out[4] = (int)sizeof(BookParams);
  out[5] = (int)sizeof(MeshTriangle);
  out[6] = (int)sizeof(MeshGrid);
}
