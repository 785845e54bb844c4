// Whole-solver energy checks in a closed drum: conservation when nothing
// dissipates, and the power balance of a turning charge.
#include <catch2/catch.hpp>

#include <cstdio>
#include <random>

#include "core/drum.h"
#include "helpers.h"

using namespace mc;
using namespace mc::test;

TEST_CASE("an elastic box of bouncing balls keeps its energy", "[physics][energy]") {
  // e = 1, μ = 0, no rolling resistance: only the integrator can change the
  // energy (kinetic + rotational + gravity + elastic in contacts).
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    DrumSpec spec;
    spec.n_balls = 300;
    spec.restitution = 1.0;
    spec.mu_slide = 0.0;
    spec.mu_roll = 0.0;
    spec.speed_fraction = 0.0;
    spec.law = law;
    Scene sc = make_drum(spec);
    std::mt19937 rng(3);
    std::normal_distribution<double> g(0.0, 1.0);
    for (Ball& b : sc.balls) b.velocity = {g(rng), g(rng), g(rng)};
    auto s = make_solver(context(), sc);
    const double e0 = s->observe(true).total_energy();
    const double scale = s->observe(false).kinetic_J;  // gravity's zero is arbitrary
    double worst = 0;
    long collisions_seen = 0;
    for (int k = 0; k < 10; ++k) {
      s->advance(1000);
      const Observables o = s->observe(true);
      worst = std::max(worst, std::fabs(o.total_energy() - e0) / scale);
      collisions_seen += o.elastic_J > 0;
    }
    std::printf("elastic box %-6s 1e4 steps: worst |E - E0| / KE0 = %.4f %%, dissipated %.3g J\n",
                law == ContactLaw::hertz ? "hertz" : "linear", 100 * worst, s->observe(false).dissipated_J);
    CHECK(collisions_seen > 5);
    CHECK(worst < 0.005);
  }
}

TEST_CASE("a turning drum at steady state: torque power equals dissipation power plus dE/dt", "[physics][power]") {
  // 0.3 m drum, 8 lifters, 75 % of critical, friction and rolling
  // resistance: the books close for both laws. Under Hertz the tangential
  // stiffness follows the overlap, and the spring's stored energy is taken
  // with the stiffness it had (without it the dissipation came out 12 %
  // above the torque power); the dashpots' work is taken at the relative
  // speed synchronised to the step (without it 2 % high).
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    DrumSpec spec;
    spec.n_balls = 300;
    spec.law = law;
    const Scene sc = make_drum(spec);
    auto s = make_solver(context(), sc);
    const double rev_s = 2 * kPi / sc.mill_omega;
    s->advance(static_cast<long>(1.5 / sc.numerics.dt));  // warm-up: charge lifted and cycling
    const double e_start = s->observe(true).total_energy();
    s->advance(static_cast<long>(3 * rev_s / sc.numerics.dt));  // three whole revolutions
    const Observables o = s->observe(true);
    const double de_dt = (o.total_energy() - e_start) / o.interval_s;
    const double imbalance = (o.torque_power_W - o.dissipation_power_W - de_dt) / o.torque_power_W;
    std::printf("drum %-6s power over %.3f s: torque %.3f W, dissipation %.3f W, dE/dt %.3f W, imbalance %.2f %%\n",
                law == ContactLaw::hertz ? "hertz" : "linear", o.interval_s, o.torque_power_W, o.dissipation_power_W,
                de_dt, 100 * imbalance);
    INFO((law == ContactLaw::hertz ? "hertz" : "linear"));
    CHECK(o.torque_power_W > 1.0);
    CHECK(std::fabs(imbalance) < 0.02);
    // The charge is at steady state: its energy changes by under 2 % of the
    // power over the window.
    CHECK(std::fabs(de_dt) < 0.02 * o.dissipation_power_W);
    CHECK(o.wall_torque_Nm * sc.mill_omega == Approx(o.torque_power_W).epsilon(1e-3));
  }
}
