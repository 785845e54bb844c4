// The solver set up: its kernels and buffers, the parameters and tables
// uploaded from a scene, the mesh walls binned, its device memory counted.
#include "sim/solver_impl.h"

namespace mc::detail {

template <class Real>
compute::BuildOptions SolverImpl<Real>::options(const Scene& scene) {
  compute::BuildOptions o;
  o.define("MC_SCAN_WG", kScanWG).define("MC_REDUCE_WG", kReduceWG).define("MC_FG_WG", kForcesGroupWG);
  // The law is fixed for a run: built in, the force kernel drops the other
  // law's arithmetic (setup_params checks that a new scene keeps it).
  o.define("MC_LAW", scene.numerics.law == ContactLaw::hertz ? MC_LAW_HERTZ : MC_LAW_LINEAR);
  o.define("MC_ENERGY_BOOKS", scene.numerics.energy_books ? 1 : 0);
  return o;
}

template <class Real>
SolverImpl<Real>::SolverImpl(compute::Context& ctx, const Scene& scene)
    : ctx_(ctx),
      program_(ctx,
               {"scan.cl", "binning.cl", "contacts.cl", "forces.cl", "motion.cl", "reductions.cl", "profile.cl",
                "mesh_bin.cl"},
               options(scene), std::is_same_v<Real, double>),
      n_(static_cast<int>(scene.balls.size())),
      law_(scene.numerics.law),
      dt_(scene.numerics.dt),
      mill_angle_(scene.mill_angle),
      mill_omega_(scene.mill_omega),
      params_(ctx, 1, "params"),
      pairs_(ctx, 1, "pairs"),
      lifters_(ctx, 1, "lifters"),
      mesh_grid_(ctx, MC_MESH_SETS, "mesh grids"),
      mesh_tris_(ctx, 1, "mesh triangles"),
      mesh_feature_(ctx, 1, "mesh features"),
      mesh_adj_(ctx, 1, "mesh feature triangles"),
      mesh_cell_start_(ctx, 2, "mesh cell starts"),
      mesh_cell_tris_(ctx, 1, "mesh cell triangles"),
      mesh_pairs_(ctx, 1, "mesh pairs"),
      pos_(ctx, n_, "positions"),
      vel_(ctx, n_, "velocities"),
      omega_(ctx, n_, "angular velocities"),
      force_(ctx, n_, "forces"),
      torque_(ctx, n_, "torques"),
      accum_(ctx, n_, "accumulators"),
      pos_at_build_(ctx, n_, "positions at list build"),
      info_(ctx, n_, "ids and materials"),
      body_of_(ctx, 1, "component bodies"),
      slot_of_(ctx, 1, "component slots"),
      comp_offset_(ctx, 1, "component offsets"),
      body_comp_(ctx, 1, "body components"),
      body_pos_(ctx, 1, "body centres"),
      body_vel_(ctx, 1, "body velocities"),
      body_quat_(ctx, 1, "body orientations"),
      body_angmom_(ctx, 1, "body angular momenta"),
      body_inv_inertia_(ctx, 1, "body inverse inertias"),
      body_force_(ctx, 1, "body forces"),
      body_torque_(ctx, 1, "body torques"),
      wall_key_(ctx, static_cast<std::size_t>(n_) * MC_MAX_WALL_CONTACTS, "wall contact keys"),
      wall_rec_(ctx, static_cast<std::size_t>(n_) * MC_MAX_WALL_CONTACTS, "wall contact records"),
      ball_cell_(ctx, n_, "ball cell"),
      ball_rank_(ctx, n_, "ball rank in cell"),
      sorted_index_(ctx, n_, "sorted index"),
      neigh_start_(ctx, n_, "neighbour start"),
      neigh_count_(ctx, n_, "neighbour count"),
      neigh_index_(ctx, static_cast<std::size_t>(n_) + 64, "neighbour index"),
      neigh_rec_(ctx, static_cast<std::size_t>(n_) + 64, "neighbour records"),
      records_(ctx, 2, "contact records"),
      rec_state_(ctx, 2, "contact record count"),
      book_params_(ctx, 1, "book parameters"),
      pair_out_(ctx, slot_reals(static_cast<std::size_t>(n_) + 64), "pair reactions"),
      in_start_(ctx, static_cast<std::size_t>(n_) + 1, "incoming start"),
      neigh_rev_(ctx, static_cast<std::size_t>(n_) + 64, "neighbour slot"),
      status_(ctx, 1, "status"),
      partial_(ctx, (static_cast<std::size_t>(n_) / kReduceWG + 1) * kObservables, "reduction partials"),
      profile_(ctx, kProfileBins, "contact profile"),
      counts_(ctx, 3, "contact counts"),
      status_host_(ctx),
      scan_(program_, ctx, std::max<std::size_t>(n_, 1)),
      k_bin_clear_(program_, "bin_clear"),
      k_bin_count_(program_, "bin_count"),
      k_bin_scatter_(program_, "bin_scatter"),
      k_bin_sort_(program_, "bin_sort_cells"),
      k_gather4_(program_, "gather_real4"),
      k_gather2_(program_, "gather_int2"),
      k_gather_wall_(program_, "gather_wall_slot"),
      k_put_wall_(program_, "put_wall_slot"),
      k_contacts_count_(program_, "contacts_count"),
      k_contacts_fill_(program_, "contacts_fill"),
      k_forces_(program_, "forces"),
      k_motion_(program_, "motion"),
      k_reduce_(program_, "reduce_observables"),
      k_layout_(program_, "layout_sizes"),
      k_profile_(program_, "profile_contacts"),
      k_count_contacts_(program_, "count_contacts"),
      k_clear_flag_(program_, "clear_status_flag"),
      k_carry_count_(program_, "carry_count"),
      k_carry_fill_(program_, "carry_fill"),
      k_in_count_(program_, "in_count"),
      k_in_scatter_(program_, "in_scatter"),
      k_in_sort_(program_, "in_sort"),
      k_reactions_(program_, "reactions"),
      k_react_motion_(program_, "react_motion"),
      k_forces_grouped_(program_, "forces_grouped"),
      k_records_count_(program_, "records_count"),
      k_records_pack_(program_, "records_pack"),
      k_mesh_bin_(program_, "mesh_bin"),
      k_mesh_copy_(program_, "mesh_copy"),
      k_mesh_sort_(program_, "mesh_sort_cells"),
      k_body_slots_(program_, "body_slots"),
      k_body_sums_(program_, "body_sums"),
      k_body_motion_(program_, "body_motion") {
  choose_from_environment(ctx);
  if (n_ == 0) throw std::invalid_argument("scene: no balls");
  check_layouts(ctx);
  setup_params(scene);
  upload_charge(scene);
  clear_contacts();
  rebuild();
  forces();
  start_leapfrog();
  observe(true);  // start the first interval here
}

// MILLCHARGE_FORCES, MILLCHARGE_FUSED_MOTION and MILLCHARGE_STATUS_EVERY:
// the kernel variants and how often the host reads the status word.
template <class Real>
void SolverImpl<Real>::choose_from_environment(compute::Context& ctx) {
  if (const char* e = std::getenv("MILLCHARGE_FORCES"); e && *e) {
    const std::string v = e;
    if (v != "ball" && v != "grouped")
      throw std::invalid_argument("MILLCHARGE_FORCES=" + v + ": expected ball (the default) or grouped");
    grouped_forces_ = v == "grouped";
  }
  if (const char* e = std::getenv("MILLCHARGE_FUSED_MOTION"); e && *e) {
    const std::string v = e;
    if (v != "0" && v != "1")
      throw std::invalid_argument("MILLCHARGE_FUSED_MOTION=" + v + ": expected 1 (the default) or 0");
    fuse_reactions_ = v == "1";
  }
  status_every_ = ctx.info().type == "gpu" ? kGpuStatusEvery : 1;
  if (const char* e = std::getenv("MILLCHARGE_STATUS_EVERY"); e && *e) {
    char* end = nullptr;
    const long k = std::strtol(e, &end, 10);
    if (*end != '\0' || k < 1 || k > 64)
      throw std::invalid_argument(std::string("MILLCHARGE_STATUS_EVERY=") + e + ": expected a whole number from 1 to 64");
    status_every_ = static_cast<int>(k);
  }
}

// The device's struct sizes must equal the host mirrors'.
template <class Real>
void SolverImpl<Real>::check_layouts(compute::Context& ctx) {
  Buffer<int> sizes(ctx, 7, "layout sizes");
  k_layout_.args(sizes).launch(1);
  sizes.read_from_device();
  if (sizes.host[0] != static_cast<int>(sizeof(typename L::SimParams)) ||
      sizes.host[1] != static_cast<int>(sizeof(typename L::PairParams)) ||
      sizes.host[2] != static_cast<int>(sizeof(typename L::LifterPolygon)) ||
      sizes.host[3] != static_cast<int>(sizeof(real4)) ||
      sizes.host[4] != static_cast<int>(sizeof(typename L::BookParams)) ||
      sizes.host[5] != static_cast<int>(sizeof(typename L::MeshTriangle)) ||
      sizes.host[6] != static_cast<int>(sizeof(typename L::MeshGrid)))
    throw compute::Error("struct layouts differ between host and device (cl/layout.h)");

}

// The balls and the bodies (clumps) of the scene, onto the device.
template <class Real>
void SolverImpl<Real>::upload_charge(const Scene& scene) {
  // A slice keeps its balls and bodies in [0, period) (cl/periodic.h).
  auto wrap = [&](double z) {
    return scene.walls.periodic ? z - scene.walls.length * std::floor(z / scene.walls.length) : z;
  };
  const std::vector<DeviceBall> balls = device_balls(scene);
  for (int i = 0; i < n_; ++i) {
    const Ball& b = balls[i].ball;
    if (b.body < 0) total_mass_ += 1.0 / balls[i].inv_mass;
    pos_.host[i] = {Real(b.position.x), Real(b.position.y), Real(wrap(b.position.z)), Real(b.radius)};
    vel_.host[i] = {Real(b.velocity.x), Real(b.velocity.y), Real(b.velocity.z), Real(balls[i].inv_mass)};
    omega_.host[i] = {Real(b.omega.x), Real(b.omega.y), Real(b.omega.z), Real(balls[i].inv_inertia)};
    info_.host[i] = {b.id, b.material};
  }
  {
    const BodyTables bt = body_tables(scene);
    n_bodies_ = bt.n_bodies;
    auto put4 = [](const std::vector<f64::real4>& from, Buffer<real4>& to) {
      to.resize(from.size());
      for (std::size_t k = 0; k < from.size(); ++k)
        to.host[k] = {Real(from[k].x), Real(from[k].y), Real(from[k].z), Real(from[k].w)};
      to.write_to_device();
    };
    body_of_.resize(bt.body_of.size());
    body_of_.host = bt.body_of;
    body_of_.write_to_device();
    slot_of_.resize(bt.body_of.size());
    slot_of_.write_to_device();
    put4(bt.comp_offset, comp_offset_);
    body_comp_.resize(bt.body_comp.size());
    for (std::size_t k = 0; k < bt.body_comp.size(); ++k) body_comp_.host[k] = {bt.body_comp[k].x, bt.body_comp[k].y};
    body_comp_.write_to_device();
    std::vector<f64::real4> centres = bt.body_pos;
    for (auto& c : centres) c.z = wrap(c.z);
    put4(centres, body_pos_);
    put4(bt.body_vel, body_vel_);
    put4(bt.body_quat, body_quat_);
    put4(bt.body_angmom, body_angmom_);
    put4(bt.body_inv_inertia, body_inv_inertia_);
    for (auto* b : {&body_force_, &body_torque_}) {
      b->resize(bt.body_pos.size());
      b->write_to_device();
    }
    for (const Body& b : scene.bodies) total_mass_ += b.mass;
  }
}

// No wall contact, no record, empty lists and a clear status word: the
// first rebuild takes these as the previous state.
template <class Real>
void SolverImpl<Real>::clear_contacts() {
  std::fill(wall_key_.host.begin(), wall_key_.host.end(), MC_WALL_NONE);
  std::fill(wall_rec_.host.begin(), wall_rec_.host.end(), MC_NO_RECORD);
  for (auto* b : {&pos_, &vel_, &omega_, &force_, &torque_, &accum_}) b->write_to_device();
  info_.write_to_device();
  wall_key_.write_to_device();
  wall_rec_.write_to_device();
  rec_state_.write_to_device();
  // Empty lists: the first rebuild takes these as the previous lists.
  for (auto* b : {&neigh_start_, &neigh_count_}) b->write_to_device();
  status_.write_to_device();
  profile_.write_to_device();

}

// Leapfrog keeps v half a step behind x: v(−½) = v(0) − ½·dt·F(0)/m, and
// likewise each body's v and L from F(0), T(0).
template <class Real>
void SolverImpl<Real>::start_leapfrog() {
  for (auto* b : {&vel_, &omega_, &force_, &torque_}) b->read_from_device();
  for (int i = 0; i < n_; ++i) {
    auto& v = vel_.host[i];
    const auto& f = force_.host[i];
    v.x -= Real(0.5) * Real(dt_) * f.x * v.w;
    v.y -= Real(0.5) * Real(dt_) * f.y * v.w;
    v.z -= Real(0.5) * Real(dt_) * f.z * v.w;
    auto& w = omega_.host[i];
    const auto& t = torque_.host[i];
    w.x -= Real(0.5) * Real(dt_) * t.x * w.w;
    w.y -= Real(0.5) * Real(dt_) * t.y * w.w;
    w.z -= Real(0.5) * Real(dt_) * t.z * w.w;
  }
  vel_.write_to_device();
  omega_.write_to_device();
  if (n_bodies_ > 0) {  // likewise each body: v(−½) and L(−½) from F(0), T(0)
    for (auto* b : {&body_vel_, &body_angmom_, &body_force_, &body_torque_, &body_pos_, &body_quat_})
      b->read_from_device();
    const Real h = Real(0.5) * Real(dt_);
    for (int k = 0; k < n_bodies_; ++k) {
      auto& v = body_vel_.host[k];
      const auto& f = body_force_.host[k];
      const Real inv_m = body_pos_.host[k].w;
      v.x -= h * f.x * inv_m;
      v.y -= h * f.y * inv_m;
      v.z -= h * f.z * inv_m;
      const auto& q = body_quat_.host[k];
      const auto& t = body_torque_.host[k];
      const Vec3 tb = rotate({-double(q.x), -double(q.y), -double(q.z), double(q.w)}, Vec3{t.x, t.y, t.z});
      auto& L = body_angmom_.host[k];
      L.x -= h * Real(tb.x);
      L.y -= h * Real(tb.y);
      L.z -= h * Real(tb.z);
    }
    body_vel_.write_to_device();
    body_angmom_.write_to_device();
  }
}

// A table of pair parameters in the solver's precision, on the device.
template <class Buf>
void upload_pairs(const std::vector<f64::PairParams>& from, Buf& to) {
  using Real = decltype(to.host[0].kn);
  to.resize(from.size());
  for (std::size_t k = 0; k < from.size(); ++k) {
    const f64::PairParams& c = from[k];
    to.host[k] = {Real(c.kn),      Real(c.kt_over_kn), Real(c.e_star),  Real(c.g_star),
                  Real(c.damping), Real(c.mu_slide),   Real(c.mu_roll), Real(c.restitution)};
  }
  to.write_to_device();
}

template <class Real>
void SolverImpl<Real>::setup_params(const Scene& scene) {
  const SceneTables t = scene_tables(scene);
  upload_pairs(t.pairs, pairs_);
  lifters_.resize(t.lifters.size());
  for (std::size_t k = 0; k < t.lifters.size(); ++k) {
    lifters_.host[k].n_vertices = t.lifters[k].n_vertices;
    for (int v = 0; v < MC_POLY_MAX_VERTS; ++v)
      lifters_.host[k].vertices[v] = {Real(t.lifters[k].vertices[v].x), Real(t.lifters[k].vertices[v].y)};
    const auto& b = t.lifters[k].bound;
    lifters_.host[k].bound = {Real(b.x), Real(b.y), Real(b.z), Real(b.w)};
    const auto& w = t.lifters[k].wear;
    lifters_.host[k].wear = {Real(w.x), Real(w.y), Real(w.z), Real(0)};
    const auto& f = t.lifters[k].faces;
    lifters_.host[k].faces = {Real(f.x), Real(f.y), Real(f.z), Real(0)};
  }
  lifters_.write_to_device();
  setup_meshes(t);

  const f64::BookParams& tb = t.books;
  auto& bp = book_params_.host[0];
  bp = {};
  bp.energy_unit = Real(tb.energy_unit);
  bp.wear_unit = Real(tb.wear_unit);
  bp.wear_k = Real(tb.wear_k);
  bp.plate_ring_width = Real(tb.plate_ring_width);
  bp.strike_speed = Real(tb.strike_speed);
  bp.axial_span = Real(tb.axial_span);
  bp.n_types = tb.n_types;
  bp.n_elements = tb.n_elements;
  bp.shell_bins = tb.shell_bins;
  bp.axial_bins = tb.axial_bins;
  bp.plate_rings = tb.plate_rings;
  bp.plate_sectors = tb.plate_sectors;
  bp.first_lifter_element = tb.first_lifter_element;
  bp.first_plate_element = tb.first_plate_element;
  bp.first_station = tb.first_station;
  book_params_.write_to_device();
  energy_unit_ = tb.energy_unit;
  wear_unit_ = tb.wear_unit;
  n_types_ = tb.n_types;
  n_elements_ = tb.n_elements;
  n_stations_ = scene.walls.lifters.empty() ? 0 : static_cast<int>(scene.walls.lifters.size()) * MC_WEAR_STATIONS;
  spectra_ = Buffer<std::uint32_t>(ctx_, 2 * static_cast<std::size_t>(n_types_ + 1) * MC_SPECTRA_BINS * MC_SPECTRA_FIELDS,
                                   "collision spectra");
  liner_ = Buffer<std::uint32_t>(ctx_, 2 * static_cast<std::size_t>(n_elements_ + n_stations_) * MC_LINER_FIELDS,
                                 "liner sums");
  impact_axial_bins_ = tb.axial_bins;  // the whole mill's profile, then one per axial bin
  impact_profile_ = Buffer<std::uint32_t>(
      ctx_, 2 * static_cast<std::size_t>(MC_IMPACT_BINS) * (1 + static_cast<std::size_t>(impact_axial_bins_)),
      "impact profile");
  for (auto* b : {&spectra_, &liner_, &impact_profile_}) b->write_to_device();

  const f64::SimParams& tp = t.params;
  auto& sp = params_.host[0];
  sp = {};
  sp.gravity = {Real(tp.gravity.x), Real(tp.gravity.y), Real(tp.gravity.z), Real(0)};
  sp.dt = Real(tp.dt);
  sp.skin = Real(tp.skin);
  sp.shell_radius = Real(tp.shell_radius);
  sp.length = Real(tp.length);
  sp.lifter_reach = Real(tp.lifter_reach);
  sp.lifter_first_angle = Real(tp.lifter_first_angle);
  sp.lifter_spacing = Real(tp.lifter_spacing);
  sp.period = Real(tp.period);
  sp.escape_z0 = Real(tp.escape_z0);
  sp.escape_z1 = Real(tp.escape_z1);
  sp.plate_nodes = tp.plate_nodes;
  for (int k = 0; k < 2 * MC_PLATE_NODES; ++k) sp.plate_depth[k] = Real(tp.plate_depth[k]);
  sp.n_balls = tp.n_balls;
  sp.n_materials = tp.n_materials;
  sp.n_lifters = tp.n_lifters;
  sp.first_component = tp.first_component;
  sp.n_bodies = tp.n_bodies;
  sp.law = tp.law;
  // Reads every status_every_ steps need balls that take twice as many
  // steps to cross half the skin; a scene that starts faster reads every
  // step (and the motion kernel's MC_FLAG_FAST says so later).
  double v_max = 0;
  for (const Ball& b : scene.balls) v_max = std::max(v_max, b.velocity.norm());
  if (status_every_ > 1 && 2.0 * status_every_ * tp.dt * v_max >= 0.5 * tp.skin) status_every_ = 1;
  sp.status_every = status_every_;
  if (scene.numerics.law != law_)
    throw std::invalid_argument("the contact law cannot change in a running solver (its kernels are built for one)");

  double r_max = 0;
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const Ball& b : scene.balls) {
    r_max = std::max(r_max, b.radius);
    lo = {std::min(lo.x, b.position.x), std::min(lo.y, b.position.y), std::min(lo.z, b.position.z)};
    hi = {std::max(hi.x, b.position.x), std::max(hi.y, b.position.y), std::max(hi.z, b.position.z)};
  }
  const Walls& w = scene.walls;
  const double skin = tp.skin;

