// The liner moved by its wear (the life study, docs/liner-life.md): a lifter
// bar's outline moved into the steel by the depth each of its wear stations
// lost, the shell's radius grown by its mean depth, the bar kept a valid
// convex profile. No OpenCL.
#pragma once

#include <vector>

#include "core/lifters.h"
#include "core/vec.h"

namespace mc {

struct WornLifter {
  std::vector<Vec2> outline;  // the bar's frame above the worn shell (core/lifters.h)
  double booked_area = 0;     // m², the stations' volume per metre of mill
  double removed_area = 0;    // m², the cross-section the new outline lost above the old shell
  double scale = 1;           // on the stations' depths, to remove the booked area
  int spread = 1;             // passes of 1 2 1 smoothing the depths took
  bool worn_away = false;     // less than kWornAwayHeight left above the shell
};

// A bar lower than this above the shell is worn away, m.
inline constexpr double kWornAwayHeight = 1e-3;

// Wears one bar: `outline` in its frame above a shell of radius R,
// `station_area` the volume each of its MC_WEAR_STATIONS stations lost over
// the stage per metre of mill (m²), `shell_depth` how far the shell between
// the bars wore back (m). Each point of the exposed outline moves inward
// along its normal by its station's depth (interpolated between station
// centres): what is left is the bar less a strip under each piece of its
// outline, and its convex hull, thinned to at most kLifterMaxPoints points
// with its feet on the worn shell, is the worn bar. The depths are scaled
// (by at most 2) so that the area removed equals the booked area to 1e-5;
// where wear gathers on a corner more than a convex bar can lose there, the
// depths are first smoothed along the outline until it can (`spread`).
WornLifter wear_lifter(const std::vector<Vec2>& outline, double R, const std::vector<double>& station_area,
                       double shell_depth);

// Where each wear station lies in the bar's frame (its centre on the
// outline) and its length along the outline, m.
struct StationPlace {
  Vec2 centre;
  double length = 0;
};
std::vector<StationPlace> station_places(const std::vector<Vec2>& outline, double R);

}  // namespace mc
