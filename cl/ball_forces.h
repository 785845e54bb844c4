/* ball_forces.h — all forces and torques on one ball: its listed neighbours,
 * the shell, the end plates and the lifters, plus gravity. The forces kernel
 * runs it for every ball; the CPU reference (src/sim/reference.cpp) loops
 * over it, so a test of the reference tests the kernel's arithmetic.
 *
 * Each pair is listed once, by the ball with the lower index (half lists),
 * and its force is evaluated once. The ball adds its own side; the partner's
 * side (−F, its torque, half the dissipation) goes into the partner's
 * incoming slot of pair_out (neigh_rev[k] says which; MC_SLOT_REALS), and
 * ball_reactions adds a ball's incoming slots, which lie side by side, after
 * every ball is done. In a periodic slice a pair is seen through the
 * partner's nearest image along z (periodic.h), so a pair across the seam
 * is evaluated, and keeps its spring, as any other. Each ball sums in a fixed order, so there are no
 * atomics and the result does not depend on thread order. A pair's stored
 * energy is booked to the ball that lists it (only its total is reported).
 * Walls have infinite mass and turn with the mill: their velocity at the
 * contact point is ω ẑ × r.
 *
 * Each touching contact keeps a record (layout.h, books.h): its spring and
 * what it has lost since it began; a list entry or wall slot that touches
 * holds its record's index. When a contact opens, its record joins the
 * collision spectra; wall contacts also book each step on the liner
 * element under them. */
#ifndef MC_BALL_FORCES_H
#define MC_BALL_FORCES_H

typedef struct {
  real cos_angle, sin_angle; /* of the mill angle: mill frame = world
                                rotated by it about +z */
  real omega;                /* rad/s */
} MillState;

/* Whether two balls touch: the overlap r_i + r_j − |p_i − p_j| that
 * pair_geometry computes is positive. The squared distance alone can say
 * "touching" for an overlap that rounds to below zero, whose Hertz root is
 * a NaN; so the overlap itself decides. */
MC_FN int pair_touches(v3 p_i, real r_i, v3 p_j, real r_j) {
  const v3 dx = v3_sub(p_i, p_j);
  const real d2 = v3_dot(dx, dx);
  const real reach = r_i + r_j;
  /* Most listed pairs are apart: the square decides those without a root. */
  return d2 < reach * reach && d2 > R(0.0) && reach - sqrt(d2) > R(0.0);
}

/* The geometry of a ball–ball contact seen from ball i: normal from j to i,
 * overlap, contact-point velocities, effective mass and radius. Positions,
 * velocities and spins are xyz; inv_m and inv_I are the balls' 1/m, 1/I. */
MC_FN ContactGeom pair_geometry(v3 p_i, real r_i, v3 v_i, v3 w_i, real inv_m_i, real inv_I_i,
                                v3 p_j, real r_j, v3 v_j, v3 w_j, real inv_m_j, real inv_I_j) {
  const v3 dx = v3_sub(p_i, p_j);
  const real dist = sqrt(v3_dot(dx, dx));
  const real overlap = (r_i + r_j) - dist;
  const v3 nrm = v3_scale(R(1.0) / dist, dx);
  const real arm_i = r_i - R(0.5) * overlap;
  const real arm_j = r_j - R(0.5) * overlap;
  ContactGeom g;
  g.normal = nrm;
  g.overlap = overlap;
  g.v_rel = v3_sub(v3_add(v_i, v3_cross(w_i, v3_scale(-arm_i, nrm))),
                   v3_add(v_j, v3_cross(w_j, v3_scale(arm_j, nrm))));
  g.w_rel = v3_sub(w_i, w_j);
  g.arm = arm_i;
  g.m_eff = R(1.0) / (inv_m_i + inv_m_j);
  g.r_eff = r_i * r_j / (r_i + r_j);
  g.inv_inertia_sum = inv_I_i + inv_I_j;
  return g;
}

