// Single-ball closed forms (VERIFICATION.md §2 and §3): free flight, sliding
// to rolling, and a ball carried on a turning shell.
#include <catch2/catch.hpp>

#include <cstdio>

#include "core/drum.h"
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
    const Material steel{"steel", 7800, 2e11, 0.3};
    Interaction in;
    in.restitution = 0.5;
    in.mu_slide = 0.3;
    in.kn = 1e6;
    Scene sc = bare_scene(steel, steel, in, law);
    sc.numerics.gravity = {0, 0, -9.81};
    sc.walls.length = 10.0;  // the floor is the plate z = 0
    const double r = 0.01, v0 = 1.0;
    const double m = sphere_mass(7800, r);
    // Resting overlap under gravity, so the ball starts settled.
    const PairCoefficients pc = pair_coefficients(sc, 0, 1);
    const double w = m * 9.81;
    const double rest = law == ContactLaw::hertz
                            ? std::pow(w / (4.0 / 3.0 * pc.e_star * std::sqrt(r)), 2.0 / 3.0)
                            : w / in.kn;
    sc.numerics.dt = law == ContactLaw::hertz ? 2e-6 : kPi * std::sqrt(m / in.kn) / 40;
    Ball b;
    b.radius = r;
    b.position = {0, 0, r - rest};
    b.velocity = {v0, 0, 0};
    sc.balls = {b};
    auto s = make_solver(context(), sc);
    // Sliding lasts 2·v0/(7·μ·g) ≈ 0.097 s; run well past it.
    const double t_slide = 2 * v0 / (7 * 0.3 * 9.81);
    s->advance(static_cast<long>(1.5 * t_slide / sc.numerics.dt));
    const auto bs = s->balls();
    INFO((law == ContactLaw::hertz ? "hertz" : "linear") << " v " << bs[0].velocity.x << " w*r "
                                                          << bs[0].omega.y * r);
    std::printf("rolling %-6s v/v0 %.5f (5/7 = %.5f), omega*r/v %.5f\n", law == ContactLaw::hertz ? "hertz" : "linear",
                bs[0].velocity.x / v0, 5.0 / 7.0, bs[0].omega.y * r / bs[0].velocity.x);
    CHECK(rel_err(bs[0].velocity.x / v0, 5.0 / 7.0) < 0.01);
    // Rolling without slip: ω·r = v.
    CHECK(rel_err(bs[0].omega.y * r, bs[0].velocity.x) < 0.01);
  }
}

TEST_CASE("a ball carried on a turning shell leaves where cos(alpha) = phi^2", "[physics][mill]") {
  // With sliding and rolling friction high, the ball turns with the shell as
  // one body until the normal force vanishes: α from the top vertical with
  // cos α = φ² (VERIFICATION.md §3). Slip starts where sin α = μ(φ² − cos α),
  // within 0.1° of that for μ = 1000. The damping sees velocities half a
  // step old (leapfrog, as LIGGGHTS' velocity Verlet), which on a circular
  // path reads as a normal speed v·ω·dt/2 and shifts the departure by O(dt):
  // 2.2° at φ = 0.9 with 40 steps per contact, so 160 are used here.
  for (double phi : {0.6, 0.75, 0.9}) {
    const Material steel{"steel", 7800, 2e11, 0.3};
    Interaction in;
    in.restitution = 0.3;
    in.mu_slide = 1000.0;
    in.mu_roll = 1000.0;
    // Soft enough that the overlap (~2.5e-5 m) is hundreds of float ulps at
    // 0.5 m from the axis; with kn = 1e6 it is ~8 ulps and round-off jitter
    // opens the contact early.
    in.kn = 2e4;
    Scene sc = bare_scene(steel, steel, in, ContactLaw::linear);
    sc.numerics.gravity = {0, -9.81, 0};
    const double D = 1.02, r = 0.01, Rb = 0.5 * D - r;
    sc.walls.shell_radius = 0.5 * D;
    sc.walls.length = 0.1;
    const double omega = phi * std::sqrt(9.81 / Rb);
    sc.mill_omega = omega;
    const double m = sphere_mass(7800, r);
    sc.numerics.dt = kPi * std::sqrt(m / in.kn) / 160;
    Ball b;
    b.radius = r;
    const double rest = m * 9.81 * (1 + phi * phi) / in.kn;
    b.position = {0, -(Rb + rest), 0.05};
    b.velocity = {omega * Rb, 0, 0};
    b.omega = {0, 0, omega};
    sc.balls = {b};
    auto s = make_solver(context(), sc);
    double alpha_leave = -1;
    const long max_steps = static_cast<long>(1.0 / (omega / (2 * kPi)) / sc.numerics.dt);
    for (long k = 0; k < max_steps && alpha_leave < 0; k += 10) {
      s->advance(10);
      const auto bs = s->balls();
      const Vec3 p = bs[0].position;
      const double rho = std::hypot(p.x, p.y);
      if (p.y > 0 && p.x > 0 && rho + r < 0.5 * D) alpha_leave = std::atan2(p.x, p.y) * 180 / kPi;
    }
    const double expected = std::acos(phi * phi) * 180 / kPi;
    std::printf("shell carry phi %.2f: leaves %.2f deg from top (theory %.2f)\n", phi, alpha_leave, expected);
    INFO("phi " << phi);
    CHECK(std::fabs(alpha_leave - expected) < 2.0);
  }
}
