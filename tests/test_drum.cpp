// Whole-solver energy checks in a closed drum (tests/checks.cpp sets them
// up): conservation when nothing dissipates, and the power balance of a
// turning charge.
#include <catch2/catch.hpp>

#include <cstdio>

#include "checks.h"
#include "helpers.h"

using namespace mc;
using namespace mc::test;

TEST_CASE("an elastic box of bouncing balls keeps its energy", "[physics][energy]") {
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    const checks::ElasticBox box = checks::elastic_box(context(), law);
    std::printf("elastic box %-6s 1e4 steps: worst |E - E0| / KE0 = %.4f %%, dissipated %.3g J\n",
                law == ContactLaw::hertz ? "hertz" : "linear", 100 * box.worst_drift, box.dissipated_J);
    CHECK(box.samples_with_contacts > 5);
    CHECK(box.worst_drift < 0.005);
  }
}

TEST_CASE("a turning drum at steady state: torque power equals dissipation power plus dE/dt", "[physics][power]") {
  // Friction and rolling resistance, both laws: the books close. Under Hertz
  // the tangential stiffness follows the overlap, and the spring's stored
  // energy is taken with the stiffness it had (without it the dissipation
  // came out 12 % above the torque power); the dashpots' work is taken at
  // the relative speed synchronised to the step (without it 2 % high).
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    const checks::PowerBalance b = checks::drum_power_balance(context(), law);
    std::printf("drum %-6s power over %.3f s: torque %.3f W, dissipation %.3f W, dE/dt %.3f W, imbalance %.2f %%\n",
                law == ContactLaw::hertz ? "hertz" : "linear", b.window_s, b.torque_power_W, b.dissipation_power_W,
                b.energy_change_W, 100 * b.imbalance());
    INFO((law == ContactLaw::hertz ? "hertz" : "linear"));
    CHECK(b.torque_power_W > 1.0);
    CHECK(std::fabs(b.imbalance()) < 0.02);
    // The charge is at steady state: its energy changes by under 2 % of the
    // power over the window.
    CHECK(std::fabs(b.energy_change_W) < 0.02 * b.dissipation_power_W);
    CHECK(b.torque_times_omega_W == Approx(b.torque_power_W).epsilon(1e-3));
  }
}
