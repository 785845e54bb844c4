/* reductions.cl — the sums the mill observers need, one partial sum per
 * work-group (the host adds the few partials in double):
 *   0 Σ wall torque about the axis × dt since the last read (N·m·s)
 *   1 Σ work done by the walls since the last read (J)
 *   2 Σ energy dissipated in contacts since the last read (J)
 *   3 elastic energy stored in contacts now (J)
 *   4 translational kinetic energy at step n (J)
 *   5 rotational kinetic energy at step n (J)
 *   6 gravitational potential energy −m·g·x (J)
 *   7 neighbour-list entries
 *   8 Σ m·x and 9 Σ m·y: the charge's centre of mass, for its angle and
 *     for the torque-arm power M·g·x̄·ω
 *  10-12 what the open contacts have lost so far, normal, tangential and
 *     rolling (J): their records, by the ball that holds each (list entries
 *     and wall slots)
 * Velocities are stored half a step behind, so the kinetic energy uses
 * v(n) = v(n−½) + ½·dt·F(n)/m, which keeps the energy check second order.
 * With reset != 0 the accumulators 0–2 are zeroed for the next interval. */
#include "mc_shim.h"
#include "layout.h"
#include "periodic.h"
#include "motion.h"
#include "rigid.h"
#include "body.h"

#ifndef MC_ENERGY_BOOKS
#define MC_ENERGY_BOOKS 1
#endif

#define MC_N_OBSERVABLES 13

__kernel __attribute__((reqd_work_group_size(MC_REDUCE_WG, 1, 1)))
void reduce_observables(__global const SimParams* sp,
                        __global const real4* pos, __global const real4* vel,
                        __global const real4* omega,
                        __global const real4* force,
                        __global const real4* torque, __global real4* accum,
                        __global const int* neigh_start, __global const int* neigh_count,
                        __global const int* neigh_index, __global const int* neigh_rec,
                        __global const int* wall_key, __global const int* wall_rec,
                        __global const real4* records, int reset, __global real* partial,
                        __global const int2* info, __global const int2* body_comp,
                        __global const int* body_of, __global const real4* body_pos,
                        __global const real4* body_vel, __global const real4* body_quat,
                        __global const real4* body_angmom, __global const real4* body_inv_inertia,
                        __global const real4* body_force, __global const real4* body_torque) {
  __local real tmp[MC_REDUCE_WG * MC_N_OBSERVABLES];
  const int i = get_global_id(0);
  const int lid = get_local_id(0);
  real v[MC_N_OBSERVABLES];
  for (int k = 0; k < MC_N_OBSERVABLES; ++k) v[k] = R(0.0);
  if (i < sp->n_balls) {
    const real half_dt = R(0.5) * sp->dt;
    const real4 a = accum[i];
    const real4 vh = vel[i];
    const real4 wh = omega[i];
    const real3 vn = xyz_of(vh) + half_dt * vh.w * xyz_of(force[i]);
    const real3 wn = xyz_of(wh) + half_dt * wh.w * xyz_of(torque[i]);
    const real mass = R(1.0) / vh.w;
    v[0] = a.x;
    v[1] = a.y;
    v[2] = a.z;
    v[3] = a.w;
    const int id = info[i].x;
    if (!MC_IS_COMPONENT(sp, id)) {
      v[4] = R(0.5) * mass * dot(vn, vn);
      v[5] = R(0.5) * dot(wn, wn) / wh.w;
      v[6] = -mass * dot(xyz_of(sp->gravity), xyz_of(pos[i]));
      v[8] = mass * pos[i].x;
      v[9] = mass * pos[i].y;
    } else {
      /* A body is counted once, by its first component, at its centre. */
      const int b = body_of[id - sp->first_component];
      if (body_comp[b].x == id) {
        body_energy(b, sp, body_pos, body_vel, body_quat, body_angmom, body_inv_inertia, body_force,
                    body_torque, &v[4], &v[5]);
        const real4 c = body_pos[b];
        const real m = R(1.0) / c.w;
        v[6] = -m * dot(xyz_of(sp->gravity), xyz_of(c));
        v[8] = m * c.x;
        v[9] = m * c.y;
      }
    }
    v[7] = (real)(2 * neigh_count[i]); /* each listed pair, from both sides */
#if MC_ENERGY_BOOKS
    const int n = sp->n_balls;
    const int b = neigh_start[i];
    for (int k = b; k < b + neigh_count[i]; ++k) {
      const int r = neigh_rec[k];
      if (MC_LINK_TOUCHING(neigh_index[k]) && r >= 0) {
        const real4 lost = records[2 * r + 1];
        v[10] += lost.x; v[11] += lost.y; v[12] += lost.z;
      }
    }
    for (int s = 0; s < MC_MAX_WALL_CONTACTS; ++s) {
      const int r = wall_rec[s * n + i];
      if (wall_key[s * n + i] != MC_WALL_NONE && r >= 0) {
        const real4 lost = records[2 * r + 1];
        v[10] += lost.x; v[11] += lost.y; v[12] += lost.z;
      }
    }
#endif
    if (reset) accum[i] = make_real4(0, 0, 0, a.w);
  }
  for (int k = 0; k < MC_N_OBSERVABLES; ++k) tmp[k * MC_REDUCE_WG + lid] = v[k];
  barrier(CLK_LOCAL_MEM_FENCE);
  for (int stride = MC_REDUCE_WG / 2; stride > 0; stride >>= 1) {
    if (lid < stride)
      for (int k = 0; k < MC_N_OBSERVABLES; ++k)
        tmp[k * MC_REDUCE_WG + lid] += tmp[k * MC_REDUCE_WG + lid + stride];
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lid == 0)
    for (int k = 0; k < MC_N_OBSERVABLES; ++k)
      partial[get_group_id(0) * MC_N_OBSERVABLES + k] = tmp[k * MC_REDUCE_WG];
}

/* Contacts now, for reports: counts[0] ball-ball contacts (each pair counted
 * by both balls), counts[1] wall contacts, counts[2] neighbour-list entries
 * (each listed pair counted for both balls, as full lists would hold it). */
__kernel void count_contacts(__global const SimParams* sp,
                             __global const real4* pos,
                             __global const int* neigh_start,
                             __global const int* neigh_count,
                             __global const int* neigh_index,
                             __global const int* wall_key,
                             __global int* counts) {
  const int i = get_global_id(0);
  const int n = sp->n_balls;
  if (i >= n) return;
  const real4 pi = pos[i];
  int touching = 0;
  const int b = neigh_start[i];
  const int e = b + neigh_count[i];
  for (int k = b; k < e; ++k) {
    const real4 pj = pos[MC_LINK_PARTNER(neigh_index[k])];
    real3 d = xyz_of(pi) - xyz_of(pj);
    d.z = image_dz(sp, d.z);
    const real r = pi.w + pj.w;
    if (dot(d, d) < r * r) ++touching;
  }
  int walls = 0;
  for (int s = 0; s < MC_MAX_WALL_CONTACTS; ++s)
    if (wall_key[s * n + i] != MC_WALL_NONE) ++walls;
  /* Each pair is listed once; both its balls count it. */
  atomic_add(&counts[0], 2 * touching);
  atomic_add(&counts[1], walls);
  atomic_add(&counts[2], 2 * (e - b));
}
