/* layout.h — every struct that crosses the host/kernel boundary. Included by
 * the kernels and, through src/core/layout.hpp, by C++ once per precision.
 * Only `real`, `real2`, `real4` and `int` appear here, so the host mirrors
 * have the device's sizes and alignment; a kernel (layout_sizes in
 * motion.cl) reports the device's sizeof for a check at start-up. */
#ifndef MC_LAYOUT_H
#define MC_LAYOUT_H

/* Contact-history slots for walls kept per ball: shell, one end plate and two
 * lifters at once. A ball needing more is flagged (MC_FLAG_WALL_OVERFLOW). */
#define MC_MAX_WALL_CONTACTS 4
/* Vertices of one lifter cross-section (convex polygon, counter-clockwise):
 * four for a new h × w × θ bar, more for a measured or worn profile. */
#define MC_POLY_MAX_VERTS 16
/* Wear stations along a lifter bar's exposed outline, from where its leading
 * face leaves the shell, over its top, to where its trailing face enters it,
 * in equal lengths: where on the bar the wear falls (the life study). */
#define MC_WEAR_STATIONS 32
/* Rings of a worn end plate (src/core/plate_wear.h): one depth per ring,
 * the rings of equal width from the axis to the shell. */
#define MC_PLATE_NODES 16

/* Keys of wall contacts in the history slots. */
#define MC_WALL_NONE (-1)
#define MC_WALL_SHELL 0
#define MC_WALL_PLATE_LOW 1  /* z = 0 */
#define MC_WALL_PLATE_HIGH 2 /* z = length */
#define MC_WALL_LIFTER0 3    /* lifter k has key 3 + k */
/* A contact with a mesh wall is keyed by the mesh feature it touches (a
 * triangle's face, an edge or a vertex: cl/mesh.h) as MC_WALL_MESH0 + its
 * feature index. Lifter keys stay below it (lifters.rows <= 400). */
#define MC_WALL_MESH0 (1 << 20)

/* Bits of the status word the kernels raise. */
#define MC_FLAG_REBUILD 1       /* a ball moved more than half the skin */
#define MC_FLAG_WALL_OVERFLOW 2 /* more wall contacts than history slots */
#define MC_FLAG_NOT_FINITE 4    /* NaN or Inf in a ball's state */
#define MC_FLAG_ESCAPED 8       /* a ball wholly outside the shell or the end plates */
#define MC_FLAG_RECORDS_FULL 16 /* a contact found the record pool full */
#define MC_FLAG_PACK_RECORDS 32 /* the record pool is past its mark: pack it */
#define MC_FLAG_FAST 64         /* a ball crosses half the skin within twice
                                   status_every steps: the host must read the
                                   status word every step */

/* A neighbour-list entry (a link) holds the partner's index j while the
 * pair is apart, and ~j (negative) while it touched at the last force
 * evaluation: only then is the entry's tangential spring live. A pair that
 * starts to touch starts with no spring, so an apart entry's spring is never
 * read (nor cleared). */
#define MC_LINK_TOUCHING(link) ((link) < 0)
#define MC_LINK_PARTNER(link) ((link) < 0 ? ~(link) : (link))
#define MC_LINK_TOUCHED(j) (~(j))

/* Contact records: the history of each open contact, from first touch to
 * separation (one collision), kept in a pool that only touching contacts
 * use. A touching list entry or wall slot holds its record's index (or
 * MC_NO_RECORD when the pool was full). Record r is two real4s:
 *   rec[2r]     = tangential spring ξ (xyz, m), normal impact speed at
 *                 first touch (w, m/s)
 *   rec[2r + 1] = energy lost so far in the normal, tangential and rolling
 *                 parts (xyz, J), steps in contact (w)
 * New contacts take records from the end of the pool (an atomic counter);
 * each rebuild, and a pool past its mark, packs the records of the open
 * contacts to the front (which moves records and changes no result). */
#define MC_NO_RECORD (-1)

