#include "sim/solver.h"

#include <algorithm>
#include <cstdio>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "compute/program.h"
#include "sim/layout.hpp"
#include "sim/tables.h"

namespace mc {

using compute::Buffer;
using compute::Kernel;
using compute::LocalBytes;

namespace {

constexpr int kScanWG = 256;
constexpr int kReduceWG = 64;
constexpr int kForcesGroupWG = 64;  // balls per work-group of forces_grouped
constexpr int kObservables = 13;

// Exclusive prefix sum on the device (cl/scan.cl).
class Scan {
 public:
  Scan(compute::Program& prog, compute::Context& ctx, std::size_t max_n)
      : blocks_(prog, "scan_blocks"),
        block_sums_k_(prog, "scan_block_sums"),
        add_(prog, "scan_add"),
        block_sums_(ctx, max_n / kScanWG + 1, "scan block sums"),
        total_(ctx, 1, "scan total") {}

  template <class In>
  void run(const In& in, Buffer<int>& out, int n) {
    const int n_blocks = (n + kScanWG - 1) / kScanWG;
    if (static_cast<std::size_t>(n_blocks) > block_sums_.size())
      block_sums_.resize(n_blocks);
    blocks_.args(in, out, block_sums_, n).launch(static_cast<std::size_t>(n_blocks) * kScanWG, kScanWG);
    block_sums_k_.args(block_sums_, n_blocks, total_).launch(kScanWG, kScanWG);
    add_.args(out, block_sums_, n).launch(n);
  }
  int read_total() {
    total_.read_from_device();
    return total_.host[0];
  }
  std::size_t bytes() const { return block_sums_.bytes() + total_.bytes(); }

 private:
  Kernel blocks_, block_sums_k_, add_;
  Buffer<int> block_sums_, total_;
};

template <class Real>
class SolverImpl final : public Solver {
  using L = Layout<Real>;
  using real4 = typename L::real4;
  using int2 = typename L::int2;

 public:
  SolverImpl(compute::Context& ctx, const Scene& scene);

  void advance(long steps) override;
  std::vector<BallState> balls() override;
  std::vector<BodyState> bodies() override;
  Observables observe(bool reset) override;
  std::vector<std::pair<int, int>> neighbour_pairs() override;
  void set_mill_omega(double w) override { mill_omega_ = w; }
  void set_velocity_damping(double rate_per_s) override {
    params_.host[0].velocity_damping = Real(rate_per_s > 0 ? -std::expm1(-rate_per_s * dt_) : 0.0);
    params_.write_to_device();
  }
  void sample_contact_profile() override;
  std::vector<long> take_contact_profile() override;
  void set_stage_timing(bool on) override;
  StageTimes stage_times() const override { return stages_; }
  ContactStats contact_stats() override;
  BookSums read_books() override;
  void reset_books() override;
  long records_refused() override {
    rec_state_.read_from_device();
    return records_refused_ + rec_state_.host[1];
  }
  SolverState save_state() override;
  void restore_state(const SolverState& state) override;
  void poison_ball(int id) override;
  void write_instances(const cl::Buffer& out) override;

  double time_s() const override { return time_; }
  long steps() const override { return steps_; }
  long rebuilds() const override { return rebuilds_; }
  double mill_angle() const override { return mill_angle_; }
  double dt() const override { return dt_; }
  std::size_t device_bytes() const override;
  const char* forces_kernel() const override { return grouped_forces_ ? "grouped" : "ball"; }
  int status_every() const override { return status_every_; }
  const compute::DeviceInfo& device() const override { return ctx_.info(); }

 private:
  static compute::BuildOptions options(const Scene& scene);
  void setup_params(const Scene& scene);
  void setup_meshes(const SceneTables& t);
  void rebuild();
  void forces(bool defer_reactions = false);
  void reactions();
  void index_incoming();
  void pack_records(bool in_rebuild);
  void restore_springs(const SolverState& state);
  void motion();
  void read_status();
  void wait_status();
  void check_status_now();
  void read_every_step();
  void lap(double StageTimes::*stage);
  // Entries the lists are given room for when they hold `entries`: a
  // sixteenth to spare.
  static std::size_t list_capacity(std::size_t entries) { return entries + entries / 16 + 64; }
  // Reals of pair_out_ for `entries` slots.
  static std::size_t slot_reals(std::size_t entries) { return entries * MC_SLOT_REALS; }
  // Entries in the neighbour lists, from the host copies of starts and counts.
  std::size_t list_entries() const {
    return static_cast<std::size_t>(neigh_start_.host[n_ - 1]) + neigh_count_.host[n_ - 1];
  }

  compute::Context& ctx_;
  compute::Program program_;
  int n_;
  ContactLaw law_;  // built into the kernels (MC_LAW)
  double dt_;
  double time_ = 0;
  long steps_ = 0;
  long rebuilds_ = 0;
  double mill_angle_;
  double mill_omega_;
  double observed_since_ = 0;
  int n_cells_ = 1;