  // Grid over the mill (or the balls when there is no mill), one cell of
  // margin; cells at least 2·r_max + skin wide. A cap on the cell count keeps
  // memory bounded for balls spread far apart (clamping stays correct). In a
  // periodic slice the z cells tile the period exactly from z = 0, and there
  // are at least 3 of them, so that the stencil visits no cell twice (the
  // case's shortest slice, core/mill_case.h, keeps to this).
  if (w.shell_radius > 0) {
    lo.x = std::min(lo.x, -w.shell_radius);
    lo.y = std::min(lo.y, -w.shell_radius);
    hi.x = std::max(hi.x, w.shell_radius);
    hi.y = std::max(hi.y, w.shell_radius);
  }
  if (w.length > 0) {  // and worn plates' dishes behind them
    lo.z = std::min(lo.z, w.periodic ? 0.0 : tp.escape_z0);
    hi.z = std::max(hi.z, w.periodic ? w.length : std::max(w.length, tp.escape_z1));
  }
  if (tp.period <= 0 && t.mesh_z1 >= t.mesh_z0) {  // the grid spans the meshes too (cone ends reach past the belly)
    lo.z = std::min(lo.z, t.mesh_z0);
    hi.z = std::max(hi.z, t.mesh_z1);
  }
  const double period = tp.period;
  auto z_cells = [&](double c) { return static_cast<long>(std::floor(period / c)); };
  double cell = 2.0 * r_max + skin;
  if (period > 0) {
    if (z_cells(cell) < 3) {
      std::ostringstream m;
      m << "mill.length: a periodic slice of " << period << " m holds " << z_cells(cell)
        << " grid cells of 2 r_max + skin = " << cell << " m along the axis and needs at least 3: make it at least "
        << 3 * cell << " m long";
      throw std::invalid_argument(m.str());
    }
    cell = period / z_cells(cell);
  }
  auto dims = [&](double c) {
    return std::array<long, 3>{static_cast<long>(std::ceil((hi.x - lo.x) / c)) + 3,
                               static_cast<long>(std::ceil((hi.y - lo.y) / c)) + 3,
                               period > 0 ? z_cells(c) : static_cast<long>(std::ceil((hi.z - lo.z) / c)) + 3};
  };
  const long max_cells = std::max<long>(4L * n_, 1L << 16);
  auto d = dims(cell);
  while (d[0] * d[1] * d[2] > max_cells) {
    if (period > 0 && z_cells(cell * 1.25) < 3) break;  // the slice keeps its 3 cells
    cell *= 1.25;
    if (period > 0) cell = period / z_cells(cell);
    d = dims(cell);
  }
  sp.grid_origin = {Real(lo.x - cell), Real(lo.y - cell), Real(period > 0 ? 0.0 : lo.z - cell), Real(cell)};
  sp.grid_nx = static_cast<int>(d[0]);
  sp.grid_ny = static_cast<int>(d[1]);
  sp.grid_nz = static_cast<int>(d[2]);
  n_cells_ = static_cast<int>(d[0] * d[1] * d[2]);
  params_.write_to_device();

