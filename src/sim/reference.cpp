#include "sim/reference.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

#include "core/layout.hpp"
#include "sim/tables.h"

namespace mc {

using namespace mc::f64;

struct ReferenceSolver::State {
  SimParams sp{};
  std::vector<PairParams> pairs;
  std::vector<LifterPolygon> lifters;
  // Mesh walls, their cells binned on the host (core/wall_mesh.h)
  std::array<MeshGrid, MC_MESH_SETS> mesh_grid{};
  std::vector<MeshTriangle> mesh_tris;
  std::vector<int2> mesh_feature;
  std::vector<int> mesh_adj;
  std::vector<int> mesh_cell_start, mesh_cell_tris;
  std::vector<PairParams> mesh_pairs;
  std::vector<real4> pos, vel, omega, force, torque, accum, pos_at_build;
  std::vector<int2> info;
  // Rigid bodies (cl/body.h): balls keep their order here, so a component's
  // slot is its id.
  int n_bodies = 0;
  std::vector<int> body_of, slot_of;
  std::vector<int2> body_comp;
  std::vector<real4> comp_offset, body_pos, body_vel, body_quat, body_angmom, body_inv_inertia, body_force,
      body_torque;
  std::vector<int> wall_key;
  std::vector<int> wall_rec;    // each slot's contact record
  std::vector<int> neigh_start, neigh_count, neigh_index;  // partners j > i
  std::vector<int> neigh_rec;   // each touching entry's record
  std::vector<real> pair_out;    // the partner's side, MC_SLOT_REALS per entry
  std::vector<int> in_start, neigh_rev;  // each ball's incoming slots (n + 1); each entry's slot
  std::map<std::pair<int, int>, int> history;  // (i, j) → record, by index
  // The books: records are never packed here (a few thousand steps at most).
  std::vector<real4> records;
  int rec_state[2] = {0, 0};
  BookParams book_params{};
  std::vector<uint> spectra, liner, impact_profile;
  int status = 0;
  double time = 0, angle = 0, omega_mill = 0;
  int n = 0;

