/* instances.cl — the viewer's per-ball data (layout in instances.h), in the
 * solver's current (cell) order. Velocities are stored half a step behind,
 * so the speed uses v(n) = v(n−½) + ½·dt·F(n)/m as the reductions do; the
 * component spheres of a rigid body (body.h) show their body's speed. */
#include "mc_shim.h"
#include "layout.h"
#include "instances.h"

__kernel void write_instances(__global const SimParams* sp, __global const real4* pos,
                              __global const real4* vel, __global const real4* force,
                              __global const int2* info, __global const real4* accum,
                              real interval_s, __global float* out, __global const int* body_of,
                              __global const real4* body_pos, __global const real4* body_vel,
                              __global const real4* body_force) {
  const int i = get_global_id(0);
  if (i >= sp->n_balls) return;
  const real4 p = pos[i];
  const real4 vh = vel[i];
  real3 v = xyz_of(vh) + R(0.5) * sp->dt * vh.w * xyz_of(force[i]);
  const int id = info[i].x;
  if (MC_IS_COMPONENT(sp, id)) { /* a clump's sphere shows its body's speed */
    const int b = body_of[id - sp->first_component];
    v = xyz_of(body_vel[b]) + R(0.5) * sp->dt * body_pos[b].w * xyz_of(body_force[b]);
  }
  const real power = interval_s > R(0.0) ? accum[i].z / interval_s : R(0.0);
  __global float* o = out + (size_t)i * MC_INSTANCE_FLOATS;
  vstore4((float4)((float)p.x, (float)p.y, (float)p.z, (float)p.w), 0, o);
  vstore4((float4)((float)length(v), (float)info[i].y, (float)power, (float)info[i].x), 1, o);
}