  cell_start_ = Buffer<int>(ctx_, static_cast<std::size_t>(n_cells_) + 1, "cell start");
}

// The mesh walls' tables, and their triangles binned on the device (they do
// not move in their set's frame, so this is done when the walls are set).
template <class Real>
void SolverImpl<Real>::setup_meshes(const SceneTables& t) {
  const std::size_t n_tris = t.mesh_tris.size();
  // What the device must hold for them (the cells' lists, sized after
  // counting, at least one entry a triangle): refused, naming the count,
  // when that alone exceeds what is left of the device's memory.
  const std::size_t need = n_tris * (sizeof(typename L::MeshTriangle) + 4 + 3 * sizeof(int2)) +
                           (static_cast<std::size_t>(t.mesh_cells) + 1) * sizeof(int);
  const std::size_t have = ctx_.memory_bytes() > ctx_.allocated_bytes() ? ctx_.memory_bytes() - ctx_.allocated_bytes() : 0;
  if (t.mesh_grid[0].n_triangles + t.mesh_grid[1].n_triangles > 0 && need > have) {
    char m[320];
    std::snprintf(m, sizeof m,
                  "walls.mesh: %zu triangles need %.1f MiB of device memory and %s has %.1f MiB left after the "
                  "balls; use coarser meshes (fewer triangles) or a device with more memory",
                  n_tris, need / 1048576.0, ctx_.info().name.c_str(), have / 1048576.0);
    throw std::invalid_argument(m);
  }
  mesh_grid_.resize(MC_MESH_SETS);
  for (int s = 0; s < MC_MESH_SETS; ++s) {
    const f64::MeshGrid& g = t.mesh_grid[s];
    auto& d = mesh_grid_.host[s];
    d = {};
    d.origin = {Real(g.origin.x), Real(g.origin.y), Real(g.origin.z), Real(g.origin.w)};
    d.core_r2 = Real(g.core_r2);
    d.core_z0 = Real(std::clamp(g.core_z0, -1e30, 1e30));
    d.core_z1 = Real(std::clamp(g.core_z1, -1e30, 1e30));
    d.reach = Real(g.reach);
    d.nx = g.nx;
    d.ny = g.ny;
    d.nz = g.nz;
    d.first_cell = g.first_cell;
    d.n_triangles = g.n_triangles;
  }
  mesh_grid_.write_to_device();
  mesh_tris_.resize(n_tris);
  for (std::size_t k = 0; k < n_tris; ++k) {
    const f64::MeshTriangle& m = t.mesh_tris[k];
    auto& d = mesh_tris_.host[k];
    d.a = {Real(m.a.x), Real(m.a.y), Real(m.a.z), Real(m.a.w)};
    d.b = {Real(m.b.x), Real(m.b.y), Real(m.b.z), Real(m.b.w)};
    d.c = {Real(m.c.x), Real(m.c.y), Real(m.c.z), Real(0)};
    d.n = {Real(m.n.x), Real(m.n.y), Real(m.n.z), Real(0)};
    for (int f = 0; f < 6; ++f) d.feat[f] = m.feat[f];
    d.pair_row = m.pair_row;
    d.element = m.element;
  }
  mesh_tris_.write_to_device();
  mesh_feature_.resize(t.mesh_feature.size());
  for (std::size_t k = 0; k < t.mesh_feature.size(); ++k) mesh_feature_.host[k] = {t.mesh_feature[k].x, t.mesh_feature[k].y};
  mesh_feature_.write_to_device();
  mesh_adj_.resize(t.mesh_adj.size());
  std::copy(t.mesh_adj.begin(), t.mesh_adj.end(), mesh_adj_.host.begin());
  mesh_adj_.write_to_device();
  upload_pairs(t.mesh_pairs, mesh_pairs_);

  const int n_cells = t.mesh_cells;
  mesh_cell_start_.resize(static_cast<std::size_t>(n_cells) + 1);
  const int n_real = t.mesh_grid[0].n_triangles + t.mesh_grid[1].n_triangles;
  if (n_real == 0) {
    std::fill(mesh_cell_start_.host.begin(), mesh_cell_start_.host.end(), 0);
    mesh_cell_start_.write_to_device();
    return;
  }
  const int n_first = t.mesh_grid[0].n_triangles;
  k_bin_clear_.args(mesh_cell_start_, n_cells + 1).launch(n_cells + 1);
  k_mesh_bin_.args(mesh_grid_, mesh_tris_, n_real, n_first, 0, mesh_cell_start_, mesh_cell_tris_).launch(n_real);
  scan_.run(mesh_cell_start_, mesh_cell_start_, n_cells + 1);
  const int total = scan_.read_total();
  mesh_cell_tris_.resize(std::max(total, 1));
  Buffer<int> cursor(ctx_, static_cast<std::size_t>(n_cells) + 1, "mesh cell cursors");
  k_mesh_copy_.args(n_cells + 1, mesh_cell_start_, cursor).launch(n_cells + 1);
  k_mesh_bin_.args(mesh_grid_, mesh_tris_, n_real, n_first, 1, cursor, mesh_cell_tris_).launch(n_real);
  k_mesh_sort_.args(n_cells, mesh_cell_start_, mesh_cell_tris_).launch(n_cells);
  ctx_.queue().finish();
}

