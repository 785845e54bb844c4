// Toe and shoulder of the charge (Morrell's convention, DESIGN.md) from the
// angular distribution of ball–shell and ball–lifter contacts.
#pragma once

#include <vector>

namespace mc {

struct ChargeAngles {
  bool found = false;       // false: no clear band (empty, or contacts all round)
  double toe_deg = 0;       // where the charge lands back on the shell
  double shoulder_deg = 0;  // where it leaves the shell
};

// `counts` covers 360° in equal bins from 3 o'clock counter-clockwise. The
// counts are smoothed over `smooth_bins` bins (circular moving average); the
// band is the run of bins at or above threshold × peak that contains the peak,
// and its ends, interpolated to the crossing, are the toe (the start, going
// counter-clockwise) and the shoulder (the end): the mill turns
// counter-clockwise, so the charge rides the shell from the toe past the
// bottom up to the shoulder.
ChargeAngles toe_and_shoulder(const std::vector<long>& counts, double threshold = 0.2, int smooth_bins = 5);

}  // namespace mc
