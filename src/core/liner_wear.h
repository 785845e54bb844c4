// The liner moved by its wear (the life study, docs/liner-life.md): a lifter
// bar's outline moved into the steel by the depth each of its wear stations
// lost, the shell's radius grown by its mean depth, the bar kept a valid
// convex profile. No OpenCL.
#pragma once

#include <cmath>
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
// depths are first smoothed along the outline until it can: 1 2 1 passes
// doubled (`spread`, the passes of the wider), the last two blended by the
// least share of the wider that does, so that the shape moves on smoothly
// as the booked wear grows.
WornLifter wear_lifter(const std::vector<Vec2>& outline, double R, const std::vector<double>& station_area,
                       double shell_depth);

// Where each wear station lies in the bar's frame (its centre on the
// outline) and its length along the outline, m.
struct StationPlace {
  Vec2 centre;
  double length = 0;
};
std::vector<StationPlace> station_places(const std::vector<Vec2>& outline, double R);

// A stage's wear rates on one bar: its stations' volume per second over a
// mill of `length` (m³/s), the shell's mean depth per hour (m/h).
struct BarWearRates {
  std::vector<double> station_m3_s;
  double length = 1, shell_m_per_h = 0;
};

// The bar (outline above a shell of radius R) after `hours` of those rates,
// worn as wear_lifter wears it.
WornLifter wear_for_hours(const std::vector<Vec2>& outline, double R, const BarWearRates& rates, double hours);

// How fast those rates wear the bar's top back (m per hour): the mean over
// its stations whose centre lies above 90 % of its height (the highest
// station's where none does).
double top_wear_m_per_h(const std::vector<Vec2>& outline, double R, const BarWearRates& rates);

// The hours in which those rates take `loss` (m) off the bar's height above
// the shell: the height it actually loses as it wears (its top rounds, its
// faces lay back, the shell falls away under it), found by bisection on
// wear_for_hours to 1e-9; negative when that wear does not lower it (the
// shell wears as fast as its top) or `loss` is not positive.
double hours_to_lose(const std::vector<Vec2>& outline, double R, const BarWearRates& rates, double loss);

// A liner's consumption as plants book it: grams of steel worn per kWh the
// mill draws, from a wear rate (kg/h) and the mill's power (W): kg/h over
// kW is kg/kWh, so g/kWh = 1e6 · kg/h / W. NaN without a positive power.
inline double grams_per_kWh(double kg_per_h, double power_W) {
  return power_W > 0 ? kg_per_h * 1e6 / power_W : NAN;
}

}  // namespace mc
