// An ore as the grinding model takes it (what an ore file describes,
// src/io/ore_file.h): its density and hold-up, the size series and the
// feed on it, its appearance function (Austin's B or Tavares' t10) and the
// parameters of one of the three rate models.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "grind/pbm.h"

namespace mc::grind {

enum class RateModel { austin, energy, spectrum };
// The appearance function of broken material: Austin's B, or Tavares'
// energy-dependent t10 (the spectrum model only).
enum class Appearance { austin, t10 };
// The collision energy the spectrum model's fracture parameters are set
// against: the impact energy at first touch (1/2 m* vn^2, what a drop-weight
// test or load cell delivers) or the normal energy the collision loses,
// each over the collision's own R*; or, for an ore fitted before those were
// booked, the normal loss with one radius for every collision (half the
// charge's number-mean radius between balls, the radius on walls), as it
// was fitted.
enum class EnergyBasis { impact, loss, loss_one_radius };
inline const char* basis_name(EnergyBasis b) {
  return b == EnergyBasis::impact ? "impact" : b == EnergyBasis::loss ? "loss" : "loss_one_radius";
}
// The basis a name gives; false for a name that is none.
inline bool basis_of(const std::string& name, EnergyBasis* b) {
  for (EnergyBasis x : {EnergyBasis::impact, EnergyBasis::loss, EnergyBasis::loss_one_radius})
    if (name == basis_name(x)) return *b = x, true;
  return false;
}

// What a fit to batch tests leaves open (the [fitted] table's covariance and
// held parameters; docs/grinding-intervals.md). The fitted variables are
// the logarithm of a scale ("log(efficiency)") and any other parameter
// itself, as the fit moves them.
struct HeldParameter {
  std::string name;             // the ore file's key
  double value = 0;             // held at (file units)
  double lo = 0, hi = 0;        // what the data leave open (file units)
  std::string why;
  // The free variables refitted with this one at lo and at hi (empty: the
  // refit failed; the free ones then stay at their fitted values).
  std::vector<double> free_at_lo, free_at_hi;
};
// A point of the held parameters: each one's value, and the free variables
// refitted there.
struct HeldEdge {
  std::vector<double> held;  // each held parameter's value (file units), in the order of `held`
  std::vector<double> free;  // the free variables refitted there
  // The held parameter whose profile ends here (the others refitted with
  // the free ones); -1: a point where several were moved together.
  int of = -1;
};
struct FitCovariance {
  bool given = false;                       // the ore file has one (an ore fitted before has not)
  std::vector<std::string> names;           // the free parameters, ore file keys
  std::vector<double> values;               // their fitted variables at the fit
  // Covariance of the fitted variables (s² the fit's), taken at `best`
  // where there are held parameters (an ore fitted before: at the fit).
  std::vector<std::vector<double>> matrix;
  double residual_variance_pp2 = 0;         // s² of the fit
  int dof = 0;                              // data − free parameters
  std::vector<HeldParameter> held;          // unidentified, held at their start, or on their bound
  // Where the held parameters fit the data best (the least sum of squares
  // their profiles met), the free ones refitted there: the centre the held
  // ones' reach is measured from. Empty held: none kept.
  HeldEdge best;
  // The edge of the data around `best`: each held parameter alone to its
  // range's ends, and two to four together toward each corner of their
  // ranges, as far as the data allow.
  std::vector<HeldEdge> edges;
  // The tests' information on every fitted variable at `best` (else at the fit), the free
  // ones' then the held ones': JᵀJ / s² of the weighted residuals (what a
  // next test adds to: next_test.h). Empty: not kept.
  std::vector<std::vector<double>> information;
  // The weighted sum of squares at the fit (where the held parameters are
  // held) and at `best`, and the profile limit from `best`
  // (fitted.ssr_held, ssr_best, ssr_limit): ssr_fit > ssr_limit says the
  // ore's own values lie outside the data's 95 % region. 0: not kept.
  double ssr_fit = 0, ssr_best = 0, ssr_limit = 0;
  // The fitted ore's tables hashed (io::ore_tables_hash; fitted.tables_fnv1a):
  // a hand edit of any key, fitted or not, leaves the covariance stale. "":
  // not kept.
  std::string tables_hash;
};

// The contact law and parameters of the DEM run an ore was fitted through
// (the [fitted] table of an ore file): the normal energy spectrum, and so
// the fitted parameters, hold only under these (docs/grinding.md).
struct ContactRecord {
  std::string law;  // "linear" or "hertz"; empty: the ore was not fitted
  double restitution = 0, friction = 0, rolling_friction = 0;
  double stiffness_N_m = 0;      // linear law
  double youngs_modulus_Pa = 0;  // hertz: the balls' material
  std::string pairs;  // the case's [[contact.pair]] overrides, as text ("" : none)
  // The spectrum the ore was fitted on: "impact", "loss" or
  // "loss_one_radius" (an ore fitted before the severity spectra were
  // booked, whose [fitted] table has none); "" for other rate models.
  std::string energy_basis;
  // What else the ore file's [fitted] table says (not compared).
  std::string test, run, parameters;
  double rms_residual_pp = 0;
  // The fit's residuals' lag-1 autocorrelation along the sieves
  // (residual_lag1; fit.h): NaN where not kept.
  double residual_lag1 = std::numeric_limits<double>::quiet_NaN();
  // The sieve errors' correlation from one sieve to the next the fit took
  // (sieve_error_rho; sieve_errors.h): 0, independent. Its tests' refits
  // (the intervals' held reach, the next test) whiten by it.
  double sieve_error_rho = 0;
  FitCovariance covariance;  // a batch test's fit only
};

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
  Appearance appearance = Appearance::austin;
  AustinBreakage breakage;
  T10Breakage t10;
  RateModel model = RateModel::energy;
  AustinRates austin;
  EnergyRates energy;
  Fracture fracture;
  double packing = 0.6, efficiency = 1.0;
  EnergyBasis energy_basis = EnergyBasis::impact;
  bool energy_basis_given = false;  // rates.energy_basis in the file
  int tanks = 1;
  ContactRecord fitted_under;
};

}  // namespace mc::grind
