/* walls.h — geometry of the mill's walls in the mill frame (which turns about
 * +z): the inside of the shell cylinder, the two end plates, and lifter bars
 * as convex polygons extruded along z. Stateless, shared by kernels and the
 * CPU reference. */
#ifndef MC_WALLS_H
#define MC_WALLS_H

/* Signed distance from point p to a convex polygon (counter-clockwise
 * vertices), positive outside. `outward` receives the unit direction from the
 * polygon to p: from the closest boundary point when outside (face or corner,
 * the sphere-face / sphere-edge contacts of a prism), or the normal of the
 * least-penetrated face when p is inside. */
MC_FN real polygon_signed_distance(MC_GLOBAL const LifterPolygon* poly, real2 p,
                                   real2* outward) {
  const int nv = poly->n_vertices;
  real best_inside = -R(1e30);
  real2 best_inside_normal = make_real2(0, 0);
  real best_out2 = R(1e30);
  real2 best_out_point = p;
  int outside = 0;
  for (int k = 0; k < nv; ++k) {
    const real2 a = poly->vertices[k];
    const real2 b = poly->vertices[(k + 1) % nv];
    const real2 e = b - a;
    const real e_len = sqrt(dot(e, e));
    const real2 nrm = make_real2(e.y / e_len, -e.x / e_len); /* outward for CCW */
    const real2 ap = p - a;
    const real side = dot(ap, nrm);
    if (side > R(0.0)) outside = 1;
    if (side > best_inside) { best_inside = side; best_inside_normal = nrm; }
    real t = dot(ap, e) / (e_len * e_len);
    t = fmin(fmax(t, R(0.0)), R(1.0));
    const real2 q = a + t * e;
    const real2 pq = p - q;
    const real d2 = dot(pq, pq);
    if (d2 < best_out2) { best_out2 = d2; best_out_point = q; }
  }
  if (!outside) {
    *outward = best_inside_normal;
    return best_inside;
  }
  const real dist = sqrt(best_out2);
  const real2 dir = p - best_out_point;
  *outward = (dist > R(0.0)) ? make_real2(dir.x / dist, dir.y / dist) : best_inside_normal;
  return dist;
}

/* Overlap of a ball (centre p, radius r, mill frame) with the shell's inside
 * surface; `normal` points from the shell to the ball (towards the axis). */
MC_FN real shell_overlap(real3 p, real r, real shell_radius, real3* normal) {
  const real rho = sqrt(p.x * p.x + p.y * p.y);
  const real inv = (rho > R(0.0)) ? R(1.0) / rho : R(0.0);
  *normal = make_real3(-p.x * inv, -p.y * inv, R(0.0));
  return rho + r - shell_radius;
}

/* The nearest point to (u, v) of the segment from (a0, b0) to (a1, b1), in
 * a plate's (rho, height) plane: kept in *best (squared distance) and *cu,
 * *cv where it is nearer than what *best holds. */
MC_FN void plate_piece(real u, real v, real a0, real b0, real a1, real b1, real* best, real* cu, real* cv) {
  const real du = a1 - a0, dv = b1 - b0;
  const real len2 = du * du + dv * dv;
  real t = len2 > R(0.0) ? ((u - a0) * du + (v - b0) * dv) / len2 : R(0.0);
  t = fmin(fmax(t, R(0.0)), R(1.0));
  const real qu = a0 + t * du, qv = b0 + t * dv;
  const real d2 = (u - qu) * (u - qu) + (v - qv) * (v - qv);
  if (d2 < *best) {
    *best = d2;
    *cu = qu;
    *cv = qv;
  }
}

/* The worn face's depth at rho (plate_overlap's dish; src/core/plate_wear.h
 * plate_surface_depth): `first` its first depth, n rings of width w. */
MC_FN real plate_depth_at(MC_GLOBAL const SimParams* sp, int first, int n, real w, real rho) {
  int j = (int)floor(rho / w);
  j = j < 0 ? 0 : j > n - 1 ? n - 1 : j;
  const real f = rho / w - (real)j;
  const real d = sp->plate_depth[first + j];
  if (f < R(0.25) && j > 0) return sp->plate_depth[first + j - 1] + (f + R(0.25)) * R(2.0) * (d - sp->plate_depth[first + j - 1]);
  if (f > R(0.75) && j < n - 1) return d + (f - R(0.75)) * R(2.0) * (sp->plate_depth[first + j + 1] - d);
  return d;
}

