#include "sim/tables.h"

#include <algorithm>
#include <cmath>

#include "core/lifters.h"
#include "core/liner.h"
#include "core/plate_wear.h"

namespace mc {
namespace {

// The mesh walls' tables (SceneTables), the liner's elements already laid out.
void mesh_tables(const Scene& scene, const LinerLayout& liner, double r_max, SceneTables& t) {
  const std::vector<WallMesh>& meshes = scene.walls.meshes;
  const std::vector<MeshTriangleRef> order = mesh_device_order(meshes);
  const MeshTopology topo = mesh_topology(meshes);
  const int nm = scene.wall_index();
  // The pair table: a row of n_materials entries per mesh (its material and
  // its interactions with the ball materials).
  std::vector<int> row(meshes.size(), 0);
  Scene s;  // the materials alone, each mesh's as the wall's in turn
  s.materials = scene.materials;
  s.interactions = scene.interactions;
  s.numerics = scene.numerics;
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    s.wall_material = meshes[m].material;
    for (int a = 0; a < nm; ++a) s.set_interaction(a, nm, meshes[m].interactions.at(a));
    row[m] = static_cast<int>(t.mesh_pairs.size());
    for (int a = 0; a < nm; ++a) {
      const PairCoefficients c = pair_coefficients(s, a, nm);
      t.mesh_pairs.push_back({c.kn, c.kt_over_kn, c.e_star, c.g_star, c.damping, c.mu_slide, c.mu_roll,
                              c.restitution});
    }
  }
  if (t.mesh_pairs.empty()) t.mesh_pairs.push_back(f64::PairParams{});
  const int T = topo.n_triangles, E = topo.n_edges;
  for (int k = 0; k < T; ++k) {
    const WallMesh& m = meshes[order[k].mesh];
    const Triangle& tri = m.triangles[order[k].triangle];
    f64::MeshTriangle d{};
    d.a = {tri.v[0].x, tri.v[0].y, tri.v[0].z, m.material.wear_coefficient};
    d.b = {tri.v[1].x, tri.v[1].y, tri.v[1].z, m.material.impact_wear_threshold_speed};
    d.c = {tri.v[2].x, tri.v[2].y, tri.v[2].z, 0};
    const Vec3 n = triangle_unit_normal(tri);
    d.n = {n.x, n.y, n.z, 0};
    for (int e = 0; e < 3; ++e) d.feat[e] = T + topo.edges[k][e];
    for (int v = 0; v < 3; ++v) d.feat[3 + v] = T + E + topo.vertices[k][v];
    d.pair_row = row[order[k].mesh];
    d.element = liner.first_mesh + k;
    t.mesh_tris.push_back(d);
    t.mesh_set_triangles[m.turning ? 0 : 1].push_back(tri);
    for (const Vec3& v : tri.v) t.mesh_z0 = std::min(t.mesh_z0, v.z), t.mesh_z1 = std::max(t.mesh_z1, v.z);
  }
  if (t.mesh_tris.empty()) t.mesh_tris.push_back(f64::MeshTriangle{});
  // Each feature's patch and wall type (that of the mesh of a triangle
  // holding it; a feature belongs to one mesh).
  t.mesh_feature.assign(std::max(topo.features(), 1), f64::int2{0, 0});
  for (int k = 0; k < T; ++k) {
    const int type = static_cast<int>(meshes[order[k].mesh].part);
    t.mesh_feature[k] = {topo.patch[k], type};
    for (int e = 0; e < 3; ++e) t.mesh_feature[T + topo.edges[k][e]] = {topo.patch[T + topo.edges[k][e]], type};
    for (int v = 0; v < 3; ++v)
      t.mesh_feature[T + E + topo.vertices[k][v]] = {topo.patch[T + E + topo.vertices[k][v]], type};
  }
  const int F = topo.features();
  t.mesh_adj.assign(static_cast<std::size_t>(F) + 1, 0);
  for (int f = 0; f <= F; ++f) t.mesh_adj[f] = F + 1 + topo.adj_start[f];
  t.mesh_adj.insert(t.mesh_adj.end(), topo.adj_tris.begin(), topo.adj_tris.end());
  // The grids: reach the largest ball radius (and a little: rounding in
  // float must not drop a triangle that touches).
  const double reach = r_max * (1 + 1e-4) + 1e-6;
  int first_cell = 0;
  for (int s = 0; s < MC_MESH_SETS; ++s) {
    const MeshGridSpec g = mesh_grid_spec(t.mesh_set_triangles[s], reach);
    t.mesh_grid_specs[s] = g;
    f64::MeshGrid& d = t.mesh_grid[s];
    d.origin = {g.origin.x, g.origin.y, g.origin.z, g.cell};
    d.core_r2 = g.core_r2;
    d.core_z0 = g.core_z0;
    d.core_z1 = g.core_z1;
    d.reach = g.reach;
    d.nx = g.nx;
    d.ny = g.ny;
    d.nz = g.nz;
    d.first_cell = first_cell;
    d.n_triangles = g.n_triangles;
    first_cell += static_cast<int>(g.cells());
  }
  t.mesh_cells = first_cell;
}

// The least distance from the mill axis to the polygon edge a–b. A flat top
// comes closest to the axis at its middle, not at its corners: a reach taken
// at the vertices missed a ball meeting the middle of a top face until it
// overlapped by the difference less the margin (0.14 mm on the lab mill's
// bars, 0.24 mm for 50 mm balls on 40 mm square bars in a 0.9 m mill), and
// the contact then began with that overlap and an energy no impact has.
double distance_to_axis(const Vec2& a, const Vec2& b) {
  const double ex = b.x - a.x, ey = b.y - a.y;
  const double len2 = ex * ex + ey * ey;
  const double t = len2 > 0 ? std::clamp(-(a.x * ex + a.y * ey) / len2, 0.0, 1.0) : 0.0;
  return std::hypot(a.x + t * ex, a.y + t * ey);
}

}  // namespace

