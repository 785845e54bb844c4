/* profile.cl — where the charge touches the mill. Each ball that touches the
 * shell or a lifter now adds one count to the bin of its angle about the mill
 * axis in the lab frame, counter-clockwise from 3 o'clock (Morrell's
 * convention, DESIGN.md). Mesh walls count unless they are part of the ends:
 * a ball on a cone head or an end lifter is not on the belly. The host
 * samples this every few steps; the time-averaged histogram gives the toe
 * and the shoulder of the charge. */
#include "mc_shim.h"
#include "layout.h"

__kernel void profile_contacts(__global const SimParams* sp,
                               __global const real4* pos,
                               __global const int* wall_key, __global const int2* mesh_feature,
                               int n_bins, __global int* hist) {
  const int i = get_global_id(0);
  const int n = sp->n_balls;
  if (i >= n) return;
  int touching = 0;
  for (int s = 0; s < MC_MAX_WALL_CONTACTS; ++s) {
    const int key = wall_key[s * n + i];
    if (key == MC_WALL_SHELL || (key >= MC_WALL_LIFTER0 && key < MC_WALL_MESH0)) touching = 1;
    if (key >= MC_WALL_MESH0 && mesh_feature[key - MC_WALL_MESH0].y != MC_WALL_TYPE_PLATE) touching = 1;
  }
  if (!touching) return;
  const real4 p = pos[i];
  const real two_pi = R(6.283185307179586);
  real a = atan2(p.y, p.x);
  if (a < R(0.0)) a += two_pi;
  int b = (int)(a / two_pi * (real)n_bins);
  b = clamp(b, 0, n_bins - 1);
  atomic_inc(&hist[b]);
}
