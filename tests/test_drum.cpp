// Whole-solver energy checks in a closed drum (tests/checks.cpp sets them
// up): conservation when nothing dissipates, and the power balance of a
// turning charge.
#include <catch2/catch.hpp>

#include <cmath>
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

TEST_CASE("Hertz books close on a mill of few large balls, both force kernels", "[physics][power][books]") {
  // The 0.9 m mill of 50 mm balls: eight square 40 mm bars, 48 % of
  // critical (22 rpm), dt 1e-5 s (about 15 steps a contact at tip speed),
  // one revolution after 1.5 s. Hertz overlaps of large stiff balls are a
  // few tens of micrometres: a ball that met the middle of a bar's top went
  // unseen until it overlapped by 0.24 mm (the top's corners lie 0.49 mm
  // farther from the axis than its middle, less the test's margin), gained
  // or lost energy at each such impact, and the dissipation came out 6.5 %
  // above the torque power.
  DrumSpec spec;
  spec.diameter = 0.9;
  spec.length = 0.1;
  spec.n_balls = 170;
  spec.radius_min = spec.radius_max = 0.025;
  spec.speed_fraction = 0.48;
  spec.lifter = LifterProfile{0.04, 0.04, 0.0, {}};
  spec.law = ContactLaw::hertz;
  spec.restitution = 0.5;
  spec.mu_slide = 0.3;
  spec.mu_roll = 0.01;
  const double tc = 1.534e-4;  // check's shortest contact of this mill at tip speed
  spec.dt_fraction = 1e-5 / tc;
  for (const char* forces : {"ball", "grouped"}) {
    const checks::PowerBalance b = checks::drum_power_balance(context(), spec, 1.5, 1, forces);
    std::printf("mill of 50 mm balls, hertz, %-7s forces over %.3f s: torque %.3f W, dissipation %.3f W, dE/dt %.3f W, "
                "imbalance %.2f %%\n",
                forces, b.window_s, b.torque_power_W, b.dissipation_power_W, b.energy_change_W, 100 * b.imbalance());
    INFO(forces);
    CHECK(b.torque_power_W > 100.0);
    CHECK(std::fabs(b.imbalance()) < 0.01);
  }
}

TEST_CASE("a ball meeting a lifter's flat top keeps its energy wherever it strikes (e = 1, no friction)", "[physics][energy]") {
  // A 50 mm ball at 1 m/s square onto the top of a 40 x 40 mm bar, no
  // gravity, from the middle of the top face out past its corner. The top
  // comes closest to the axis at its middle: a ball there must be tested
  // against the bar from first touch, or its contact begins overlapped and
  // the rebound gains or loses energy (seen: 0.34 to 2.97 of it).
  DrumSpec spec;
  spec.diameter = 0.9;
  spec.n_balls = 1;
  spec.radius_min = spec.radius_max = 0.025;
  spec.speed_fraction = 0.0;
  spec.lifter = LifterProfile{0.04, 0.04, 0.0, {}};  // row 0 on the +x axis: its top at x = 0.41 m
  spec.law = ContactLaw::hertz;
  spec.restitution = 1.0;
  spec.mu_slide = 0.0;
  spec.mu_roll = 0.0;
  spec.dt_fraction = 1e-5 / 1.534e-4;
  for (double y0 : {0.0, 0.004, 0.008, 0.012, 0.018, 0.03}) {
    Scene sc = make_drum(spec);
    sc.numerics.gravity = {0, 0, 0};
    sc.balls[0].position = {0.33, y0, 0.05};
    sc.balls[0].velocity = {1.0, 0, 0};
    auto s = make_solver(context(), sc);
    const double e0 = s->observe(false).total_energy();
    s->advance(static_cast<long>(0.15 / sc.numerics.dt));  // in, struck and back out
    const Observables o = s->observe(false);
    INFO("ball " << y0 << " m off the bar's middle");
    CHECK(s->balls()[0].velocity.x < -0.5);  // it struck the bar and came back
    CHECK(o.elastic_J == 0.0);                // and left it
    CHECK(o.total_energy() == Approx(e0).epsilon(0.005));
  }
}
