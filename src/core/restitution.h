// Damping calibrated from the coefficient of restitution.
#pragma once

namespace mc {

enum class ContactLaw { linear, hertz };

// The dimensionless damping `d` of cl/contact_law.h (γ = d·sqrt(S·m*)) whose
// rebound velocity ratio is e, with the normal force clipped at zero.
//
// Why not the closed forms of DESIGN.md: ζ = −ln e/sqrt(π² + ln² e) is exact
// for a linear dashpot only while the contact may pull; with Fn ≥ 0 the
// contact ends early and e = 0.1 rebounds at 0.25, e = 0.5 at 0.55. The Hertz
// form (β, sqrt(5/6)) gives the same ratios. So the one-parameter contact ODE
// is solved here in dimensionless form and d found by bisection:
//   linear: x'' = −x − d·x'
//   Hertz:  x'' = −x^1.5 − d·sqrt(3/2)·x^0.25·x'   (γ = d·sqrt(Sn m*))
// x(0) = 0, x'(0) = 1; the rebound ratio is −x' when the force reaches zero.
// Both ratios are independent of impact speed, size and stiffness.
double damping_for_restitution(ContactLaw law, double e);

// The rebound ratio of the dimensionless contact with damping d (the forward
// problem, also used by the tests).
double restitution_for_damping(ContactLaw law, double d);

}  // namespace mc
