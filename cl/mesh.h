/* mesh.h — what a ball touches of the mesh walls: triangles read from STL
 * files or built from the case (cone ends, end lifters), in two sets, one
 * turning with the mill (mill frame) and one standing still (lab frame).
 * Stateless, shared by the force kernels and the CPU reference; the forces
 * themselves go through ball_forces.h's wall_contact like any wall's.
 *
 * A ball finds its candidate triangles in one cell of its set's grid
 * (layout.h MeshGrid, filled by mesh_bin.cl). A triangle counts only from
 * the side its normal faces (the charge's side). Each candidate's closest
 * point is on its face, on one of its edges or on one of its vertices
 * (Ericson, Real-Time Collision Detection, 2005, §5.1.5), and that feature
 * names the contact. An edge or vertex counts only where the ball's centre
 * lies in its normal cone, leaning into none of the triangles round it
 * that face the ball (mesh_in_cone): elsewhere a triangle round it comes
 * nearer. Of the candidates, those that are one contact of a smooth surface
 * seen from several triangles are dropped by the rule of Hu et al. (2013, Int. J.
 * Numer. Meth. Eng. 94:787): every face contact is kept; an edge contact is
 * dropped when a triangle with a face contact has that edge, or when
 * another triangle already gave the same edge; a vertex contact is dropped
 * when a face contact's triangle or a kept edge has that vertex, or another
 * triangle already gave it; beyond Hu's rule, an edge or vertex contact on
 * or behind a face contact's plane, or of its smooth surface within half
 * its overlap of the plane, is dropped (a ball pressed deep into a fine
 * mesh: mesh_within). So a ball on the shared edge or vertex of coplanar
 * triangles feels one contact, and a ball in a concave corner feels each
 * face; contacts of one smooth patch whose normals lie within 20° are one
 * contact, the nearest. Triangles sharing an edge at less than
 * kSmoothDegrees (src/core/wall_mesh.h) belong to one smooth patch; a
 * contact that moves from one feature to another of its patch keeps its
 * record (its tangential spring and its losses so far). */
#ifndef MC_MESH_H
#define MC_MESH_H

/* The mesh walls' device tables, as the force kernels see them. */
typedef struct {
  MC_GLOBAL const MeshGrid* grid;       /* MC_MESH_SETS */
  MC_GLOBAL const MeshTriangle* tris;
  MC_GLOBAL const int2* feature;        /* per feature: smooth patch, wall type (MC_WALL_TYPE_*) */
  MC_GLOBAL const int* adj;             /* feature f's triangles: adj[adj[f] .. adj[f + 1]) */
  MC_GLOBAL const int* cell_start;      /* per set: its cells' starts, n + 1 */
  MC_GLOBAL const int* cell_tris;       /* the triangles of the cells, ascending in each */
  MC_GLOBAL const PairParams* pairs;    /* ball material × mesh material, row tri.pair_row */
} Meshes;

/* Where on triangle abc the closest point to p lies: MC_MESH_FACE, an edge
 * (MC_MESH_EDGE0 + 0 ab, 1 bc, 2 ca) or a vertex (MC_MESH_VERTEX0 + 0 a,
 * 1 b, 2 c); region − 1 indexes MeshTriangle.feat. */
#define MC_MESH_FACE 0
/* cos 20°: src/core/wall_mesh.h kSmoothDegrees, the angle below which two
 * triangles' normals make one smooth surface. */
#define MC_MESH_SMOOTH_COS R(0.93969262078590838)
/* How far in front of a face contact's plane (m) an edge or vertex still
 * counts as on it (float rounding of coplanar triangles). */
#define MC_MESH_BEHIND_TOL R(1e-6)
#define MC_MESH_EDGE0 1
#define MC_MESH_VERTEX0 4
/* sin 0.06° and 2 µm: how far an edge or vertex contact's normal may lean
 * into a triangle round it and still count (float rounding of the closest
 * point at a mill's coordinates, and of welded vertices: mesh_in_cone). */
#define MC_MESH_CONE_SIN R(1e-3)
#define MC_MESH_CONE_ABS R(2e-6)

