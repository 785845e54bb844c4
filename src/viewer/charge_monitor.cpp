#include "viewer/charge_monitor.h"

#include <cmath>
#include <numeric>

namespace mc::viewer {

void ChargeMonitor::clear() {
  work_J_ = dissipated_J_ = span_s_ = 0;
  profile_since_ = -1;
  hold_until_s_ = -1;
  profiles_.clear();
  torque_w_.clear();
  diss_w_.clear();
  toe_deg_.clear();
  shoulder_deg_.clear();
  angles_ = {};
  profile_sum_.clear();
  profile_all_.assign(kProfileBins, 0);
  all_span_s_ = 0;
}

void ChargeMonitor::push(std::vector<float>& v, float x) {
  if (v.size() >= kHistory) v.erase(v.begin());
  v.push_back(x);
}

void ChargeMonitor::after_steps(Solver& solver, double time_s, bool turning) {
  last_ = solver.observe(true);
  rms_speed_ = last_.charge_mass_kg > 0 ? std::sqrt(2 * last_.kinetic_J / last_.charge_mass_kg) : 0;
  if (!turning) {
    solver.take_contact_profile();  // nothing from settling counts
    return;
  }
  if (time_s < hold_until_s_) {
    work_J_ = dissipated_J_ = span_s_ = 0;
  } else {
    work_J_ += last_.wall_work_J;
    dissipated_J_ += last_.dissipated_J;
    span_s_ += last_.interval_s;
  }
  if (span_s_ >= kPowerEvery) {
    push(torque_w_, static_cast<float>(work_J_ / span_s_));
    push(diss_w_, static_cast<float>(dissipated_J_ / span_s_));
    work_J_ = dissipated_J_ = span_s_ = 0;
  }
  solver.sample_contact_profile();
  if (profile_since_ < 0) profile_since_ = time_s;
  if (time_s - profile_since_ >= kProfileEvery) {
    profiles_.push_back(solver.take_contact_profile());
    if (profiles_.size() > static_cast<std::size_t>(kProfileWindow)) profiles_.pop_front();
    for (std::size_t k = 0; k < profile_all_.size() && k < profiles_.back().size(); ++k) profile_all_[k] += profiles_.back()[k];
    all_span_s_ += time_s - profile_since_;
    profile_since_ = time_s;
    std::vector<long> sum(kProfileBins, 0);
    for (const auto& p : profiles_)
      for (std::size_t k = 0; k < sum.size() && k < p.size(); ++k) sum[k] += p[k];
    angles_ = toe_and_shoulder(sum);
    profile_sum_ = sum;
    if (angles_.found) {
      push(toe_deg_, static_cast<float>(angles_.toe_deg));
      push(shoulder_deg_, static_cast<float>(angles_.shoulder_deg));
    }
  }
}

double ChargeMonitor::mean_torque_power() const {
  return torque_w_.empty() ? 0 : std::accumulate(torque_w_.begin(), torque_w_.end(), 0.0) / torque_w_.size();
}

double ChargeMonitor::mean_dissipation_power() const {
  return diss_w_.empty() ? 0 : std::accumulate(diss_w_.begin(), diss_w_.end(), 0.0) / diss_w_.size();
}

}  // namespace mc::viewer