/* Collision energy spectra: per pair type, energy lost per collision in
 * log-spaced bins, 10 a decade from 1e-9 to 1e3 J, with one bin below (bin
 * 0, also losses <= 0) and one above (the last). Each bin sums, as 64-bit
 * integers (two uints, low word first, so that sums are exact and do not
 * depend on the order of the atomic adds): collisions, normal, tangential
 * and rolling losses (J, in units of the bin's lower edge · 2^-24), impact
 * speeds (units of 2^-24 m/s) and steps in contact. The last two fields
 * bin the same collisions a second time, by their normal loss alone (the
 * normal energy spectrum): the collisions whose normal loss falls in the
 * bin, and those losses (units as above). The last six bin each collision
 * by its severity, energy over its own effective radius R* (r_i r_j /
 * (r_i + r_j) for two balls, the ball's radius on a wall), which sets the
 * specific energy a breakage model gives the particles it catches: the bin
 * of x = E · MC_SPECTRA_R_REF / R*, the energy of as severe a collision
 * with R* = 1 cm. Twice: E the impact energy at first touch (1/2 m* vn^2,
 * vn the approach speed), then E the normal loss. Each holds the
 * collisions, their E (units of the bin's lower edge · 2^-24) and their R*
 * (units of MC_SPECTRA_R_REF · 2^-24). */
#define MC_SPECTRA_DECADES 12
#define MC_SPECTRA_PER_DECADE 10
#define MC_SPECTRA_LOG_MIN (-9)
#define MC_SPECTRA_BINS (MC_SPECTRA_DECADES * MC_SPECTRA_PER_DECADE + 2)
#define MC_SPECTRA_FIELDS 14
#define MC_SPECTRA_COUNT 0
#define MC_SPECTRA_NORMAL 1
#define MC_SPECTRA_TANGENTIAL 2
#define MC_SPECTRA_ROLLING 3
#define MC_SPECTRA_SPEED 4
#define MC_SPECTRA_STEPS 5
#define MC_SPECTRA_BY_NORMAL 6
#define MC_SPECTRA_BY_NORMAL_ENERGY 7
#define MC_SPECTRA_IMPACT 8          /* by impact severity: collisions */
#define MC_SPECTRA_IMPACT_ENERGY 9   /*   their impact energy, J */
#define MC_SPECTRA_IMPACT_RADIUS 10  /*   their R*, m */
#define MC_SPECTRA_LOSS 11           /* by loss severity: collisions */
#define MC_SPECTRA_LOSS_ENERGY 12    /*   their normal loss, J */
#define MC_SPECTRA_LOSS_RADIUS 13    /*   their R*, m */
#define MC_SPECTRA_R_REF 0.01        /* m: the R* a severity bin is named for */
#define MC_SPECTRA_SCALE 16777216.0 /* 2^24 */
/* Wall pair types after the ball–ball ones: per ball material. */
#define MC_WALL_TYPE_SHELL 0
#define MC_WALL_TYPE_LIFTER 1
#define MC_WALL_TYPE_PLATE 2
#define MC_WALL_TYPES 3

/* Liner elements sum, as 64-bit integers like the spectra: impacts
 * (collisions that began on the element), impact energy (the normal loss,
 * J), shear energy (the tangential loss, J), both in units of energy_unit,
 * Archard's sliding wear volume (units of wear_unit), and the strike energy
 * the impact wear reads (Bitter's deformation wear): at each contact's
 * first touch ½ m (vn − K)² for an approach speed vn above the liner
 * material's threshold K, m the ball's mass (J, units of energy_unit). */
#define MC_LINER_FIELDS 5
#define MC_LINER_IMPACTS 0
#define MC_LINER_NORMAL 1
#define MC_LINER_SHEAR 2
#define MC_LINER_WEAR 3
#define MC_LINER_STRIKE 4
/* Faces of a lifter row, in element order. */
#define MC_FACE_LEADING 0 /* the face ahead, counter-clockwise */
#define MC_FACE_TOP 1
#define MC_FACE_TRAILING 2
/* The lab-frame profile of impact energy on the shell and the lifters, a
 * bin a degree counter-clockwise from 3 o'clock (the impact point). */
