// The end plates over a life study (docs/liner-life.md#the-end-plates):
// what a stage's run booked on each plate's rings and sectors, the depth
// per ring it wears them at, and the plates after a stage's hours. A plate
// turns with the mill, so each ring wears alike all round: its sectors are
// the ring's samples, and their spread its standard error. The worn plates
// go to the next stage's case as [liner] plate_depth_mm (core/plate_wear.h).
// No OpenCL, no files.
#pragma once

#include <array>
#include <vector>

namespace mc::life {

// A run's books on the end plates: per plate (z = 0, then z = length), per
// ring (from the axis out), per sector, the sliding wear at the case's
// coefficient (m³/s) and the strike energy (J/s). Empty: the study does not
// wear its plates.
struct PlateBooks {
  std::array<std::vector<std::vector<double>>, 2> sliding_m3_s, strike_W;
  bool empty() const { return sliding_m3_s[0].empty(); }
  int rings() const { return static_cast<int>(sliding_m3_s[0].size()); }
  int sectors() const { return empty() ? 0 : static_cast<int>(sliding_m3_s[0][0].size()); }
};

// Each ring's wear depth rate (m per case hour) at a mix (volume = sliding
// · the sliding wear booked + impact · the strike energy, impact in m³/J),
// on plates of radius R cut in equal rings; and its standard error, the
// spread of the ring's sectors' rates over the root of their count.
struct PlateRates {
  std::array<std::vector<double>, 2> m_per_h, se_m_per_h;
};
PlateRates plate_rates(const PlateBooks& b, double sliding, double impact, double R);

// A stage's step on the plates: the ring depths after `hours` of `rates`
// from `depth` (m; empty: as new), each ring moved by what it booked
// (core/plate_wear.h plate_increment: never back), and per ring the volume
// the rates booked (m³) and the volume the face lost (the change of the
// ring's mean depth times its area): equal, except in a ring held where it
// was, which loses a little more.
struct PlateStep {
  std::array<std::vector<double>, 2> depth, booked_m3, removed_m3;  // per plate, per ring
};
PlateStep wear_plates(const std::array<std::vector<double>, 2>& depth, const PlateRates& rates, double hours,
                      double R);

// The face lost per ring (m³) between two states of one plate's depths.
std::vector<double> plate_removed(const std::vector<double>& before, const std::vector<double>& after, double R);

}  // namespace mc::life
