/* books.h — where the energy goes: each open contact's record (its spring
 * and what it has lost so far), the collision spectra a record joins when
 * its contact opens, and the liner's elements, which sum what the walls
 * take each step. Shared by the force kernels and the CPU reference.
 *
 * Sums that many work-items add to are 64-bit integers (fixed point), kept
 * as two uints and added with 32-bit atomics: integer sums are exact and do
 * not depend on the order of the adds, so a run stays deterministic and a
 * resumed run ends bit for bit as the unbroken one. (64-bit atomics are an
 * optional extension that Mesa's rusticl lacks.)
 *
 * With MC_ENERGY_BOOKS 0 (the benchmark's "off" build) a record keeps only
 * its spring: no losses, spectra or liner sums. */
#ifndef MC_BOOKS_H
#define MC_BOOKS_H

#ifndef MC_ENERGY_BOOKS
#define MC_ENERGY_BOOKS 1
#endif

/* What the force kernels book into, besides forces. */
typedef struct {
  MC_GLOBAL real4* records;      /* the pool, two real4 a record (layout.h) */
  MC_GLOBAL int* rec_state;      /* [0] records taken, [1] contacts that found
                                    the pool full */
  int capacity;                  /* records the pool holds */
  int mark;                      /* a record taken here asks for the pool to
                                    be packed */
  MC_GLOBAL uint* spectra;       /* (n_types + 1) × MC_SPECTRA_BINS × fields */
  MC_GLOBAL uint* liner;         /* n_elements × MC_LINER_FIELDS */
  MC_GLOBAL uint* impact_profile; /* MC_IMPACT_BINS for the whole mill, then
                                     MC_IMPACT_BINS for each axial bin; energy_unit */
  MC_GLOBAL const BookParams* bp;
  MC_GLOBAL int* status;
} Books;

/* *a += v, a 64-bit integer as two uints (low word first). The high word
 * takes the carry of the low one; for small values of either sign it takes
 * nothing, so most adds are one atomic. */
MC_FN void add_u64(MC_GLOBAL uint* a, long v) {
  const uint lo = (uint)v;
  const uint hi = (uint)(((ulong)v) >> 32);
  const uint old = MC_ATOMIC_ADD(a, lo);
  const uint h = hi + (uint)(old + lo < old);
  if (h != 0u) MC_ATOMIC_ADD(a + 1, h);
}

/* A real in units of `unit`, rounded to the nearest. */
MC_FN long fixed_of(real x, real inv_unit) { return MC_ROUND_LONG(x * inv_unit); }

/* ------------------------------------------------------------ records */

/* A record for a contact that begins, or MC_NO_RECORD when the pool is
 * full (the host then packs and grows it; the contact meanwhile keeps no
 * spring and its losses go to the spectra's last row). */
MC_FN int record_take(Books* b) {
  const int r = MC_ATOMIC_INC(&b->rec_state[0]);
  if (r == b->mark) MC_ATOMIC_OR(b->status, MC_FLAG_PACK_RECORDS);
  if (r < b->capacity) return r;
  MC_ATOMIC_INC(&b->rec_state[1]);
  MC_ATOMIC_OR(b->status, MC_FLAG_RECORDS_FULL | MC_FLAG_PACK_RECORDS);
  return MC_NO_RECORD;
}

MC_FN v3 record_spring(Books* b, int rec) {
  return rec >= 0 ? v3_of(xyz_of(b->records[2 * rec])) : v3_make(0, 0, 0);
}

/* ------------------------------------------------------------ spectra */

/* Bin of a collision that lost e joules: 0 below 1e-9 J (and e <= 0), then
 * ten a decade, the last above 1e3 J. */
MC_FN int spectra_bin(real e) {
  if (!(e > R(1e-9))) return 0;
  if (!(e < R(1e3))) return MC_SPECTRA_BINS - 1; /* also an infinite energy of a run that blew up */
  const real u = (log10(e) - R(MC_SPECTRA_LOG_MIN)) * R(MC_SPECTRA_PER_DECADE);
  const int k = (int)floor(u) + 1;
  return k < MC_SPECTRA_BINS - 1 ? k : MC_SPECTRA_BINS - 1;
}

/* Lower edge of a bin, J (bin 0: 1e-9 J, the unit's base for it too). */
MC_FN real spectra_edge(int bin) {
  const int k = bin < 1 ? 1 : bin;
  return pow(R(10.0), R(MC_SPECTRA_LOG_MIN) + (real)(k - 1) / R(MC_SPECTRA_PER_DECADE));
}

