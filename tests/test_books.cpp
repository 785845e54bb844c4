// Where the energy goes: the collision records, spectra and liner sums
// against closed forms (a head-on collision, Chung & Ooi's impacts 3 and 4,
// a ball at rest, a ball sliding on a plate) and against the dissipation of
// a turning drum (cl/books.h).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>

#include "checks.h"
#include "core/drum.h"
#include "core/liner.h"
#include "helpers.h"
#include "sim/energy_report.h"
#include "core/layout.hpp"

using namespace mc;
using namespace mc::test;

namespace {

// Collisions closed in `books`, all bins of one type (or all types: -1).
double collisions(const BookSums& b, int type = -1) {
  double n = 0;
  for (int t = 0; t < b.n_types; ++t)
    if (type < 0 || t == type)
      for (int k = 0; k < MC_SPECTRA_BINS; ++k) n += b.at(t, k, MC_SPECTRA_COUNT);
  return n;
}

// The one closed collision's bin, losses and impact speed.
struct OneCollision {
  int type = -1, bin = -1;
  double normal = 0, tangential = 0, rolling = 0, speed = 0;
  double total() const { return normal + tangential + rolling; }
};

OneCollision the_collision(const BookSums& b) {
  OneCollision c;
  for (int t = 0; t < b.n_types; ++t)
    for (int k = 0; k < MC_SPECTRA_BINS; ++k)
      if (b.at(t, k, MC_SPECTRA_COUNT) > 0) {
        c.type = t;
        c.bin = k;
        c.normal = b.at(t, k, MC_SPECTRA_NORMAL);
        c.tangential = b.at(t, k, MC_SPECTRA_TANGENTIAL);
        c.rolling = b.at(t, k, MC_SPECTRA_ROLLING);
        c.speed = b.at(t, k, MC_SPECTRA_SPEED);
      }
  return c;
}

int expected_bin(double e) { return f64::spectra_bin(e); }

// The one closed collision in the normal energy spectrum: its bin there
// and its normal loss.
std::pair<int, double> the_normal_collision(const BookSums& b) {
  std::pair<int, double> c{-1, 0.0};
  for (int t = 0; t < b.n_types; ++t)
    for (int k = 0; k < MC_SPECTRA_BINS; ++k)
      if (b.at(t, k, MC_SPECTRA_BY_NORMAL) > 0) c = {k, b.at(t, k, MC_SPECTRA_BY_NORMAL_ENERGY)};
  return c;
}

// Steps until ball 0 has left every contact (after touching one).
void run_until_apart(Solver& s, long max_steps) {
  bool touched = false;
  for (long k = 0; k < max_steps; k += 10) {
    s.advance(10);
    const bool touching = s.contact_stats().ball_contacts_per_ball + s.contact_stats().wall_contacts_per_ball > 0;
    if (touching) touched = true;
    if (touched && !touching) return;
  }
  FAIL("the contact did not end within " << max_steps << " steps");
}

}  // namespace

TEST_CASE("a head-on collision records one collision of (1 - e^2) m* v^2 / 2 in its bin", "[books][physics]") {
  const Material steel{"steel", 7800, 2e11, 0.3};
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz})
    for (double e : {0.3, 0.7}) {
      Interaction in;
      in.restitution = e;
      in.mu_slide = 0;
      in.mu_roll = 0;
      in.kn = 1e6;
      Scene sc = bare_scene(steel, steel, in, law, Precision::double_);
      const double r = 0.01, v = 0.8;  // each ball, towards the other
      const double m = sphere_mass(7800, r), m_eff = m / 2;
      sc.numerics.dt = law == ContactLaw::hertz ? 2e-7 : kPi * std::sqrt(m_eff / in.kn) / 100;
      Ball a, b;
      a.id = 0, b.id = 1;
      a.radius = b.radius = r;
      a.position = {-r - 1e-4, 0, 0};
      b.position = {r + 1e-4, 0, 0};
      a.velocity = {v, 0, 0};
      b.velocity = {-v, 0, 0};
      sc.balls = {a, b};
      auto s = make_solver(context(), sc);
      run_until_apart(*s, 200000);
      const auto balls = s->balls();
      const BookSums books = s->read_books();
      const double expected = (1 - e * e) * 0.5 * m_eff * (2 * v) * (2 * v);
      // What the balls lost, from their rebound.
      const double v_out = balls[1].velocity.x - balls[0].velocity.x;
      const double lost = 0.5 * m_eff * ((2 * v) * (2 * v) - v_out * v_out);
      const OneCollision c = the_collision(books);
      std::printf("head-on %-6s e %.1f: one collision of %.6g J (closed form %.6g J, kinetic energy lost %.6g J), bin %d "
                  "(%d), impact speed %.5f m/s\n",
                  law == ContactLaw::hertz ? "hertz" : "linear", e, c.total(), expected, lost, c.bin,
                  expected_bin(expected), c.speed);
      INFO((law == ContactLaw::hertz ? "hertz" : "linear") << " e " << e);
      CHECK(collisions(books) == 1);
      CHECK(c.type == f64::ball_pair_type(0, 0, 1));
      CHECK(c.bin == expected_bin(expected));
      CHECK(c.total() == Approx(expected).epsilon(0.02));
      CHECK(c.total() == Approx(lost).epsilon(0.002));   // the books are what the balls lost
      CHECK(c.tangential == Approx(0).margin(1e-9 * expected));
      CHECK(c.speed == Approx(2 * v).epsilon(0.01));
      CHECK(s->observe(false).open_loss_J() == 0);       // nothing left open
    }
}

