#include "core/morrell.h"

#include <cmath>

namespace mc {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;

// The net power, and the inner radius r_i of the active charge.
double net_power(const MorrellInput& in, double toe, double shoulder, double* inner_radius) {
  const double rm = 0.5 * in.diameter;
  const double J = in.filling;
  const double N = in.speed_rpm / 60.0;  // rev/s
  // Fraction of the time the charge spends on the shell (β) from the time
  // on the shell t_c and the time in flight t_f.
  const double arc = 2 * kPi + shoulder - toe;  // angle of the charge's free surface side
  const double r_mean = 0.5 * rm * (1 + std::sqrt(std::max(0.0, 1 - 2 * kPi * J / arc)));
  const double t_c = (2 * kPi - toe + shoulder) / (2 * kPi * 0.5 * N);
  const double drop = std::max(0.0, std::sin(shoulder) - std::sin(toe));
  const double t_f = std::sqrt(2 * r_mean * drop / kG);
  const double beta = t_c / (t_f + t_c);
  const double ri = rm * std::sqrt(std::max(0.0, 1 - 2 * kPi * beta * J / arc));
  if (inner_radius) *inner_radius = ri;
  const double z = std::pow(1 - J, 0.4532);
  const double rc = in.charge_density;
  const double lift = kPi * kG * in.length * N * rm / (3 * (rm - z * ri)) *
                      (2 * rm * rm * rm - 3 * z * rm * rm * ri + ri * ri * ri * (3 * z - 2)) * rc * drop;
  const double kinetic = in.length * rc * std::pow(N * rm * kPi / (rm - z * ri), 3) *
                         (std::pow(rm - z * ri, 4) - std::pow(ri, 4) * std::pow(z - 1, 4));
  return lift + kinetic;
}

}  // namespace

double morrell_net_power(const MorrellInput& in, double toe, double shoulder) {
  return net_power(in, toe, shoulder, nullptr);
}

MorrellResult morrell_c_model(const MorrellInput& in) {
  const double J = in.filling, phi = in.speed_fraction;
  // The speed at which the charge would centrifuge as a whole, and the
  // empirical toe and shoulder (fits to photographs of a glass-ended mill).
  const double phi_c_limit = 0.35 * (3.364 - J);
  const double phi_c = phi > phi_c_limit ? phi : phi_c_limit;
  const double toe = 2.5307 * (1.2796 - J) * (1 - std::exp(-19.42 * (phi_c - phi))) + kPi / 2;
  const double shoulder = kPi / 2 - (toe - kPi / 2) * ((0.3386 + 0.1041 * phi) + (1.54 - 2.5673 * phi) * J);
  MorrellResult r;
  r.toe_deg = toe * 180 / kPi;
  r.shoulder_deg = shoulder * 180 / kPi;
  r.net_power_W = net_power(in, toe, shoulder, &r.inner_radius_m);
  r.charge_power_W = kMorrellK * r.net_power_W;
  return r;
}

}  // namespace mc