template <class Real>
std::size_t SolverImpl<Real>::device_bytes() const {
  std::size_t b = params_.bytes() + pairs_.bytes() + lifters_.bytes() + mesh_grid_.bytes() + mesh_tris_.bytes() +
                  mesh_feature_.bytes() + mesh_adj_.bytes() + mesh_cell_start_.bytes() + mesh_cell_tris_.bytes() + mesh_pairs_.bytes() + status_.bytes() + profile_.bytes() + counts_.bytes() +
                  partial_.bytes() + scan_.bytes();
  for (const auto* x : {&pos_, &vel_, &omega_, &force_, &torque_, &accum_, &pos_at_build_, &comp_offset_, &body_pos_,
                        &body_vel_, &body_quat_, &body_angmom_, &body_inv_inertia_, &body_force_, &body_torque_})
    b += x->bytes();
  b += body_of_.bytes() + slot_of_.bytes() + body_comp_.bytes();
  b += pair_out_.bytes() + records_.bytes() + book_params_.bytes() + spectra_.bytes() + liner_.bytes() +
       impact_profile_.bytes();
  for (const auto* x : {&wall_key_, &wall_rec_, &neigh_rec_, &rec_state_, &cell_start_, &ball_cell_,
                        &ball_rank_, &sorted_index_, &neigh_start_, &neigh_count_, &neigh_index_,
                        &in_start_, &neigh_rev_})
    b += x->bytes();
  return b + info_.bytes();
}