/* The wall slots of one ball while its walls are done: the old ones (key,
 * record, whether a contact renewed it) and the new ones. */
typedef struct {
  int old_key[MC_MAX_WALL_CONTACTS];
  int old_rec[MC_MAX_WALL_CONTACTS];
  int renewed[MC_MAX_WALL_CONTACTS];
  int new_key[MC_MAX_WALL_CONTACTS];
  int new_rec[MC_MAX_WALL_CONTACTS];
  int n_new;
  int overflow;
} WallSlots;

/* What a ball gathers in a step: force and torque on it, the torque of its
 * wall contacts about the mill axis, the energy lost and the energy stored. */
typedef struct {
  real3 f, t;
  real torque_axis, dissipated, elastic;
} BallSums;

/* Which wall a contact touches, as wall_contact books it. */
typedef struct {
  int key;      /* the slot's key from this step on */
  int match;    /* the old slot it continues: the same key, or a mesh
                   contact of the same smooth patch that it follows */
  int element;  /* its liner element; < 0: from the geometry (liner_element) */
  int type;     /* MC_WALL_TYPE_*, for the impact profile */
  int turning;  /* 1: the wall turns with the mill; 0: it stands still
                   (no velocity, no torque on the mill) */
  real wear_k;  /* Archard's coefficient of its material, m³/(N·m) */
  real strike_k; /* its material's strike threshold speed, m/s */
} WallRef;

/* The reference of a shell, end-plate or lifter contact. */
MC_FN WallRef analytic_wall(int key, Books* books) {
  WallRef w;
  w.key = w.match = key;
  w.element = -1;
  w.type = key == MC_WALL_SHELL ? MC_WALL_TYPE_SHELL : key >= MC_WALL_LIFTER0 ? MC_WALL_TYPE_LIFTER : MC_WALL_TYPE_PLATE;
  w.turning = 1;
  w.wear_k = books->bp->wear_k;
  w.strike_k = books->bp->strike_speed;
  return w;
}

/* One wall contact: its record (the slot's with the key it continues, or a
 * new one), the law, force, torque and observables into the ball's sums,
 * the books. */
