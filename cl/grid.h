/* grid.h — the uniform grid of binning and neighbour search. Cells are at
 * least as wide as the largest contact distance (2·r_max + skin), so a ball's
 * neighbours lie in its own and the 26 adjacent cells. Coordinates outside
 * the grid are clamped to the edge cells: clamping moves two points at most
 * as far apart in cells as they were, so no pair is missed. On a periodic
 * axis (SimParams.period > 0, periodic.h) the z cells tile the period from
 * z = 0 and a z coordinate is taken modulo them instead: the neighbours of
 * the last cell are in the first. */
#ifndef MC_GRID_H
#define MC_GRID_H

MC_FN int grid_coord(real x, real origin, real cell, int n) {
  int c = (int)floor((x - origin) / cell);
  return c < 0 ? 0 : (c >= n ? n - 1 : c);
}

/* Cell c of a periodic axis of n cells, any integer c. */
MC_FN int grid_wrap(int c, int n) {
  const int m = c % n;
  return m < 0 ? m + n : m;
}

MC_FN int4 grid_cell_of(MC_GLOBAL const SimParams* sp, real3 p) {
  int4 c;
  c.x = grid_coord(p.x, sp->grid_origin.x, sp->grid_origin.w, sp->grid_nx);
  c.y = grid_coord(p.y, sp->grid_origin.y, sp->grid_origin.w, sp->grid_ny);
  c.z = sp->period > R(0.0)
            ? grid_wrap((int)floor((p.z - sp->grid_origin.z) / sp->grid_origin.w), sp->grid_nz)
            : grid_coord(p.z, sp->grid_origin.z, sp->grid_origin.w, sp->grid_nz);
  c.w = (c.z * sp->grid_ny + c.y) * sp->grid_nx + c.x;
  return c;
}

#endif /* MC_GRID_H */
