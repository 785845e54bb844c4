// Which batch test to run next (docs/grinding-intervals.md, "Which test to
// run next"): for a candidate test (a mill's run and grinding times, read
// on the usual sieves), the 95 % interval a product of the fitted ore is
// expected to have once that test is fitted with the others. Linear: the
// current fit's information on its variables plus the candidate's Fisher
// information JᵀJ / s² at the fitted ore, inverted; a held parameter the
// sum would fix (its expected standard error within the fit's own limit
// for identifying it) joins the free ones, the others keep their ranges.
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
  std::vector<std::string> fixes;  // held parameters the test would fix
  int data = 0;                    // the candidate's readings that carry information
};

// The expected interval, after the candidate test, of the product whose
// sensitivity at the fitted ore is `s` (sensitivities(..., true): with its
// gradient in the held parameters too).
//
// The current information on the free variables f and held ones h is
// rebuilt from what the ore keeps: Λ_ff = C⁻¹; the held ones' coupling to
// the free from the refits at their range's ends (the free ones move by B
// per unit of h: Λ_fh = -Λ_ff B, Λ_hh = Bᵀ Λ_ff B + S); S_j = t²/Δ_j² from
// the profile's reach Δ_j where the data bound it, 0 where the range is
// open. The candidate adds J_cᵀ J_c / s², J_c the derivatives of its
// readings (pp) in (f, h) at the fitted ore.
NextTestWidth expected_after(const Ore& ore, const FitCovariance& u, const Sensitivity& s,
                             const TestInMill& candidate);

}  // namespace mc::grind