MC_FN void wall_contact(WallRef wr, real3 n, real overlap, real3 p, real4 vel, real4 om, real radius, PairParams pp,
                        MillState mill, MC_GLOBAL const SimParams* sp,
                        MC_GLOBAL const LifterPolygon* lifters, int law, WallSlots* ws, Books* books,
                        BallSums* sums) {
  int rec = MC_NO_RECORD;
  int matched = 0; /* the contact was there the step before (with or without a record) */
  for (int s = 0; s < MC_MAX_WALL_CONTACTS; ++s)
    if (ws->old_key[s] == wr.match && !ws->renewed[s]) {
      rec = ws->old_rec[s];
      ws->renewed[s] = 1;
      matched = 1;
      break;
    }
  /* A new contact takes a record (so does one that found the pool full, at
   * the next try). */
  const int fresh = rec < 0;
  const real dt = sp->dt;
  const real arm = radius - overlap;
  const real3 rc = p - arm * n; /* contact point, world frame */
  const real omega = wr.turning ? mill.omega : R(0.0);
  const real3 w_mill = make_real3(0, 0, omega);
  const real3 v_wall = cross(w_mill, rc);
  const real3 w_ball = xyz_of(om);
  ContactGeom g;
  g.normal = v3_of(n);
  g.overlap = overlap;
  g.v_rel = v3_of(xyz_of(vel) + cross(w_ball, -arm * n) - v_wall);
  g.w_rel = v3_of(w_ball - w_mill);
  g.arm = arm;
  g.m_eff = R(1.0) / vel.w;
  g.r_eff = radius;
  g.inv_inertia_sum = om.w;
  const ContactOut c = contact_force(pp, g, record_spring(books, rec), dt, law);
  if (fresh) rec = record_take(books);
  sums->f += real3_of(c.force);
  sums->t += real3_of(c.torque);
  /* Torque of the wall on the ball about the mill axis: r_c × F plus the
   * rolling couple (a wall standing still drives nothing). */
  if (wr.turning) sums->torque_axis += rc.x * c.force.y - rc.y * c.force.x + c.rolling.z;
  sums->dissipated += c.dissipated;
  sums->elastic += c.elastic;
  record_step(books, rec, fresh, v3_dot(g.v_rel, g.normal), c);
#if MC_ENERGY_BOOKS
  int element = wr.element;
  const real3 rm = rotate_z(rc, mill.cos_angle, -mill.sin_angle); /* the contact point in the mill frame */
  const int on_bar = wr.element < 0 && wr.key >= MC_WALL_LIFTER0 && wr.key < MC_WALL_MESH0;
  const real along = on_bar ? lifter_path_place(&lifters[wr.key - MC_WALL_LIFTER0], make_real2(rm.x, rm.y)) : R(0.0);
  if (element < 0) element = liner_element(books->bp, sp, lifters, wr.key, rm, along);
  /* The strike energy at first touch (Bitter's deformation wear): the
   * ball's mass and its approach speed above the material's threshold;
   * once a contact, also one that found the record pool full. */
  const real over = fmax(-v3_dot(g.v_rel, g.normal), R(0.0)) - wr.strike_k;
  const real strike = !matched && over > R(0.0) ? R(0.5) * g.m_eff * over * over : R(0.0);
  liner_step(books, element, fresh, c, wr.wear_k, strike, wr.type != MC_WALL_TYPE_PLATE, atan2_fast(rc.y, rc.x),
             axial_bin_of(books->bp, sp, rm.z));
  if (on_bar) { /* where on the bar: its wear station */
    const int k = wr.key - MC_WALL_LIFTER0;
    liner_step(books, lifter_station(books->bp, &lifters[k], k, along), fresh, c, wr.wear_k, strike, 0, R(0.0), -1);
  }
#endif
  if (ws->n_new < MC_MAX_WALL_CONTACTS) {
    ws->new_key[ws->n_new] = wr.key;
    ws->new_rec[ws->n_new] = rec;
    ws->n_new += 1;
  } else {
    ws->overflow = 1;
  }
}

/* The mesh walls on a ball at p (lab frame): each set's candidates in the
 * ball's cell, Hu et al.'s rule (mesh.h), and each contact through
 * wall_contact, keyed by its feature and continuing the slot of the same
 * feature or, failing that, of its smooth patch. */
