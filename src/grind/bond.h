// Bond's locked-cycle test run on the population balance (docs/grinding-scale-up.md):
// the test's charge, the size series put on its closing sieve, and the
// test itself with Bond's work index from it.
#pragma once

#include <vector>

#include "grind/ore.h"
#include "grind/pbm.h"

namespace mc::grind {

// In Bond's test the mill holds 700 cm³ of packed feed.
double bond_charge_kg(const Ore& ore);

// Bond's test screens at P1: the series is moved up to put P1 on a class
// top (it still covers the feed; the classes keep their count), and the
// feed (and its F80) is put on the moved classes.
void put_sieve_on_class_top(Ore& ore, double p1_m);

// The closing sieve must leave class tops below it (P1 above the finest
// top of the moved series): throws std::invalid_argument naming --bond.
void check_bond_sieve(const SizeSeries& s, double p1_m);

// Bond's locked-cycle test (F. C. Bond 1961, the standard procedure): 700
// cm³ of feed, ground, screened at P1; the undersize replaced by fresh
// feed; the revolutions of each cycle set so that the undersize is 1/3.5
// of the charge (a circulating load of 250 %); Gbp the net grams of
// undersize made per revolution. The laboratory stops once three cycles
// agree within 3 %; here the cycles go on to the equilibrium that rule
// approximates: Gbp changing by less than kBondSteady (relative) from one
// cycle to the next, the load then 250 % (steady false: not reached in
// kBondMaxCycles). Wi in kWh per tonne (Bond's per short ton x 1.10231).
constexpr double kBondSteady = 1e-7;
constexpr int kBondMaxCycles = 2000;
constexpr double kShortTonsPerTonne = 1000 / 907.18474;
struct BondResult {
  double p1_um = 0, gbp_g_rev = 0, p80_um = 0, f80_um = 0, wi_kWh_t = 0, charge_g = 0, circulating_load = 0;
  int cycles = 0;
  bool steady = false;
  std::vector<double> gbp_by_cycle, revs_by_cycle;
};

// The test on a feed (class masses summing to 1) with rates S per minute
// in a mill turning at `rpm`, screened at p1_m.
BondResult bond_test(const SizeSeries& s, const std::vector<double>& feed, const std::vector<double>& S_per_min,
                     const std::vector<std::vector<double>>& b, double rpm, double charge_kg, double p1_m);

}  // namespace mc::grind
