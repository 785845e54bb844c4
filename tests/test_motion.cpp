// Single-ball closed forms (VERIFICATION.md §2 and §3): free flight, sliding
// to rolling, and a ball carried on a turning shell.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>

#include "checks.h"
#include "helpers.h"

using namespace mc;
using namespace mc::test;

TEST_CASE("free flight follows the parabola", "[physics][motion]") {
  for (Precision prec : {Precision::single, Precision::double_}) {
    const Material steel{"steel", 7800, 2e11, 0.3};
    Scene sc = bare_scene(steel, steel, Interaction{}, ContactLaw::hertz, prec);
    sc.numerics.gravity = {0, -9.81, 0};
    sc.numerics.dt = 1e-3;
    Ball b;
    b.radius = 0.01;
    b.velocity = {2.0, 3.0, -1.0};
    sc.balls = {b};
    auto s = make_solver(context(), sc);
    s->advance(500);  // 0.5 s; a half-step error in v(−½) would show as 2.5e-3 m
    const double t = s->time_s();
    const auto bs = s->balls();
    const double tol = prec == Precision::double_ ? 1e-9 : 1e-4;
    CHECK(bs[0].position.x == Approx(2.0 * t).margin(tol));
    CHECK(bs[0].position.y == Approx(3.0 * t - 0.5 * 9.81 * t * t).margin(tol));
    CHECK(bs[0].position.z == Approx(-1.0 * t).margin(tol));
    CHECK(bs[0].velocity.y == Approx(3.0 - 9.81 * t).margin(tol * 10));
  }
}

TEST_CASE("a ball sliding on a floor starts rolling at 5/7 of its speed", "[physics][motion]") {
  for (ContactLaw law : {ContactLaw::hertz, ContactLaw::linear}) {
    const checks::Rolling r = checks::sliding_to_rolling(context(), law);
    INFO((law == ContactLaw::hertz ? "hertz" : "linear") << " v/v0 " << r.speed_ratio << " w*r/v " << r.slip_ratio);
    std::printf("rolling %-6s v/v0 %.5f (5/7 = %.5f), omega*r/v %.5f\n", law == ContactLaw::hertz ? "hertz" : "linear",
                r.speed_ratio, 5.0 / 7.0, r.slip_ratio);
    CHECK(rel_err(r.speed_ratio, 5.0 / 7.0) < 0.01);
    // Rolling without slip: ω·r = v.
    CHECK(rel_err(r.slip_ratio, 1.0) < 0.01);
  }
}

TEST_CASE("a ball carried on a turning shell leaves where cos(alpha) = phi^2", "[physics][mill]") {
  // VERIFICATION.md §3: it leaves at α from the top vertical with
  // cos α = φ², and lands on the same circle 3α past the top after
  // 4 ω Rb sin α / g (tests/checks.cpp says why the setup is as it is).
  for (double phi : {0.6, 0.75, 0.9}) {
    const checks::ShellFlight f = checks::shell_flight(context(), phi);
    std::printf("shell carry phi %.2f: leaves %.2f deg from top (theory %.2f), lands %.2f deg past it (%.2f) "
                "after %.4f s (%.4f)\n",
                phi, f.departure_deg, f.departure_theory_deg, f.landing_deg, f.landing_theory_deg, f.flight_s,
                f.flight_theory_s);
    INFO("phi " << phi);
    CHECK(std::fabs(f.departure_deg - f.departure_theory_deg) < 2.0);
    CHECK(std::fabs(f.landing_deg - f.landing_theory_deg) < 2.0);
    CHECK(rel_err(f.flight_s, f.flight_theory_s) < 0.015);
  }
}

TEST_CASE("settling damping slows a free ball as exp(-rate t), and off leaves it alone", "[physics][motion]") {
  for (Precision prec : {Precision::single, Precision::double_}) {
    const Material steel{"steel", 7800, 2e11, 0.3};
    Scene sc = bare_scene(steel, steel, Interaction{}, ContactLaw::hertz, prec);
    sc.numerics.dt = 1e-4;
    Ball b;
    b.radius = 0.01;
    b.velocity = {2.0, -1.0, 0.5};
    b.omega = {0.0, 0.0, 30.0};
    sc.balls = {b};
    auto s = make_solver(context(), sc);
    s->set_velocity_damping(10.0);
    s->advance(1000);  // 0.1 s: e^-1 of the speed and spin left
    const BallState damped = s->balls()[0];
    const double left = std::exp(-10.0 * s->time_s());
    INFO((prec == Precision::double_ ? "double" : "float"));
    CHECK(damped.velocity.x == Approx(2.0 * left).epsilon(1e-4));
    CHECK(damped.velocity.y == Approx(-1.0 * left).epsilon(1e-4));
    CHECK(damped.omega.z == Approx(30.0 * left).epsilon(1e-4));
    s->set_velocity_damping(0.0);
    s->advance(1000);
    const BallState free = s->balls()[0];
    CHECK(free.velocity.x == damped.velocity.x);
    CHECK(free.omega.z == damped.omega.z);
  }
}