MC_FN void mesh_walls(const Meshes* m, real3 p, real4 vi, real4 wi, real ri, int mat_i, MillState mill,
                      MC_GLOBAL const SimParams* sp, MC_GLOBAL const LifterPolygon* lifters, int law, WallSlots* ws,
                      Books* books, BallSums* sums) {
  for (int set = 0; set < MC_MESH_SETS; ++set) {
    const int turning = set == 0;
    const real c = mill.cos_angle, s = mill.sin_angle;
    const real3 q = turning ? rotate_z(p, c, -s) : p;
    MeshHit hits[MC_MESH_HITS];
    const int nh = mesh_candidates(m, set, q, ri, hits, &ws->overflow);
    if (nh == 0) continue;
    int keep[MC_MESH_HITS];
    mesh_keep(m, hits, nh, keep);
    /* Which old slot each contact continues: first every contact whose
     * feature had a slot, then the others take a slot of their smooth
     * patch that no contact continues (a contact that slid onto the next
     * triangle), so that two contacts of one patch never share a record. */
    int match[MC_MESH_HITS];
    int claimed[MC_MAX_WALL_CONTACTS];
    for (int k = 0; k < MC_MAX_WALL_CONTACTS; ++k) claimed[k] = ws->renewed[k];
    for (int h = 0; h < nh; ++h) {
      match[h] = -1;
      if (!keep[h]) continue;
      for (int k = 0; k < MC_MAX_WALL_CONTACTS; ++k)
        if (!claimed[k] && ws->old_key[k] == MC_WALL_MESH0 + hits[h].feature) {
          claimed[k] = 1;
          match[h] = ws->old_key[k];
          break;
        }
    }
    for (int h = 0; h < nh; ++h) {
      if (!keep[h] || match[h] >= 0) continue;
      const int patch = m->feature[hits[h].feature].x;
      for (int k = 0; k < MC_MAX_WALL_CONTACTS; ++k) {
        const int ok = ws->old_key[k];
        if (!claimed[k] && ok >= MC_WALL_MESH0 && m->feature[ok - MC_WALL_MESH0].x == patch) {
          claimed[k] = 1;
          match[h] = ok;
          break;
        }
      }
    }
    for (int h = 0; h < nh; ++h) {
      if (!keep[h]) continue;
      MC_GLOBAL const MeshTriangle* tr = m->tris + hits[h].tri;
      WallRef wr;
      wr.key = MC_WALL_MESH0 + hits[h].feature;
      const int2 fi = m->feature[hits[h].feature];
      wr.match = match[h] >= 0 ? match[h] : wr.key;
      wr.element = tr->element;
      wr.type = fi.y;
      wr.turning = turning;
      wr.wear_k = tr->a.w;
      wr.strike_k = tr->b.w;
      const real3 nrm = turning ? rotate_z(hits[h].normal, c, s) : hits[h].normal;
      const PairParams pp = m->pairs[tr->pair_row + mat_i];
      wall_contact(wr, nrm, ri - hits[h].dist, p, vi, wi, ri, pp, mill, sp, lifters, law, ws,
                   books, sums);
    }
  }
}

/* The partner's side of a touching pair that ball i lists, into the
 * partner's incoming slot (MC_SLOT_REALS reals): −F, half the energy lost,
 * and its torque. j sees −n, −F and −M_roll with its own lever arm, so its
 * tangential torque is −arm_j·(−n) × (−F) = −arm_j·n × F (n × F = n × F_t). */
MC_FN void store_partner_side(MC_GLOBAL real* slot, ContactGeom g, ContactOut c, real r_j) {
  const real arm_j = r_j - R(0.5) * g.overlap;
  const v3 t_j = v3_sub(v3_scale(-arm_j, v3_cross(g.normal, c.force)), c.rolling);
  slot[0] = -c.force.x;
  slot[1] = -c.force.y;
  slot[2] = -c.force.z;
  slot[3] = R(0.5) * c.dissipated;
  slot[4] = t_j.x;
  slot[5] = t_j.y;
  slot[6] = t_j.z;
}

/* A pair that opened: its collision joins the spectra, the entry holds no
 * record (an index left behind would differ from run to run, as records
 * are taken in whatever order the threads come), and its reaction is gone. */
MC_FN void pair_opened(int k, int j, int mat_i, real m_eff, real r_eff, MC_GLOBAL const SimParams* sp,
                       MC_GLOBAL const int2* info, MC_GLOBAL int* neigh_index, MC_GLOBAL int* neigh_rec,
                       MC_GLOBAL const int* neigh_rev, MC_GLOBAL real* pair_out, Books* books) {
  record_close(books, neigh_rec[k], ball_pair_type(mat_i, info[j].y, sp->n_materials), m_eff, r_eff);
  neigh_index[k] = j;
  neigh_rec[k] = MC_NO_RECORD;
  MC_GLOBAL real* slot = pair_out + MC_SLOT_REALS * neigh_rev[k];
  for (int r = 0; r < MC_SLOT_REALS; ++r) slot[r] = R(0.0);
}

/* List entry k of a ball at p with radius r, inverse mass inv_m and
 * material mat: whether the pair touches now. A pair that touched and no
 * longer does is opened here (pair_opened). The entry's link and the partner's position (its nearest
 * image in a periodic slice, periodic.h) are left in *link and *pj4 for
 * pair_contact. */
