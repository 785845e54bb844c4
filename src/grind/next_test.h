// Which batch test to run next (docs/grinding-next-test.md): for a candidate test (a mill's run and grinding times, read
// on the usual sieves), the 95 % interval a product of the fitted ore is
// expected to have once that test is fitted with the others. Linear: the
// current fit's information on its variables (free and held) plus the
// candidate's Fisher information JᵀJ / s² at the fitted ore (its best point, best_point), inverted; the
// held parameters' reach now scaled by how much their linear reach falls
// (never grown; unchanged, but for t, by a candidate without information).
#pragma once

#include <string>
#include <vector>

#include "grind/fit.h"
#include "grind/interval.h"
#include "grind/ore.h"

namespace mc::grind {

// The usual batch test's sieves, 3.35 mm and the √2 series from 2.36 mm
// down to 53 µm (13), those within the ore's size classes; the ore's feed
// read at them; the grinding times; noise as the first test's (weight 1).
BatchTest candidate_test(const Ore& ore, const std::vector<double>& times_min);

struct NextTestWidth {
  Interval expected;               // the product's expected 95 % interval after the test
  double width = std::numeric_limits<double>::quiet_NaN();  // expected.hi - expected.lo
  std::vector<std::string> fixes;  // held parameters the test would fix (expected standard error within the fit's limit)
  int data = 0;                    // the candidate's readings that carry information
  // √(gᵀ L_ff⁻¹ g): the free part's standard deviation after the test (the
  // held ones given); √(cᵀ Σ c): over the free and every held one the
  // information after reaches.
  double sd = std::numeric_limits<double>::quiet_NaN(), sd_all = std::numeric_limits<double>::quiet_NaN();
  // The held parameters' expected reach below and above the centre (≥ 0).
  double reach_down = std::numeric_limits<double>::quiet_NaN(), reach_up = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::vector<double>> added;  // the candidate's information J_cᵀ J_c / s² (every variable)
};

// The expected interval, after the candidate test, of the product whose
// sensitivity at the fitted ore is `s` (sensitivities(..., true): with its
// gradient in the held parameters too). The current information is the
// tests' JᵀJ / s² on the free and the held variables that the fit kept
// (FitCovariance::information), at s² = interval_variance; the candidate
// adds J_cᵀ J_c / s², J_c the derivatives of its readings (pp) at the
// fitted ore's best point (best_point), its readings taken to scatter as the first test's. The free
// part: t √(gᵀ L_ff⁻¹ g). The held parameters' reach, each side: their
// reach now times min(1, linear after / linear now), the linear reach
// t √(cᵀ Σ c − gᵀ L_ff⁻¹ g) of the information after the test against the
// same of the tests' information alone (t at its ν); at least the reach
// now of the held ones without information even after (in quadrature);
// where none is informed now, the lesser of the reach now and the linear
// after. Centred where the interval now is. An ore
// without the information matrix gets no interval (expected.valid() false).
NextTestWidth expected_after(const Ore& ore, const FitCovariance& u, const Sensitivity& s,
                             const TestInMill& candidate);

}  // namespace mc::grind
