// An ore as the grinding model takes it (what an ore file describes,
// src/io/ore_file.h): its density and hold-up, the size series and the
// feed on it, Austin's appearance function and the parameters of one of
// the three rate models.
#pragma once

#include <string>
#include <vector>

#include "grind/pbm.h"

namespace mc::grind {

enum class RateModel { austin, energy, spectrum };

struct Ore {
  std::string name;
  double density = 0;        // kg/m³
  double holdup_kg = 0;      // ore in the mill; or from powder_filling
  double powder_filling = 0; // U: the ball bed's voids the ore fills
  double bed_porosity = 0.4; // of the ore's own bed
  double bulk_density = 0;   // kg/m³ of the packed feed (Bond's 700 cm³), 0: density (1 - bed_porosity)
  SizeSeries sizes;
  std::vector<double> feed;  // class masses
  std::vector<double> sieve_m, sieve_passing;  // the feed as given
  double ratio = 0;
  double f80_m = 0;
  AustinBreakage breakage;
  RateModel model = RateModel::energy;
  AustinRates austin;
  EnergyRates energy;
  Fracture fracture;
  double packing = 0.6, efficiency = 1.0;
  int tanks = 1;
};

}  // namespace mc::grind
