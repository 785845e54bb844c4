// Chung & Ooi (2011) particle-impact benchmarks, run through the kernels
// (tests/checks.cpp sets them up). Reference values are Hertz/Mindlin
// theory (../shared/reference/VERIFICATION.md).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdio>

#include "checks.h"
#include "helpers.h"

using namespace mc;
using namespace mc::test;

TEST_CASE("Chung & Ooi test 1: equal spheres head-on match Hertz", "[physics][chung-ooi]") {
  for (Precision prec : {Precision::single, Precision::double_}) {
    for (const checks::BenchMaterial& c : checks::chung_ooi_1_materials()) {
      const checks::NormalImpact me = checks::chung_ooi_1(context(), c, prec);
      const checks::HertzTheory& th = me.theory;
      INFO(c.name << (prec == Precision::double_ ? " double" : " float"));
      std::printf("C&O 1 %-9s %-6s dmax %.2f um (%.2f)  Fmax %.3f kN (%.3f)  tc %.2f us (%.2f)\n", c.name,
                  prec == Precision::double_ ? "double" : "float", me.delta_max * 1e6, th.delta_max * 1e6,
                  me.f_max / 1e3, th.f_max / 1e3, me.t_contact * 1e6, th.t_contact * 1e6);
      CHECK(rel_err(me.delta_max, th.delta_max) < 0.02);
      CHECK(rel_err(me.f_max, th.f_max) < 0.02);
      CHECK(rel_err(me.t_contact, th.t_contact) < 0.02);
      // The published table (rounded) agrees with the formulas.
      CHECK(rel_err(th.delta_max, c.table_delta) < 0.01);
      CHECK(rel_err(th.f_max, c.table_force) < 0.01);
      CHECK(rel_err(th.t_contact, c.table_time) < 0.01);
      // e = 1: the spheres leave at their approach speed.
      CHECK(rel_err(me.rebound_speed_ratio, 1.0) < 0.005);
    }
  }
}

TEST_CASE("Chung & Ooi test 2: sphere onto a rigid wall matches Hertz", "[physics][chung-ooi]") {
  for (const checks::BenchMaterial& c : checks::chung_ooi_2_materials()) {
    const checks::NormalImpact me = checks::chung_ooi_2(context(), c);
    const checks::HertzTheory& th = me.theory;
    INFO(c.name);
    std::printf("C&O 2 %-9s dmax %.2f um (%.2f)  Fmax %.3f kN (%.3f)  tc %.4f ms (%.4f)\n", c.name,
                me.delta_max * 1e6, th.delta_max * 1e6, me.f_max / 1e3, th.f_max / 1e3, me.t_contact * 1e3,
                th.t_contact * 1e3);
    CHECK(rel_err(me.delta_max, th.delta_max) < 0.02);
    CHECK(rel_err(me.f_max, th.f_max) < 0.02);
    CHECK(rel_err(me.t_contact, th.t_contact) < 0.02);
    CHECK(rel_err(th.delta_max, c.table_delta) < 0.01);
    CHECK(rel_err(th.f_max, c.table_force) < 0.01);
    CHECK(rel_err(th.t_contact, c.table_time) < 0.01);
  }
}

TEST_CASE("Chung & Ooi test 3: rebound restitution equals the input e", "[physics][chung-ooi]") {
  double worst = 0;
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    for (const Material& mat : checks::chung_ooi_3_materials()) {
      for (int k = 1; k <= 10; ++k) {
        const double e = 0.1 * k;
        const double e_measured = checks::chung_ooi_3(context(), law, mat, e);
        INFO((law == ContactLaw::hertz ? "hertz " : "linear ") << mat.name << " e " << e);
        CHECK(rel_err(e_measured, e) < 0.02);
        worst = std::max(worst, rel_err(e_measured, e));
      }
    }
  }
  std::printf("C&O 3 worst restitution error over both laws, 2 materials, e 0.1..1.0: %.3f %%\n", 100 * worst);
}

TEST_CASE("Chung & Ooi test 4: oblique impact in the sliding range", "[physics][chung-ooi]") {
  double worst_et = 0, worst_w = 0;
  for (const Material& mat : checks::chung_ooi_4_materials()) {
    for (double theta_deg : {35.0, 45.0, 55.0, 65.0, 75.0, 85.0}) {
      const checks::ObliqueImpact o = checks::chung_ooi_4(context(), mat, theta_deg);
      INFO(mat.name << " theta " << theta_deg << " e_t " << o.et << " (" << o.et_theory << ") w " << o.spin << " ("
                    << o.spin_theory << ")");
      CHECK(rel_err(o.et, o.et_theory) < 0.03);
      CHECK(rel_err(o.spin, o.spin_theory) < 0.03);
      worst_et = std::max(worst_et, rel_err(o.et, o.et_theory));
      worst_w = std::max(worst_w, rel_err(o.spin, o.spin_theory));
    }
  }
  std::printf("C&O 4 worst errors, theta 35..85 deg: tangential restitution %.3f %%, rebound spin %.3f %%\n",
              100 * worst_et, 100 * worst_w);
}
