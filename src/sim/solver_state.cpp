// The saved state: every device array a step needs, packed into a
// SolverState for checkpoints, and restored (with the states of older
// millcharge versions).
#include "sim/solver_impl.h"

namespace mc::detail {

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

// Books of a checkpoint written by an older millcharge widen to today's
// fields a cell (`olds`: the widths it may have had): the spectra had six
// before the normal energy spectrum and eight before the severity spectra,
// the liner four before the strike energy. The fields it lacked start at
// zero, so they hold only what happens after the load: millcharge grind
// checks that the spectrum it reads covers every collision; a run resumed
// mid-window from such a checkpoint books the strike energy (impact wear)
// of the rest of its window only, over the whole window's seconds, and
// has no halves (the checkpoint holds none).
// A state saved before the impact profile was kept by axial bin holds the
// whole mill's alone: read into the first block, the axial blocks zero
// (their sums then begin at the resume). True where it was such a state.
bool whole_mill_profile_only(const SolverState& st, compute::Buffer<std::uint32_t>& b) {
  for (const auto& [key, bytes] : st.arrays) {
    if (key != "impact_profile") continue;
    if (bytes.size() != 2 * MC_IMPACT_BINS * sizeof(std::uint32_t)) return false;
    std::fill(b.host.begin(), b.host.end(), 0u);
    std::memcpy(b.host.data(), bytes.data(), bytes.size());
    b.write_to_device();
    return true;
  }
  return false;
}

bool widen_old(const SolverState& st, const char* name, compute::Buffer<std::uint32_t>& b, std::size_t fields,
               std::initializer_list<std::size_t> olds) {
  for (const auto& [key, bytes] : st.arrays) {
    if (key != name) continue;
    const std::size_t cells = b.size() / (2 * fields);
    for (const std::size_t before : olds) {
      if (bytes.size() != cells * 2 * before * sizeof(std::uint32_t)) continue;
      std::fill(b.host.begin(), b.host.end(), 0u);
      for (std::size_t c = 0; c < cells; ++c)
        std::memcpy(b.host.data() + c * 2 * fields, bytes.data() + c * 2 * before * 4,
                    2 * before * sizeof(std::uint32_t));
      b.write_to_device();
      return true;
    }
    return false;
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
    if (!widen_old(st, "spectra", spectra_, MC_SPECTRA_FIELDS, {6, 8})) get_array(st, "spectra", spectra_, false);
    if (!widen_old(st, "liner", liner_, MC_LINER_FIELDS, {4})) get_array(st, "liner", liner_, false);
    // Resumed from such a state, the bins' sums begin mid-window: none are
    // reported until the books start again (reset_books).
    impact_axial_partial_ = whole_mill_profile_only(st, impact_profile_);
    if (!impact_axial_partial_) get_array(st, "impact_profile", impact_profile_, false);
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

// This file's members, for both precisions.
template SolverState SolverImpl<float>::save_state();
template SolverState SolverImpl<double>::save_state();
template void SolverImpl<float>::restore_state(const SolverState& st);
template void SolverImpl<double>::restore_state(const SolverState& st);
template void SolverImpl<float>::restore_springs(const SolverState& st);
template void SolverImpl<double>::restore_springs(const SolverState& st);

}  // namespace mc::detail