TEST_CASE("Chung & Ooi test 3: each impact on a wall loses (1 - e^2) of its normal energy", "[books][physics]") {
  const Material materials[] = {{"alumina", 4000, 3.8e11, 0.23}, {"cast iron", 7000, 1.0e11, 0.25}};
  const double r = 0.0025, v = 3.9;
  for (const Material& mat : materials)
    for (double e : {0.2, 0.5, 0.8}) {
      Interaction in;
      in.restitution = e;
      in.mu_slide = 0;
      in.mu_roll = 0;
      Scene sc = bare_scene(mat, rigid_wall(), in, ContactLaw::hertz);
      sc.walls.length = 1.0;  // the plate z = 0
      sc.numerics.dt = 2e-8;
      Ball a;
      a.radius = r;
      a.position = {0, 0, r + 1e-6};
      a.velocity = {0, 0, -v};
      sc.balls = {a};
      auto s = make_solver(context(), sc);
      run_until_apart(*s, 100000);
      const double m = sphere_mass(mat.density, r);
      const double vz = s->balls()[0].velocity.z;
      const OneCollision c = the_collision(s->read_books());
      const double expected = (1 - e * e) * 0.5 * m * v * v;
      INFO(mat.name << " e " << e << " loss " << c.total() << " expected " << expected);
      CHECK(collisions(s->read_books()) == 1);
      CHECK(c.type == f64::wall_pair_type(0, MC_WALL_PLATE_LOW, 1));
      CHECK(c.normal == Approx(expected).epsilon(0.02));
      CHECK(c.normal == Approx(0.5 * m * (v * v - vz * vz)).epsilon(0.002));
    }
}

TEST_CASE("Chung & Ooi test 4: the tangential loss of an oblique impact in the sliding range", "[books][physics]") {
  // Sliding through the whole contact (tan θ >= 3.5 μ (1 + e)): the wall's
  // friction impulse is μ(1 + e)·m·Vn, so the tangential speed drops by
  // a = μ(1 + e)·Vn and the spin gains 5a/(2R); the loss is
  // ½m·(Vt² − (Vt − a)² − 2.5·a²) = ½m·(2·Vt·a − 3.5·a²).
  const Material mat{"alumina", 4000, 3.8e11, 0.23};
  const double e = 0.98, mu = 0.092, r = 0.0025, speed = 3.9;
  double worst = 0;
  for (double theta_deg : {45.0, 65.0, 85.0}) {
    Interaction in;
    in.restitution = e;
    in.mu_slide = mu;
    in.mu_roll = 0;
    Scene sc = bare_scene(mat, rigid_wall(), in, ContactLaw::hertz);
    sc.walls.length = 1.0;
    sc.numerics.dt = 2e-8;
    const double th = theta_deg * kPi / 180, vn = speed * std::cos(th), vt = speed * std::sin(th);
    Ball a;
    a.radius = r;
    a.position = {0, 0, r + 1e-7};
    a.velocity = {vt, 0, -vn};
    sc.balls = {a};
    auto s = make_solver(context(), sc);
    run_until_apart(*s, 100000);
    const double m = sphere_mass(mat.density, r);
    const double da = mu * (1 + e) * vn;
    const double expected = 0.5 * m * (2 * vt * da - 3.5 * da * da);
    const BookSums books = s->read_books();
    const OneCollision c = the_collision(books);
    const BallState b = s->balls()[0];
    const double lost_t = 0.5 * m * (vt * vt - b.velocity.x * b.velocity.x) - 0.5 * 0.4 * m * r * r * b.omega.y * b.omega.y;
    INFO("theta " << theta_deg << " tangential loss " << c.tangential << " expected " << expected << " balls lost "
                  << lost_t);
    CHECK(c.tangential == Approx(expected).epsilon(0.02));
    CHECK(c.tangential == Approx(lost_t).epsilon(0.005));
    // The normal energy spectrum holds it once more, in its normal loss's
    // bin (below the whole loss's: a tenth of it at 85 degrees).
    const auto [normal_bin, normal_J] = the_normal_collision(books);
    CHECK(normal_bin == expected_bin(c.normal));
    CHECK(normal_bin < c.bin);
    // (The first spectrum rounds it to its whole loss's bin: 2^-24 of a
    // bin a decade above, a few parts in a million of it here.)
    CHECK(normal_J == Approx(c.normal).epsilon(2e-5));
    worst = std::max(worst, rel_err(c.tangential, expected));
  }
  std::printf("C&O 4 tangential loss, theta 45..85 deg: worst error %.3f %%\n", 100 * worst);
}

