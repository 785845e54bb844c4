// Impact wear (docs/liner-life.md): Bitter's deformation wear, a volume of
// impact_wear_coefficient · ½ m (vn − K)² for each collision with the liner,
// vn the approach speed at first touch and K the material's threshold.
// Against the closed form: one ball striking a plate (the analytic end
// plate and a mesh plate of another material) at known speed and angle.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <vector>

#include "core/layout.hpp"
#include "core/lifters.h"
#include "core/liner.h"
#include "helpers.h"
#include "sim/energy_report.h"

using namespace mc;
using namespace mc::test;

namespace {

const Material kSteel{"steel", 7800, 2e11, 0.3};

// A ball of radius r a micrometre above the plate z = 0, moving at `speed`
// at `angle_deg` to the plate's surface, no gravity; the liner (analytic
// plate) or the mesh plate's material with the impact wear given.
Scene strike_scene(double speed, double angle_deg, bool mesh, double k_impact, double threshold) {
  Interaction in;
  in.restitution = 0.5;
  in.mu_slide = 0.3;
  in.mu_roll = 0;
  in.kn = 1e6;
  Material liner = kSteel;
  liner.impact_wear_coefficient = mesh ? 0 : k_impact;  // the mesh's own material carries it
  liner.impact_wear_threshold_speed = mesh ? 0 : threshold;
  Scene s = bare_scene(kSteel, liner, in, ContactLaw::linear, Precision::double_);
  const double r = 0.01, m = sphere_mass(7800, r);
  s.numerics.dt = kPi * std::sqrt(m / in.kn) / 60;
  if (mesh) {
    const Vec3 a{-1, -1, 0}, b{1, -1, 0}, c{1, 1, 0}, d{-1, 1, 0};
    WallMesh w;
    w.name = "plate";
    w.triangles = {{{a, b, c}}, {{a, c, d}}};
    w.material = kSteel;
    w.material.name = "plate steel";
    w.material.density = 7000;
    w.material.impact_wear_coefficient = k_impact;
    w.material.impact_wear_threshold_speed = threshold;
    w.interactions = {s.interaction(0, s.wall_index())};
    s.walls.meshes = {w};
  } else {
    s.walls.length = 1.0;  // the plate z = 0
  }
  const double a = angle_deg * kPi / 180;
  Ball ball;
  ball.radius = r;
  ball.position = {0, 0, r + 1e-6};
  ball.velocity = {speed * std::cos(a), 0, -speed * std::sin(a)};
  s.balls = {ball};
  return s;
}

}  // namespace

TEST_CASE("a ball striking a plate books Bitter's deformation wear: k 1/2 m (V sin a - K)^2, apart from sliding",
          "[books][physics][wear][impact_wear]") {
  const double r = 0.01, m = sphere_mass(7800, r), k = 3e-11;
  for (const bool mesh : {false, true})
    for (const double angle : {90.0, 45.0, 20.0})
      for (const double threshold : {0.0, 0.4, 2.5}) {
        const double speed = 3.0;
        Scene sc = strike_scene(speed, angle, mesh, k, threshold);
        auto s = make_solver(context(), sc);
        // Down, the contact (60 steps), back up and clear.
        s->advance(400);
        const BookSums books = s->read_books();
        const LinerLayout layout = liner_layout(sc);
        const LinerReport rep = liner_report(sc, layout, books, 1.0, {}, ChargeAngles{});
        const double vn = speed * std::sin(angle * kPi / 180), over = std::max(vn - threshold, 0.0);
        const double strike = 0.5 * m * over * over;
        double booked = 0, sliding = 0, impacts = 0, kg_h = 0;
        for (int e = 0; e < books.n_elements; ++e) booked += books.liner_at(e, MC_LINER_STRIKE);
        for (const LinerElementRates& x : rep.elements) {
          sliding += x.sliding_m3_per_s;
          impacts += x.impacts_per_s;
        }
        for (const LinerPartRates& p : rep.parts) kg_h += p.impact_kg_per_h;
        std::printf("%s, %2.0f deg, K %.1f m/s: strike %.9g J (closed form %.9g), impact wear %.6g m^3 (k E %.6g), "
                    "sliding %.4g m^3\n",
                    mesh ? "mesh plate" : "end plate ", angle, threshold, booked, strike,
                    rep.impact_kg_per_h / ((mesh ? 7000 : 7800) * 3600.0), k * strike, sliding);
        INFO((mesh ? "mesh" : "end plate") << " at " << angle << " deg, K " << threshold);
        CHECK(impacts == 1);
        CHECK(booked == Approx(strike).epsilon(1e-9).margin(1e-15));
        // The volume, in kg/h of the element's material over a window of 1 s.
        const double density = mesh ? 7000 : 7800;
        CHECK(rep.impact_kg_per_h == Approx(k * strike * density * 3600).epsilon(1e-9).margin(1e-18));
        CHECK(kg_h == Approx(rep.impact_kg_per_h).epsilon(1e-12).margin(1e-18));
        // Sliding apart: nothing at normal incidence, something on the
        // oblique strikes (friction slides the contact point).
        if (angle == 90.0) CHECK(sliding == Approx(0).margin(1e-18));
        else CHECK(sliding > 0);
        CHECK(rep.wear_kg_per_h == Approx(rep.sliding_kg_per_h + rep.impact_kg_per_h).epsilon(1e-12));
      }
}