MC_FN real3 triangle_closest(real3 p, real3 a, real3 b, real3 c, int* region) {
  const real3 ab = b - a, ac = c - a, ap = p - a;
  const real d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= R(0.0) && d2 <= R(0.0)) { *region = MC_MESH_VERTEX0; return a; }
  const real3 bp = p - b;
  const real d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= R(0.0) && d4 <= d3) { *region = MC_MESH_VERTEX0 + 1; return b; }
  const real vc = d1 * d4 - d3 * d2;
  if (vc <= R(0.0) && d1 >= R(0.0) && d3 <= R(0.0)) {
    *region = MC_MESH_EDGE0;
    return a + (d1 / (d1 - d3)) * ab;
  }
  const real3 cp = p - c;
  const real d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= R(0.0) && d5 <= d6) { *region = MC_MESH_VERTEX0 + 2; return c; }
  const real vb = d5 * d2 - d1 * d6;
  if (vb <= R(0.0) && d2 >= R(0.0) && d6 <= R(0.0)) {
    *region = MC_MESH_EDGE0 + 2;
    return a + (d2 / (d2 - d6)) * ac;
  }
  const real va = d3 * d6 - d5 * d4;
  if (va <= R(0.0) && d4 - d3 >= R(0.0) && d5 - d6 >= R(0.0)) {
    *region = MC_MESH_EDGE0 + 1;
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const real inv = R(1.0) / (va + vb + vc);
  *region = MC_MESH_FACE;
  return a + (vb * inv) * ab + (vc * inv) * ac;
}

/* Whether an edge or vertex contact of triangle tr (region, closest point
 * cp, unit normal n from cp to the ball's centre q) lies in the feature's
 * normal cone: n leans into none of the triangles round the feature that
 * face the ball, so every other vertex x of theirs has (x − cp)·n ≤ 0
 * (within MC_MESH_CONE_SIN |x − cp| + MC_MESH_CONE_ABS). Only then is the
 * feature the nearest part of the surface near the ball, as on a convex
 * edge or corner. Where n leans into a triangle, that triangle comes nearer
 * the ball elsewhere and gives the contact itself (its face, or another
 * edge or vertex), as on a flat or gently curved surface cut into
 * triangles, where an edge across the surface is never the nearest point.
 * A triangle the ball is behind gives no contact (mesh_candidates), so it
 * does not count here either: a triangle of a scan turned the wrong way
 * round must not leave a hole. The feature's own vertices are not tested:
 * welded, they need not be the same to the bit. */
MC_FN int mesh_in_cone(const Meshes* m, MC_GLOBAL const MeshTriangle* tr, int region, real3 q, real3 cp,
                       real3 n) {
  const int f = tr->feat[region - 1];
  int v0 = f, v1 = f;
  if (region < MC_MESH_VERTEX0) {
    const int e = region - MC_MESH_EDGE0;
    v0 = tr->feat[3 + e];
    v1 = tr->feat[3 + (e + 1) % 3];
  }
  const int b = m->adj[f], e = m->adj[f + 1];
  for (int k = b; k < e; ++k) {
    MC_GLOBAL const MeshTriangle* t = m->tris + m->adj[k];
    if (!(dot(q - xyz_of(t->a), xyz_of(t->n)) > R(0.0))) continue;
    for (int j = 0; j < 3; ++j) {
      const int vf = t->feat[3 + j];
      if (vf == v0 || vf == v1) continue;
      const real3 w = xyz_of(j == 0 ? t->a : j == 1 ? t->b : t->c) - cp;
      const real lean = dot(w, n);
      if (lean > MC_MESH_CONE_ABS && lean > MC_MESH_CONE_SIN * sqrt(dot(w, w)) + MC_MESH_CONE_ABS) return 0;
    }
  }
  return 1;
}

/* A candidate contact of a ball with a triangle of one set. */
typedef struct {
  int tri;
  int region;   /* MC_MESH_FACE, MC_MESH_EDGE0 + k, MC_MESH_VERTEX0 + k */
  int feature;  /* the triangle for a face, else tri.feat[region − 1] */
  real dist;    /* centre to the closest point, m */
  real3 normal; /* from the closest point to the centre, the set's frame */
} MeshHit;

/* Whether the list already holds edge or vertex feature f (another
 * triangle gave it: the same contact). */
MC_FN int mesh_listed(const MeshHit* hits, int nh, int f) {
  for (int j = 0; j < nh; ++j)
    if (hits[j].region != MC_MESH_FACE && hits[j].feature == f) return 1;
  return 0;
}

/* Whether edge or vertex contact e is part of face contact f's contact:
 * on or behind f's plane, or of f's smooth surface and within half f's
 * overlap of the plane. A ball pressed deep into a finely meshed face reaches the
 * edges and vertices of the triangles round the one it is over, whose
 * normals lean away from the face's by more than a smooth surface's 20°;
 * on a flat, gently curved or worn surface those lie about in the face's
 * plane, and the ball feels the surface once. A concave corner's other
 * face, or a fillet curving up round the ball, stands about a ball radius
 * above the plane and stays a contact; so does any other surface's edge.
 * e's point's height over f's plane is dist_f − dist_e n_e·n_f. */
