// The severity spectra the breakage model reads (cl/layout.h): each
// collision's impact energy at first touch (1/2 m* vn^2) and its normal
// loss, binned by energy over the collision's own R*, with that R*. Against
// closed forms: two unequal balls head on, and a ball bouncing on a plate
// under gravity, one impact per bounce whatever the stiffness.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <vector>

#include "core/layout.hpp"
#include "helpers.h"
#include "sim/energy_report.h"

using namespace mc;
using namespace mc::test;

namespace {

// One severity spectrum (impact or loss: its first field) of all types.
struct Severity {
  double count = 0, energy = 0, radius = 0;
};

Severity severity_bin(const BookSums& b, int field, int bin) {
  Severity s;
  for (int t = 0; t < b.n_types; ++t) {
    s.count += b.at(t, bin, field);
    s.energy += b.at(t, bin, field + 1);
    s.radius += b.at(t, bin, field + 2);
  }
  return s;
}

Severity severity_all(const BookSums& b, int field) {
  Severity s;
  for (int k = 0; k < MC_SPECTRA_BINS; ++k) {
    const Severity x = severity_bin(b, field, k);
    s.count += x.count, s.energy += x.energy, s.radius += x.radius;
  }
  return s;
}

int severity_bin_of(double e_J, double r_eff_m) { return f64::spectra_bin(e_J * MC_SPECTRA_R_REF / r_eff_m); }

}  // namespace

TEST_CASE("two unequal balls book 1/2 m* vn^2 at first touch and (1 - e^2) of it as loss, with their own R*",
          "[books][physics][severity]") {
  const Material steel{"steel", 7800, 2e11, 0.3};
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz})
    for (double e : {0.4, 0.7}) {
      Interaction in;
      in.restitution = e;
      in.mu_slide = 0;
      in.mu_roll = 0;
      in.kn = 1e6;
      Scene sc = bare_scene(steel, steel, in, law, Precision::double_);
      for (const bool small_first : {false, true}) {
      INFO("the small ball is ball " << (small_first ? 0 : 1));
      const double ra = small_first ? 0.00775 : 0.0184, rb = small_first ? 0.0184 : 0.00775;  // Bond's extremes
      const double ma = sphere_mass(7800, ra), mb = sphere_mass(7800, rb);
      const double m_eff = ma * mb / (ma + mb), r_eff = ra * rb / (ra + rb);
      const double va = 0.5, vb = -1.5, vn = va - vb;
      sc.numerics.dt = law == ContactLaw::hertz ? 2e-7 : kPi * std::sqrt(m_eff / in.kn) / 100;
      Ball a, b;
      a.id = 0, b.id = 1;
      a.radius = ra, b.radius = rb;
      a.position = {-ra - 1e-4, 0, 0};
      b.position = {rb + 1e-4, 0, 0};
      a.velocity = {va, 0, 0};
      b.velocity = {vb, 0, 0};
      sc.balls = {a, b};
      auto s = make_solver(context(), sc);
      bool touched = false;
      for (int k = 0; k < 200000; k += 10) {
        s->advance(10);
        const bool touching = s->contact_stats().ball_contacts_per_ball > 0;
        touched = touched || touching;
        if (touched && !touching) break;
      }
      REQUIRE(touched);
      const BookSums books = s->read_books();
      const auto balls = s->balls();
      const double impact = 0.5 * m_eff * vn * vn;  // the closed form
      const double v_out = balls[1].velocity.x - balls[0].velocity.x;
      const double lost = impact - 0.5 * m_eff * v_out * v_out;  // what the balls lost
      const Severity im = severity_all(books, MC_SPECTRA_IMPACT), lo = severity_all(books, MC_SPECTRA_LOSS);
      const int bin_i = severity_bin_of(impact, r_eff), bin_l = severity_bin_of(lost, r_eff);
      std::printf("unequal balls %-6s e %.1f: impact %.6g J (closed form %.6g), loss %.6g J (balls lost %.6g, "
                  "(1-e^2) of the impact %.6g), R* %.5g m (closed form %.5g), bins %d / %d\n",
                  law == ContactLaw::hertz ? "hertz" : "linear", e, im.energy, impact, lo.energy, lost,
                  (1 - e * e) * impact, im.radius, r_eff, bin_i, bin_l);
      INFO((law == ContactLaw::hertz ? "hertz" : "linear") << " e " << e);
      CHECK(im.count == 1);
      CHECK(lo.count == 1);
      CHECK(severity_bin(books, MC_SPECTRA_IMPACT, bin_i).count == 1);
      CHECK(severity_bin(books, MC_SPECTRA_LOSS, bin_l).count == 1);
      // vn at the first step in contact, before any force: exact to rounding.
      CHECK(im.energy == Approx(impact).epsilon(1e-5));
      CHECK(im.radius == Approx(r_eff).epsilon(1e-6));  // its own R*, not the charge's mean
      CHECK(lo.energy == Approx(lost).epsilon(2e-3));   // the loss is what the balls lost
      // and (1 - e^2) of the impact: the linear law's clipped end rebounds a
      // little slower than e (0.4-0.5 % more loss at 100 steps a contact),
      // Hertz's to 1e-3.
      CHECK(lo.energy == Approx((1 - e * e) * impact).epsilon(law == ContactLaw::linear ? 6e-3 : 1e-3));
      // The pair's row holds them; summary.json's rates say the same.
      const SpectraReport rep = spectra_report(sc, books, 1.0, 0, 0, 0);
      CHECK(rep.all.impact_W == Approx(im.energy).epsilon(1e-12));
      CHECK(rep.all.impact_r_eff_m == Approx(r_eff).epsilon(1e-6));
      CHECK(rep.all.loss_W == Approx(rep.all.normal_W).epsilon(1e-6));
      }
    }
}

