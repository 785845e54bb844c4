/* body.h — rigid bodies of overlapping spheres (clumps), shared by the
 * kernels (motion.cl) and the CPU reference. Needs periodic.h, motion.h
 * and rigid.h.
 *
 * A body's component spheres are balls like any other in the binning, the
 * neighbour lists and the force kernels (two components of one body are
 * never listed as a pair): each gathers the forces and torques of its
 * contacts, without gravity. Their velocity's w holds the body's 1/M, so
 * that a contact's damping sees the body's mass, and their spin's w the
 * body's largest 1/I (the rolling torque's cap). Then, each step:
 *   body_sum   the components' forces and torques summed to the body, the
 *              torque of a force about the centre of mass added, gravity on
 *              the body's mass (after the force kernels: the books read
 *              them);
 *   body_move  the leapfrog on the centre of mass, the kick and the free
 *              rotation (rigid.h) on the angular momentum and orientation,
 *              and the components placed from the body: position, the
 *              velocity of the body at that point, the body's spin.
 * The components of body b are the balls with ids body_comp[b].x onwards
 * (body_comp[b].y of them); slot_of[id - first_component] is where each
 * lies now (the balls are reordered by cell at each rebuild). Body arrays:
 *   body_pos   centre of mass xyz (in [0, period) in a slice); w: 1/M
 *   body_vel   v(n−½); w: 0
 *   body_quat  orientation, body → lab (rigid.h)
 *   body_angmom  L(n−½) in the body frame; w: 0
 *   body_inv_inertia  1/Ix, 1/Iy, 1/Iz (principal); w: 0
 *   body_force, body_torque  F(n) and the lab-frame torque T(n) about the
 *              centre of mass
 *   comp_offset  each component's centre in the body frame (by id −
 *              first_component); w: 0 */
#ifndef MC_BODY_H
#define MC_BODY_H

MC_FN void body_sum(int b, MC_GLOBAL const SimParams* sp, MC_GLOBAL const real4* pos,
                    MC_GLOBAL const real4* force, MC_GLOBAL const real4* torque,
                    MC_GLOBAL const int* slot_of, MC_GLOBAL const int2* body_comp,
                    MC_GLOBAL const real4* body_pos, MC_GLOBAL real4* body_force,
                    MC_GLOBAL real4* body_torque) {
  const int2 bc = body_comp[b];
  const real4 c = body_pos[b];
  real3 f = (R(1.0) / c.w) * xyz_of(sp->gravity);
  real3 t = make_real3(R(0), R(0), R(0));
  for (int k = 0; k < bc.y; ++k) {
    const int i = slot_of[bc.x - sp->first_component + k];
    const real4 p = pos[i];
    const real3 fi = xyz_of(force[i]);
    real3 r = xyz_of(p) - xyz_of(c);
    r.z = image_dz(sp, r.z);
    f += fi;
    t += xyz_of(torque[i]) + cross(r, fi);
  }
  body_force[b] = make_real4(f.x, f.y, f.z, R(0));
  body_torque[b] = make_real4(t.x, t.y, t.z, R(0));
}

/* One step of body b; returns the status flags of its components. */
MC_FN int body_move(int b, MC_GLOBAL const SimParams* sp, MC_GLOBAL real4* pos, MC_GLOBAL real4* vel,
                    MC_GLOBAL real4* omega, MC_GLOBAL const real4* pos_at_build,
                    MC_GLOBAL const int* slot_of, MC_GLOBAL const int2* body_comp,
                    MC_GLOBAL const real4* comp_offset, MC_GLOBAL real4* body_pos,
                    MC_GLOBAL real4* body_vel, MC_GLOBAL real4* body_quat, MC_GLOBAL real4* body_angmom,
                    MC_GLOBAL const real4* body_inv_inertia, MC_GLOBAL const real4* body_force,
                    MC_GLOBAL const real4* body_torque) {
  const real dt = sp->dt;
  real4 c = body_pos[b];
  real4 v = body_vel[b];
  const real4 f = body_force[b];
  real4 q = body_quat[b];
  real3 L = xyz_of(body_angmom[b]);
  const real3 inv_i = xyz_of(body_inv_inertia[b]);
  v.x += dt * f.x * c.w; v.y += dt * f.y * c.w; v.z += dt * f.z * c.w;
  rigid_kick(dt, xyz_of(body_torque[b]), q, &L);
  if (sp->velocity_damping > R(0.0)) { /* while settling, as the balls */
    const real keep = R(1.0) - sp->velocity_damping;
    v.x *= keep; v.y *= keep; v.z *= keep;
    L = keep * L;
  }
  c.x += dt * v.x; c.y += dt * v.y; c.z += dt * v.z;
  c.z = wrap_z(sp, c.z);
  rigid_free_rotation(dt, inv_i, &q, &L);
  body_pos[b] = c;
  body_vel[b] = v;
  body_quat[b] = q;
  body_angmom[b] = make_real4(L.x, L.y, L.z, R(0));
  /* The components: placed at the new orientation, moving with the body's
   * velocity at that point (the spin at the new orientation). */
  const real3 w = rigid_omega_lab(q, L, inv_i);
  const int2 bc = body_comp[b];
  int flags = 0;
  for (int k = 0; k < bc.y; ++k) {
    const int slot = bc.x - sp->first_component + k;
    const int i = slot_of[slot];
    const real3 r = quat_rotate(q, xyz_of(comp_offset[slot]));
    const real3 vc = xyz_of(v) + cross(w, r);
    real4 p = pos[i];
    p.x = c.x + r.x; p.y = c.y + r.y; p.z = wrap_z(sp, c.z + r.z);
    const real4 vi = make_real4(vc.x, vc.y, vc.z, vel[i].w);
    const real4 wi = make_real4(w.x, w.y, w.z, omega[i].w);
    pos[i] = p;
    vel[i] = vi;
    omega[i] = wi;
    flags |= ball_flags(sp, p, vi, wi, pos_at_build[i]);
  }
  return flags;
}

/* What body b holds at step n for the books: translational and rotational
 * kinetic energy at n (v(n) = v(n−½) + ½·dt·F(n)/M, likewise L), into
 * e->x and e->y. */
MC_FN void body_energy(int b, MC_GLOBAL const SimParams* sp, MC_GLOBAL const real4* body_pos,
                       MC_GLOBAL const real4* body_vel, MC_GLOBAL const real4* body_quat,
                       MC_GLOBAL const real4* body_angmom, MC_GLOBAL const real4* body_inv_inertia,
                       MC_GLOBAL const real4* body_force, MC_GLOBAL const real4* body_torque, real* ke_t,
                       real* ke_r) {
  const real half_dt = R(0.5) * sp->dt;
  const real inv_m = body_pos[b].w;
  const real3 vn = xyz_of(body_vel[b]) + (half_dt * inv_m) * xyz_of(body_force[b]);
  const real3 Ln = xyz_of(body_angmom[b]) + half_dt * quat_rotate_inverse(body_quat[b], xyz_of(body_torque[b]));
  const real3 ii = xyz_of(body_inv_inertia[b]);
  *ke_t = R(0.5) * dot(vn, vn) / inv_m;
  *ke_r = R(0.5) * (Ln.x * Ln.x * ii.x + Ln.y * Ln.y * ii.y + Ln.z * Ln.z * ii.z);
}

#endif /* MC_BODY_H */
