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

/* A worn end plate (plate 0 at z = 0, 1 at z = length) at distance rho
 * from the axis: how far its surface lies behind the plate's plane, m, and
 * the slope of that depth along rho. Linear between the depths at the
 * rings' centres, flat inside the first and outside the last
 * (src/core/plate_wear.h plate_surface_depth); 0 for flat plates. */
MC_FN real plate_depth(MC_GLOBAL const SimParams* sp, int plate, real rho, real* slope) {
  *slope = R(0.0);
  const int n = sp->plate_nodes;
  if (n <= 0) return R(0.0);
  const int first = plate * MC_PLATE_NODES;
  const real u = rho * (real)n / sp->shell_radius - R(0.5);
  if (u <= R(0.0)) return sp->plate_depth[first];
  if (u >= (real)(n - 1)) return sp->plate_depth[first + n - 1];
  const int j = (int)floor(u);
  const real d0 = sp->plate_depth[first + j], d1 = sp->plate_depth[first + j + 1];
  *slope = (d1 - d0) * (real)n / sp->shell_radius;
  return d0 + (u - (real)j) * (d1 - d0);
}

/* Overlap of a ball (centre p, radius r, mill frame) with end plate
 * `plate`, worn or flat; `normal` points from the plate to the ball. A worn
 * plate's surface is taken as its tangent plane below the ball: the depths
 * change over a ring's width, many balls across. */
MC_FN real plate_overlap(MC_GLOBAL const SimParams* sp, int plate, real3 p, real r, real3* normal) {
  const real sign = plate == 0 ? R(1.0) : R(-1.0);
  const real gap = plate == 0 ? p.z : sp->length - p.z; /* to the plate's plane */
  if (sp->plate_nodes <= 0) {
    *normal = make_real3(0, 0, sign);
    return r - gap;
  }
  const real rho = sqrt(p.x * p.x + p.y * p.y);
  real slope;
  const real depth = plate_depth(sp, plate, rho, &slope);
  const real inv_len = R(1.0) / sqrt(R(1.0) + slope * slope);
  const real inv_rho = rho > R(0.0) ? R(1.0) / rho : R(0.0);
  *normal = make_real3(slope * p.x * inv_rho * inv_len, slope * p.y * inv_rho * inv_len, sign * inv_len);
  return r - (gap + depth) * inv_len;
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