  // parameters
  Buffer<typename L::SimParams> params_;
  Buffer<typename L::PairParams> pairs_;
  Buffer<typename L::LifterPolygon> lifters_;
  // Mesh walls (cl/mesh.h): each set's grid, the triangles, each feature's
  // (patch, wall type), the cells (starts, then triangles; filled by
  // mesh_bin.cl when the walls are set), ball × mesh material pairs.
  Buffer<typename L::MeshGrid> mesh_grid_;
  Buffer<typename L::MeshTriangle> mesh_tris_;
  Buffer<int2> mesh_feature_;
  Buffer<int> mesh_cell_start_, mesh_cell_tris_;
  Buffer<typename L::PairParams> mesh_pairs_;
  // ball state, in cell order after each rebuild
  Buffer<real4> pos_, vel_, omega_, force_, torque_, accum_, pos_at_build_;
  Buffer<int2> info_;  // (id, material)
  // Rigid bodies (cl/body.h; one dummy entry each when there are none):
  // each component's body and offset and where it lies now (by id −
  // first component), each body's components and state.
  int n_bodies_ = 0;
  Buffer<int> body_of_, slot_of_;
  Buffer<real4> comp_offset_;
  Buffer<int2> body_comp_;
  Buffer<real4> body_pos_, body_vel_, body_quat_, body_angmom_, body_inv_inertia_, body_force_, body_torque_;
  Buffer<int> wall_key_;
  Buffer<int> wall_rec_;  // each slot's contact record
  // binning
  // cell_start_ has n_cells + 1 entries (the last is the number of balls);
  // while binning it first holds the counts, scanned in place. ball_cell_
  // and ball_rank_ are free once the balls are scattered: they then hold
  // the carried springs' starts and counts, and count the incoming slots.
  Buffer<int> cell_start_, ball_cell_, ball_rank_, sorted_index_;
  // neighbour lists (each pair once, in the lower ball's list); the records
  // carried over a rebuild (compact: only pairs in contact; partner index in
  // the old order) use free arrays: starts and counts in ball_cell_ and
  // ball_rank_, partners in neigh_rev_, records in pair_out_
  Buffer<int> neigh_start_, neigh_count_, neigh_index_;
  Buffer<int> neigh_rec_;  // a touching entry's contact record
  // The contact records (cl/layout.h): the pool, what it holds, and the
  // books they feed: collision spectra, liner elements, the lab-frame
  // profile of impact energy on the liner (64-bit sums as uint pairs).
  Buffer<real4> records_;
  Buffer<int> rec_state_;  // records taken, contacts that found the pool full
  int rec_capacity_ = 0, rec_mark_ = 0;
  long records_refused_ = 0;  // contacts that found the pool full, so far
  Buffer<typename L::BookParams> book_params_;
  Buffer<std::uint32_t> spectra_, liner_, impact_profile_;
  int n_types_ = 0, n_elements_ = 0;
  double energy_unit_ = 0, wear_unit_ = 0;
  // Each ball's incoming slots (one per pair a lower ball lists with it, side
  // by side from in_start_[j] to in_start_[j + 1]) and the slot of each
  // entry (neigh_rev_). The slots (MC_SLOT_REALS reals each) hold the
  // partner's side of the pairs that touch, which the reactions add up.
  // Between a force evaluation's reactions and the next rebuild the slots
  // are free, so they are also the scratch of the rebuild: the gathers into
  // cell order go through them, and the slot index is sorted in them.
  Buffer<Real> pair_out_;
  Buffer<int> in_start_, neigh_rev_;
  // status word and reduction partials
  Buffer<int> status_;
  Buffer<Real> partial_;
  Buffer<int> profile_;
  Buffer<int> counts_;
  double total_mass_ = 0;

  // The status word is read every status_every_ steps (on steps whose count
  // is a multiple of it, so a resumed run reads where the unbroken one did),
  // without waiting, and acted on at the next step; between reads the host
  // does not wait for the queue (the motion kernel flags a rebuild
  // 2 × status_every_ steps early to allow for this).
  int status_every_ = 1;
  compute::PinnedInt status_host_;
  cl::Event status_event_;
  bool status_in_flight_ = false;
  int pending_flags_ = 0;  // read, not yet acted on

  bool timing_ = false;
  StageTimes stages_;
  std::chrono::steady_clock::time_point lap_start_;

  Scan scan_;
  Kernel k_bin_clear_, k_bin_count_, k_bin_scatter_, k_bin_sort_, k_gather4_, k_gather2_,
      k_gather_wall_, k_put_wall_, k_contacts_count_, k_contacts_fill_, k_forces_, k_motion_, k_reduce_,
      k_layout_, k_profile_, k_count_contacts_, k_clear_flag_, k_carry_count_, k_carry_fill_, k_in_count_,
      k_in_scatter_, k_in_sort_, k_reactions_, k_react_motion_, k_forces_grouped_, k_records_count_, k_records_pack_, k_mesh_bin_,
      k_mesh_copy_, k_mesh_sort_, k_body_slots_, k_body_sums_, k_body_motion_;
  bool grouped_forces_ = false;
  // The reactions of a step's forces added by the next step's motion kernel
  // (react_motion: one launch fewer a step) where the charge has no bodies;
  // MILLCHARGE_FUSED_MOTION=0 keeps them a kernel of their own.
  bool fuse_reactions_ = true;
  bool reactions_deferred_ = false;  // the last forces' reactions are not yet added
  // The viewer's kernel, built on first use so that headless runs skip it.
  std::unique_ptr<compute::Program> view_program_;
  std::unique_ptr<Kernel> k_instances_;
};

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
  if (n_ == 0) throw std::invalid_argument("scene: no balls");

  // The device's struct sizes must equal the host mirrors'.
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

  setup_params(scene);

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