MC_FN int entry_touches(int k, v3 p, real r, real inv_m, int mat, MC_GLOBAL const SimParams* sp,
                        MC_GLOBAL const real4* pos, MC_GLOBAL const real4* vel, MC_GLOBAL const int2* info,
                        MC_GLOBAL int* neigh_index, MC_GLOBAL int* neigh_rec, MC_GLOBAL const int* neigh_rev,
                        MC_GLOBAL real* pair_out, Books* books, int* link, real4* pj4) {
  *link = neigh_index[k];
  const int j = MC_LINK_PARTNER(*link);
  *pj4 = image_of(sp, pos[j], p.z); /* across the seam of a slice, its nearest image */
  if (pair_touches(p, r, v3_of(xyz_of(*pj4)), (*pj4).w)) return 1;
  if (MC_LINK_TOUCHING(*link)) {
    const real rj = (*pj4).w; /* m* and R* as pair_geometry has them */
    pair_opened(k, j, mat, R(1.0) / (inv_m + vel[j].w), r * rj / (r + rj), sp, info, neigh_index, neigh_rec,
                neigh_rev, pair_out, books);
  }
  return 0;
}

/* One touching pair, list entry k of ball i (its position, velocity, spin,
 * material; link: the entry as it was; pj4: the partner's position, its
 * nearest image in a periodic slice):
 * the law, ball i's side into its sums, the partner's into its slot, the
 * spring and the losses into the pair's record (a new one for a pair that
 * begins to touch), the touching flag into the entry. */
MC_FN void pair_contact(real4 pi4, real4 vi, real4 wi, int mat_i, int k, int link, real4 pj4,
                        MC_GLOBAL const SimParams* sp, MC_GLOBAL const PairParams* pairs,
                        MC_GLOBAL const real4* vel, MC_GLOBAL const real4* omega,
                        MC_GLOBAL const int2* info, MC_GLOBAL int* neigh_index,
                        MC_GLOBAL int* neigh_rec, MC_GLOBAL const int* neigh_rev,
                        MC_GLOBAL real* pair_out, Books* books, int law, BallSums* s) {
  const int j = MC_LINK_PARTNER(link);
  const real4 vj = vel[j], wj = omega[j];
  const ContactGeom g = pair_geometry(v3_of(xyz_of(pi4)), pi4.w, v3_of(xyz_of(vi)), v3_of(xyz_of(wi)), vi.w, wi.w,
                                      v3_of(xyz_of(pj4)), pj4.w, v3_of(xyz_of(vj)), v3_of(xyz_of(wj)), vj.w, wj.w);
  const PairParams pp = pairs[MC_PAIR_INDEX(sp, mat_i, info[j].y)];
  /* A new contact takes a record and starts with no spring (so does one
   * that found the pool full, at the next try). */
  const int old_rec = MC_LINK_TOUCHING(link) ? neigh_rec[k] : MC_NO_RECORD;
  const int fresh = old_rec < 0;
  const ContactOut c = contact_force(pp, g, record_spring(books, old_rec), sp->dt, law);
  const int rec = fresh ? record_take(books) : old_rec;
  s->f += real3_of(c.force);
  s->t += real3_of(c.torque);
  s->dissipated += R(0.5) * c.dissipated;
  s->elastic += c.elastic;
  store_partner_side(pair_out + MC_SLOT_REALS * neigh_rev[k], g, c, pj4.w);
  record_step(books, rec, fresh, v3_dot(g.v_rel, g.normal), c);
  if (fresh) {
    neigh_index[k] = MC_LINK_TOUCHED(j);
    neigh_rec[k] = rec;
  }
}

MC_FN BallSums ball_sums_zero(void) {
  BallSums s;
  s.f = s.t = make_real3(0, 0, 0);
  s.torque_axis = s.dissipated = s.elastic = R(0.0);
  return s;
}

/* Gravity: where a ball's sums start. A body's component starts from
 * zero: its body takes gravity once (cl/body.h). */