MC_FN int mesh_within(const Meshes* m, const MeshHit* f, const MeshHit* e, real r) {
  const real height = f->dist - e->dist * dot(e->normal, f->normal);
  if (height < MC_MESH_BEHIND_TOL) return 1; /* on the plane or behind it */
  /* An edge or vertex where two smooth surfaces meet takes the surface of
   * the triangle that listed it first: the surface of the triangle that
   * gave this hit counts too. */
  const int patch = m->feature[f->feature].x;
  if (patch != m->feature[e->feature].x && patch != m->feature[e->tri].x) return 0;
  return height < R(0.5) * (r - f->dist) + MC_MESH_BEHIND_TOL;
}

/* One candidate into the list (mesh_candidates): an edge or vertex another
 * triangle already listed is the same contact (Hu's rule drops it), and
 * one within a face contact's (mesh_within) is none; a face contact strikes
 * those listed before it. Returns 0 where the list is full. */
MC_FN int mesh_list(const Meshes* m, MeshHit* hits, int* nh, const MeshHit* hit, real r) {
  if (hit->region != MC_MESH_FACE) {
    for (int j = 0; j < *nh; ++j)
      if (hits[j].region == MC_MESH_FACE ? mesh_within(m, &hits[j], hit, r) : hits[j].feature == hit->feature)
        return 1;
  } else {
    int kept = 0;
    for (int j = 0; j < *nh; ++j)
      if (hits[j].region == MC_MESH_FACE || !mesh_within(m, hit, &hits[j], r)) hits[kept++] = hits[j];
    *nh = kept;
  }
  if (*nh >= MC_MESH_HITS) return 0;
  hits[(*nh)++] = *hit;
  return 1;
}

/* Whether triangle t has feature f among its edges (0) or vertices (3). */
MC_FN int triangle_has(MC_GLOBAL const MeshTriangle* t, int from, int f) {
  return t->feat[from] == f || t->feat[from + 1] == f || t->feat[from + 2] == f;
}

/* The candidates of a ball centred at q (the set's frame), radius r, in its
 * cell of set s: at most MC_MESH_HITS (more raises *overflow). */
MC_FN int mesh_candidates(const Meshes* m, int s, real3 q, real r, MeshHit* hits, int* overflow) {
  MC_GLOBAL const MeshGrid* g = m->grid + s;
  if (g->n_triangles == 0) return 0;
  if (q.x * q.x + q.y * q.y < g->core_r2 && q.z > g->core_z0 && q.z < g->core_z1) return 0;
  const real inv = R(1.0) / g->origin.w;
  const int cx = (int)floor((q.x - g->origin.x) * inv);
  const int cy = (int)floor((q.y - g->origin.y) * inv);
  const int cz = (int)floor((q.z - g->origin.z) * inv);
  if (cx < 0 || cy < 0 || cz < 0 || cx >= g->nx || cy >= g->ny || cz >= g->nz) return 0;
  const int cell = g->first_cell + (cz * g->ny + cy) * g->nx + cx;
  const int b = m->cell_start[cell], e = m->cell_start[cell + 1];
  /* Faces and edges alike in one pass. Where the list fills (edges of a
   * surface whose face is still to come), it is gathered again: the faces
   * first, then the edges and vertices, which the faces strike as they
   * come; only then is a full list an overflow. */
  int nh = 0, full = 0;
  for (int pass = 0; pass < 3; ++pass) {
    if (pass > 0 && !full) break;
    if (pass == 1) nh = 0;
    for (int k = b; k < e && !(pass == 0 && full); ++k) {
      const int t = m->cell_tris[k];
      MC_GLOBAL const MeshTriangle* tr = m->tris + t;
      const real3 a = xyz_of(tr->a);
      const real3 n = xyz_of(tr->n);
      const real h = dot(q - a, n); /* height over the triangle's plane */
      if (!(h > R(0.0) && h < r)) continue;
      int region;
      const real3 cp = triangle_closest(q, a, xyz_of(tr->b), xyz_of(tr->c), &region);
      if ((pass == 1 && region != MC_MESH_FACE) || (pass == 2 && region == MC_MESH_FACE)) continue;
      MeshHit hit;
      hit.tri = t;
      hit.region = region;
      if (region == MC_MESH_FACE) {
        hit.dist = h;
        hit.normal = n;
        hit.feature = t;
      } else {
        const real3 d = q - cp;
        const real d2 = dot(d, d);
        if (!(d2 < r * r)) continue;
        hit.dist = sqrt(d2);
        hit.normal = (R(1.0) / hit.dist) * d;
        hit.feature = tr->feat[region - 1];
        if (mesh_listed(hits, nh, hit.feature) || !mesh_in_cone(m, tr, region, q, cp, hit.normal)) continue;
      }
      if (!mesh_list(m, hits, &nh, &hit, r)) {
        if (pass == 0) full = 1;
        else *overflow = 1;
      }
    }
  }
  return nh;
}

