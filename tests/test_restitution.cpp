// The damping calibration of src/core/restitution.cpp.
#include <catch2/catch.hpp>

#include <cmath>

#include "core/restitution.h"

using namespace mc;

TEST_CASE("calibrated damping reproduces e under the no-tension rule", "[physics][restitution]") {
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    double previous = 1e9;
    for (double e : {0.05, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99}) {
      const double d = damping_for_restitution(law, e);
      CHECK(restitution_for_damping(law, d) == Approx(e).epsilon(1e-6));
      CHECK(d < previous);  // less damping for bouncier contacts
      previous = d;
    }
    CHECK(damping_for_restitution(law, 1.0) == 0.0);
    CHECK(restitution_for_damping(law, 0.0) == Approx(1.0).epsilon(1e-6));
    CHECK_THROWS(damping_for_restitution(law, 0.0));
    CHECK_THROWS(damping_for_restitution(law, 1.2));
  }
}

TEST_CASE("the closed-form damping of DESIGN.md misses e once Fn >= 0", "[physics][restitution]") {
  // Why the calibration exists: ζ = −ln e / sqrt(π² + ln² e) rebounds at
  // about 0.25 for e = 0.1 when the contact may not pull.
  const double e = 0.1, le = std::log(e);
  const double zeta = -le / std::sqrt(M_PI * M_PI + le * le);
  const double got = restitution_for_damping(ContactLaw::linear, 2 * zeta);
  CHECK(got == Approx(0.2527).margin(0.002));
  const double beta = le / std::sqrt(le * le + M_PI * M_PI);
  const double got_hertz = restitution_for_damping(ContactLaw::hertz, -2 * std::sqrt(5.0 / 6.0) * beta);
  CHECK(got_hertz == Approx(0.2527).margin(0.002));
}