MC_FN BallSums ball_sums_start(MC_GLOBAL const SimParams* sp, real4 vi, int id) {
  BallSums s = ball_sums_zero();
  if (!MC_IS_COMPONENT(sp, id)) s.f = (R(1.0) / vi.w) * xyz_of(sp->gravity);
  return s;
}

/* The shell, the end plates and the lifters on ball i, in the mill frame.
 * A wall slot that no contact renews was a collision that ended. */
MC_FN void ball_walls(int i, real4 pi4, real4 vi, real4 wi, int mat_i, MC_GLOBAL const SimParams* sp,
                      MC_GLOBAL const PairParams* pairs, MC_GLOBAL const LifterPolygon* lifters, const Meshes* meshes,
                      MillState mill, MC_GLOBAL int* wall_key, MC_GLOBAL int* wall_rec, Books* books, int law,
                      BallSums* sums) {
  const int n = sp->n_balls;
  const real3 p = xyz_of(pi4);
  const real ri = pi4.w;
  /* Most balls touch no wall and touched none last step; they skip the wall
   * code. Slots fill from the first, so an empty first slot means no wall
   * history. The tests below are margins around the exact ones inside (a
   * ball that passes them still has to overlap). */
  const int nl = sp->n_lifters;
  const real rho2 = p.x * p.x + p.y * p.y;
  const real margin = R(1e-4) * ri;
  const real r_clear = sp->shell_radius - ri - margin;
  const int any_old = wall_key[i] != MC_WALL_NONE;
  const int near_shell = sp->shell_radius > R(0.0) && (r_clear <= R(0.0) || rho2 > r_clear * r_clear);
  const int near_wall =
      any_old || near_shell ||
      /* (a worn plate's face lies behind its plane: the same test holds) */
      (sp->length > R(0.0) && (p.z < ri + margin || p.z > sp->length - ri - margin)) ||
      (nl > 0 && rho2 > sp->lifter_reach * sp->lifter_reach) || mesh_near(meshes, rho2, p.z);
  if (!near_wall) return;
  WallSlots ws;
  for (int s = 0; s < MC_MAX_WALL_CONTACTS; ++s) {
    ws.old_key[s] = any_old ? wall_key[s * n + i] : MC_WALL_NONE;
    ws.old_rec[s] = ws.old_key[s] != MC_WALL_NONE ? wall_rec[s * n + i] : MC_NO_RECORD;
    ws.renewed[s] = 0;
    ws.new_key[s] = MC_WALL_NONE;
    ws.new_rec[s] = MC_NO_RECORD;
  }
  ws.n_new = 0;
  ws.overflow = 0;
  const PairParams pw = pairs[MC_PAIR_INDEX(sp, mat_i, sp->n_materials)];

  if (near_shell) { /* the root only for a ball that may reach the shell */
    real3 nrm;
    const real ov = shell_overlap(p, ri, sp->shell_radius, &nrm);
    if (ov > R(0.0))
      wall_contact(analytic_wall(MC_WALL_SHELL, books), nrm, ov, p, vi, wi, ri, pw, mill, sp, lifters, law, &ws, books,
                   sums);
  }
  if (sp->length > R(0.0)) {
    /* A worn plate's dish is axisymmetric: the same in the lab frame. */
    real3 n_low, n_high;
    const real ov_low = plate_overlap(sp, 0, p, ri, &n_low);
    if (ov_low > R(0.0))
      wall_contact(analytic_wall(MC_WALL_PLATE_LOW, books), n_low, ov_low, p, vi, wi, ri, pw, mill, sp, lifters, law,
                   &ws, books, sums);
    const real ov_high = plate_overlap(sp, 1, p, ri, &n_high);
    if (ov_high > R(0.0))
      wall_contact(analytic_wall(MC_WALL_PLATE_HIGH, books), n_high, ov_high, p, vi, wi, ri, pw, mill, sp, lifters,
                   law, &ws, books, sums);
  }
  if (nl > 0 && rho2 > sp->lifter_reach * sp->lifter_reach) {
    const real c = mill.cos_angle, s = mill.sin_angle;
    const real3 pm = rotate_z(p, c, -s); /* into the mill frame */
    const int k0 = nearest_lifter(atan2_fast(pm.y, pm.x), sp->lifter_first_angle,
                                  sp->lifter_spacing, nl);
    const int k_lo = (nl >= 3) ? -1 : 0;
    const int k_hi = (nl >= 3) ? 1 : nl - 1;
    for (int dk = k_lo; dk <= k_hi; ++dk) {
      const int k = (nl >= 3) ? (k0 + dk + nl) % nl : dk;
      /* Most balls near the shell are clear of the bar's bounding circle. */
      const real4 bd = lifters[k].bound;
      const real bx = pm.x - bd.x, by = pm.y - bd.y, br = bd.z + ri;
      if (bx * bx + by * by >= br * br) continue;
      real2 out2;
      const real dist =
          polygon_signed_distance(&lifters[k], make_real2(pm.x, pm.y), &out2);
      const real ov = ri - dist;
      if (ov > R(0.0)) {
        const real3 nrm = rotate_z(make_real3(out2.x, out2.y, 0), c, s);
        wall_contact(analytic_wall(MC_WALL_LIFTER0 + k, books), nrm, ov, p, vi, wi, ri, pw, mill, sp, lifters, law, &ws,
                     books, sums);
      }
    }
  }
  mesh_walls(meshes, p, vi, wi, ri, mat_i, mill, sp, lifters, law, &ws, books, sums);
  /* Collisions that ended; a ball that touched no wall and touches none
   * keeps its empty slots. */
  if (any_old)
    for (int s = 0; s < MC_MAX_WALL_CONTACTS; ++s)
      if (ws.old_key[s] != MC_WALL_NONE && !ws.renewed[s])
        record_close(books, ws.old_rec[s],
                     wall_type_pair(mat_i, wall_type_of(meshes, ws.old_key[s]), sp->n_materials),
                     R(1.0) / vi.w, pi4.w);
  if (any_old || ws.n_new > 0)
    for (int s = 0; s < MC_MAX_WALL_CONTACTS; ++s) {
      wall_key[s * n + i] = ws.new_key[s];
      wall_rec[s * n + i] = ws.new_rec[s];
    }
  if (ws.overflow) MC_ATOMIC_OR(books->status, MC_FLAG_WALL_OVERFLOW);
}