MC_FN int ball_pair_type(int a, int b, int n_materials) {
  const int lo = a < b ? a : b, hi = a < b ? b : a;
  return lo * n_materials - lo * (lo - 1) / 2 + (hi - lo);
}

/* The spectra's row of a ball material's contacts with a wall type. */
MC_FN int wall_type_pair(int material, int wall_type, int n_materials) {
  return n_materials * (n_materials + 1) / 2 + MC_WALL_TYPES * material + wall_type;
}

/* ... with the analytic wall of a slot key (shell, end plate, lifter). */
MC_FN int wall_pair_type(int material, int key, int n_materials) {
  const int w = key == MC_WALL_SHELL ? MC_WALL_TYPE_SHELL
                : key >= MC_WALL_LIFTER0 ? MC_WALL_TYPE_LIFTER : MC_WALL_TYPE_PLATE;
  return wall_type_pair(material, w, n_materials);
}

MC_FN MC_GLOBAL uint* spectra_cell(Books* b, int type, int bin) {
  return b->spectra + 2 * MC_SPECTRA_FIELDS * (type * MC_SPECTRA_BINS + bin);
}

/* A collision's energy e (J) into the severity fields from `field`
 * (count, energy, radius) of its type's bin of e · R_ref / r_eff. */
MC_FN void severity_book(Books* b, int type, int field, real e, real r_eff) {
  const real x = e * R(MC_SPECTRA_R_REF) / r_eff;
  const int bin = spectra_bin(x);
  MC_GLOBAL uint* cell = spectra_cell(b, type, bin);
  add_u64(cell + 2 * field, 1);
  add_u64(cell + 2 * (field + 1), fixed_of(e, R(MC_SPECTRA_SCALE) / spectra_edge(bin)));
  add_u64(cell + 2 * (field + 2), fixed_of(r_eff, R(MC_SPECTRA_SCALE) / R(MC_SPECTRA_R_REF)));
}

/* A collision that ended: its record into the histograms of its type;
 * m_eff and r_eff are the pair's m* and R* (pair_geometry's, a wall's). */
MC_FN void record_close(Books* b, int rec, int type, real m_eff, real r_eff) {
#if MC_ENERGY_BOOKS
  if (rec < 0) return;
  const real4 head = b->records[2 * rec];
  const real4 lost = b->records[2 * rec + 1];
  const int bin = spectra_bin(lost.x + lost.y + lost.z);
  const real inv_unit = R(MC_SPECTRA_SCALE) / spectra_edge(bin);
  MC_GLOBAL uint* cell = spectra_cell(b, type, bin);
  add_u64(cell + 2 * MC_SPECTRA_COUNT, 1);
  add_u64(cell + 2 * MC_SPECTRA_NORMAL, fixed_of(lost.x, inv_unit));
  add_u64(cell + 2 * MC_SPECTRA_TANGENTIAL, fixed_of(lost.y, inv_unit));
  add_u64(cell + 2 * MC_SPECTRA_ROLLING, fixed_of(lost.z, inv_unit));
  add_u64(cell + 2 * MC_SPECTRA_SPEED, fixed_of(head.w, R(MC_SPECTRA_SCALE)));
  add_u64(cell + 2 * MC_SPECTRA_STEPS, (long)lost.w);
  /* The normal energy spectrum: the same collision by its normal loss. */
  const int bin_n = spectra_bin(lost.x);
  MC_GLOBAL uint* cell_n = spectra_cell(b, type, bin_n);
  add_u64(cell_n + 2 * MC_SPECTRA_BY_NORMAL, 1);
  add_u64(cell_n + 2 * MC_SPECTRA_BY_NORMAL_ENERGY, fixed_of(lost.x, R(MC_SPECTRA_SCALE) / spectra_edge(bin_n)));
  /* By severity: the impact energy at first touch, and the normal loss. */
  severity_book(b, type, MC_SPECTRA_IMPACT, R(0.5) * m_eff * head.w * head.w, r_eff);
  severity_book(b, type, MC_SPECTRA_LOSS, lost.x, r_eff);
#else
  (void)m_eff;
  (void)r_eff;
#endif
}

/* A step of a contact: its new spring into its record and, with the books
 * on, its losses; `fresh`: the contact began this step, with normal speed
 * vn (negative approaching). Losses of a contact without a record go to the
 * spectra's last row (n_types), bin 0, uncounted. */
