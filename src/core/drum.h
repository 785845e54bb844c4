// A closed laboratory drum with lifters and a packed charge, built in code.
// The engine's tests and the default `run` use it until case files exist.
#pragma once

#include <cstdint>

#include "core/lifters.h"
#include "core/scene.h"

namespace mc {

struct DrumSpec {
  double diameter = 0.30;        // inside the liners, m
  double length = 0.10;          // m
  int n_balls = 400;
  double radius_min = 0.006;     // m
  double radius_max = 0.008;     // m
  double speed_fraction = 0.75;  // of critical
  int lifter_rows = 8;
  LifterProfile lifter{0.012, 0.012, 15.0, {}};
  ContactLaw law = ContactLaw::linear;
  Precision precision = Precision::single;
  double restitution = 0.5;
  double mu_slide = 0.5;
  double mu_roll = 0.02;
  double kn = 2.0e5;             // N/m, linear law
  double dt_fraction = 1.0 / 25; // dt = contact time × this
  std::uint32_t seed = 12345;
};

// Critical speed in rad/s of a drum for balls of diameter d: Nc = 42.3/sqrt(D−d) rpm.
double critical_omega(double diameter, double ball_diameter);

// Balls on a jittered lattice in the lowest part of the drum, clear of the
// shell, the plates, the lifters and each other, at rest; dt from the contact
// time of the smallest ball pair (linear) or of an impact at tip speed (Hertz).
// Throws std::invalid_argument when the balls do not fit.
Scene make_drum(const DrumSpec& spec);

// Contact time of two balls of radius r and mass m (linear law, no damping)
// or of a Hertz impact at speed v.
double contact_time_linear(double kn, double m_eff);
double contact_time_hertz(double e_star, double r_eff, double m_eff, double v);

}  // namespace mc