SceneTables scene_tables(const Scene& scene) {
  validate(scene);
  SceneTables t;
  const int nm = scene.wall_index();
  for (int a = 0; a <= nm; ++a)
    for (int b = 0; b <= nm; ++b) {
      const PairCoefficients c = pair_coefficients(scene, a, b);
      t.pairs.push_back({c.kn, c.kt_over_kn, c.e_star, c.g_star, c.damping, c.mu_slide, c.mu_roll,
                         c.restitution});
    }
  const Walls& w = scene.walls;
  double r_max = 0;
  for (const Ball& b : scene.balls) r_max = std::max(r_max, b.radius);
  double reach = w.shell_radius;
  static_assert(kLifterMaxPoints == MC_POLY_MAX_VERTS && kWearStations == MC_WEAR_STATIONS);
  for (const auto& poly : w.lifters) {
    f64::LifterPolygon p{};
    p.n_vertices = static_cast<int>(poly.size());
    double cx = 0, cy = 0;
    for (std::size_t v = 0; v < poly.size(); ++v) {
      p.vertices[v] = {poly[v].x, poly[v].y};
      reach = std::min(reach, distance_to_axis(poly[v], poly[(v + 1) % poly.size()]));
      cx += poly[v].x / static_cast<double>(poly.size());
      cy += poly[v].y / static_cast<double>(poly.size());
    }
    double radius = 0;
    for (const auto& v : poly) radius = std::max(radius, std::hypot(v.x - cx, v.y - cy));
    // A little over, so that rounding in float never rejects a touching ball.
    const double centre = w.lifter_first_angle + 2.0 * M_PI * static_cast<double>(t.lifters.size()) /
                                                     static_cast<double>(w.lifters.size());
    const FootAngles feet = w.shell_radius > 0 ? lifter_foot_angles(poly, w.shell_radius, centre) : FootAngles{};
    p.bound = {cx, cy, radius * (1 + 1e-4) + 1e-6, feet.lead};
    const WearPath path = lifter_wear_path(poly, w.shell_radius > 0 ? w.shell_radius : 1e300);
    p.wear = {path.from, path.to, static_cast<double>(path.start), 0.0};
    const FaceSplit split = lifter_face_split(poly, w.shell_radius > 0 ? w.shell_radius : 1e300,
                                              Vec2{std::cos(centre), std::sin(centre)});
    p.faces = {split.top_from, split.top_to, feet.trail, 0.0};
    t.lifters.push_back(p);
  }
  if (t.lifters.empty()) t.lifters.push_back(f64::LifterPolygon{});
  const int nl = static_cast<int>(w.lifters.size());
  f64::SimParams& sp = t.params;
  const Vec3 g = scene.numerics.gravity;
  sp.gravity = {g.x, g.y, g.z, 0};
  sp.dt = scene.numerics.dt;
  sp.skin = scene.numerics.skin > 0 ? scene.numerics.skin : default_skin(scene);
  sp.shell_radius = w.shell_radius;
  sp.length = w.has_end_plates() ? w.length : 0.0;
  sp.period = w.periodic ? w.length : 0.0;
  // A ball centre farther than this from the axis may touch a lifter.
  sp.lifter_reach = std::max(0.0, reach - 1.01 * r_max);
  sp.status_every = 1;  // the solver sets its own (Solver::status_every)
  sp.lifter_first_angle = w.lifter_first_angle;
  sp.lifter_spacing = nl > 0 ? 2.0 * M_PI / nl : 1.0;
  sp.n_balls = static_cast<int>(scene.balls.size());
  sp.n_bodies = static_cast<int>(scene.bodies.size());
  sp.first_component = scene.bodies.empty() ? sp.n_balls : scene.bodies.front().first;
  sp.n_materials = nm;
  sp.n_lifters = nl;
  sp.law = scene.numerics.law == ContactLaw::hertz ? MC_LAW_HERTZ : MC_LAW_LINEAR;

  // The books: fixed-point units from the scale of the mill (the heaviest
  // ball lifted across the diameter), 2^-44 of it, so an element's sums hold
  // 2^19 such lifts and resolve a part in 10^13 of one.
  const LinerLayout liner = liner_layout(scene);
  double m_max = 0;
  for (const Ball& b : scene.balls) m_max = std::max(m_max, ball_mass(scene, b));
  const double lift = std::max(m_max, 1e-6) * 9.81 * (w.shell_radius > 0 ? 2 * w.shell_radius : 1.0);
  f64::BookParams& bp = t.books;
  bp.energy_unit = std::ldexp(lift, -44);
  bp.wear_k = scene.wall_material.wear_coefficient;
  bp.wear_unit = std::max(bp.wear_k, 1e-30) * bp.energy_unit;
  bp.strike_speed = scene.wall_material.impact_wear_threshold_speed;
  bp.plate_ring_width = (w.shell_radius > 0 ? w.shell_radius : 1.0) / liner.plate_rings;
  bp.n_types = n_pair_types(nm);
  bp.n_elements = liner.size();
  bp.shell_bins = liner.shell_bins;
  bp.axial_bins = liner.axial_bins;
  bp.axial_span = liner.length;
  bp.plate_rings = liner.plate_rings;
  bp.plate_sectors = liner.plate_sectors;
  bp.first_lifter_element = liner.first_lifter;
  bp.first_plate_element = liner.first_plate;
  bp.first_station = liner.size();
  mesh_tables(scene, liner, r_max, t);
  // A ball wholly past the mill's ends has gone through one: the end plates
  // bound the mill, or, closed by mesh ends (cone heads), the meshes' axial
  // extent. A slice has no ends.
  if (w.has_end_plates()) {
    // Worn plates lie behind their planes (core/plate_wear.h).
    double deepest[2] = {0, 0};
    if (w.plates_worn()) {
      sp.plate_nodes = scene.liner.plate_rings;
      for (int p = 0; p < 2; ++p) {
        const std::vector<double>& depth = w.plate_depth[p];
        if (depth.size() != static_cast<std::size_t>(sp.plate_nodes) || depth.size() > MC_PLATE_NODES)
          throw std::invalid_argument("liner.plate_depth_mm: one depth per ring of liner.plate_rings (at most " +
                                      std::to_string(MC_PLATE_NODES) + ") on each plate");
        for (std::size_t j = 0; j < depth.size(); ++j) {
          sp.plate_depth[p * MC_PLATE_NODES + j] = depth[j];
          deepest[p] = std::max(deepest[p], depth[j]);
        }
      }
    }
    sp.escape_z0 = -deepest[0];
    sp.escape_z1 = w.length + deepest[1];
  } else if (!w.periodic && t.mesh_z1 >= t.mesh_z0) {
    sp.escape_z0 = t.mesh_z0;
    sp.escape_z1 = t.mesh_z1;
  }
  return t;
}