MC_FN void record_step(Books* b, int rec, int fresh, real vn, ContactOut c) {
  if (rec >= 0) {
#if MC_ENERGY_BOOKS
    const real4 before = fresh ? make_real4(0, 0, 0, 0) : b->records[2 * rec + 1];
    const real v_impact = fresh ? fmax(-vn, R(0.0)) : b->records[2 * rec].w;
    b->records[2 * rec] = make_real4(c.spring.x, c.spring.y, c.spring.z, v_impact);
    b->records[2 * rec + 1] = make_real4(before.x + c.loss_normal, before.y + c.loss_tangential,
                                         before.z + c.loss_rolling, before.w + R(1.0));
#else
    b->records[2 * rec] = make_real4(c.spring.x, c.spring.y, c.spring.z, R(0.0));
#endif
    return;
  }
#if MC_ENERGY_BOOKS
  const real inv_unit = R(MC_SPECTRA_SCALE) / spectra_edge(0);
  MC_GLOBAL uint* cell = spectra_cell(b, b->bp->n_types, 0);
  add_u64(cell + 2 * MC_SPECTRA_NORMAL, fixed_of(c.loss_normal, inv_unit));
  add_u64(cell + 2 * MC_SPECTRA_TANGENTIAL, fixed_of(c.loss_tangential, inv_unit));
  add_u64(cell + 2 * MC_SPECTRA_ROLLING, fixed_of(c.loss_rolling, inv_unit));
#endif
}

/* ------------------------------------------------------------ the liner */

/* The liner element under a wall contact: `key` the wall, `rc` the contact
 * point in the mill frame, `along` (lifters) the contact's place along the
 * bar's wear path (lifter_path_place). Element order (src/sim/liner.h): the shell, gap by
 * gap (gap k from row k to row k + 1, counter-clockwise), shell_bins over
 * its bare arc, each in axial bins; then each lifter row's leading face, top
 * and trailing face, in axial bins; then the end plates (z = 0, then
 * z = length) in rings and sectors. */
/* The axial bin of the shell's and lifters' elements at z (m, mill frame):
 * equal spans of bp->axial_span (the liner layout's length: between flat
 * end plates or cone heads, or a slice's period). */
MC_FN int axial_bin_of(MC_GLOBAL const BookParams* bp, MC_GLOBAL const SimParams* sp, real z) {
  int axial = 0;
  const real span = bp->axial_span > R(0.0) ? bp->axial_span : sp->length > R(0.0) ? sp->length : sp->period;
  if (span > R(0.0)) {
    axial = (int)floor(z / span * (real)bp->axial_bins);
    axial = axial < 0 ? 0 : axial >= bp->axial_bins ? bp->axial_bins - 1 : axial;
  }
  return axial;
}

MC_FN int liner_element(MC_GLOBAL const BookParams* bp, MC_GLOBAL const SimParams* sp,
                        MC_GLOBAL const LifterPolygon* lifters, int key, real3 rc, real along) {
  const real two_pi = R(6.283185307179586);
  const int nl = sp->n_lifters;
  const int axial = axial_bin_of(bp, sp, rc.z);
  real theta = atan2_fast(rc.y, rc.x);
  theta = theta < R(0.0) ? theta + two_pi : theta;
  if (key == MC_WALL_SHELL) {
    int gap = 0;
    real u = theta / two_pi;
    if (nl > 0) {
      real rel = theta - sp->lifter_first_angle;
      rel -= two_pi * floor(rel / two_pi);
      gap = (int)floor(rel / sp->lifter_spacing);
      gap = gap >= nl ? nl - 1 : gap;
      const real from = lifters[gap].bound.w;
      const real to = sp->lifter_spacing - lifters[(gap + 1) % nl].faces.z;
      u = (rel - (real)gap * sp->lifter_spacing - from) / (to - from);
    }
    int j = (int)floor(u * (real)bp->shell_bins);
    j = j < 0 ? 0 : j >= bp->shell_bins ? bp->shell_bins - 1 : j;
    return (gap * bp->shell_bins + j) * bp->axial_bins + axial;
  }
  if (key >= MC_WALL_LIFTER0) {
    /* Its face by place: the leading face up to where the top begins, the
     * trailing face after it ends, however far either lays back. */
    const int k = key - MC_WALL_LIFTER0;
    const real4 fc = lifters[k].faces;
    const int face = along < fc.x ? MC_FACE_LEADING : along <= fc.y ? MC_FACE_TOP : MC_FACE_TRAILING;
    return bp->first_lifter_element + (k * 3 + face) * bp->axial_bins + axial;
  }
  const int plate = key == MC_WALL_PLATE_HIGH ? 1 : 0;
  int ring = (int)floor(sqrt(rc.x * rc.x + rc.y * rc.y) / bp->plate_ring_width);
  ring = ring < 0 ? 0 : ring >= bp->plate_rings ? bp->plate_rings - 1 : ring;
  int sector = (int)floor(theta / two_pi * (real)bp->plate_sectors);
  sector = sector < 0 ? 0 : sector >= bp->plate_sectors ? bp->plate_sectors - 1 : sector;
  return bp->first_plate_element + (plate * bp->plate_rings + ring) * bp->plate_sectors + sector;
}