/* Overlap of a ball (centre p, radius r, mill frame) with end plate
 * `plate` (0 at z = 0, 1 at z = length), flat or worn; `normal` points from
 * the plate to the ball. A worn plate (src/core/plate_wear.h) is a dish,
 * the same all round: in the plane of rho (from the axis) and the height
 * above the plate's plane towards the charge, its face is flat at each
 * ring's depth across the ring's middle half and straight from one ring's
 * depth to the next over the quarter-rings either side of their edge. The
 * contact is with the face's nearest point: the pieces within a ball's
 * radius of the centre are searched, so that the overlap runs on without a
 * jump across the corners between pieces. */
MC_FN real plate_overlap(MC_GLOBAL const SimParams* sp, int plate, real3 p, real r, real3* normal) {
  const real sign = plate == 0 ? R(1.0) : R(-1.0);
  const real gap = plate == 0 ? p.z : sp->length - p.z; /* above the plate's plane */
  const int n = sp->plate_nodes;
  /* Every point of a worn face lies at or behind the plate's plane: a ball
   * clear of the plane is clear of the face. */
  if (n <= 0 || gap >= r) {
    *normal = make_real3(0, 0, sign);
    return r - gap;
  }
  const real rho = sqrt(p.x * p.x + p.y * p.y);
  const real w = sp->shell_radius / (real)n, q = R(0.25) * w;
  const int first = plate * MC_PLATE_NODES;
  int j0 = (int)floor((rho - r) / w), j1 = (int)floor((rho + r) / w);
  j0 = j0 < 0 ? 0 : j0 > n - 1 ? n - 1 : j0;
  j1 = j1 < 0 ? 0 : j1 > n - 1 ? n - 1 : j1;
  real best = R(1e30), cu = rho, cv = R(0.0);
  for (int j = j0; j <= j1; ++j) {
    const real d = sp->plate_depth[first + j];
    const real a = j == 0 ? -w : (real)j * w + q;                    /* the flat middle, from */
    const real b = j == n - 1 ? (real)(n + 1) * w : (real)(j + 1) * w - q; /* and to */
    plate_piece(rho, gap, a, -d, b, -d, &best, &cu, &cv);
    if (j + 1 < n) plate_piece(rho, gap, b, -d, b + R(2.0) * q, -sp->plate_depth[first + j + 1], &best, &cu, &cv);
    if (j > 0) plate_piece(rho, gap, a - R(2.0) * q, -sp->plate_depth[first + j - 1], a, -d, &best, &cu, &cv);
  }
  real dist = sqrt(best);
  real nu = dist > R(0.0) ? (rho - cu) / dist : R(0.0), nv = dist > R(0.0) ? (gap - cv) / dist : R(1.0);
  /* A centre behind the face (deeper than the plate there): its overlap
   * runs on past the radius, the normal into the charge. */
  if (gap < -plate_depth_at(sp, first, n, w, rho)) {
    dist = -dist;
    nu = -nu;
    nv = -nv;
  }
  const real inv_rho = rho > R(0.0) ? R(1.0) / rho : R(0.0);
  *normal = make_real3(nu * p.x * inv_rho, nu * p.y * inv_rho, sign * nv);
  return r - dist;
}

/* Rotation about +z by angle (c = cos, s = sin). */
MC_FN real3 rotate_z(real3 v, real c, real s) {
  return make_real3(c * v.x - s * v.y, s * v.x + c * v.y, v.z);
}

/* atan2(y, x) within 1e-5 rad, without the library call: it only picks the
 * nearest lifter row, whose neighbours are tested too. Octant reduction and
 * a degree-11 odd polynomial for atan on [0, 1]. */
MC_FN real atan2_fast(real y, real x) {
  const real ax = fabs(x), ay = fabs(y);
  const real hi = fmax(ax, ay), lo = fmin(ax, ay);
  const real t = hi > R(0.0) ? lo / hi : R(0.0);
  const real t2 = t * t;
  real a = ((((R(-0.0117212) * t2 + R(0.05265332)) * t2 - R(0.11643287)) * t2 + R(0.19354346)) * t2 -
            R(0.33262347)) * t2 + R(0.99997726);
  a *= t;
  a = ay > ax ? R(1.5707963267948966) - a : a;
  a = x < R(0.0) ? R(3.141592653589793) - a : a;
  return y < R(0.0) ? -a : a;
}

/* Index of the lifter row whose centre angle is nearest to `angle` (rad,
 * mill frame), for rows spaced evenly starting at `first`. */
MC_FN int nearest_lifter(real angle, real first, real spacing, int n_lifters) {
  const real two_pi = R(6.283185307179586);
  real a = angle - first;
  a = a - two_pi * floor(a / two_pi);
  int k = (int)floor(a / spacing + R(0.5));
  if (k >= n_lifters) k -= n_lifters;
  return k;
}

#endif /* MC_WALLS_H */
