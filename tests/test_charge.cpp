// The charge as placed before settling, the toe/shoulder finder on known
// distributions, and Morrell's C-model against hand-worked values.
#include <catch2/catch.hpp>

#include <cmath>
#include <map>

#include "core/lifters.h"
#include "core/mill_case.h"
#include "core/morrell.h"
#include "io/case_file.h"
#include "sim/charge_profile.h"

namespace {

// Checks a placed charge: count, sizes, inside the mill, clear of lifters and
// of each other (cell grid, exact pair test).
void check_placement(const mc::MillCase& c) {
  const mc::MillDerived d = mc::derive(c);
  const mc::Scene s = mc::build_scene(c, d);
  REQUIRE(static_cast<long>(s.balls.size()) == d.n_balls);
  const double R = 0.5 * c.diameter;
  double rmax = 0, y_mean = 0;
  for (const mc::Ball& b : s.balls) {
    rmax = std::max(rmax, b.radius);
    y_mean += b.position.y / s.balls.size();
    REQUIRE(std::hypot(b.position.x, b.position.y) + b.radius <= R);
    REQUIRE(b.position.z - b.radius >= 0);
    REQUIRE(b.position.z + b.radius <= c.length);
    for (const auto& poly : s.walls.lifters) REQUIRE(mc::polygon_signed_distance(poly, b.position.x, b.position.y) >= b.radius);
  }
  CHECK(y_mean < -0.2 * R);  // in the lower part of the mill
  std::map<std::tuple<long, long, long>, std::vector<int>> cells;
  const double h = 2 * rmax;
  auto key = [&](const mc::Vec3& p) {
    return std::make_tuple(std::lround(std::floor(p.x / h)), std::lround(std::floor(p.y / h)),
                           std::lround(std::floor(p.z / h)));
  };
  for (int i = 0; i < static_cast<int>(s.balls.size()); ++i) cells[key(s.balls[i].position)].push_back(i);
  long overlaps = 0;
  for (int i = 0; i < static_cast<int>(s.balls.size()); ++i) {
    const auto [cx, cy, cz] = key(s.balls[i].position);
    for (long dx = -1; dx <= 1; ++dx)
      for (long dy = -1; dy <= 1; ++dy)
        for (long dz = -1; dz <= 1; ++dz) {
          auto it = cells.find({cx + dx, cy + dy, cz + dz});
          if (it == cells.end()) continue;
          for (int j : it->second)
            if (j > i && (s.balls[i].position - s.balls[j].position).norm() < s.balls[i].radius + s.balls[j].radius)
              ++overlaps;
        }
  }
  CHECK(overlaps == 0);
}

}  // namespace

TEST_CASE("the charge is placed without overlaps, inside the mill, clear of the lifters", "[charge]") {
  SECTION("lab mill, one size") { check_placement(mc::io::read_case(mc::io::default_case())); }
  SECTION("SAG mill C shortened: balls and a range of rock sizes, high/low lifters") {
    check_placement(mc::io::read_case(mc::io::case_dir() / "mill_c.toml", {"mill.length=0.6"}));
  }
}

TEST_CASE("more filling than fits is refused naming charge.filling", "[charge]") {
  // A mill barely longer than a ball holds one layer: J 0.5 at porosity 0.2
  // cannot be placed.
  mc::MillCase c = mc::io::read_case(mc::io::default_case(),
                                     {"mill.length=0.028", "charge.filling=0.5", "charge.porosity=0.2"});
  const mc::MillDerived d = mc::derive(c);
  CHECK_THROWS_WITH(mc::build_scene(c, d), Catch::Contains("charge.filling: only"));
}

TEST_CASE("toe and shoulder from a contact distribution", "[profile]") {
  // A band from 230° counter-clockwise through 270° and 0° to 50°.
  std::vector<long> h(360, 0);
  for (int a = 230; a < 410; ++a) h[a % 360] = 100;
  h[120] = 15;  // a stray landing far from the band
  const mc::ChargeAngles a = mc::toe_and_shoulder(h, 0.2, 1);
  REQUIRE(a.found);
  CHECK(a.toe_deg == Approx(230).margin(1.0));
  CHECK(a.shoulder_deg == Approx(50).margin(1.0));
  // Smoothing keeps the ends within a bin.
  const mc::ChargeAngles s = mc::toe_and_shoulder(h, 0.2, 5);
  CHECK(s.toe_deg == Approx(230).margin(1.5));
  CHECK(s.shoulder_deg == Approx(50).margin(1.5));
  // Nothing, or contacts all round (a centrifuging charge): no band.
  CHECK_FALSE(mc::toe_and_shoulder(std::vector<long>(360, 0)).found);
  CHECK_FALSE(mc::toe_and_shoulder(std::vector<long>(360, 7)).found);
}

TEST_CASE("Morrell's C-model: the empirical angles and the power's scaling", "[morrell]") {
  mc::MorrellInput in;
  in.diameter = 0.9;
  in.length = 0.15;
  in.filling = 0.30;
  in.speed_fraction = 0.75;
  in.speed_rpm = 0.75 * 45.23;
  in.charge_density = 7800 * 0.6;
  const mc::MorrellResult m = mc::morrell_c_model(in);
  // By hand: φc = 0.35 (3.364 − 0.3) = 1.0724; θT = 2.5307 (0.9796)
  // (1 − e^{−19.42 (0.3224)}) + π/2 = 4.0452 rad; θS = π/2 − (θT − π/2)
  // (0.4167 − 0.1157) = 0.8258 rad.
  CHECK(m.toe_deg == Approx(4.0452 * 180 / M_PI).margin(0.05));
  CHECK(m.shoulder_deg == Approx(0.8258 * 180 / M_PI).margin(0.05));
  CHECK(m.net_power_W > 300);
  CHECK(m.net_power_W < 1500);
  CHECK(m.charge_power_W == Approx(1.26 * m.net_power_W).epsilon(1e-12));
  CHECK(m.inner_radius_m > 0);
  CHECK(m.inner_radius_m < 0.45);
  // Linear in length and in charge density.
  mc::MorrellInput longer = in;
  longer.length *= 2;
  CHECK(mc::morrell_c_model(longer).net_power_W == Approx(2 * m.net_power_W).epsilon(1e-9));
  mc::MorrellInput denser = in;
  denser.charge_density *= 1.5;
  CHECK(mc::morrell_c_model(denser).net_power_W == Approx(1.5 * m.net_power_W).epsilon(1e-9));
  // Power rises with speed below 80 % of critical.
  double last = 0;
  for (double phi : {0.5, 0.6, 0.7, 0.8}) {
    mc::MorrellInput s = in;
    s.speed_fraction = phi;
    s.speed_rpm = phi * 45.23;
    const double p = mc::morrell_c_model(s).net_power_W;
    CHECK(p > last);
    last = p;
  }
}