/* Where a contact point `p` (mill frame) lies on a lifter bar: the closest
 * point of its outline, as a length along its wear path (layout.h
 * LifterPolygon.wear), which sets its face (liner_element) and its station. */
MC_FN real lifter_path_place(MC_GLOBAL const LifterPolygon* poly, real2 p) {
  const int nv = poly->n_vertices;
  const int start = (int)poly->wear.z;
  real along = R(0.0), best_d2 = R(1e30), best_s = R(0.0);
  for (int j = 0; j < nv; ++j) {
    const int v = (start + j) % nv;
    const real2 a = poly->vertices[v];
    const real2 e = poly->vertices[(v + 1) % nv] - a;
    const real len2 = dot(e, e);
    real t = len2 > R(0.0) ? dot(p - a, e) / len2 : R(0.0);
    t = fmin(fmax(t, R(0.0)), R(1.0));
    const real2 d = p - (a + t * e);
    const real d2 = dot(d, d);
    const real len = sqrt(len2);
    if (d2 < best_d2) { best_d2 = d2; best_s = along + t * len; }
    along += len;
  }
  return best_s;
}

/* The wear station of a contact at `along` (lifter_path_place) on lifter
 * row k: MC_WEAR_STATIONS equal parts of the exposed outline; row k's
 * stations follow bp->first_station. */
MC_FN int lifter_station(MC_GLOBAL const BookParams* bp, MC_GLOBAL const LifterPolygon* poly, int k, real along) {
  const real span = poly->wear.y - poly->wear.x;
  int j = span > R(0.0) ? (int)floor((along - poly->wear.x) / span * (real)MC_WEAR_STATIONS) : 0;
  j = j < 0 ? 0 : j >= MC_WEAR_STATIONS ? MC_WEAR_STATIONS - 1 : j;
  return bp->first_station + k * MC_WEAR_STATIONS + j;
}

/* A wall contact's step on its element: an impact when it began, its normal
 * loss, its tangential loss, Archard's wear volume (coefficient wear_k) and
 * its strike energy (J, nonzero only at first touch: wall_contact); on the
 * shell and the lifters (`profile`) also the normal loss at its lab-frame
 * angle (`lab_angle`, rad), for the whole mill and for its axial bin
 * (`axial`, axial_bin_of). */
MC_FN void liner_step(Books* b, int element, int fresh, ContactOut c, real wear_k, real strike, int profile,
                      real lab_angle, int axial) {
#if MC_ENERGY_BOOKS
  MC_GLOBAL const BookParams* bp = b->bp;
  MC_GLOBAL uint* cell = b->liner + 2 * MC_LINER_FIELDS * element;
  const real inv_e = R(1.0) / bp->energy_unit;
  if (fresh) add_u64(cell + 2 * MC_LINER_IMPACTS, 1);
  add_u64(cell + 2 * MC_LINER_NORMAL, fixed_of(c.loss_normal, inv_e));
  add_u64(cell + 2 * MC_LINER_SHEAR, fixed_of(c.loss_tangential, inv_e));
  if (c.slide > R(0.0))
    add_u64(cell + 2 * MC_LINER_WEAR, fixed_of(wear_k * c.normal_force * c.slide, R(1.0) / bp->wear_unit));
  if (strike > R(0.0)) add_u64(cell + 2 * MC_LINER_STRIKE, fixed_of(strike, inv_e));
  if (profile) {
    const real two_pi = R(6.283185307179586);
    real a = lab_angle < R(0.0) ? lab_angle + two_pi : lab_angle;
    int bin = (int)floor(a / two_pi * (real)MC_IMPACT_BINS);
    bin = bin < 0 ? 0 : bin >= MC_IMPACT_BINS ? MC_IMPACT_BINS - 1 : bin;
    const long q = fixed_of(c.loss_normal, inv_e);
    add_u64(b->impact_profile + 2 * bin, q);
    if (axial >= 0 && axial < bp->axial_bins) add_u64(b->impact_profile + 2 * ((1 + axial) * MC_IMPACT_BINS + bin), q);
  }
#endif
}

#endif /* MC_BOOKS_H */