#define MC_IMPACT_BINS 360

/* A pair's slot in its higher ball's incoming slots holds that ball's side
 * of the pair while it touches: the force (3 reals), half the energy the
 * contact dissipated this step (1), the torque (3). Zero while apart. */
#define MC_SLOT_REALS 7

#define MC_LAW_LINEAR 0
#define MC_LAW_HERTZ 1

/* Coefficients of one material pair (ball–ball, or ball–liner when one side
 * is the wall material). Derived on the host from materials and the case. */
typedef struct {
  real kn;         /* linear law: normal stiffness, N/m */
  real kt_over_kn; /* linear law: tangential / normal stiffness */
  real e_star;     /* Hertz: effective Young's modulus, Pa */
  real g_star;     /* Hertz: effective shear modulus, Pa */
  real damping;    /* dimensionless damping, calibrated so that the
                      rebound restitution equals the input e (see
                      src/core/restitution.cpp) */
  real mu_slide;   /* Coulomb sliding friction */
  real mu_roll;    /* rolling resistance (constant directional torque) */
  real restitution; /* input e, kept for reports */
} PairParams;

/* One lifter bar: a convex polygon in the mill's x–y cross-section,
 * extruded along z over the whole length. */
typedef struct {
  real2 vertices[MC_POLY_MAX_VERTS];
  int n_vertices;
  int pad0, pad1, pad2;
  real4 bound; /* a circle holding the polygon: centre xy, radius z; w the
                  angle (rad) from the row's centre to where the bar meets
                  the shell ahead (counter-clockwise): the bare shell after
                  it begins there */
  real4 wear;  /* the wear stations' path: it starts at vertex z and runs
                  along the edges in order; the exposed outline is from
                  x to y (m along that path) */
  real4 faces; /* where its faces meet, m along the wear path: the leading
                  face up to x, the top from x to y, the trailing face
                  after y (src/core/lifters.h lifter_face_split); z the
                  angle (rad) from the row's centre to where the bar meets
                  the shell behind: the bare shell before it ends there */
} LifterPolygon;

/* Parameters fixed for a run (changed only at a step boundary by the host). */
typedef struct {
  real4 gravity;     /* xyz, m/s² */
  real4 grid_origin; /* xyz of the lower grid corner; w = cell size, m */
  real plate_depth[2 * MC_PLATE_NODES]; /* worn end plates: each plate's
                        (z = 0, then z = length) depth behind its plane at
                        its rings, m (walls.h plate_overlap) */
  real dt;           /* s */
  real skin;         /* Verlet skin, m: pairs closer than r1+r2+skin are listed */
  real shell_radius; /* inside radius of the shell, m; <= 0: no shell */
  real length;       /* end plates at z = 0 and z = length; <= 0: none */
  real lifter_reach; /* a ball centre farther than this from the axis may
                        touch a lifter */
  real lifter_first_angle; /* centre angle of lifter 0 in the mill frame, rad */
  real lifter_spacing;     /* angle between lifter rows, rad */
  real velocity_damping; /* fraction of each ball's velocity and spin taken
                            away each step (viscous damping while the charge
                            settles); 0 while the mill turns */
  real period;       /* > 0: a periodic slice, z taken modulo period over
                        [0, period), no end plates (length is 0); the grid's
                        z cells tile the period (periodic.h) */
  real escape_z0, escape_z1; /* escape_z1 > escape_z0: the mill reaches from
                        z0 to z1 along the axis (its end plates, or its mesh
                        ends such as cone heads), and a ball wholly outside
                        has gone through an end; 0 for a slice */
  int grid_nx, grid_ny, grid_nz;
  int n_balls;
  int n_materials;   /* ball materials; the wall material has index n_materials */
  int n_lifters;
  int law;           /* MC_LAW_LINEAR or MC_LAW_HERTZ */
  int status_every;  /* steps between the host's reads of the status word
                        (>= 1): the rebuild flag goes up that many steps'
                        travel earlier */
  int first_component; /* balls with ids from here on are the component
                        spheres of rigid bodies (clumps, cl/body.h), the
                        components of each body side by side; n_balls
                        when there are none */
  int n_bodies;
  int plate_nodes;   /* rings of the worn plates' depths (0: flat plates);
                        their width is shell_radius / plate_nodes */
  int pad2, pad3;
} SimParams;

