/* periodic.h — a periodic axial slice (SimParams.period > 0): the mill axis
 * z is taken modulo the period, with no end plates, so that a slice of a
 * long mill stands for its middle. Positions are kept in [0, period); a ball
 * that leaves one end enters at the other with its velocity and spin. Pairs
 * see each other through the minimum image along z: the partner shifted by
 * whole periods to lie within half a period of the ball. The grid's z cells
 * tile the period (at least 3, grid.h), so the 27-cell stencil never visits
 * a cell twice and a pair is never listed twice. Stateless, shared by the
 * kernels and the CPU reference. */
#ifndef MC_PERIODIC_H
#define MC_PERIODIC_H

/* dz reduced to the minimum image, |dz| <= period / 2. */
MC_FN real image_dz(MC_GLOBAL const SimParams* sp, real dz) {
  const real L = sp->period;
  return L > R(0.0) ? dz - L * floor(dz / L + R(0.5)) : dz;
}

/* z of a partner at z_j as seen from a ball at z_i: the nearest image
 * (z_j itself, to the bit, when the axis is not periodic). */
MC_FN real image_z(MC_GLOBAL const SimParams* sp, real z_j, real z_i) {
  const real L = sp->period;
  return L > R(0.0) ? z_j + L * floor((z_i - z_j) / L + R(0.5)) : z_j;
}

/* A partner's position (radius in w) moved to its nearest image. */
MC_FN real4 image_of(MC_GLOBAL const SimParams* sp, real4 p_j, real z_i) {
  real4 q = p_j;
  q.z = image_z(sp, p_j.z, z_i);
  return q;
}

/* z brought into [0, period) (a rounding may leave it at period itself,
 * which the grid takes modulo its cells). */
MC_FN real wrap_z(MC_GLOBAL const SimParams* sp, real z) {
  const real L = sp->period;
  return L > R(0.0) ? z - L * floor(z / L) : z;
}

#endif /* MC_PERIODIC_H */