BodyTables body_tables(const Scene& scene) {
  BodyTables t;
  const int n = static_cast<int>(scene.balls.size());
  t.n_bodies = static_cast<int>(scene.bodies.size());
  t.first_component = scene.bodies.empty() ? n : scene.bodies.front().first;
  const int n_comp = n - t.first_component;
  t.body_of.assign(std::max(n_comp, 1), 0);
  t.comp_offset.assign(std::max(n_comp, 1), f64::real4{0, 0, 0, 0});
  for (const Ball& b : scene.balls)
    if (b.body >= 0) {
      t.body_of[b.id - t.first_component] = b.body;
      t.comp_offset[b.id - t.first_component] = {b.offset.x, b.offset.y, b.offset.z, 0};
    }
  for (const Body& b : scene.bodies) {
    t.body_comp.push_back({b.first, b.count});
    t.body_pos.push_back({b.position.x, b.position.y, b.position.z, 1.0 / b.mass});
    t.body_vel.push_back({b.velocity.x, b.velocity.y, b.velocity.z, 0});
    const auto& q = b.orientation;
    t.body_quat.push_back({q[0], q[1], q[2], q[3]});
    // L in the body frame: I ω_body, with ω_body = q* ω q.
    const Vec3 wb = rotate({-q[0], -q[1], -q[2], q[3]}, b.omega);
    t.body_angmom.push_back({b.inertia.x * wb.x, b.inertia.y * wb.y, b.inertia.z * wb.z, 0});
    t.body_inv_inertia.push_back({1 / b.inertia.x, 1 / b.inertia.y, 1 / b.inertia.z, 0});
  }
  if (t.body_comp.empty()) {
    t.body_comp.push_back({0, 0});
    for (auto* v : {&t.body_pos, &t.body_vel, &t.body_angmom, &t.body_inv_inertia}) v->push_back({0, 0, 0, 0});
    t.body_quat.push_back({0, 0, 0, 1});
  }
  return t;
}