TEST_CASE("a ball resting on a plate records no new collisions while it rests", "[books][physics]") {
  const Material steel{"steel", 7800, 2e11, 0.3};
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    Interaction in;
    in.restitution = 0.5;
    in.mu_slide = 0.3;
    in.mu_roll = 0.01;
    in.kn = 1e6;
    Scene sc = bare_scene(steel, steel, in, law);
    sc.numerics.gravity = {0, 0, -9.81};
    sc.walls.length = 10.0;
    const double r = 0.01, m = sphere_mass(7800, r);
    sc.numerics.dt = law == ContactLaw::hertz ? 2e-6 : kPi * std::sqrt(m / in.kn) / 40;
    Ball b;
    b.radius = r;
    b.position = {0, 0, r + 0.002};  // dropped from 2 mm: it bounces, then rests
    sc.balls = {b};
    auto s = make_solver(context(), sc);
    s->advance(static_cast<long>(0.3 / sc.numerics.dt));
    const double bounces = collisions(s->read_books());
    s->reset_books();
    s->advance(static_cast<long>(0.3 / sc.numerics.dt));
    const BookSums rest = s->read_books();
    std::printf("resting %-6s: %.0f collisions while it settled, %.0f in the next 0.3 s at rest\n",
                law == ContactLaw::hertz ? "hertz" : "linear", bounces, collisions(rest));
    INFO((law == ContactLaw::hertz ? "hertz" : "linear"));
    CHECK(bounces >= 2);  // it did bounce
    CHECK(collisions(rest) == 0);
    CHECK(s->contact_stats().wall_contacts_per_ball == 1);  // and its contact is open
  }
}

TEST_CASE("a ball sliding on a plate: shear work mu m g s and Archard volume k m g s", "[books][physics][wear]") {
  // The sliding-to-rolling check (tests/checks.cpp): the contact point slips
  // s = v0² / (7 μ g) before the ball rolls (it decelerates by μg while the
  // spin's rim speed grows by 5/2 μg).
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    const checks::Rolling r = checks::sliding_to_rolling(context(), law);
    std::printf("sliding %-6s: shear work %.6g J (mu m g s %.6g J), wear %.6g m^3 (k m g s %.6g m^3)\n",
                law == ContactLaw::hertz ? "hertz" : "linear", r.shear_J, r.shear_theory_J, r.wear_m3, r.wear_theory_m3);
    INFO((law == ContactLaw::hertz ? "hertz" : "linear"));
    CHECK(r.shear_J == Approx(r.shear_theory_J).epsilon(0.01));
    CHECK(r.wear_m3 == Approx(r.wear_theory_m3).epsilon(0.01));
  }
}

TEST_CASE("a turning drum: the spectra's closed collisions and open contacts book its dissipation", "[books][power]") {
  // Each law, after a warm-up: what closed in the window plus the change in
  // what the open contacts hold is the dissipation, within 1 %.
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    DrumSpec spec;
    spec.n_balls = 200;
    spec.law = law;
    const Scene sc = make_drum(spec);
    auto s = make_solver(context(), sc);
    const double rev_s = 2 * kPi / sc.mill_omega;
    s->advance(static_cast<long>(0.8 / sc.numerics.dt));
    const Observables o0 = s->observe(true);
    s->reset_books();
    s->advance(static_cast<long>((law == ContactLaw::hertz ? 0.3 : 1.0) * rev_s / sc.numerics.dt));
    const Observables o1 = s->observe(true);
    const BookSums b = s->read_books();
    const double books_J = b.closed_loss_J() + o1.open_loss_J() - o0.open_loss_J();
    std::printf("drum %-6s: dissipated %.5g J, spectra %.5g J (closed %.5g, open %.3g -> %.3g), %.0f collisions, %ld "
                "refused\n",
                law == ContactLaw::hertz ? "hertz" : "linear", o1.dissipated_J, books_J, b.closed_loss_J(),
                o0.open_loss_J(), o1.open_loss_J(), collisions(b), s->records_refused());
    INFO((law == ContactLaw::hertz ? "hertz" : "linear"));
    CHECK(collisions(b) > 100);
    CHECK(books_J == Approx(o1.dissipated_J).epsilon(0.01));
    // The normal energy spectrum bins the same collisions and normal losses.
    double by_normal = 0, by_normal_J = 0, normal_J = 0;
    for (int t = 0; t < b.n_types; ++t)
      for (int k = 0; k < MC_SPECTRA_BINS; ++k) {
        by_normal += b.at(t, k, MC_SPECTRA_BY_NORMAL);
        by_normal_J += b.at(t, k, MC_SPECTRA_BY_NORMAL_ENERGY);
        normal_J += b.at(t, k, MC_SPECTRA_NORMAL);
      }
    CHECK(by_normal == collisions(b));
    CHECK(by_normal_J == Approx(normal_J).epsilon(1e-6));
    CHECK(s->records_refused() == 0);
  }
}
