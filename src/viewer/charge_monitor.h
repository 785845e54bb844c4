// What the panel plots while the mill turns: torque and dissipation power,
// toe and shoulder (from the contact profile of the last half second), and
// the charge's speed for the settling test. The plotted series run on across
// an edit, with the edit marked; the averages (mean power, toe and shoulder
// from the whole profile) restart at each edit and take nothing from the
// settle-in after it (the caller says when the charge is held). No GL here.
#pragma once

#include <deque>
#include <vector>

#include "sim/charge_profile.h"
#include "sim/solver.h"

namespace mc::viewer {

// A mean with its standard error from batch means (DESIGN.md, "Answers
// with their uncertainty"); error < 0 where fewer than three batches closed.
struct MeanWithError {
  double mean = 0, error = -1;
  int batches = 0;
};

class ChargeMonitor {
 public:
  static constexpr std::size_t kHistory = 300;  // points kept per series
  static constexpr double kPowerEvery = 0.02;    // s simulated per power point
  static constexpr double kProfileEvery = 0.1;   // s simulated per toe/shoulder point
  static constexpr int kProfileWindow = 5;       // profiles summed for one toe/shoulder
  static constexpr int kPowerBatch = 10;         // power points per batch of the standard error (0.2 s)

  void clear();  // everything, the plots too (a fresh charge)
  // The averages start again (an edit): the plots keep their points, and
  // the edit is marked where the next point will go.
  void restart();
  // After each frame that stepped: reads the solver's sums since the last
  // reset (and resets them), and samples the contact profile while turning.
  // `time_s` is the viewer's simulated time. While held (the start-up jolt
  // after the mill starts: the power; after an edit: both) the sums or
  // profiles are read and thrown away: no plot point, nothing averaged.
  void after_steps(Solver& solver, double time_s, bool turning, bool hold_power, bool hold_profile);

  const std::vector<float>& torque_power() const { return torque_w_; }
  const std::vector<float>& dissipation_power() const { return diss_w_; }
  const std::vector<float>& toe() const { return toe_deg_; }
  const std::vector<float>& shoulder() const { return shoulder_deg_; }
  // Where edits fall in the series above: indices of the first point after.
  const std::vector<int>& power_marks() const { return power_marks_; }
  const std::vector<int>& angle_marks() const { return angle_marks_; }
  const ChargeAngles& angles() const { return angles_; }
  // Toe and shoulder from every contact profile since the mill began
  // turning in the window (or since clear() or restart()), and the time they span.
  ChargeAngles all_angles() const { return toe_and_shoulder(profile_all_); }
  double all_span_s() const { return all_span_s_; }
  // Toe and shoulder of each closed batch of kProfileWindow profiles since
  // then, as means with standard errors.
  MeanWithError toe_mean() const { return batch_mean(toe_batches_); }
  MeanWithError shoulder_mean() const { return batch_mean(shoulder_batches_); }
  // The contact profiles summed for the angles (kProfileBins counts).
  const std::vector<long>& profile() const { return profile_sum_; }
  // Torque and dissipation power since the mill began turning or since the
  // last edit (after its hold): work over the time it spans.
  MeanWithError mean_torque_power() const;
  double mean_dissipation_power() const { return mean_span_s_ > 0 ? mean_diss_J_ / mean_span_s_ : 0; }
  double mean_span_s() const { return mean_span_s_; }
  double rms_speed() const { return rms_speed_; }
  const Observables& last() const { return last_; }

 private:
  static void push_pair(std::vector<float>& a, std::vector<float>& b, std::vector<int>& marks, float xa, float xb);
  static MeanWithError batch_mean(const std::vector<double>& batches);
  double work_J_ = 0, dissipated_J_ = 0, span_s_ = 0;  // the open power point
  double mean_work_J_ = 0, mean_diss_J_ = 0, mean_span_s_ = 0;
  std::vector<double> power_batches_;  // closed batches of kPowerBatch points
  double batch_work_J_ = 0, batch_span_s_ = 0;
  int batch_points_ = 0;
  double profile_since_ = -1;
  std::deque<std::vector<long>> profiles_;
  int profiles_taken_ = 0;
  std::vector<double> toe_batches_, shoulder_batches_;
  std::vector<float> torque_w_, diss_w_, toe_deg_, shoulder_deg_;
  std::vector<int> power_marks_, angle_marks_;
  ChargeAngles angles_;
  std::vector<long> profile_sum_;
  std::vector<long> profile_all_ = std::vector<long>(kProfileBins, 0);
  double all_span_s_ = 0;
  double rms_speed_ = 0;
  Observables last_;
};

}  // namespace mc::viewer
