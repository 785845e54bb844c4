/* rigid.h — the rotation of a rigid body (a clump of spheres), shared by the
 * kernels and the CPU reference (included after mc_shim.h).
 *
 * A body's orientation is a unit quaternion q, vector part in x, y, z and
 * scalar part in w, that takes body-frame vectors to the lab frame:
 * v_lab = q v_body q*. Its angular momentum L is kept in the body frame,
 * whose axes are the principal axes (the inertia tensor there is diagonal,
 * I = diag(Ix, Iy, Iz)), so that ω_body = L / I component by component.
 *
 * A step is a kick and a free rotation. The kick adds the torque's impulse
 * (a lab-frame vector) to L. The free rotation is the splitting of
 * Dullweber, Leimkuhler & McLachlan (J. Chem. Phys. 107, 5840, 1997): the
 * free rigid body's Hamiltonian Lx²/2Ix + Ly²/2Iy + Lz²/2Iz is split by
 * axis, and each part's flow is an exact turn about one body axis at the
 * fixed rate L_k/I_k; the turns x(dt/2), y(dt/2), z(dt), y(dt/2), x(dt/2)
 * make a symplectic, time-reversible step of second order that keeps |L|
 * and the lab-frame L to rounding and the energy within O(dt²) without
 * drift. LAMMPS's rigid bodies use the quaternion form of the same
 * splitting (Miller et al., J. Chem. Phys. 116, 8649, 2002). */
#ifndef MC_RIGID_H
#define MC_RIGID_H

/* The Hamilton product a ⊗ b. */
MC_FN real4 quat_mul(real4 a, real4 b) {
  return make_real4(a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                    a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                    a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
                    a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z);
}

/* q v q*: a body-frame vector in the lab frame (q a unit quaternion). */
MC_FN real3 quat_rotate(real4 q, real3 v) {
  const real3 u = make_real3(q.x, q.y, q.z);
  const real3 t = R(2) * cross(u, v);
  return v + q.w * t + cross(u, t);
}

/* q* v q: a lab-frame vector in the body frame. */
MC_FN real3 quat_rotate_inverse(real4 q, real3 v) {
  return quat_rotate(make_real4(-q.x, -q.y, -q.z, q.w), v);
}

MC_FN real4 quat_normalised(real4 q) {
  const real n = sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  return make_real4(q.x / n, q.y / n, q.z / n, q.w / n);
}

/* The body turns by `angle` about its own axis k (0 x, 1 y, 2 z):
 * q ← q ⊗ (sin(a/2) e_k, cos(a/2)); a lab-fixed vector's body components
 * then turn by −angle about that axis, which L_body does. */
MC_FN void rigid_turn(int k, real angle, real4* q, real3* L) {
  const real s = sin(R(0.5) * angle), c = cos(R(0.5) * angle);
  const real4 r = k == 0 ? make_real4(s, R(0), R(0), c) : k == 1 ? make_real4(R(0), s, R(0), c)
                                                                 : make_real4(R(0), R(0), s, c);
  *q = quat_mul(*q, r);
  /* The two components the turn mixes, turned by -angle: sin from the half
   * angle's, and cos - 1 as -2 sin²(angle/2), not cos rounded near 1,
   * which in float would shrink L by parts in 10⁸ every turn. */
  const real sa = R(2) * s * c, cm1 = R(-2) * s * s;
  const real3 l = *L;
  real u, v;
  if (k == 0) u = l.y, v = l.z;
  else if (k == 1) u = l.z, v = l.x;
  else u = l.x, v = l.y;
  const real u1 = u + (sa * v + cm1 * u), v1 = v + (cm1 * v - sa * u);
  if (k == 0)
    *L = make_real3(l.x, u1, v1);
  else if (k == 1)
    *L = make_real3(v1, l.y, u1);
  else
    *L = make_real3(u1, v1, l.z);
}

/* The free rotation over dt (inv_inertia = 1/Ix, 1/Iy, 1/Iz); q is
 * renormalised at the end (the turns keep its norm to rounding). */
MC_FN void rigid_free_rotation(real dt, real3 inv_inertia, real4* q, real3* L) {
  rigid_turn(0, R(0.5) * dt * (*L).x * inv_inertia.x, q, L);
  rigid_turn(1, R(0.5) * dt * (*L).y * inv_inertia.y, q, L);
  rigid_turn(2, dt * (*L).z * inv_inertia.z, q, L);
  rigid_turn(1, R(0.5) * dt * (*L).y * inv_inertia.y, q, L);
  rigid_turn(0, R(0.5) * dt * (*L).x * inv_inertia.x, q, L);
  *q = quat_normalised(*q);
}

/* The kick: a lab-frame torque acting for dt. */
MC_FN void rigid_kick(real dt, real3 torque_lab, real4 q, real3* L) {
  *L = *L + dt * quat_rotate_inverse(q, torque_lab);
}

/* The angular velocity in the lab frame. */
MC_FN real3 rigid_omega_lab(real4 q, real3 L, real3 inv_inertia) {
  return quat_rotate(q, make_real3(L.x * inv_inertia.x, L.y * inv_inertia.y, L.z * inv_inertia.z));
}

#endif /* MC_RIGID_H */
