// What the panel plots while the mill turns: torque and dissipation power,
// toe and shoulder (from the contact profile of the last half second), and
// the charge's speed for the settling test. No GL here.
#pragma once

#include <deque>
#include <vector>

#include "sim/charge_profile.h"
#include "sim/solver.h"

namespace mc::viewer {

class ChargeMonitor {
 public:
  static constexpr std::size_t kHistory = 300;  // points kept per series
  static constexpr double kPowerEvery = 0.02;    // s simulated per power point
  static constexpr double kProfileEvery = 0.1;   // s simulated per toe/shoulder point
  static constexpr int kProfileWindow = 5;       // profiles summed for one toe/shoulder

  void clear();
  // No power points before this simulated time: the start-up jolt of the
  // mill would flatten the plot (as `run`'s power.png leaves it out).
  void hold_power_until(double time_s) { hold_until_s_ = time_s; }
  // After each frame that stepped: reads the solver's sums since the last
  // reset (and resets them), and samples the contact profile while turning.
  // `time_s` is the viewer's simulated time.
  void after_steps(Solver& solver, double time_s, bool turning);

  const std::vector<float>& torque_power() const { return torque_w_; }
  const std::vector<float>& dissipation_power() const { return diss_w_; }
  const std::vector<float>& toe() const { return toe_deg_; }
  const std::vector<float>& shoulder() const { return shoulder_deg_; }
  const ChargeAngles& angles() const { return angles_; }
  // Toe and shoulder from every contact profile since the mill began
  // turning in the window (or since clear()), and the time they span.
  ChargeAngles all_angles() const { return toe_and_shoulder(profile_all_); }
  double all_span_s() const { return all_span_s_; }
  // The contact profiles summed for the angles (kProfileBins counts).
  const std::vector<long>& profile() const { return profile_sum_; }
  double mean_torque_power() const;       // over the plotted history
  double mean_dissipation_power() const;
  double rms_speed() const { return rms_speed_; }
  const Observables& last() const { return last_; }

 private:
  static void push(std::vector<float>& v, float x);
  double work_J_ = 0, dissipated_J_ = 0, span_s_ = 0;
  double profile_since_ = -1;
  double hold_until_s_ = -1;
  std::deque<std::vector<long>> profiles_;
  std::vector<float> torque_w_, diss_w_, toe_deg_, shoulder_deg_;
  ChargeAngles angles_;
  std::vector<long> profile_sum_;
  std::vector<long> profile_all_ = std::vector<long>(kProfileBins, 0);
  double all_span_s_ = 0;
  double rms_speed_ = 0;
  Observables last_;
};

}  // namespace mc::viewer
