// The step: binning and the neighbour lists (rebuild), the forces and
// their reactions, the motion, and the status word the host reads to act
// on rebuilds, record packing and blow-ups.
#include "sim/solver_impl.h"

namespace mc::detail {

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

template <class Real>
void SolverImpl<Real>::forces(bool defer_reactions) {
  (grouped_forces_ ? k_forces_grouped_ : k_forces_)
      .args(params_, pairs_, lifters_, std::cos(mill_angle_), std::sin(mill_angle_), mill_omega_, pos_, vel_,
            omega_, info_,
            neigh_start_, neigh_count_, neigh_index_, neigh_rec_, neigh_rev_, pair_out_, wall_key_, wall_rec_, force_,
            torque_, accum_, status_, records_, rec_state_, rec_capacity_, rec_mark_, spectra_, liner_,
            impact_profile_, book_params_, mesh_grid_, mesh_tris_, mesh_feature_, mesh_adj_, mesh_cell_start_, mesh_cell_tris_,
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

// This file's members, for both precisions.
template void SolverImpl<float>::rebuild();
template void SolverImpl<double>::rebuild();
template void SolverImpl<float>::forces(bool defer_reactions);
template void SolverImpl<double>::forces(bool defer_reactions);
template void SolverImpl<float>::pack_records(bool in_rebuild);
template void SolverImpl<double>::pack_records(bool in_rebuild);
template void SolverImpl<float>::index_incoming();
template void SolverImpl<double>::index_incoming();
template void SolverImpl<float>::reactions();
template void SolverImpl<double>::reactions();
template void SolverImpl<float>::motion();
template void SolverImpl<double>::motion();
template void SolverImpl<float>::lap(double StageTimes::*stage);
template void SolverImpl<double>::lap(double StageTimes::*stage);
template void SolverImpl<float>::set_stage_timing(bool on);
template void SolverImpl<double>::set_stage_timing(bool on);
template void SolverImpl<float>::read_status();
template void SolverImpl<double>::read_status();
template void SolverImpl<float>::wait_status();
template void SolverImpl<double>::wait_status();
template void SolverImpl<float>::advance(long steps);
template void SolverImpl<double>::advance(long steps);
template void SolverImpl<float>::read_every_step();
template void SolverImpl<double>::read_every_step();
template void SolverImpl<float>::check_status_now();
template void SolverImpl<double>::check_status_now();

}  // namespace mc::detail
