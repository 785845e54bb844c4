#include "viewer/charge_monitor.h"

#include "sim/batch_means.h"

#include <cmath>
#include <numeric>

namespace mc::viewer {

void ChargeMonitor::clear() {
  restart();
  torque_w_.clear();
  diss_w_.clear();
  toe_deg_.clear();
  shoulder_deg_.clear();
  power_marks_.clear();
  angle_marks_.clear();
}

void ChargeMonitor::restart() {
  work_J_ = dissipated_J_ = span_s_ = 0;
  mean_work_J_ = mean_diss_J_ = mean_span_s_ = 0;
  power_batches_.clear();
  batch_work_J_ = batch_span_s_ = 0;
  batch_points_ = 0;
  profile_since_ = -1;
  profiles_.clear();
  profiles_taken_ = 0;
  toe_batches_.clear();
  shoulder_batches_.clear();
  angles_ = {};
  profile_sum_.clear();
  profile_all_.assign(kProfileBins, 0);
  all_span_s_ = 0;
  // The edit's mark: before the next point of each series (one mark where
  // edits come faster than points).
  auto mark = [](std::vector<int>& marks, const std::vector<float>& series) {
    const int at = static_cast<int>(series.size());
    if (!series.empty() && (marks.empty() || marks.back() != at)) marks.push_back(at);
  };
  mark(power_marks_, torque_w_);
  mark(angle_marks_, toe_deg_);
}

void ChargeMonitor::push_pair(std::vector<float>& a, std::vector<float>& b, std::vector<int>& marks, float xa, float xb) {
  if (a.size() >= kHistory) {
    a.erase(a.begin());
    b.erase(b.begin());
    for (int& m : marks) --m;
    while (!marks.empty() && marks.front() < 0) marks.erase(marks.begin());
  }
  a.push_back(xa);
  b.push_back(xb);
}

MeanWithError ChargeMonitor::batch_mean(const std::vector<double>& batches) {
  MeanWithError m;
  m.batches = static_cast<int>(batches.size());
  if (batches.empty()) return m;
  m.mean = std::accumulate(batches.begin(), batches.end(), 0.0) / batches.size();
  // The run's own rule (sim/batch_means.h): neighbouring batches merged
  // while their means are correlated; an error from three batches or more
  // left, and none while they are still correlated (it would be too small).
  const BatchMeans b = batch_means(batches);
  if (b.batches >= 3 && !b.correlated && std::isfinite(b.sem)) m.error = b.sem;
  return m;
}

MeanWithError ChargeMonitor::mean_torque_power() const {
  MeanWithError m = batch_mean(power_batches_);
  m.mean = mean_span_s_ > 0 ? mean_work_J_ / mean_span_s_ : 0;  // every point, the open batch too
  return m;
}

void ChargeMonitor::after_steps(Solver& solver, double time_s, bool turning, bool hold_power, bool hold_profile) {
  last_ = solver.observe(true);
  rms_speed_ = last_.charge_mass_kg > 0 ? std::sqrt(2 * last_.kinetic_J / last_.charge_mass_kg) : 0;
  if (!turning || hold_profile) {
    solver.take_contact_profile();  // nothing from settling, or from the jolt after an edit, counts
    work_J_ = dissipated_J_ = span_s_ = 0;
    profile_since_ = -1;
    return;
  }
  if (hold_power) {
    work_J_ = dissipated_J_ = span_s_ = 0;
  } else {
    work_J_ += last_.wall_work_J;
    dissipated_J_ += last_.dissipated_J;
    span_s_ += last_.interval_s;
  }
  if (span_s_ >= kPowerEvery) {
    push_pair(torque_w_, diss_w_, power_marks_, static_cast<float>(work_J_ / span_s_),
              static_cast<float>(dissipated_J_ / span_s_));
    mean_work_J_ += work_J_;
    mean_diss_J_ += dissipated_J_;
    mean_span_s_ += span_s_;
    batch_work_J_ += work_J_;
    batch_span_s_ += span_s_;
    if (++batch_points_ == kPowerBatch) {
      power_batches_.push_back(batch_work_J_ / batch_span_s_);
      batch_work_J_ = batch_span_s_ = 0;
      batch_points_ = 0;
    }
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
    if (angles_.found)
      push_pair(toe_deg_, shoulder_deg_, angle_marks_, static_cast<float>(angles_.toe_deg),
                static_cast<float>(angles_.shoulder_deg));
    // Every kProfileWindow-th profile closes a batch: the window's sum is
    // then one of profiles not in any earlier batch.
    if (++profiles_taken_ % kProfileWindow == 0 && angles_.found) {
      toe_batches_.push_back(angles_.toe_deg);
      shoulder_batches_.push_back(angles_.shoulder_deg);
    }
  }
}

}  // namespace mc::viewer