std::vector<DeviceBall> device_balls(const Scene& scene) {
  std::vector<DeviceBall> out;
  out.reserve(scene.balls.size());
  for (const Ball& b : scene.balls) {
    DeviceBall d;
    d.ball = b;
    if (b.body < 0) {
      const double m = ball_mass(scene, b);
      d.inv_mass = 1.0 / m;
      d.inv_inertia = 1.0 / (0.4 * m * b.radius * b.radius);
    } else {
      const Body& body = scene.bodies.at(b.body);
      const Vec3 r = rotate(body.orientation, b.offset);
      const Vec3& w = body.omega;
      d.ball.position = body.position + r;
      d.ball.velocity = body.velocity + Vec3{w.y * r.z - w.z * r.y, w.z * r.x - w.x * r.z, w.x * r.y - w.y * r.x};
      d.ball.omega = w;
      d.inv_mass = 1.0 / body.mass;
      d.inv_inertia = 1.0 / std::min({body.inertia.x, body.inertia.y, body.inertia.z});
    }
    out.push_back(d);
  }
  std::sort(out.begin(), out.end(), [](const DeviceBall& a, const DeviceBall& b) { return a.ball.id < b.ball.id; });
  return out;
}

void mesh_cells_host(const SceneTables& t, std::vector<int>& starts, std::vector<int>& tris) {
  starts.assign(1, 0);
  tris.clear();
  int first = 0;
  for (int s = 0; s < MC_MESH_SETS; ++s) {
    std::vector<int> st, tr;
    mesh_bin_host(t.mesh_grid_specs[s], t.mesh_set_triangles[s], first, st, tr);
    const int base = static_cast<int>(tris.size());
    starts.pop_back();
    for (int v : st) starts.push_back(base + v);
    tris.insert(tris.end(), tr.begin(), tr.end());
    first += static_cast<int>(t.mesh_set_triangles[s].size());
  }
}

}  // namespace mc
