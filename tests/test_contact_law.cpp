// Chung & Ooi (2011) particle-impact benchmarks, run through the kernels.
// Reference values are Hertz/Mindlin theory (../shared/reference/VERIFICATION.md).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdio>

#include "helpers.h"

using namespace mc;
using namespace mc::test;

namespace {

struct HertzTheory {
  double delta_max, f_max, t_contact;
};

HertzTheory hertz(double e_star, double r_eff, double m_eff, double v) {
  HertzTheory h;
  h.delta_max = std::pow(15.0 * m_eff * v * v / (16.0 * e_star * std::sqrt(r_eff)), 0.4);
  h.f_max = 4.0 / 3.0 * e_star * std::sqrt(r_eff) * std::pow(h.delta_max, 1.5);
  h.t_contact = 2.868 * std::pow(m_eff * m_eff / (r_eff * e_star * e_star * v), 0.2);
  return h;
}

struct Measured {
  double delta_max = 0, f_max = 0, t_contact = 0;
  Vec3 v_after, w_after;
};

// Steps until the contact has ended; the overlap comes from `overlap_of`.
template <class OverlapFn>
Measured run_impact(Solver& s, int ball, OverlapFn overlap_of, long max_steps) {
  Measured m;
  bool touched = false;
  long steps_in_contact = 0;
  double prev_overlap = 0;
  double t_first = 0, t_last = 0;
  for (long k = 0; k < max_steps; ++k) {
    const auto b = s.balls();
    const double ov = overlap_of(b);
    const double f = b[ball].force.norm();
    if (ov > 0) {
      if (!touched) t_first = s.time_s() - s.dt() * ov / (ov - prev_overlap);  // interpolate entry
      touched = true;
      ++steps_in_contact;
      m.delta_max = std::max(m.delta_max, ov);
      m.f_max = std::max(m.f_max, f);
    } else if (touched) {
      t_last = s.time_s() - s.dt() * (-ov) / (prev_overlap - ov);  // interpolate exit
      m.t_contact = t_last - t_first;
      m.v_after = b[ball].velocity;
      m.w_after = b[ball].omega;
      return m;
    }
    prev_overlap = ov;
    s.advance(1);
  }
  FAIL("contact did not end within " << max_steps << " steps");
  return m;
}

}  // namespace

TEST_CASE("Chung & Ooi test 1: equal spheres head-on match Hertz", "[physics][chung-ooi]") {
  struct Case {
    const char* name;
    double E, nu, rho, table_delta_um, table_f_kN, table_tc_us;
  };
  const Case cases[] = {{"glass", 4.8e10, 0.20, 2800, 274, 10.70, 40.3},
                        {"limestone", 2.0e10, 0.25, 2500, 368, 7.11, 54.2}};
  for (Precision prec : {Precision::single, Precision::double_}) {
    for (const Case& c : cases) {
      const double r = 0.010, v = 10.0;
      const Material mat{c.name, c.rho, c.E, c.nu};
      Interaction in;
      in.restitution = 1.0;
      in.mu_slide = 0.0;
      Scene sc = bare_scene(mat, mat, in, ContactLaw::hertz, prec);
      const double m = sphere_mass(c.rho, r);
      const PairCoefficients pc = pair_coefficients(sc, 0, 0);
      const HertzTheory th = hertz(pc.e_star, r / 2, m / 2, 2 * v);
      sc.numerics.dt = th.t_contact / 400;
      Ball a, b;
      a.id = 0; a.radius = r; a.position = {-r - 0.2 * th.delta_max, 0, 0}; a.velocity = {v, 0, 0};
      b.id = 1; b.radius = r; b.position = {r + 0.2 * th.delta_max, 0, 0}; b.velocity = {-v, 0, 0};
      sc.balls = {a, b};
      auto s = make_solver(context(), sc);
      const Measured me = run_impact(
          *s, 0, [&](const std::vector<BallState>& bs) { return 2 * r - (bs[1].position - bs[0].position).norm(); },
          2000);
      INFO(c.name << (prec == Precision::double_ ? " double" : " float"));
      std::printf("C&O 1 %-9s %-6s dmax %.2f um (%.2f)  Fmax %.3f kN (%.3f)  tc %.2f us (%.2f)\n", c.name,
                  prec == Precision::double_ ? "double" : "float", me.delta_max * 1e6, th.delta_max * 1e6,
                  me.f_max / 1e3, th.f_max / 1e3, me.t_contact * 1e6, th.t_contact * 1e6);
      CHECK(rel_err(me.delta_max, th.delta_max) < 0.02);
      CHECK(rel_err(me.f_max, th.f_max) < 0.02);
      CHECK(rel_err(me.t_contact, th.t_contact) < 0.02);
      // The published table (rounded) agrees with the formulas.
      CHECK(rel_err(th.delta_max * 1e6, c.table_delta_um) < 0.01);
      CHECK(rel_err(th.f_max / 1e3, c.table_f_kN) < 0.01);
      CHECK(rel_err(th.t_contact * 1e6, c.table_tc_us) < 0.01);
      // e = 1: the spheres leave at their approach speed.
      CHECK(rel_err(-me.v_after.x, v) < 0.005);
    }
  }
}