// This file's members, for both precisions.
template void SolverImpl<float>::choose_from_environment(compute::Context& ctx);
template void SolverImpl<double>::choose_from_environment(compute::Context& ctx);
template void SolverImpl<float>::check_layouts(compute::Context& ctx);
template void SolverImpl<double>::check_layouts(compute::Context& ctx);
template void SolverImpl<float>::upload_charge(const Scene& scene);
template void SolverImpl<double>::upload_charge(const Scene& scene);
template void SolverImpl<float>::clear_contacts();
template void SolverImpl<double>::clear_contacts();
template void SolverImpl<float>::start_leapfrog();
template void SolverImpl<double>::start_leapfrog();
template compute::BuildOptions SolverImpl<float>::options(const Scene& scene);
template compute::BuildOptions SolverImpl<double>::options(const Scene& scene);
template SolverImpl<float>::SolverImpl(compute::Context& ctx, const Scene& scene);
template SolverImpl<double>::SolverImpl(compute::Context& ctx, const Scene& scene);
template void SolverImpl<float>::setup_params(const Scene& scene);
template void SolverImpl<double>::setup_params(const Scene& scene);
template void SolverImpl<float>::setup_meshes(const SceneTables& t);
template void SolverImpl<double>::setup_meshes(const SceneTables& t);
template std::size_t SolverImpl<float>::device_bytes() const;
template std::size_t SolverImpl<double>::device_bytes() const;

}  // namespace mc::detail
