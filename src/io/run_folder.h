// A finished run's folder as `millcharge grind` reads it: the mill's power,
// speed and filling from summary.json, the mill and its balls from
// case.toml and, for the spectrum rates, the normal energy spectrum from
// spectra.csv, checked against summary.json. A missing, damaged or older
// run is refused naming the file (and the line).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "grind/ore.h"
#include "grind/pbm.h"

namespace mc::io {

struct Run {
  double speed_rpm = 0;
  double power_W = 0, filling = 0, mill_volume = 0, porosity = 0.4, ball_radius_m = 0;
  // The severity spectrum the grind reads (cl/layout.h): collisions binned
  // by energy over their own R*, each bin with its mean energy and mean R*;
  // the energy at first touch or the normal loss (`basis`).
  std::vector<grind::SpectrumBin> spectrum;
  grind::EnergyBasis basis = grind::EnergyBasis::impact;
  bool clumps = false;  // the charge holds clumps of spheres
  std::string title;
  // The power's books over the averaging window (summary.json): a run whose
  // torque and dissipation differ is not yet in steady motion.
  double dissipation_W = 0, imbalance = 0, energy_change_W = 0;
  // The case's contact law and default parameters (the balls' material's
  // Young's modulus for Hertz): what a fitted ore records and is checked
  // against. `pair_overrides`: the case sets some pairs apart.
  grind::ContactRecord contact;
  int pair_overrides = 0;
};

// `need_spectrum`: read spectra.csv too (the spectrum rate model), its
// severity spectrum of `basis`.
Run read_run(const std::filesystem::path& dir, bool need_spectrum,
             grind::EnergyBasis basis = grind::EnergyBasis::impact);

}  // namespace mc::io