TEST_CASE("Chung & Ooi test 2: sphere onto a rigid wall matches Hertz", "[physics][chung-ooi]") {
  struct Case {
    const char* name;
    double E, nu, rho, table_delta_um, table_f_kN, table_tc_ms;
  };
  const Case cases[] = {{"Al alloy", 7.0e10, 0.30, 2699, 49.7, 11.37, 0.732},
                        {"Mg alloy", 4.0e10, 0.35, 1800, 52.1, 7.23, 0.767}};
  for (const Case& c : cases) {
    const double r = 0.10, v = 0.2;
    const Material mat{c.name, c.rho, c.E, c.nu};
    Interaction in;
    in.restitution = 1.0;
    in.mu_slide = 0.0;
    Scene sc = bare_scene(mat, rigid_wall(), in, ContactLaw::hertz);
    sc.walls.length = 10.0;  // end plate at z = 0 is the wall
    const double m = sphere_mass(c.rho, r);
    const PairCoefficients pc = pair_coefficients(sc, 0, 1);
    const HertzTheory th = hertz(pc.e_star, r, m, v);
    sc.numerics.dt = th.t_contact / 400;
    Ball a;
    a.radius = r;
    a.position = {0, 0, r + 0.2 * th.delta_max};
    a.velocity = {0, 0, -v};
    sc.balls = {a};
    auto s = make_solver(context(), sc);
    const Measured me =
        run_impact(*s, 0, [&](const std::vector<BallState>& bs) { return r - bs[0].position.z; }, 2000);
    INFO(c.name);
    std::printf("C&O 2 %-9s dmax %.2f um (%.2f)  Fmax %.3f kN (%.3f)  tc %.4f ms (%.4f)\n", c.name,
                me.delta_max * 1e6, th.delta_max * 1e6, me.f_max / 1e3, th.f_max / 1e3, me.t_contact * 1e3,
                th.t_contact * 1e3);
    CHECK(rel_err(me.delta_max, th.delta_max) < 0.02);
    CHECK(rel_err(me.f_max, th.f_max) < 0.02);
    CHECK(rel_err(me.t_contact, th.t_contact) < 0.02);
    CHECK(rel_err(th.delta_max * 1e6, c.table_delta_um) < 0.01);
    CHECK(rel_err(th.f_max / 1e3, c.table_f_kN) < 0.01);
    CHECK(rel_err(th.t_contact * 1e3, c.table_tc_ms) < 0.01);
  }
}

