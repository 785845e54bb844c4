// What the host reads back: observables, the energy books and liner sums,
// contact statistics and profiles, balls and bodies for outputs, and the
// viewer's instances.
#include "sim/solver_impl.h"

namespace mc::detail {

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
        const bool count = f == MC_SPECTRA_COUNT || f == MC_SPECTRA_STEPS || f == MC_SPECTRA_BY_NORMAL ||
                           f == MC_SPECTRA_IMPACT || f == MC_SPECTRA_LOSS;
        const bool radius = f == MC_SPECTRA_IMPACT_RADIUS || f == MC_SPECTRA_LOSS_RADIUS;
        out.spectra[q] = count                    ? v
                         : f == MC_SPECTRA_SPEED ? v / MC_SPECTRA_SCALE
                         : radius                ? v * (MC_SPECTRA_R_REF / MC_SPECTRA_SCALE)
                                                 : v * e_unit;
      }
    }
  auto liner_value = [&](std::size_t q) {
    const double v = static_cast<double>(u64_at(liner_.host, q));
    const int f = static_cast<int>(q % MC_LINER_FIELDS);
    return f == MC_LINER_IMPACTS ? v : f == MC_LINER_WEAR ? v * wear_unit_ : v * energy_unit_;
  };
  out.liner.resize(static_cast<std::size_t>(n_elements_) * MC_LINER_FIELDS);
  for (std::size_t q = 0; q < out.liner.size(); ++q) out.liner[q] = liner_value(q);
  out.n_stations = n_stations_;
  out.stations.resize(static_cast<std::size_t>(n_stations_) * MC_LINER_FIELDS);
  for (std::size_t q = 0; q < out.stations.size(); ++q) out.stations[q] = liner_value(out.liner.size() + q);
  out.impact_profile.resize(MC_IMPACT_BINS);
  for (int b = 0; b < MC_IMPACT_BINS; ++b) out.impact_profile[b] = u64_at(impact_profile_.host, b) * energy_unit_;
  out.impact_axial_bins = impact_axial_partial_ ? 0 : impact_axial_bins_;
  out.impact_profile_axial.resize(static_cast<std::size_t>(MC_IMPACT_BINS) * impact_axial_bins_);
  for (std::size_t q = 0; q < out.impact_profile_axial.size(); ++q)
    out.impact_profile_axial[q] = u64_at(impact_profile_.host, MC_IMPACT_BINS + q) * energy_unit_;
  return out;
}

template <class Real>
void SolverImpl<Real>::reset_books() {
  wait_status();
  for (auto* b : {&spectra_, &liner_, &impact_profile_}) {
    std::fill(b->host.begin(), b->host.end(), 0u);
    b->write_to_device();
  }
  impact_axial_partial_ = false;  // every sum begins here
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

// This file's members, for both precisions.
template Observables SolverImpl<float>::observe(bool reset);
template Observables SolverImpl<double>::observe(bool reset);
template BookSums SolverImpl<float>::read_books();
template BookSums SolverImpl<double>::read_books();
template void SolverImpl<float>::reset_books();
template void SolverImpl<double>::reset_books();
template void SolverImpl<float>::sample_contact_profile();
template void SolverImpl<double>::sample_contact_profile();
template ContactStats SolverImpl<float>::contact_stats();
template ContactStats SolverImpl<double>::contact_stats();
template std::vector<long> SolverImpl<float>::take_contact_profile();
template std::vector<long> SolverImpl<double>::take_contact_profile();
template void SolverImpl<float>::poison_ball(int id);
template void SolverImpl<double>::poison_ball(int id);
template void SolverImpl<float>::write_instances(const cl::Buffer& out);
template void SolverImpl<double>::write_instances(const cl::Buffer& out);
template std::vector<BallState> SolverImpl<float>::balls();
template std::vector<BallState> SolverImpl<double>::balls();
template std::vector<BodyState> SolverImpl<float>::bodies();
template std::vector<BodyState> SolverImpl<double>::bodies();
template std::vector<std::pair<int, int>> SolverImpl<float>::neighbour_pairs();
template std::vector<std::pair<int, int>> SolverImpl<double>::neighbour_pairs();

}  // namespace mc::detail