/* A ball's sums into its force, torque and accumulators. */
MC_FN void ball_store(int i, BallSums s, MillState mill, real dt, MC_GLOBAL real4* force,
                      MC_GLOBAL real4* torque, MC_GLOBAL real4* accum) {
  force[i] = make_real4(s.f.x, s.f.y, s.f.z, R(0.0));
  torque[i] = make_real4(s.t.x, s.t.y, s.t.z, R(0.0));
  const real4 a = accum[i];
  accum[i] = make_real4(a.x + s.torque_axis * dt,
                        a.y + s.torque_axis * mill.omega * dt,
                        a.z + s.dissipated, s.elastic);
}

/* The law the kernels are built for (MC_LAW), or the scene's. */
#ifdef MC_LAW
#define MC_RUN_LAW(sp) (MC_LAW)
#else
#define MC_RUN_LAW(sp) ((sp)->law)
#endif

MC_FN void ball_forces(
    int i, MC_GLOBAL const SimParams* sp, MC_GLOBAL const PairParams* pairs,
    MC_GLOBAL const LifterPolygon* lifters, MillState mill,
    MC_GLOBAL const real4* pos, MC_GLOBAL const real4* vel,
    MC_GLOBAL const real4* omega, MC_GLOBAL const int2* info,
    MC_GLOBAL const int* neigh_start, MC_GLOBAL const int* neigh_count,
    MC_GLOBAL int* neigh_index, MC_GLOBAL int* neigh_rec,
    MC_GLOBAL const int* neigh_rev, MC_GLOBAL real* pair_out,
    MC_GLOBAL int* wall_key, MC_GLOBAL int* wall_rec,
    MC_GLOBAL real4* force, MC_GLOBAL real4* torque, MC_GLOBAL real4* accum,
    Books* books, const Meshes* meshes) {
  const int law = MC_RUN_LAW(sp);
  const real4 pi4 = pos[i];
  const real4 vi = vel[i];
  const real4 wi = omega[i];
  const int2 info_i = info[i];
  const int mat_i = info_i.y;
  const v3 p = v3_of(xyz_of(pi4));
  BallSums s = ball_sums_start(sp, vi, info_i.x);

  /* ---- ball–ball ---- */
  /* The list holds the partners j > i. An entry's link says whether the
   * pair touched at the last evaluation (MC_LINK_*): only then does it hold
   * a record. So an apart pair, most of the list, costs its partner's
   * position and nothing else, and the link changes only when a contact
   * opens or closes. A touching pair leaves the
   * partner's side in its slot neigh_rev[k] (MC_SLOT_REALS); a pair that
   * opens clears it, so the slots of apart pairs are zero. */
  const int start = neigh_start[i];
  const int count = neigh_count[i];
  for (int k = start; k < start + count; ++k) {
    int link;
    real4 pj4;
    if (entry_touches(k, p, pi4.w, vi.w, mat_i, sp, pos, vel, info, neigh_index, neigh_rec, neigh_rev, pair_out,
                      books, &link, &pj4))
      pair_contact(pi4, vi, wi, mat_i, k, link, pj4, sp, pairs, vel, omega, info, neigh_index, neigh_rec,
                   neigh_rev, pair_out, books, law, &s);
  }

  ball_walls(i, pi4, vi, wi, mat_i, sp, pairs, lifters, meshes, mill, wall_key, wall_rec, books, law, &s);
  ball_store(i, s, mill, sp->dt, force, torque, accum);
}