/* Whether the ball with this id is a component sphere of a rigid body. */
#define MC_IS_COMPONENT(sp, id) ((id) >= (sp)->first_component)

/* How the energy is booked: the spectra's pair types and the liner's
 * elements (src/sim/liner.h lays them out), derived on the host. */
typedef struct {
  real energy_unit;     /* J per count of the liner's energy sums */
  real wear_unit;       /* m³ per count of the liner's wear sums */
  real wear_k;          /* Archard: volume = wear_k · Fn · sliding distance, m³/(N·m) */
  real plate_ring_width; /* m, radial width of the end plates' rings */
  real strike_speed;    /* m/s: the liner material's threshold K of the
                           strike energy (MC_LINER_STRIKE) */
  real axial_span;      /* m the axial bins divide equally from z = 0: the
                           mill's length (a slice's period) */
  int n_types;          /* pair types (the spectra's rows; one more row
                           holds the losses of contacts without a record) */
  int n_elements;       /* liner elements */
  int shell_bins;       /* shell elements between two lifter rows (or around
                           a smooth shell) */
  int axial_bins;       /* of the shell and the lifters */
  int plate_rings, plate_sectors;
  int first_lifter_element; /* the shell's elements come first */
  int first_plate_element;
  int first_station;    /* after the elements: each lifter row's
                           MC_WEAR_STATIONS stations, with the elements'
                           fields */
  int pad0;
} BookParams;

/* Mesh walls (cl/mesh.h, src/core/wall_mesh.h): triangles in the frame of
 * their set, the mill frame for the meshes that turn with the mill, the lab
 * frame for those that stand still. Each triangle's normal faces the charge;
 * a ball touches a triangle only from that side. Features: triangle t is
 * feature t, edge e is n_triangles + e, vertex v is n_triangles + n_edges + v
 * (edges and vertices shared by the triangles of one mesh). */
#define MC_MESH_SETS 2     /* set 0 turns with the mill, set 1 stands still */
#define MC_MESH_HITS 16    /* candidate contacts of one ball with one set */
typedef struct {
  real4 a, b, c;   /* vertices, m; a.w: Archard wear coefficient, m³/(N·m);
                      b.w: the strike threshold K of its material, m/s */
  real4 n;         /* unit normal towards the charge */
  int feat[6];     /* features of the edges ab, bc, ca and the vertices a, b, c */
  int pair_row;    /* its material's row of the mesh pair table (× n_materials) */
  int element;     /* its liner element (the books') */
} MeshTriangle;

/* The grid of one set's triangles, in the set's frame: cell c lists every
 * triangle within reach (the largest ball radius) of some point of the
 * cell, so a ball centre in c needs that cell alone. The core is a cylinder
 * about the axis no triangle reaches: balls inside it skip the grid. */
typedef struct {
  real4 origin;        /* lower corner xyz; w: cell size, m */
  real core_r2;        /* squared radius of the core, m² */
  real core_z0, core_z1; /* its axial extent, m */
  real reach;          /* m: the largest ball radius the cells were filled for */
  int nx, ny, nz;
  int first_cell;      /* this set's first entry in cell_start (n cells + 1) */
  int n_triangles;     /* 0: an empty set */
  int pad0, pad1, pad2;
} MeshGrid;

/* The pair table has (n_materials + 1)² entries, wall material last. */
#define MC_PAIR_INDEX(params, a, b) ((a) * ((params)->n_materials + 1) + (b))

#endif /* MC_LAYOUT_H */
