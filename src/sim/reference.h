// The CPU reference of the step: the same physics functions as the kernels
// (cl/ball_forces.h, cl/motion.h), in double, with brute-force neighbour
// lists and no reordering. Tests compare the kernels with it ball by ball.
// O(N²) per step: for a few thousand balls at most.
#pragma once

#include <memory>
#include <vector>

#include "core/scene.h"
#include "sim/solver.h"

namespace mc {

class ReferenceSolver {
 public:
  explicit ReferenceSolver(const Scene& scene);
  ~ReferenceSolver();
  void advance(long steps);
  std::vector<BallState> balls() const;  // sorted by id
  std::vector<BodyState> bodies() const;
  double time_s() const;

 private:
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace mc
