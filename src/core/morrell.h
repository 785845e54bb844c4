// Morrell's C-model of the power drawn by a tumbling mill's charge (Morrell
// 1996, Trans. IMM C105; the form used in JKSimMet), an engineering band to
// compare a DEM result with. Angles follow Morrell's convention (DESIGN.md):
// radians or degrees counter-clockwise from 3 o'clock, mill turning
// counter-clockwise; the toe near 200–250°, the shoulder near 30–70°.
#pragma once

namespace mc {

struct MorrellInput {
  double diameter = 0;        // m, inside the liners
  double length = 0;          // m, of the cylinder
  double filling = 0;         // J, fraction of the mill volume the charge fills
  double speed_fraction = 0;  // of critical
  double speed_rpm = 0;
  double charge_density = 0;  // kg/m³ of the bulk charge (balls and voids)
};

// Morrell's lumped calibration of the theory to 76 measured mills: the
// charge's share of the measured power (gross less no-load) is k times the
// theoretical net power, k = 1.26. A DEM charge's power compares with k·P_net.
inline constexpr double kMorrellK = 1.26;

struct MorrellResult {
  double toe_deg = 0, shoulder_deg = 0;  // the model's empirical charge angles
  double net_power_W = 0;                // theoretical, with those angles
  double charge_power_W = 0;             // k · net_power_W: the model's prediction
  double inner_radius_m = 0;             // r_i, inner surface of the active charge
};

// The model's own toe and shoulder and the net power they give. A dry charge:
// no slurry pool term.
MorrellResult morrell_c_model(const MorrellInput& in);

// The net power with given toe and shoulder angles (rad), e.g. a DEM's.
double morrell_net_power(const MorrellInput& in, double toe_rad, double shoulder_rad);

}  // namespace mc