TEST_CASE("impact wear off books the strike energy and adds nothing to the wear", "[books][wear][impact_wear]") {
  Scene sc = strike_scene(2.0, 60.0, false, 0.0, 0.0);
  auto s = make_solver(context(), sc);
  s->advance(400);
  const BookSums books = s->read_books();
  const LinerReport rep = liner_report(sc, liner_layout(sc), books, 1.0, {}, ChargeAngles{});
  const double vn = 2.0 * std::sin(60 * kPi / 180), m = sphere_mass(7800, 0.01);
  CHECK(rep.strike_W == Approx(0.5 * m * vn * vn).epsilon(1e-9));
  CHECK(rep.impact_kg_per_h == 0);
  CHECK(rep.wear_kg_per_h == rep.sliding_kg_per_h);
}

namespace {

// The turning mill's strikes: the wall's own speed at the contact point
// counts where it is along the liner's normal, and not where it is along
// the liner. Books of elements and of lifter wear stations, summed.
struct Struck {
  double elements = 0, stations = 0, impacts = 0;
};

// A shell of radius R turning at omega, 0.1 m long, no gravity; the liner
// with impact wear and threshold K; a contact of 60 steps for mass m.
Scene turning_scene(Precision precision, double K, double R, double omega, double m) {
  Interaction in;
  in.restitution = 0.5;
  in.mu_slide = 0.3;
  in.mu_roll = 0;
  in.kn = 1e6;
  Material liner = kSteel;
  liner.impact_wear_coefficient = 1e-11;
  liner.impact_wear_threshold_speed = K;
  Scene sc = bare_scene(kSteel, liner, in, ContactLaw::linear, precision);
  sc.numerics.dt = kPi * std::sqrt(m / in.kn) / 60;
  sc.walls.shell_radius = R;
  sc.walls.length = 0.1;
  sc.mill_omega = omega;
  return sc;
}

Struck strikes_of(const Scene& sc, int steps) {
  auto s = make_solver(context(), sc);
  s->advance(steps);
  const BookSums books = s->read_books();
  Struck out;
  for (int e = 0; e < books.n_elements; ++e) {
    out.elements += books.liner_at(e, MC_LINER_STRIKE);
    out.impacts += books.liner_at(e, MC_LINER_IMPACTS);
  }
  for (std::size_t i = MC_LINER_STRIKE; i < books.stations.size(); i += MC_LINER_FIELDS) out.stations += books.stations[i];
  return out;
}

}  // namespace

TEST_CASE("a turning lifter face sweeping into a ball at rest books 1/2 m (w rho - K)^2", "[books][physics][wear][impact_wear]") {
  // A radial-faced bar (152 mm scaled down: 30 mm high, 20 mm top) at angle
  // 0 of a 0.25 m shell turning at w; a ball at rest a micrometre ahead of
  // its leading face at radius rho. The face plane is parallel to the
  // radial line: its speed along its normal at radius rho is w rho.
  const double R = 0.25, h = 0.03, w = 0.02, r = 0.008, omega = 4.0, m = sphere_mass(7800, r);
  for (const Precision precision : {Precision::double_, Precision::single})
    for (const double threshold : {0.0, 0.3}) {
      Scene sc = turning_scene(precision, threshold, R, omega, m);
      LifterProfile bar;
      bar.height = h, bar.top_width = w, bar.face_angle_deg = 0;
      sc.walls.lifters = lifter_rows(R, 8, {bar}, 0.0);
      const double rho = R - 0.5 * h;
      Ball b;
      b.radius = r;
      b.position = {rho, 0.5 * w + r + 1e-6, 0.05};
      sc.balls = {b};
      const Struck got = strikes_of(sc, 200);  // the contact is 60 steps; the ball clears the face after
      const double over = std::max(omega * rho - threshold, 0.0), strike = 0.5 * m * over * over;
      INFO((precision == Precision::double_ ? "double" : "float") << ", K " << threshold);
      CHECK(got.impacts == 1);
      const double eps = precision == Precision::double_ ? 1e-5 : 1e-4;
      CHECK(got.elements == Approx(strike).epsilon(eps));
      CHECK(got.stations == Approx(strike).epsilon(eps));
    }
}

TEST_CASE("a ball dropped onto the turning shell books its radial speed alone, not the shell's", "[books][physics][wear][impact_wear]") {
  // The shell moves at w R = 1 m/s along itself; the ball meets it at 1.5
  // m/s along the radius: the strike is 1/2 m (1.5 - K)^2, where |v_rel|
  // would give 1/2 m (1.5^2 + 1^2).
  const double R = 0.25, r = 0.008, omega = 4.0, speed = 1.5, m = sphere_mass(7800, r);
  for (const Precision precision : {Precision::double_, Precision::single}) {
    Scene sc = turning_scene(precision, 0.2, R, omega, m);
    Ball b;
    b.radius = r;
    b.position = {0, -(R - r - 1e-6), 0.05};
    b.velocity = {0, -speed, 0};
    sc.balls = {b};
    const Struck got = strikes_of(sc, 200);
    INFO((precision == Precision::double_ ? "double" : "float"));
    CHECK(got.impacts == 1);
    CHECK(got.elements == Approx(0.5 * m * (speed - 0.2) * (speed - 0.2)).epsilon(precision == Precision::double_ ? 1e-6 : 1e-4));
    CHECK(got.stations == 0);
  }
}
