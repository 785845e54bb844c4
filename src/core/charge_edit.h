// Changing the case of a mill whose charge is moving (the viewer's panel):
// the balls stay where they are, the walls and contact table follow the new
// case, and the change never leaves a large overlap for the solver to blow up
// on. Balls that a grown or added lifter would overlap are moved into free
// space above the charge (removed when there is none); a new filling adds
// balls there or takes them from the top of the charge. No OpenCL here.
#pragma once

#include <cstdint>
#include <vector>

#include "core/mill_case.h"
#include "core/scene.h"

namespace mc {

struct ChargeEditResult {
  Scene scene;        // walls, pairs and numerics of the new case; the kept balls
  long added = 0;     // new balls dropped above the charge
  long removed = 0;   // taken from the top, or no room found for them
  long moved = 0;     // lifted out of a lifter into free space
};

struct ChargeEditOptions {
  bool match_counts = false;     // bring the balls per size class to d.class_counts
  double mill_angle = 0;         // rad, the mill's angle now (lifters turn with it)
  double mill_omega = 0;         // rad/s to keep turning at
  // A ball is moved when the new walls overlap it by more than this fraction
  // of its radius and more than the previous walls did (a ball pressed into
  // an unchanged lifter by an impact stays).
  double allowed_overlap = 0.02;
  const Walls* previous_walls = nullptr;  // null: every overlap counts
  std::uint32_t seed = 1;        // sizes and places of new balls
};

// The scene of case `c` (derived `d`) holding `balls` (lab frame, now). Ids
// are renumbered 0..n−1 in the order kept. Throws std::invalid_argument when
// the case is invalid for a scene (see build_walls).
ChargeEditResult edit_charge(const MillCase& c, const MillDerived& d, std::vector<Ball> balls,
                             const ChargeEditOptions& options);

// The size class of a ball: the first class of its material whose diameter
// range holds its diameter, else the nearest class of its material; −1 when
// no class has its material.
int size_class_of(const MillCase& c, const Ball& b);

// The deepest overlap in a scene, as a fraction of the smaller radius: ball
// against ball, shell, end plates and lifters (turned by scene.mill_angle).
// For checks; O(n) with a cell grid.
double deepest_overlap(const Scene& scene);

}  // namespace mc