/* Hu et al.'s rule over the candidates: keep[h] says which are contacts. */
MC_FN void mesh_keep(const Meshes* m, const MeshHit* hits, int nh, int* keep) {
  for (int h = 0; h < nh; ++h) keep[h] = hits[h].region == MC_MESH_FACE;
  for (int h = 0; h < nh; ++h) {
    if (hits[h].region == MC_MESH_FACE || hits[h].region >= MC_MESH_VERTEX0) continue;
    int k = 1;
    for (int j = 0; j < nh && k; ++j) {
      if (hits[j].region == MC_MESH_FACE && triangle_has(m->tris + hits[j].tri, 0, hits[h].feature)) k = 0;
      if (j < h && keep[j] && hits[j].feature == hits[h].feature) k = 0;
    }
    keep[h] = k;
  }
  for (int h = 0; h < nh; ++h) {
    if (hits[h].region < MC_MESH_VERTEX0) continue;
    const int v = hits[h].feature;
    int k = 1;
    for (int j = 0; j < nh && k; ++j) {
      if (j == h) continue;
      MC_GLOBAL const MeshTriangle* tj = m->tris + hits[j].tri;
      if (hits[j].region == MC_MESH_FACE && triangle_has(tj, 3, v)) k = 0;
      if (hits[j].region >= MC_MESH_EDGE0 && hits[j].region < MC_MESH_VERTEX0 && keep[j]) {
        const int e = hits[j].region - MC_MESH_EDGE0;
        if (tj->feat[3 + e] == v || tj->feat[3 + (e + 1) % 3] == v) k = 0;
      }
      if (j < h && keep[j] && hits[j].feature == v) k = 0;
    }
    keep[h] = k;
  }
  /* One contact per smooth surface where it curves gently: of the contacts
   * of one smooth patch whose normals lie within MC_MESH_SMOOTH_COS of each
   * other (a ball over a shallow dish of a worn or scanned surface sees a
   * face of each triangle round a vertex), the nearest is the contact.
   * Contacts of one patch at a larger angle (a ball in a fillet that
   * curves round it) stay apart, as concave corners between patches do.
   * An edge or vertex counts with its own patch and with that of the
   * triangle that gave it (the patch of a feature where two meet is its
   * first triangle's: the edges round a triangle turned the wrong way
   * round would take that triangle's). */
  for (int h = 0; h < nh; ++h) {
    if (!keep[h]) continue;
    const int p = m->feature[hits[h].feature].x, pt = m->feature[hits[h].tri].x;
    for (int j = 0; j < nh; ++j) {
      if (j == h || !keep[j]) continue;
      const int q = m->feature[hits[j].feature].x, qt = m->feature[hits[j].tri].x;
      if (q != p && q != pt && qt != p && qt != pt) continue;
      if (dot(hits[j].normal, hits[h].normal) < MC_MESH_SMOOTH_COS) continue;
      if (hits[j].dist < hits[h].dist || (hits[j].dist == hits[h].dist && j < h)) {
        keep[h] = 0;
        break;
      }
    }
  }
}

/* Whether a ball centre at squared distance rho2 from the axis and axial
 * position z is outside the core of some set (it may touch a triangle). */
MC_FN int mesh_near(const Meshes* m, real rho2, real z) {
  int near = 0;
  for (int s = 0; s < MC_MESH_SETS; ++s) {
    MC_GLOBAL const MeshGrid* g = m->grid + s;
    near |= g->n_triangles > 0 && !(rho2 < g->core_r2 && z > g->core_z0 && z < g->core_z1);
  }
  return near;
}

/* The wall type (MC_WALL_TYPE_*) of a wall slot's key. */
MC_FN int wall_type_of(const Meshes* m, int key) {
  if (key >= MC_WALL_MESH0) return m->feature[key - MC_WALL_MESH0].y;
  return key == MC_WALL_SHELL ? MC_WALL_TYPE_SHELL : key >= MC_WALL_LIFTER0 ? MC_WALL_TYPE_LIFTER : MC_WALL_TYPE_PLATE;
}

#endif /* MC_MESH_H */
