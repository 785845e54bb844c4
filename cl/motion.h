/* motion.h — the leapfrog update of one ball, shared by motion.cl and the CPU
 * reference. Returns the status flags it raises. Needs periodic.h: in a
 * slice the ball's z is wrapped into the period after the drift. */
#ifndef MC_MOTION_H
#define MC_MOTION_H

/* The status flags of a ball now at p (radius in w) with velocity v and
 * spin w, listed at b: shared by the balls' update and the rigid bodies'
 * (cl/body.h). */
MC_FN int ball_flags(MC_GLOBAL const SimParams* sp, real4 p, real4 v, real4 w, real4 b) {
  int flags = 0;
  const real dt = sp->dt;
  const real dx = p.x - b.x, dy = p.y - b.y, dz = image_dz(sp, p.z - b.z); /* wrapped or not */
  /* The host reads the status word every status_every steps, without
   * stalling the queue, and acts on it one step after the read: a flag
   * raised now may wait status_every steps. The flag goes up twice that
   * many steps' travel early (two when the host reads every step): a
   * collision in the steps it waits may speed the ball up. */
  const real reach =
      R(0.5) * sp->skin - (real)(2 * sp->status_every) * dt * sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
  if (reach <= R(0.0) || dx * dx + dy * dy + dz * dz > reach * reach) flags |= MC_FLAG_REBUILD;
  /* Too fast for reads every status_every steps: a rebuild may come only
   * that often, and this ball would leave the skin in between. */
  if (sp->status_every > 1 && reach <= R(0.0)) flags |= MC_FLAG_FAST;
  /* A ball wholly outside the shell or past the mill's ends (its plates or
   * its mesh ends) has gone through a wall: the contact was too soft or too
   * short for this dt. */
  const real rho2 = p.x * p.x + p.y * p.y;
  const real out_r = sp->shell_radius + p.w;
  if ((sp->shell_radius > R(0.0) && rho2 > out_r * out_r) ||
      (sp->escape_z1 > sp->escape_z0 && (p.z < sp->escape_z0 - p.w || p.z > sp->escape_z1 + p.w)))
    flags |= MC_FLAG_ESCAPED;
  /* Comparisons with NaN are false, so this also catches NaN. */
  const real big = R(1e30);
  if (!(fabs(p.x) + fabs(p.y) + fabs(p.z) + fabs(v.x) + fabs(v.y) + fabs(v.z) +
            fabs(w.x) + fabs(w.y) + fabs(w.z) < big))
    flags |= MC_FLAG_NOT_FINITE;
  return flags;
}

MC_FN int integrate_ball(int i, MC_GLOBAL const SimParams* sp,
                         MC_GLOBAL real4* pos, MC_GLOBAL real4* vel,
                         MC_GLOBAL real4* omega, MC_GLOBAL const real4* force,
                         MC_GLOBAL const real4* torque,
                         MC_GLOBAL const real4* pos_at_build) {
  const real dt = sp->dt;
  real4 v = vel[i];
  real4 p = pos[i];
  real4 w = omega[i];
  const real4 f = force[i];
  const real4 t = torque[i];
  v.x += dt * f.x * v.w; v.y += dt * f.y * v.w; v.z += dt * f.z * v.w;
  p.x += dt * v.x; p.y += dt * v.y; p.z += dt * v.z;
  p.z = wrap_z(sp, p.z); /* a slice: leaving one end is entering at the other */
  w.x += dt * t.x * w.w; w.y += dt * t.y * w.w; w.z += dt * t.z * w.w;
  if (sp->velocity_damping > R(0.0)) { /* only while settling: the turning
                                          mill's steps stay as they were */
    const real keep = R(1.0) - sp->velocity_damping;
    v.x *= keep; v.y *= keep; v.z *= keep;
    w.x *= keep; w.y *= keep; w.z *= keep;
  }
  vel[i] = v;
  pos[i] = p;
  omega[i] = w;
  return ball_flags(sp, p, v, w, pos_at_build[i]);
}

#endif /* MC_MOTION_H */