TEST_CASE("Chung & Ooi test 3: rebound restitution equals the input e", "[physics][chung-ooi]") {
  const Material materials[] = {{"alumina", 4000, 3.8e11, 0.23}, {"cast iron", 7000, 1.0e11, 0.25}};
  double worst = 0;
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    for (const Material& mat : materials) {
      for (int k = 1; k <= 10; ++k) {
        const double e = 0.1 * k, r = 0.0025, v = 3.9;
        Interaction in;
        in.restitution = e;
        in.mu_slide = 0.0;
        in.kn = 1.0e7;
        Scene sc = bare_scene(mat, rigid_wall(), in, law);
        sc.walls.length = 1.0;
        const double m = sphere_mass(mat.density, r);
        const PairCoefficients pc = pair_coefficients(sc, 0, 1);
        const double tc = law == ContactLaw::hertz ? hertz(pc.e_star, r, m, v).t_contact
                                                   : kPi * std::sqrt(m / in.kn);
        sc.numerics.dt = tc / 200;
        Ball a;
        a.radius = r;
        a.position = {0, 0, r + 1e-7};
        a.velocity = {0, 0, -v};
        sc.balls = {a};
        auto s = make_solver(context(), sc);
        const Measured me =
            run_impact(*s, 0, [&](const std::vector<BallState>& bs) { return r - bs[0].position.z; }, 4000);
        const double e_measured = me.v_after.z / v;
        INFO((law == ContactLaw::hertz ? "hertz " : "linear ") << mat.name << " e " << e);
        CHECK(rel_err(e_measured, e) < 0.02);
        worst = std::max(worst, rel_err(e_measured, e));
      }
    }
  }
  std::printf("C&O 3 worst restitution error over both laws, 2 materials, e 0.1..1.0: %.3f %%\n", 100 * worst);
}

TEST_CASE("Chung & Ooi test 4: oblique impact in the sliding range", "[physics][chung-ooi]") {
  const Material materials[] = {{"alumina", 4000, 3.8e11, 0.23}, {"Al alloy", 2700, 7.0e10, 0.33}};
  const double e = 0.98, mu = 0.092, r = 0.0025, speed = 3.9;
  double worst_et = 0, worst_w = 0;
  for (const Material& mat : materials) {
    for (double theta_deg : {35.0, 45.0, 55.0, 65.0, 75.0, 85.0}) {
      Interaction in;
      in.restitution = e;
      in.mu_slide = mu;
      Scene sc = bare_scene(mat, rigid_wall(), in, ContactLaw::hertz);
      sc.walls.length = 1.0;
      const double th = theta_deg * kPi / 180;
      const double vn = speed * std::cos(th), vt = speed * std::sin(th);
      const double m = sphere_mass(mat.density, r);
      const PairCoefficients pc = pair_coefficients(sc, 0, 1);
      sc.numerics.dt = hertz(pc.e_star, r, m, vn).t_contact / 200;
      Ball a;
      a.radius = r;
      a.position = {0, 0, r + 1e-7};
      a.velocity = {vt, 0, -vn};
      sc.balls = {a};
      auto s = make_solver(context(), sc);
      const Measured me =
          run_impact(*s, 0, [&](const std::vector<BallState>& bs) { return r - bs[0].position.z; }, 4000);
      const double et_theory = 1 - mu * (1 + e) / std::tan(th);
      const double w_theory = 5 * mu * (1 + e) * vn / (2 * r);
      const double et = me.v_after.x / vt;
      // Friction acts along −x at the contact below the centre: spin about +y.
      const double w = me.w_after.y;
      INFO(mat.name << " theta " << theta_deg << " e_t " << et << " (" << et_theory << ") w " << w << " ("
                    << w_theory << ")");
      CHECK(rel_err(et, et_theory) < 0.03);
      CHECK(rel_err(w, w_theory) < 0.03);
      worst_et = std::max(worst_et, rel_err(et, et_theory));
      worst_w = std::max(worst_w, rel_err(w, w_theory));
    }
  }
  std::printf("C&O 4 worst errors, theta 35..85 deg: tangential restitution %.3f %%, rebound spin %.3f %%\n",
              100 * worst_et, 100 * worst_w);
}
