/* motion.cl — leapfrog (kick–drift) integration, translation and rotation:
 * v(n+½) = v(n−½) + dt·F(n)/m, x(n+1) = x(n) + dt·v(n+½), likewise ω with the
 * torque (spheres, isotropic inertia). Gravity is already in F. Raises the
 * rebuild flag when a ball has moved more than half the skin since the
 * neighbour lists were built, and the not-finite flag on NaN or Inf. */
#include "mc_shim.h"
#include "layout.h"
#include "periodic.h"
#include "motion.h"
#include "rigid.h" /* compiled here so that the kernels build it; no kernel calls it yet */

__kernel void motion(__global const SimParams* sp, __global real4* pos,
                     __global real4* vel, __global real4* omega,
                     __global const real4* force, __global const real4* torque,
                     __global const real4* pos_at_build, __global int* status) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  const int flags = integrate_ball(i, sp, pos, vel, omega, force, torque, pos_at_build);
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
