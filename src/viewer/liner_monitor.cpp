#include "viewer/liner_monitor.h"

#include "core/layout.hpp"

namespace mc::viewer {

void LinerMonitor::set_scene(const Scene& scene) {
  scene_ = scene;
  scene_.balls.clear();
  layout_ = liner_layout(scene_);
  clear();
}

void LinerMonitor::clear() {
  reads_.clear();
  spans_.clear();
  since_ = -1;
  ready_ = false;
  report_ = recent_ = {};
  ++version_;
}

void LinerMonitor::after_steps(Solver& solver, double time_s, bool turning, bool held, const std::vector<long>& profile,
                               const ChargeAngles& angles) {
  if (!turning || held) {
    if (since_ >= 0) clear();
    return;
  }
  if (since_ < 0) {  // the window starts as the mill turns
    solver.reset_books();
    since_ = time_s;
    return;
  }
  if (time_s - since_ < kReadEvery) return;
  reads_.push_back(solver.read_books());
  solver.reset_books();
  spans_.push_back(time_s - since_);
  since_ = time_s;
  if (reads_.size() > static_cast<std::size_t>(kWindow)) {
    reads_.pop_front();
    spans_.pop_front();
  }
  if (static_cast<int>(reads_.back().liner.size()) != layout_.size() * MC_LINER_FIELDS) return;  // a solver of another scene
  // The last `count` reads summed into one set of books over their span.
  auto report_of = [&](std::size_t count) {
    const std::size_t from = reads_.size() - std::min(count, reads_.size());
    BookSums sum = reads_[from];
    double span = spans_[from];
    for (std::size_t k = from + 1; k < reads_.size(); ++k) {
      span += spans_[k];
      for (std::size_t q = 0; q < sum.liner.size(); ++q) sum.liner[q] += reads_[k].liner[q];
      for (std::size_t q = 0; q < sum.impact_profile.size(); ++q) sum.impact_profile[q] += reads_[k].impact_profile[q];
      for (std::size_t q = 0; q < sum.impact_profile_axial.size() && q < reads_[k].impact_profile_axial.size(); ++q)
        sum.impact_profile_axial[q] += reads_[k].impact_profile_axial[q];
    }
    return liner_report(scene_, layout_, sum, span, profile, angles);
  };
  report_ = report_of(kWindow);
  recent_ = report_of(kRecent);
  ready_ = true;
  ++version_;
}

}  // namespace mc::viewer
