// What the viewer colours the liner with while the mill turns: the liner's
// sums read from the solver's energy books every 0.05 simulated seconds
// (which resets them), as rates per element over the last 0.1 s (where the
// charge strikes now: the liner turns through the strike zone) and, over
// the last two seconds, the impact point (sim/energy_report.h). No GL here.
#pragma once

#include <deque>
#include <vector>

#include "core/liner.h"
#include "core/scene.h"
#include "sim/charge_profile.h"
#include "sim/energy_report.h"
#include "sim/solver.h"

namespace mc::viewer {

class LinerMonitor {
 public:
  static constexpr double kReadEvery = 0.05;  // s simulated between reads
  static constexpr int kRecent = 2;           // reads summed for the colours: 0.1 s
  static constexpr int kWindow = 40;          // reads summed for the impact point: 2 s

  void set_scene(const Scene& scene);  // the layout and materials (after an edit)
  void clear();
  // After each frame that stepped; the charge's contact profile and its toe
  // and shoulder now. While `held` (the settle-in after an edit) nothing is
  // booked: the window starts again after it.
  void after_steps(Solver& solver, double time_s, bool turning, bool held, const std::vector<long>& profile,
                   const ChargeAngles& angles);

  const LinerLayout& layout() const { return layout_; }
  bool ready() const { return ready_; }
  const LinerReport& report() const { return report_; }   // two seconds
  const LinerReport& recent() const { return recent_; }   // the last 0.1 s
  // Increases when the report changes (the renderer's colours follow).
  long version() const { return version_; }

 private:
  Scene scene_;  // materials and walls only
  LinerLayout layout_;
  std::deque<BookSums> reads_;
  std::deque<double> spans_;
  double since_ = -1;
  bool ready_ = false;
  LinerReport report_, recent_;
  long version_ = 0;
};

}  // namespace mc::viewer