  void build_lists() {
    // Every pair within touching distance, once (in the lower ball's list),
    // with its spring carried over; and the entries that hold each ball.
    neigh_index.clear();
    neigh_rec.clear();
    std::vector<std::vector<int>> incoming(n);
    for (int i = 0; i < n; ++i) {
      neigh_start[i] = static_cast<int>(neigh_index.size());
      for (int j = i + 1; j < n; ++j) {
        const double dx = pos[i].x - pos[j].x, dy = pos[i].y - pos[j].y;
        const double dz = image_dz(&sp, pos[i].z - pos[j].z);  // the minimum image in a slice
        const double cut = pos[i].w + pos[j].w;
        if (dx * dx + dy * dy + dz * dz >= cut * cut) continue;
        if (MC_IS_COMPONENT(&sp, info[i].x) && MC_IS_COMPONENT(&sp, info[j].x) &&
            body_of[info[i].x - sp.first_component] == body_of[info[j].x - sp.first_component])
          continue;
        auto it = history.find({i, j});
        incoming[j].push_back(static_cast<int>(neigh_index.size()));
        neigh_index.push_back(it != history.end() ? MC_LINK_TOUCHED(j) : j);
        neigh_rec.push_back(it != history.end() ? it->second : MC_NO_RECORD);
      }
      neigh_count[i] = static_cast<int>(neigh_index.size()) - neigh_start[i];
    }
    pair_out.assign(MC_SLOT_REALS * neigh_index.size(), real{0});
    neigh_rev.assign(neigh_index.size(), 0);
    int q = 0;
    for (int j = 0; j < n; ++j) {
      in_start[j] = q;
      for (int k : incoming[j]) neigh_rev[k] = q++;
    }
    in_start[n] = q;
  }
  void save_history() {
    // The records of the pairs that touch now (the others have none).
    history.clear();
    for (int i = 0; i < n; ++i)
      for (int k = neigh_start[i]; k < neigh_start[i] + neigh_count[i]; ++k)
        if (MC_LINK_TOUCHING(neigh_index[k])) history[{i, MC_LINK_PARTNER(neigh_index[k])}] = neigh_rec[k];
  }
  void forces() {
    build_lists();
    // Room for every listed pair and wall slot to begin a contact.
    const std::size_t room = rec_state[0] + neigh_index.size() + wall_key.size();
    if (records.size() < 2 * room) records.resize(2 * room + 1024);
    Books books;
    books.records = records.data();
    books.rec_state = rec_state;
    books.capacity = static_cast<int>(records.size() / 2);
    books.mark = books.capacity;
    books.spectra = spectra.data();
    books.liner = liner.data();
    books.impact_profile = impact_profile.data();
    books.bp = &book_params;
    books.status = &status;
    MillState mill{std::cos(angle), std::sin(angle), omega_mill};
    Meshes meshes;
    meshes.grid = mesh_grid.data();
    meshes.tris = mesh_tris.data();
    meshes.feature = mesh_feature.data();
    meshes.adj = mesh_adj.data();
    meshes.cell_start = mesh_cell_start.data();
    meshes.cell_tris = mesh_cell_tris.data();
    meshes.pairs = mesh_pairs.data();
    for (int i = 0; i < n; ++i)
      ball_forces(i, &sp, pairs.data(), lifters.data(), mill, pos.data(), vel.data(), omega.data(),
                  info.data(), neigh_start.data(), neigh_count.data(), neigh_index.data(),
                  neigh_rec.data(), neigh_rev.data(), pair_out.data(), wall_key.data(), wall_rec.data(),
                  force.data(), torque.data(), accum.data(), &books, &meshes);
    for (int j = 0; j < n; ++j)
      ball_reactions(j, in_start.data(), pair_out.data(), force.data(), torque.data(), accum.data());
    for (int b = 0; b < n_bodies; ++b)
      body_sum(b, &sp, pos.data(), force.data(), torque.data(), slot_of.data(), body_comp.data(), body_pos.data(),
               body_force.data(), body_torque.data());
    save_history();
  }
};

ReferenceSolver::ReferenceSolver(const Scene& scene) : s_(std::make_unique<State>()) {
  State& s = *s_;
  SceneTables tables = scene_tables(scene);
  s.n = static_cast<int>(scene.balls.size());
  s.sp = tables.params;
  s.pairs = std::move(tables.pairs);
  s.lifters = std::move(tables.lifters);
  s.mesh_grid = tables.mesh_grid;
  s.mesh_tris = tables.mesh_tris;
  s.mesh_feature = tables.mesh_feature;
  s.mesh_adj = tables.mesh_adj;
  s.mesh_pairs = tables.mesh_pairs;
  mesh_cells_host(tables, s.mesh_cell_start, s.mesh_cell_tris);
  if (s.mesh_cell_tris.empty()) s.mesh_cell_tris.push_back(0);
  s.book_params = tables.books;
  s.spectra.assign(2 * static_cast<std::size_t>(s.book_params.n_types + 1) * MC_SPECTRA_BINS * MC_SPECTRA_FIELDS, 0u);
  s.liner.assign(2 * (static_cast<std::size_t>(s.book_params.n_elements) +
                      static_cast<std::size_t>(scene.walls.lifters.size()) * MC_WEAR_STATIONS) *
                     MC_LINER_FIELDS,
                 0u);
  s.impact_profile.assign(2 * static_cast<std::size_t>(MC_IMPACT_BINS) * (1 + s.book_params.axial_bins), 0u);
  const SimParams& sp = s.sp;

  const std::vector<DeviceBall> balls = device_balls(scene);
  const int n = s.n;
  s.pos.resize(n); s.vel.resize(n); s.omega.resize(n); s.force.resize(n); s.torque.resize(n);
  s.accum.assign(n, real4{0, 0, 0, 0}); s.pos_at_build.resize(n); s.info.resize(n);
  s.wall_key.assign(static_cast<std::size_t>(n) * MC_MAX_WALL_CONTACTS, MC_WALL_NONE);
  s.wall_rec.assign(static_cast<std::size_t>(n) * MC_MAX_WALL_CONTACTS, MC_NO_RECORD);
  s.neigh_start.assign(n, 0); s.neigh_count.assign(n, 0);
  s.in_start.assign(n + 1, 0);
  for (int i = 0; i < n; ++i) {
    const Ball& b = balls[i].ball;
    s.pos[i] = {b.position.x, b.position.y, wrap_z(&s.sp, b.position.z), b.radius};
    s.vel[i] = {b.velocity.x, b.velocity.y, b.velocity.z, balls[i].inv_mass};
    s.omega[i] = {b.omega.x, b.omega.y, b.omega.z, balls[i].inv_inertia};
    s.info[i] = {b.id, b.material};
  }
  {
    BodyTables bt = body_tables(scene);
    s.n_bodies = bt.n_bodies;
    s.body_of = bt.body_of;
    s.slot_of.resize(bt.body_of.size());
    for (std::size_t c = 0; c < s.slot_of.size(); ++c) s.slot_of[c] = bt.first_component + static_cast<int>(c);
    s.body_comp = bt.body_comp;
    s.comp_offset = bt.comp_offset;
    s.body_pos = bt.body_pos;
    for (auto& c : s.body_pos) c.z = wrap_z(&s.sp, c.z);
    s.body_vel = bt.body_vel;
    s.body_quat = bt.body_quat;
    s.body_angmom = bt.body_angmom;
    s.body_inv_inertia = bt.body_inv_inertia;
    s.body_force.assign(s.body_pos.size(), real4{0, 0, 0, 0});
    s.body_torque = s.body_force;
  }
  s.pos_at_build = s.pos;
  s.angle = scene.mill_angle;
  s.omega_mill = scene.mill_omega;
  s.forces();
  const double h = 0.5 * sp.dt;
  for (int i = 0; i < n; ++i) {
    s.vel[i].x -= h * s.force[i].x * s.vel[i].w;
    s.vel[i].y -= h * s.force[i].y * s.vel[i].w;
    s.vel[i].z -= h * s.force[i].z * s.vel[i].w;
    s.omega[i].x -= h * s.torque[i].x * s.omega[i].w;
    s.omega[i].y -= h * s.torque[i].y * s.omega[i].w;
    s.omega[i].z -= h * s.torque[i].z * s.omega[i].w;
  }
  for (int b = 0; b < s.n_bodies; ++b) {
    s.body_vel[b].x -= h * s.body_force[b].x * s.body_pos[b].w;
    s.body_vel[b].y -= h * s.body_force[b].y * s.body_pos[b].w;
    s.body_vel[b].z -= h * s.body_force[b].z * s.body_pos[b].w;
    const real3 tb = quat_rotate_inverse(s.body_quat[b], xyz_of(s.body_torque[b]));
    s.body_angmom[b].x -= h * tb.x;
    s.body_angmom[b].y -= h * tb.y;
    s.body_angmom[b].z -= h * tb.z;
  }
}

ReferenceSolver::~ReferenceSolver() = default;

void ReferenceSolver::advance(long steps) {
  State& s = *s_;
  for (long k = 0; k < steps; ++k) {
    for (int i = 0; i < s.n; ++i)
      if (!MC_IS_COMPONENT(&s.sp, s.info[i].x))
        s.status |= integrate_ball(i, &s.sp, s.pos.data(), s.vel.data(), s.omega.data(),
                                   s.force.data(), s.torque.data(), s.pos_at_build.data());
    for (int b = 0; b < s.n_bodies; ++b)
      s.status |= body_move(b, &s.sp, s.pos.data(), s.vel.data(), s.omega.data(), s.pos_at_build.data(),
                            s.slot_of.data(), s.body_comp.data(), s.comp_offset.data(), s.body_pos.data(),
                            s.body_vel.data(), s.body_quat.data(), s.body_angmom.data(), s.body_inv_inertia.data(),
                            s.body_force.data(), s.body_torque.data());
    if (s.status & MC_FLAG_NOT_FINITE) throw std::runtime_error("reference: blow-up");
    s.status = 0;
    s.time += s.sp.dt;
    s.angle = std::fmod(s.angle + s.omega_mill * s.sp.dt, 2.0 * M_PI);
    s.forces();
  }
}

std::vector<BallState> ReferenceSolver::balls() const {
  const State& s = *s_;
  std::vector<BallState> out(s.n);
  for (int i = 0; i < s.n; ++i)
    out[i] = ball_state(s.info[i].x, s.info[i].y, s.pos[i], s.vel[i], s.omega[i], s.force[i], s.torque[i], s.sp.dt);
  std::sort(out.begin(), out.end(), [](const BallState& a, const BallState& b) { return a.id < b.id; });
  return out;
}

std::vector<BodyState> ReferenceSolver::bodies() const {
  const State& s = *s_;
  std::vector<BodyState> out;
  for (int b = 0; b < s.n_bodies; ++b)
    out.push_back(body_state(s.body_pos[b], s.body_vel[b], s.body_quat[b], s.body_angmom[b], s.body_inv_inertia[b],
                             s.body_force[b], s.body_torque[b], s.sp.dt));
  return out;
}

double ReferenceSolver::time_s() const { return s_->time; }

}  // namespace mc