/* The partners' sides of ball j's pairs: its incoming slots in_start[j] ..
 * in_start[j + 1] of pair_out, one per pair listed by a lower ball, in
 * ascending order of that ball's entry (zero while the pair is apart). */
MC_FN void ball_reactions(int j, MC_GLOBAL const int* in_start,
                          MC_GLOBAL const real* pair_out,
                          MC_GLOBAL real4* force, MC_GLOBAL real4* torque,
                          MC_GLOBAL real4* accum) {
  const int b = in_start[j];
  const int e = in_start[j + 1];
  /* Every slot is added, zero or not, and the ball's sums are updated if it
   * has any slot: testing each slot, or each ball, for a force is a branch
   * that goes either way about as often, and its mispredictions cost more
   * than the adds and the streamed read-modify-write (the whole step is
   * 5-10 % faster for it on the dense 100k charge). */
  if (e == b) return;
  /* Seven plain sums: kept as real3 values, the compiler packs them into
   * vectors and reshuffles them at every slot, a chain of shuffles that the
   * next slot waits on (the kernel is some 10 % faster without it). */
  real fx = R(0.0), fy = R(0.0), fz = R(0.0), ds = R(0.0), tx = R(0.0), ty = R(0.0), tz = R(0.0);
  for (int q = b; q < e; ++q) {
    MC_GLOBAL const real* slot = pair_out + MC_SLOT_REALS * q;
    fx += slot[0]; fy += slot[1]; fz += slot[2];
    ds += slot[3];
    tx += slot[4]; ty += slot[5]; tz += slot[6];
  }
  const real4 f = force[j];
  const real4 t = torque[j];
  const real4 a = accum[j];
  force[j] = make_real4(f.x + fx, f.y + fy, f.z + fz, f.w);
  torque[j] = make_real4(t.x + tx, t.y + ty, t.z + tz, t.w);
  accum[j] = make_real4(a.x, a.y, a.z + ds, a.w);
}

#endif /* MC_BALL_FORCES_H */