TEST_CASE("a ball bouncing on a plate books one impact per bounce, alike at three stiffnesses",
          "[books][physics][severity]") {
  // Dropped from h with restitution e: bounce k meets the plate with about
  // e^(2k) m g h. Between two first touches the ball leaves and comes back
  // to the same height, so impact k + 1 is impact k less the loss of bounce
  // k, exactly. Those above 1 % of the first are k = 0..3 at e = 0.5 (e^6 =
  // 1.6 %, e^8 = 0.4 %): four, each in its own bin, whatever the spring.
  const Material steel{"steel", 7800, 2e11, 0.3};
  const double r = 0.01, h = 0.05, e = 0.5, g = 9.81;
  const double m = sphere_mass(7800, r), e0 = m * g * h;
  for (double kn : {1e5, 1e6, 1e7}) {
    Interaction in;
    in.restitution = e;
    in.mu_slide = 0;
    in.mu_roll = 0;
    in.kn = kn;
    Scene sc = bare_scene(steel, rigid_wall(), in, ContactLaw::linear, Precision::double_);
    sc.numerics.gravity = {0, 0, -g};
    sc.walls.length = 1.0;  // the plate z = 0
    sc.numerics.dt = kPi * std::sqrt(m / kn) / 60;
    Ball a;
    a.radius = r;
    a.position = {0, 0, r + h};
    sc.balls = {a};
    auto s = make_solver(context(), sc);
    // The fall and every flight: sqrt(2h/g) + (2 v0 / g) e / (1 - e).
    const double v0 = std::sqrt(2 * g * h), t_end = std::sqrt(2 * h / g) + 2 * v0 / g * e / (1 - e) + 0.05;
    s->advance(static_cast<long>(t_end / sc.numerics.dt));
    const BookSums books = s->read_books();
    INFO("kn " << kn);
    // The impacts and losses from the top bin down: above 1 % of the first
    // impact each bin holds one.
    std::vector<Severity> impacts, losses;
    double n_all = 0;
    for (int k = MC_SPECTRA_BINS - 1; k >= 0; --k) {
      const Severity im = severity_bin(books, MC_SPECTRA_IMPACT, k), lo = severity_bin(books, MC_SPECTRA_LOSS, k);
      n_all += im.count;
      if (im.count > 0 && im.energy > 0.01 * e0) impacts.push_back(im);
      if (lo.count > 0 && lo.energy > 0.01 * e0 * (1 - e * e)) losses.push_back(lo);
    }
    std::printf("kn %.0e: %zu impacts above 1 %% of the first, %g in all (the last, tiny bounces: as many as the "
                "spring allows before the ball stays on the plate)\n",
                kn, impacts.size(), n_all);
    REQUIRE(impacts.size() == 4);
    REQUIRE(losses.size() >= 4);
    for (std::size_t k = 0; k < 4; ++k) {
      const double nominal = std::pow(e, 2.0 * k) * e0;
      std::printf("kn %.0e bounce %zu: impact %.6g J (e^2k m g h %.6g), loss %.6g J (%.4f of it)\n", kn, k,
                  impacts[k].energy, nominal, losses[k].energy, losses[k].energy / impacts[k].energy);
      INFO("bounce " << k);
      CHECK(impacts[k].count == 1);
      CHECK(losses[k].count == 1);
      CHECK(impacts[k].radius == Approx(r).epsilon(1e-6));
      if (k == 0) CHECK(impacts[k].energy == Approx(e0).epsilon(1e-3));  // the free fall's m g h
      if (k > 0) CHECK(impacts[k].energy == Approx(impacts[k - 1].energy - losses[k - 1].energy).epsilon(0.01));
      // (1 - e^2) of it, where gravity's impulse over the contact, g t_c,
      // is small against the speed; the last bounces on the softest spring
      // lose a little more.
      const double g_tc = g * kPi * std::sqrt(m / kn), v_k = std::sqrt(2 * impacts[k].energy / m);
      CHECK(losses[k].energy / impacts[k].energy == Approx(1 - e * e).epsilon(g_tc < 0.05 * v_k ? 0.03 : 0.06));
      CHECK(impacts[k].energy == Approx(nominal).epsilon(0.15));
    }
  }
}
