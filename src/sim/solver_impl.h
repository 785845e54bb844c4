// The solver's implementation, shared by the files that hold its phases
// (not part of the interface: include sim/solver.h). SolverImpl<Real> is
// the OpenCL solver in float or double; its member functions live by phase:
//   solver_setup.cpp  kernels, buffers, parameters and the mesh tables
//   solver_step.cpp   the step (bin, lists, forces, motion) and its status word
//   solver_books.cpp  books, observables and what is read back for outputs
//   solver_state.cpp  the saved state (checkpoints) and its restore
// Each of those files instantiates its members for float and double.
#pragma once

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
#include "core/layout.hpp"
#include "sim/solver.h"
#include "sim/tables.h"

namespace mc::detail {

using compute::Buffer;
using compute::Kernel;
using compute::LocalBytes;

inline constexpr int kScanWG = 256;
inline constexpr int kReduceWG = 64;
inline constexpr int kForcesGroupWG = 64;  // balls per work-group of forces_grouped
inline constexpr int kObservables = 13;

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
  void choose_from_environment(compute::Context& ctx);
  void check_layouts(compute::Context& ctx);
  void upload_charge(const Scene& scene);
  void clear_contacts();
  void start_leapfrog();
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
  Buffer<int> mesh_adj_;  // tables.h mesh_adj
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
  int n_types_ = 0, n_elements_ = 0, n_stations_ = 0;  // the liner's elements, then the lifters' wear stations
  int impact_axial_bins_ = 0;                          // the impact profile's axial blocks
  bool impact_axial_partial_ = false;                  // resumed from a state without them: not reported
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

}  // namespace mc::detail