  rebuild();
  forces();
  // Leapfrog keeps v half a step behind x: v(−½) = v(0) − ½·dt·F(0)/m.
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
  observe(true);  // start the first interval here
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
    lifters_.host[k].bound = {Real(b.x), Real(b.y), Real(b.z), Real(0)};
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
  bp.n_types = tb.n_types;
  bp.n_elements = tb.n_elements;
  bp.shell_bins = tb.shell_bins;
  bp.axial_bins = tb.axial_bins;
  bp.plate_rings = tb.plate_rings;
  bp.plate_sectors = tb.plate_sectors;
  bp.first_lifter_element = tb.first_lifter_element;
  bp.first_plate_element = tb.first_plate_element;
  book_params_.write_to_device();
  energy_unit_ = tb.energy_unit;
  wear_unit_ = tb.wear_unit;
  n_types_ = tb.n_types;
  n_elements_ = tb.n_elements;
  spectra_ = Buffer<std::uint32_t>(ctx_, 2 * static_cast<std::size_t>(n_types_ + 1) * MC_SPECTRA_BINS * MC_SPECTRA_FIELDS,
                                   "collision spectra");
  liner_ = Buffer<std::uint32_t>(ctx_, 2 * static_cast<std::size_t>(n_elements_) * MC_LINER_FIELDS, "liner sums");
  impact_profile_ = Buffer<std::uint32_t>(ctx_, 2 * MC_IMPACT_BINS, "impact profile");
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
  if (w.length > 0) {
    lo.z = std::min(lo.z, 0.0);
    hi.z = std::max(hi.z, w.length);
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

template <class Real>
void SolverImpl<Real>::rebuild() {
  const int n = n_;
  // The counts per cell are scanned in place into the cell starts (each
  // work-item of the scan reads its entry before it writes it).
  k_bin_clear_.args(cell_start_, n_cells_ + 1).launch(n_cells_ + 1);
  k_bin_count_.args(params_, pos_, cell_start_, ball_cell_, ball_rank_).launch(n);
  scan_.run(cell_start_, cell_start_, n_cells_ + 1);
  k_bin_scatter_.args(n, ball_cell_, ball_rank_, cell_start_, sorted_index_).launch(n);
  k_bin_sort_.args(n_cells_, cell_start_, sorted_index_, info_).launch(n_cells_);

  // Put the ball arrays in cell order, each through the pair slots (free
  // now, and at least four reals per ball) and back; the wall slots' keys
  // through ball_cell_, free once the balls are scattered, and their
  // records through the pair slots.
  for (Buffer<real4>* b : {&pos_, &vel_, &omega_, &accum_}) {
    k_gather4_.args(n, sorted_index_, *b, pair_out_).launch(n);
    ctx_.queue().enqueueCopyBuffer(pair_out_.device(), b->device(), 0, 0, b->bytes());
  }
  k_gather2_.args(n, sorted_index_, info_, pair_out_).launch(n);
  ctx_.queue().enqueueCopyBuffer(pair_out_.device(), info_.device(), 0, 0, info_.bytes());
  if (n_bodies_ > 0) k_body_slots_.args(params_, info_, slot_of_).launch(n);
  for (int slot = 0; slot < MC_MAX_WALL_CONTACTS; ++slot) {
    k_gather_wall_.args(n, slot, sorted_index_, wall_key_, wall_rec_, ball_cell_, pair_out_).launch(n);
    k_put_wall_.args(n, slot, ball_cell_, pair_out_, wall_key_, wall_rec_).launch(n);
  }
  pos_at_build_.copy_from(pos_, n);
  lap(&StageTimes::binning_s);

  // The records of pairs in contact, out of the lists (in the old order).
  Buffer<int>& carry_start = ball_cell_;
  Buffer<int>& carry_count = ball_rank_;
  k_carry_count_.args(n, neigh_start_, neigh_count_, neigh_index_, carry_count).launch(n);
  scan_.run(carry_count, carry_start, n);
  const int carried = scan_.read_total();
  // The carried pairs are a subset of the old entries: their partners go
  // into neigh_rev_ and their records into the pair slots, both sized with
  // the old lists and free until the new lists are indexed.
  if (static_cast<std::size_t>(carried) > neigh_rev_.size() ||
      static_cast<std::size_t>(carried) > pair_out_.size())
    throw std::logic_error("carried contacts outgrow the old lists");
  Buffer<int>& carry_index = neigh_rev_;
  Buffer<Real>& carry_rec = pair_out_;  // ints
  k_carry_fill_.args(n, neigh_start_, neigh_count_, neigh_index_, neigh_rec_, carry_start, carry_index, carry_rec)
      .launch(n);
  // New lists in their place.
  k_contacts_count_.args(params_, pos_, cell_start_, neigh_count_, info_, body_of_).launch(n);
  scan_.run(neigh_count_, neigh_start_, n);
  const int total = scan_.read_total();
  if (static_cast<std::size_t>(total) > neigh_index_.size()) {
    // The lists grow as needed: no contact is ever dropped.
    const std::size_t cap = list_capacity(static_cast<std::size_t>(total));
    neigh_index_.resize(cap);
    neigh_rec_.resize(cap);
  }
  k_contacts_fill_.args(params_, pos_, cell_start_, neigh_start_, neigh_index_, neigh_rec_, sorted_index_,
                        carry_start, carry_count, carry_index, carry_rec, records_, info_, body_of_)
      .launch(n);
  pack_records(true);
  index_incoming();
  ++rebuilds_;
  lap(&StageTimes::contacts_s);
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
    d.b = {Real(m.b.x), Real(m.b.y), Real(m.b.z), Real(0)};
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
void SolverImpl<Real>::forces(bool defer_reactions) {
  (grouped_forces_ ? k_forces_grouped_ : k_forces_)
      .args(params_, pairs_, lifters_, std::cos(mill_angle_), std::sin(mill_angle_), mill_omega_, pos_, vel_,
            omega_, info_,
            neigh_start_, neigh_count_, neigh_index_, neigh_rec_, neigh_rev_, pair_out_, wall_key_, wall_rec_, force_,
            torque_, accum_, status_, records_, rec_state_, rec_capacity_, rec_mark_, spectra_, liner_,
            impact_profile_, book_params_, mesh_grid_, mesh_tris_, mesh_feature_, mesh_cell_start_, mesh_cell_tris_,
            mesh_pairs_)
      .launch(n_, grouped_forces_ ? kForcesGroupWG : 0);
  if (defer_reactions && n_bodies_ == 0)
    reactions_deferred_ = true;  // the next motion() adds them
  else
    reactions();
  if (n_bodies_ > 0)
    k_body_sums_.args(params_, pos_, force_, torque_, slot_of_, body_comp_, body_pos_, body_force_, body_torque_)
        .launch(n_bodies_);
  lap(&StageTimes::forces_s);
}

// The record pool packed: the records of the open contacts (touching list
// entries and wall slots, ball by ball) to the front, in an order that does
// not depend on the threads, through scratch (in a rebuild the pair slots,
// free until the lists are indexed; otherwise a buffer of its own for the
// while). The pool then holds them and room for the contacts that begin
// before it is packed again: a margin of as many again (at least half a
// record per ball), and the pairs that overlap now without a record (a
// charge laid anew). A record taken past half the margin asks for a pack
// (MC_FLAG_PACK_RECORDS); a contact that finds the pool full keeps no spring
// until it is packed (MC_FLAG_RECORDS_FULL, counted). Packing moves records
// and changes no result, so when it happens does not matter.
template <class Real>
void SolverImpl<Real>::pack_records(bool in_rebuild) {
  const int n = n_;
  rec_state_.read_from_device();
  records_refused_ += rec_state_.host[1];
  Buffer<int>& first = ball_cell_;  // free outside the binning and the carry
  Buffer<int>& pending = ball_rank_;
  k_records_count_
      .args(params_, pos_, neigh_start_, neigh_count_, neigh_index_, neigh_rec_, wall_key_, wall_rec_, first, pending)
      .launch(n);
  scan_.run(pending, pending, n);
  const long overlapping = scan_.read_total();
  scan_.run(first, first, n);
  const long live = scan_.read_total();
  Buffer<Real> own_scratch;
  Buffer<Real>* scratch = &pair_out_;
  const std::size_t reals = 8 * static_cast<std::size_t>(std::max(live, 1L));
  if (!in_rebuild) {
    own_scratch = Buffer<Real>(ctx_, reals, "contact records, packed");
    scratch = &own_scratch;
  } else if (reals > pair_out_.size()) {
    pair_out_.resize(reals);
  }
  k_records_pack_.args(n, neigh_start_, neigh_count_, neigh_index_, neigh_rec_, wall_key_, wall_rec_, first, records_,
                       *scratch)
      .launch(n);
  const long margin = std::max<long>({live, n / 2, 1024});
  const long capacity = live + overlapping + margin;
  if (capacity > std::numeric_limits<int>::max() / 2)
    throw std::runtime_error("contact records: " + std::to_string(capacity) + " do not fit the pool's index");
  if (static_cast<std::size_t>(capacity) * 2 > records_.size() ||
      static_cast<std::size_t>(capacity) * 2 * 3 / 2 < records_.size())
    records_.resize(static_cast<std::size_t>(capacity) * 2);
  if (live > 0) ctx_.queue().enqueueCopyBuffer(scratch->device(), records_.device(), 0, 0, 2 * live * sizeof(real4));
  // The pool's size from what it holds, not from the buffer (which may be
  // larger): the same state gives the same pool, however it came about.
  rec_capacity_ = static_cast<int>(capacity);
  rec_mark_ = static_cast<int>(live + overlapping + margin / 2);
  rec_state_.host = {static_cast<int>(live), 0};
  rec_state_.write_to_device();
  if (!in_rebuild) ctx_.finish();  // before the scratch goes
}

// Each ball's incoming slots, from the lists: counted (in place in
// in_start_), scanned, the entries scattered into their partners' slots in
// any order (pair_out_ holds this index for now, ball_rank_ counts), sorted
// per ball so that the order does not depend on the threads, and each
// entry's slot noted (neigh_rev_). Then the slots are cleared: a pair that
// touches fills its slot at the next force evaluation.
template <class Real>
void SolverImpl<Real>::index_incoming() {
  const int n = n_;
  // Sized with the lists' capacity; the slots also hold four reals per ball
  // for the gathers.
  if (neigh_index_.size() != neigh_rev_.size()) neigh_rev_.resize(neigh_index_.size());
  const std::size_t reals = std::max(slot_reals(neigh_index_.size()), 4 * static_cast<std::size_t>(n));
  if (reals != pair_out_.size()) pair_out_.resize(reals);
  k_bin_clear_.args(in_start_, n + 1).launch(n + 1);
  k_in_count_.args(n, neigh_start_, neigh_count_, neigh_index_, in_start_).launch(n);
  scan_.run(in_start_, in_start_, n + 1);
  k_bin_clear_.args(ball_rank_, n).launch(n);
  k_in_scatter_.args(n, neigh_start_, neigh_count_, neigh_index_, in_start_, ball_rank_, pair_out_).launch(n);
  k_in_sort_.args(n, in_start_, pair_out_, neigh_rev_).launch(n);
  const int words = static_cast<int>(pair_out_.bytes() / sizeof(int));
  k_bin_clear_.args(pair_out_, words).launch(words);
}

// The partners' sides added to each ball's force, torque and books.
template <class Real>
void SolverImpl<Real>::reactions() {
  k_reactions_.args(n_, in_start_, pair_out_, force_, torque_, accum_).launch(n_);
  reactions_deferred_ = false;
}

template <class Real>
void SolverImpl<Real>::motion() {
  if (reactions_deferred_) {
    k_react_motion_
        .args(params_, pos_, vel_, omega_, force_, torque_, accum_, in_start_, pair_out_, pos_at_build_, status_)
        .launch(n_);
    reactions_deferred_ = false;
  } else {
    k_motion_.args(params_, pos_, vel_, omega_, force_, torque_, pos_at_build_, status_, info_).launch(n_);
  }
  if (n_bodies_ > 0)
    k_body_motion_
        .args(params_, pos_, vel_, omega_, pos_at_build_, slot_of_, body_comp_, comp_offset_, body_pos_, body_vel_,
              body_quat_, body_angmom_, body_inv_inertia_, body_force_, body_torque_, status_)
        .launch(n_bodies_);
}

template <class Real>
void SolverImpl<Real>::lap(double StageTimes::*stage) {
  if (!timing_) return;
  ctx_.finish();
  const auto now = std::chrono::steady_clock::now();
  stages_.*stage += std::chrono::duration<double>(now - lap_start_).count();
  lap_start_ = now;
}

template <class Real>
void SolverImpl<Real>::set_stage_timing(bool on) {
  timing_ = on;
  stages_ = {};
  if (on) {
    ctx_.finish();
    lap_start_ = std::chrono::steady_clock::now();
  }
}

// Enqueues a read of the status word without waiting for it.
template <class Real>
void SolverImpl<Real>::read_status() {
  try {
    ctx_.queue().enqueueReadBuffer(status_.device(), CL_FALSE, 0, sizeof(int), status_host_.get(), nullptr,
                                   &status_event_);
  } catch (const cl::Error& e) {
    throw compute::Error("reading the status word failed: " + compute::error_name(e.err()));
  }
  status_in_flight_ = true;
}

// Waits for the status read in flight, if any; throws on a blow-up or a wall
// overflow, and leaves the flags for the next step's rebuild decision.
template <class Real>
void SolverImpl<Real>::wait_status() {
  if (!status_in_flight_) return;
  status_event_.wait();
  status_in_flight_ = false;
  pending_flags_ |= *status_host_.get();
  const int flags = pending_flags_;
  if (flags & MC_FLAG_NOT_FINITE) {
    std::ostringstream m;
    m << "blow-up at t = " << time_ << " s (step " << steps_
      << "): a ball's position or velocity is NaN or Inf. Likely causes: dt (" << dt_
      << " s) too large for the contact stiffness, or balls overlapping at the start";
    throw std::runtime_error(m.str());
  }
  if (flags & MC_FLAG_ESCAPED) {
    std::ostringstream m;
    m << "a ball left the mill at t = " << time_ << " s (step " << steps_ << ")";
    pos_.read_from_device();
    info_.read_from_device();
    const auto& sp = params_.host[0];
    for (int i = 0; i < n_; ++i) {
      const auto& p = pos_.host[i];
      const bool out_shell = sp.shell_radius > 0 && std::hypot(p.x, p.y) > sp.shell_radius + p.w;
      const bool out_ends =
          sp.escape_z1 > sp.escape_z0 && (p.z < sp.escape_z0 - p.w || p.z > sp.escape_z1 + p.w);
      if (out_shell || out_ends) {
        m << ": ball " << info_.host[i].x << " is at (" << p.x << ", " << p.y << ", " << p.z << ") m";
        break;
      }
    }
    m << ". It went through a wall: dt (" << dt_
      << " s) is too large for the contact stiffness, or the charge started overlapping a lifter or the shell";
    throw std::runtime_error(m.str());
  }
  if (flags & MC_FLAG_WALL_OVERFLOW)
    throw std::runtime_error("a ball touches more than " + std::to_string(MC_MAX_WALL_CONTACTS) +
                             " walls at once (MC_MAX_WALL_CONTACTS in cl/layout.h): lifters too close together?");
}

template <class Real>
void SolverImpl<Real>::advance(long steps) {
  for (long s = 0; s < steps; ++s) {
    motion();
    // The previous step's flags, read while this step's motion runs: a
    // rebuild they ask for comes now, before this step's forces.
    wait_status();
    lap(&StageTimes::motion_s);
    // Acted on with the other flags of a scheduled read (not the check at the
    // end of advance), so the same step drops to reads every step however a
    // run's steps are split into advance() calls.
    if ((pending_flags_ & MC_FLAG_FAST) && status_every_ > 1) read_every_step();
    if (pending_flags_ & MC_FLAG_REBUILD) {
      rebuild();  // packs the records too
      k_clear_flag_.args(status_, MC_FLAG_REBUILD | MC_FLAG_PACK_RECORDS | MC_FLAG_RECORDS_FULL).launch(1);
    } else if (pending_flags_ & MC_FLAG_PACK_RECORDS) {
      pack_records(false);
      k_clear_flag_.args(status_, MC_FLAG_PACK_RECORDS | MC_FLAG_RECORDS_FULL).launch(1);
    }
    pending_flags_ = 0;
    if (steps_ % status_every_ == 0) read_status();
    ++steps_;
    time_ += dt_;
    mill_angle_ = std::fmod(mill_angle_ + mill_omega_ * dt_, 2.0 * M_PI);
    forces(fuse_reactions_);
  }
  // Between calls the forces are whole: what is read, saved or edited now
  // sees them as an unfused step leaves them.
  if (reactions_deferred_) {
    reactions();
    lap(&StageTimes::forces_s);
  }
  wait_status();  // report a blow-up from the last read now, not later
  if (status_every_ > 1) check_status_now();
}

// A ball too fast for reads every status_every_ steps: from now on the
// status word is read every step, as on a CPU device, for the rest of the
// solver's life (and of a run resumed from its checkpoints).
template <class Real>
void SolverImpl<Real>::read_every_step() {
  status_every_ = 1;
  params_.host[0].status_every = 1;
  params_.write_to_device();
}

// A blow-up, an escape or a wall overflow since the last read, reported at
// the end of advance() as with a read every step. The flags stay on the
// device for the next read, and the rebuild decision is left to it: the
// same steps rebuild however a run's steps are split into advance() calls.
template <class Real>
void SolverImpl<Real>::check_status_now() {
  const int keep = pending_flags_;
  read_status();
  wait_status();
  pending_flags_ = keep;
}

template <class Real>
Observables SolverImpl<Real>::observe(bool reset) {
  const int groups = (n_ + kReduceWG - 1) / kReduceWG;
  k_reduce_
      .args(params_, pos_, vel_, omega_, force_, torque_, accum_, neigh_start_, neigh_count_, neigh_index_, neigh_rec_,
            wall_key_, wall_rec_, records_, reset ? 1 : 0, partial_, info_, body_comp_, body_of_, body_pos_,
            body_vel_, body_quat_, body_angmom_, body_inv_inertia_, body_force_, body_torque_)
      .launch(static_cast<std::size_t>(groups) * kReduceWG, kReduceWG);
  partial_.read_from_device();
  lap(&StageTimes::reductions_s);
  double s[kObservables] = {};
  for (int g = 0; g < groups; ++g)
    for (int k = 0; k < kObservables; ++k) s[k] += partial_.host[g * kObservables + k];
  Observables o;
  o.interval_s = time_ - observed_since_;
  const double span = o.interval_s > 0 ? o.interval_s : 1.0;
  o.wall_torque_Nm = s[0] / span;
  o.wall_work_J = s[1];
  o.dissipated_J = s[2];
  o.torque_power_W = s[1] / span;
  o.dissipation_power_W = s[2] / span;
  o.elastic_J = s[3];
  o.kinetic_J = s[4];
  o.rotational_J = s[5];
  o.potential_J = s[6];
  o.neighbours_per_ball = s[7] / n_;
  o.charge_mass_kg = total_mass_;
  o.com_x_m = s[8] / total_mass_;
  o.com_y_m = s[9] / total_mass_;
  o.open_loss_normal_J = s[10];
  o.open_loss_tangential_J = s[11];
  o.open_loss_rolling_J = s[12];
  if (reset) observed_since_ = time_;
  return o;
}

namespace {

// The 64-bit integer at pair q of a uint array (low word first).
long long u64_at(const std::vector<std::uint32_t>& a, std::size_t q) {
  const std::uint64_t v = (static_cast<std::uint64_t>(a[2 * q + 1]) << 32) | a[2 * q];
  return static_cast<long long>(v);
}

}  // namespace

template <class Real>
BookSums SolverImpl<Real>::read_books() {
  wait_status();
  for (auto* b : {&spectra_, &liner_, &impact_profile_}) b->read_from_device();
  BookSums out;
  out.n_types = n_types_;
  out.n_elements = n_elements_;
  const int rows = n_types_ + 1;
  out.spectra.resize(static_cast<std::size_t>(rows) * MC_SPECTRA_BINS * MC_SPECTRA_FIELDS);
  for (int r = 0; r < rows; ++r)
    for (int b = 0; b < MC_SPECTRA_BINS; ++b) {
      // The device's units: the bin's edge in its own precision.
      const double e_unit = static_cast<double>(
          std::pow(Real(10), Real(MC_SPECTRA_LOG_MIN) + Real(std::max(b, 1) - 1) / Real(MC_SPECTRA_PER_DECADE)) /
          Real(MC_SPECTRA_SCALE));
      for (int f = 0; f < MC_SPECTRA_FIELDS; ++f) {
        const std::size_t q = (static_cast<std::size_t>(r) * MC_SPECTRA_BINS + b) * MC_SPECTRA_FIELDS + f;
        const double v = static_cast<double>(u64_at(spectra_.host, q));
        out.spectra[q] = f == MC_SPECTRA_COUNT || f == MC_SPECTRA_STEPS || f == MC_SPECTRA_BY_NORMAL ? v
                         : f == MC_SPECTRA_SPEED                        ? v / MC_SPECTRA_SCALE
                                                                        : v * e_unit;
      }
    }
  out.liner.resize(static_cast<std::size_t>(n_elements_) * MC_LINER_FIELDS);
  for (std::size_t q = 0; q < out.liner.size(); ++q) {
    const double v = static_cast<double>(u64_at(liner_.host, q));
    const int f = static_cast<int>(q % MC_LINER_FIELDS);
    out.liner[q] = f == MC_LINER_IMPACTS ? v : f == MC_LINER_WEAR ? v * wear_unit_ : v * energy_unit_;
  }
  out.impact_profile.resize(MC_IMPACT_BINS);
  for (int b = 0; b < MC_IMPACT_BINS; ++b) out.impact_profile[b] = u64_at(impact_profile_.host, b) * energy_unit_;
  return out;
}

template <class Real>
void SolverImpl<Real>::reset_books() {
  wait_status();
  for (auto* b : {&spectra_, &liner_, &impact_profile_}) {
    std::fill(b->host.begin(), b->host.end(), 0u);
    b->write_to_device();
  }
}

template <class Real>
void SolverImpl<Real>::sample_contact_profile() {
  k_profile_.args(params_, pos_, wall_key_, mesh_feature_, kProfileBins, profile_).launch(n_);
  lap(&StageTimes::reductions_s);
}

template <class Real>
ContactStats SolverImpl<Real>::contact_stats() {
  std::fill(counts_.host.begin(), counts_.host.end(), 0);
  counts_.write_to_device();
  k_count_contacts_.args(params_, pos_, neigh_start_, neigh_count_, neigh_index_, wall_key_, counts_).launch(n_);
  counts_.read_from_device();
  ContactStats c;
  c.ball_contacts_per_ball = static_cast<double>(counts_.host[0]) / n_;
  c.wall_contacts_per_ball = static_cast<double>(counts_.host[1]) / n_;
  c.list_entries_per_ball = static_cast<double>(counts_.host[2]) / n_;
  return c;
}

template <class Real>
std::vector<long> SolverImpl<Real>::take_contact_profile() {
  profile_.read_from_device();
  std::vector<long> out(profile_.host.begin(), profile_.host.end());
  std::fill(profile_.host.begin(), profile_.host.end(), 0);
  profile_.write_to_device();
  return out;
}

namespace {

template <class T>
void put_array(SolverState& st, const char* name, compute::Buffer<T>& b, std::size_t count, bool read = true) {
  if (read) b.read_from_device();
  const auto* p = reinterpret_cast<const unsigned char*>(b.host.data());
  st.arrays.emplace_back(name, std::vector<unsigned char>(p, p + count * sizeof(T)));
}

bool has_array(const SolverState& st, const char* name) {
  for (const auto& entry : st.arrays)
    if (entry.first == name) return true;
  return false;
}

// The spectra of a checkpoint written before the normal energy spectrum
// (six fields a cell) widen to today's eight: the normal spectrum's fields
// start at zero, so it holds only the collisions that close after the load
// (millcharge grind checks that it covers them all).
constexpr int kSpectraFieldsBefore = 6;
bool widen_old_spectra(const SolverState& st, compute::Buffer<std::uint32_t>& b) {
  for (const auto& [key, bytes] : st.arrays) {
    if (key != "spectra") continue;
    const std::size_t cells = b.size() / (2 * MC_SPECTRA_FIELDS);
    if (bytes.size() != cells * 2 * kSpectraFieldsBefore * sizeof(std::uint32_t)) return false;
    std::fill(b.host.begin(), b.host.end(), 0u);
    for (std::size_t c = 0; c < cells; ++c)
      std::memcpy(b.host.data() + c * 2 * MC_SPECTRA_FIELDS, bytes.data() + c * 2 * kSpectraFieldsBefore * 4,
                  2 * kSpectraFieldsBefore * sizeof(std::uint32_t));
    b.write_to_device();
    return true;
  }
  return false;
}

template <class T>
void get_array(const SolverState& st, const char* name, compute::Buffer<T>& b, bool resize) {
  for (const auto& [key, bytes] : st.arrays) {
    if (key != name) continue;
    if (bytes.size() % sizeof(T) != 0)
      throw std::invalid_argument(std::string("state array ") + name + ": size is not a whole number of elements");
    const std::size_t count = bytes.size() / sizeof(T);
    if (resize) {
      if (count > b.size()) b.resize(count);
    } else if (count != b.size()) {
      throw std::invalid_argument(std::string("state array ") + name + " holds " + std::to_string(count) +
                                  " elements, the solver " + std::to_string(b.size()));
    }
    std::memcpy(b.host.data(), bytes.data(), bytes.size());
    b.write_to_device();
    return;
  }
  throw std::invalid_argument(std::string("state array ") + name + " is missing");
}

}  // namespace

template <class Real>
SolverState SolverImpl<Real>::save_state() {
  wait_status();
  // Records are taken in whatever order the threads come: packed, they lie
  // in ball order, so that a state saved is the same, byte for byte, however
  // the run came to it.
  pack_records(false);
  SolverState st;
  st.real_bytes = sizeof(Real);
  st.n_balls = n_;
  st.time_s = time_;
  st.steps = steps_;
  st.rebuilds = rebuilds_;
  st.mill_angle = mill_angle_;
  st.mill_omega = mill_omega_;
  st.observed_since = observed_since_;
  st.pending_flags = pending_flags_;
  const std::size_t n = n_;
  const std::size_t slots = n * MC_MAX_WALL_CONTACTS;
  put_array(st, "pos", pos_, n);
  put_array(st, "vel", vel_, n);
  put_array(st, "omega", omega_, n);
  put_array(st, "force", force_, n);
  put_array(st, "torque", torque_, n);
  put_array(st, "accum", accum_, n);
  put_array(st, "pos_at_build", pos_at_build_, n);
  put_array(st, "info", info_, n);
  if (n_bodies_ > 0) {  // a run without bodies writes what it always has
    const std::size_t nb = n_bodies_;
    put_array(st, "body_pos", body_pos_, nb);
    put_array(st, "body_vel", body_vel_, nb);
    put_array(st, "body_quat", body_quat_, nb);
    put_array(st, "body_angmom", body_angmom_, nb);
    put_array(st, "body_force", body_force_, nb);
    put_array(st, "body_torque", body_torque_, nb);
  }
  put_array(st, "wall_key", wall_key_, slots);
  put_array(st, "wall_rec", wall_rec_, slots);
  put_array(st, "neigh_start", neigh_start_, n);
  put_array(st, "neigh_count", neigh_count_, n);
  const std::size_t entries = list_entries();
  put_array(st, "neigh_half_link", neigh_index_, entries);
  put_array(st, "neigh_rec", neigh_rec_, entries);
  put_array(st, "rec_state", rec_state_, 2);
  const std::size_t taken = std::min<std::size_t>(std::max(rec_state_.host[0], 0), rec_capacity_);
  put_array(st, "records", records_, 2 * taken);
  Buffer<int> pool(ctx_, 3, "record pool");
  pool.host = {rec_capacity_, rec_mark_, static_cast<int>(records_refused_)};
  put_array(st, "record_pool", pool, 3, false);
  put_array(st, "spectra", spectra_, spectra_.size());
  put_array(st, "liner", liner_, liner_.size());
  put_array(st, "impact_profile", impact_profile_, impact_profile_.size());
  put_array(st, "status", status_, 1);
  put_array(st, "profile", profile_, kProfileBins);
  Buffer<int> every(ctx_, 1, "status reads");
  every.host = {status_every_};
  put_array(st, "status_every", every, 1, false);
  return st;
}

template <class Real>
void SolverImpl<Real>::restore_state(const SolverState& st) {
  if (st.real_bytes != static_cast<int>(sizeof(Real)))
    throw std::invalid_argument("the state was saved in " + std::string(st.real_bytes == 8 ? "double" : "float") +
                                " precision, this solver runs in " + (sizeof(Real) == 8 ? "double" : "float"));
  if (st.n_balls != n_)
    throw std::invalid_argument("the state holds " + std::to_string(st.n_balls) + " balls, the scene " +
                                std::to_string(n_));
  ctx_.finish();
  status_in_flight_ = false;
  get_array(st, "pos", pos_, false);
  get_array(st, "vel", vel_, false);
  get_array(st, "omega", omega_, false);
  get_array(st, "force", force_, false);
  get_array(st, "torque", torque_, false);
  get_array(st, "accum", accum_, false);
  get_array(st, "pos_at_build", pos_at_build_, false);
  get_array(st, "info", info_, false);
  if (n_bodies_ > 0) {
    get_array(st, "body_pos", body_pos_, false);
    get_array(st, "body_vel", body_vel_, false);
    get_array(st, "body_quat", body_quat_, false);
    get_array(st, "body_angmom", body_angmom_, false);
    get_array(st, "body_force", body_force_, false);
    get_array(st, "body_torque", body_torque_, false);
    k_body_slots_.args(params_, info_, slot_of_).launch(n_);
  } else if (has_array(st, "body_pos")) {
    throw std::invalid_argument("the state holds rigid bodies, the scene none");
  }
  get_array(st, "wall_key", wall_key_, false);
  get_array(st, "neigh_start", neigh_start_, false);
  get_array(st, "neigh_count", neigh_count_, false);
  if (has_array(st, "records")) {
    get_array(st, "wall_rec", wall_rec_, false);
    get_array(st, "neigh_half_link", neigh_index_, true);
    get_array(st, "neigh_rec", neigh_rec_, true);
    if (neigh_rec_.size() != neigh_index_.size())
      throw std::invalid_argument("state arrays neigh_half_link and neigh_rec differ in length");
    Buffer<int> pool(ctx_, 3, "record pool");
    get_array(st, "record_pool", pool, false);
    rec_capacity_ = pool.host[0];
    rec_mark_ = pool.host[1];
    records_refused_ = pool.host[2];
    if (rec_capacity_ < 1) throw std::invalid_argument("state array record_pool: a pool of no records");
    records_.resize(2 * static_cast<std::size_t>(rec_capacity_));
    get_array(st, "records", records_, true);
    get_array(st, "rec_state", rec_state_, false);
    if (!widen_old_spectra(st, spectra_)) get_array(st, "spectra", spectra_, false);
    get_array(st, "liner", liner_, false);
    get_array(st, "impact_profile", impact_profile_, false);
  } else {
    restore_springs(st);
  }
  index_incoming();
  get_array(st, "status", status_, false);
  get_array(st, "profile", profile_, false);
  if (has_array(st, "status_every")) {  // a state saved before has none: reads as this solver's
    Buffer<int> every(ctx_, 1, "status reads");
    get_array(st, "status_every", every, false);
    if (every.host[0] < 1 || every.host[0] > 64)
      throw std::invalid_argument("state array status_every: " + std::to_string(every.host[0]) + " is not 1 to 64");
    if (every.host[0] != status_every_) {
      status_every_ = every.host[0];
      params_.host[0].status_every = status_every_;
      params_.write_to_device();
    }
  }
  time_ = st.time_s;
  steps_ = st.steps;
  rebuilds_ = st.rebuilds;
  mill_angle_ = st.mill_angle;
  mill_omega_ = st.mill_omega;
  observed_since_ = st.observed_since;
  pending_flags_ = st.pending_flags;
  ctx_.finish();
}

// A state saved before the contact records: the springs lay in the list
// entries ("neigh_hist") and wall slots ("wall_hist"); earlier still with
// full lists, each pair in both balls' lists ("neigh_link"), and before that
// without the touching flag ("neigh_index", where a spring of zero marked a
// pair apart). Each touching pair and wall contact gets a record with its
// spring; what it lost before the save is not known (zero), nor its impact
// speed. The sums of the books start at zero.
template <class Real>
void SolverImpl<Real>::restore_springs(const SolverState& st) {
  Buffer<Real> hist(ctx_, 1, "saved springs"), wall_hist(ctx_, 1, "saved wall springs");
  get_array(st, "neigh_hist", hist, true);
  get_array(st, "wall_hist", wall_hist, true);
  if (has_array(st, "neigh_half_link")) {
    get_array(st, "neigh_half_link", neigh_index_, true);
  } else {
    // Saved with full lists, each pair in both balls' lists: the lower
    // ball's entry is kept.
    if (has_array(st, "neigh_link")) {
      get_array(st, "neigh_link", neigh_index_, true);
    } else {
      get_array(st, "neigh_index", neigh_index_, true);
      for (std::size_t k = 0; k < list_entries(); ++k) {
        const Real* h = &hist.host[3 * k];
        if (h[0] != 0 || h[1] != 0 || h[2] != 0) neigh_index_.host[k] = MC_LINK_TOUCHED(neigh_index_.host[k]);
      }
    }
    std::size_t kept = 0;
    for (int i = 0; i < n_; ++i) {
      const int b = neigh_start_.host[i], e = b + neigh_count_.host[i];
      neigh_start_.host[i] = static_cast<int>(kept);
      for (int k = b; k < e; ++k) {
        if (MC_LINK_PARTNER(neigh_index_.host[k]) < i) continue;
        neigh_index_.host[kept] = neigh_index_.host[k];
        for (int c = 0; c < 3; ++c) hist.host[3 * kept + c] = hist.host[3 * k + c];
        ++kept;
      }
      neigh_count_.host[i] = static_cast<int>(kept) - neigh_start_.host[i];
    }
    // Half the entries: the lists shrink to what a rebuild would give them.
    const std::size_t cap = list_capacity(kept);
    if (cap < neigh_index_.size()) {
      std::vector<int> links(neigh_index_.host.begin(), neigh_index_.host.begin() + kept);
      neigh_index_.resize(cap);
      std::copy(links.begin(), links.end(), neigh_index_.host.begin());
    }
    for (auto* b : {&neigh_start_, &neigh_count_}) b->write_to_device();
  }
  // The springs into records, ball by ball as a pack would lay them.
  neigh_rec_.resize(neigh_index_.size());
  std::vector<real4> recs;
  auto add = [&](const Real* h) {
    recs.push_back({h[0], h[1], h[2], Real(0)});
    recs.push_back({Real(0), Real(0), Real(0), Real(0)});
    return static_cast<int>(recs.size() / 2 - 1);
  };
  std::fill(neigh_rec_.host.begin(), neigh_rec_.host.end(), MC_NO_RECORD);
  std::fill(wall_rec_.host.begin(), wall_rec_.host.end(), MC_NO_RECORD);
  for (int i = 0; i < n_; ++i) {
    for (int k = neigh_start_.host[i]; k < neigh_start_.host[i] + neigh_count_.host[i]; ++k)
      if (MC_LINK_TOUCHING(neigh_index_.host[k])) neigh_rec_.host[k] = add(&hist.host[3 * k]);
    for (int s = 0; s < MC_MAX_WALL_CONTACTS; ++s) {
      const std::size_t q = static_cast<std::size_t>(s) * n_ + i;
      if (wall_key_.host[q] != MC_WALL_NONE && 3 * q + 2 < wall_hist.host.size())
        wall_rec_.host[q] = add(&wall_hist.host[3 * q]);
    }
  }
  const long live = static_cast<long>(recs.size() / 2);
  const long margin = std::max<long>({live, n_ / 2, 1024});
  rec_capacity_ = static_cast<int>(live + margin);
  rec_mark_ = static_cast<int>(live + margin / 2);
  records_.resize(2 * static_cast<std::size_t>(rec_capacity_));
  std::copy(recs.begin(), recs.end(), records_.host.begin());
  rec_state_.host = {static_cast<int>(live), 0};
  for (auto* b : {&neigh_index_, &neigh_rec_, &wall_rec_, &rec_state_}) b->write_to_device();
  records_.write_to_device();
  for (auto* b : {&spectra_, &liner_, &impact_profile_}) {
    std::fill(b->host.begin(), b->host.end(), 0u);
    b->write_to_device();
  }
}

template <class Real>
void SolverImpl<Real>::poison_ball(int id) {
  wait_status();
  info_.read_from_device();
  vel_.read_from_device();
  for (int i = 0; i < n_; ++i)
    if (info_.host[i].x == id) vel_.host[i].x = std::numeric_limits<Real>::quiet_NaN();
  vel_.write_to_device();
}

template <class Real>
void SolverImpl<Real>::write_instances(const cl::Buffer& out) {
  if (!k_instances_) {
    view_program_ = std::make_unique<compute::Program>(ctx_, std::vector<std::string>{"instances.cl"},
                                                       compute::BuildOptions(), std::is_same_v<Real, double>);
    k_instances_ = std::make_unique<Kernel>(*view_program_, "write_instances");
  }
  k_instances_->args(params_, pos_, vel_, force_, info_, accum_, time_ - observed_since_, out, body_of_, body_pos_,
                     body_vel_, body_force_)
      .launch(n_);
}

template <class Real>
std::vector<BallState> SolverImpl<Real>::balls() {
  for (auto* b : {&pos_, &vel_, &omega_, &force_, &torque_}) b->read_from_device();
  info_.read_from_device();
  std::vector<BallState> out(n_);
  for (int i = 0; i < n_; ++i)
    out[i] = ball_state(info_.host[i].x, info_.host[i].y, pos_.host[i], vel_.host[i], omega_.host[i],
                        force_.host[i], torque_.host[i], dt_);
  std::sort(out.begin(), out.end(), [](const BallState& a, const BallState& b) { return a.id < b.id; });
  return out;
}

template <class Real>
std::vector<BodyState> SolverImpl<Real>::bodies() {
  std::vector<BodyState> out;
  if (n_bodies_ == 0) return out;
  for (auto* b : {&body_pos_, &body_vel_, &body_quat_, &body_angmom_, &body_inv_inertia_, &body_force_, &body_torque_})
    b->read_from_device();
  for (int k = 0; k < n_bodies_; ++k)
    out.push_back(body_state(body_pos_.host[k], body_vel_.host[k], body_quat_.host[k], body_angmom_.host[k],
                             body_inv_inertia_.host[k], body_force_.host[k], body_torque_.host[k], dt_));
  return out;
}

template <class Real>
std::vector<std::pair<int, int>> SolverImpl<Real>::neighbour_pairs() {
  neigh_start_.read_from_device();
  neigh_count_.read_from_device();
  neigh_index_.read_from_device();
  info_.read_from_device();
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < n_; ++i)
    for (int k = neigh_start_.host[i]; k < neigh_start_.host[i] + neigh_count_.host[i]; ++k)
      out.emplace_back(info_.host[i].x, info_.host[MC_LINK_PARTNER(neigh_index_.host[k])].x);
  return out;
}

template <class Real>
std::size_t SolverImpl<Real>::device_bytes() const {
  std::size_t b = params_.bytes() + pairs_.bytes() + lifters_.bytes() + mesh_grid_.bytes() + mesh_tris_.bytes() +
                  mesh_feature_.bytes() + mesh_cell_start_.bytes() + mesh_cell_tris_.bytes() + mesh_pairs_.bytes() + status_.bytes() + profile_.bytes() + counts_.bytes() +
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

}  // namespace

double BookSums::at(int row, int bin, int field) const {
  return spectra[(static_cast<std::size_t>(row) * MC_SPECTRA_BINS + bin) * MC_SPECTRA_FIELDS + field];
}

double BookSums::closed_loss_J() const {
  double e = 0;
  for (int r = 0; r <= n_types; ++r)
    for (int b = 0; b < MC_SPECTRA_BINS; ++b)
      e += at(r, b, MC_SPECTRA_NORMAL) + at(r, b, MC_SPECTRA_TANGENTIAL) + at(r, b, MC_SPECTRA_ROLLING);
  return e;
}

double spectra_edge_J(int bin) {
  return std::pow(10.0, MC_SPECTRA_LOG_MIN + (std::max(bin, 1) - 1) / static_cast<double>(MC_SPECTRA_PER_DECADE));
}

void Solver::write_instances(const cl::Buffer&) {
  throw std::logic_error("this solver cannot feed the viewer (write_instances)");
}

double default_skin(const Scene& scene) {
  if (scene.balls.empty()) return 0.0;
  double r_min = std::numeric_limits<double>::max(), r_max = 0;
  for (const Ball& b : scene.balls) {
    r_min = std::min(r_min, b.radius);
    r_max = std::max(r_max, b.radius);
  }
  // The lists are rebuilt when a ball has moved half the skin. In a big mill
  // at the seed's step a ball thrown from the shoulder crosses 20 % of a
  // radius in a few steps (mill D: a rebuild every 9 steps, 38 % of the
  // time), so the skin also allows kSkinSteps steps at the speed of a ball
  // fallen across the mill, sqrt(2 g D), up to the smallest radius (the
  // lists grow as the skin's cube). In a periodic slice the grid keeps its
  // 3 cells along the axis.
  const Vec3 g = scene.numerics.gravity;
  const double fall = scene.walls.shell_radius > 0 ? std::sqrt(2 * g.norm() * 2 * scene.walls.shell_radius) : 0.0;
  double skin = std::clamp(2 * kSkinSteps * fall * scene.numerics.dt, 0.2 * r_min, r_min);
  if (scene.walls.periodic && scene.walls.length > 0)
    skin = std::max(0.2 * r_min, std::min(skin, 0.99 * (scene.walls.length / 3 - 2 * r_max)));
  return skin;
}

std::unique_ptr<Solver> make_solver(compute::Context& ctx, const Scene& scene) {
  validate(scene);
  if (scene.numerics.precision == Precision::double_)
    return std::make_unique<SolverImpl<double>>(ctx, scene);
  return std::make_unique<SolverImpl<float>>(ctx, scene);
}

}  // namespace mc
