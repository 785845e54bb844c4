// Worn end plates (core/plate_wear.h, cl/walls.h plate_overlap): the dish's
// rings hold the metal they lost, checked by integrating the surface
// independently; the kernels' contact against the exact distance to the
// surface; a ball on a worn plate rests at its depth and slides down its
// slope; the kernels equal the CPU reference on a dense charge against worn
// plates; the case key reads, writes back and refuses by name.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "core/drum.h"
#include "core/layout.hpp"
#include "core/mill_case.h"
#include "core/plate_wear.h"
#include "helpers.h"
#include "io/case_file.h"
#include "sim/reference.h"
#include "sim/tables.h"
#include "text_file.h"

using namespace mc;
using namespace mc::test;

namespace {

// A ring's area-weighted mean depth by the midpoint rule on 20,000 pieces:
// independent of the closed form plate_ring_means uses.
double ring_mean_numeric(const std::vector<double>& nodes, double width, int ring) {
  const int n = 20000;
  const double r0 = ring * width, r1 = (ring + 1) * width, h = (r1 - r0) / n;
  double num = 0, den = 0;
  for (int k = 0; k < n; ++k) {
    const double rho = r0 + (k + 0.5) * h;
    num += plate_surface_depth(nodes, width, rho) * rho * h;
    den += rho * h;
  }
  return num / den;
}

// The exact distance from (rho, z) to the plate at z = 0 worn as `nodes`
// (surface z = -depth(rho)), by brute force over the profile's points.
double exact_distance(const std::vector<double>& nodes, double width, double R, double rho, double z) {
  double best = 1e300;
  const int n = 200000;
  for (int k = 0; k <= n; ++k) {
    const double s = R * k / n;
    const double dz = z + plate_surface_depth(nodes, width, s), dr = rho - s;
    best = std::min(best, std::sqrt(dz * dz + dr * dr));
  }
  return best;
}

}  // namespace

TEST_CASE("a worn plate's rings hold the metal they lost", "[plates]") {
  const double R = 0.45, width = R / 4;
  const std::vector<double> depth = {1.5e-3, 1.2e-3, 4.3e-3, 1.9e-3};  // the lab mill's rings after 1000 h, about
  const std::vector<double> nodes = plate_surface_nodes(depth);
  REQUIRE(nodes.size() == 4);
  for (int j = 0; j < 4; ++j) {
    CHECK(nodes[j] >= 0);
    CHECK(plate_ring_means(nodes, width)[j] == Approx(depth[j]).margin(1e-12));
    CHECK(ring_mean_numeric(nodes, width, j) == Approx(depth[j]).epsilon(1e-6));
  }
  // The surface is not the rings' depths at their centres: the deep ring's
  // node lies deeper than its mean, its neighbours' shallower.
  CHECK(nodes[2] > depth[2] + 1e-4);
  CHECK(nodes[1] < depth[1] - 1e-4);
  // Flat inside the first centre and outside the last; the slope between.
  double slope = 1;
  CHECK(plate_surface_depth(nodes, width, 0.01, &slope) == nodes[0]);
  CHECK(slope == 0);
  CHECK(plate_surface_depth(nodes, width, 0.44, &slope) == nodes[3]);
  const double rho = 0.2, h = 1e-6;
  plate_surface_depth(nodes, width, rho, &slope);
  CHECK(slope == Approx((plate_surface_depth(nodes, width, rho + h) - plate_surface_depth(nodes, width, rho - h)) /
                        (2 * h)).epsilon(1e-6));
  // The volume lost: each ring's depth times its area, against the numeric means.
  double v = 0;
  for (int j = 0; j < 4; ++j) v += ring_mean_numeric(nodes, width, j) * M_PI * width * width * (2 * j + 1);
  CHECK(plate_worn_volume(depth, R) == Approx(v).epsilon(1e-6));

  // A deep ring between two unworn ones: the nodes beside it would stand
  // proud of the plate; they are held at 0, and the plate keeps the
  // volume its rings lost, the deep ring most of its own.
  const std::vector<double> spike = {0, 0, 6e-3, 0};
  const std::vector<double> ns = plate_surface_nodes(spike);
  for (double x : ns) CHECK(x >= 0);
  CHECK(ns[1] == 0);
  CHECK(ns[3] == 0);
  double lost = 0;
  for (int j = 0; j < 4; ++j) lost += ring_mean_numeric(ns, width, j) * M_PI * width * width * (2 * j + 1);
  CHECK(lost == Approx(plate_worn_volume(spike, R)).epsilon(1e-6));
  CHECK(ring_mean_numeric(ns, width, 2) > 0.6 * 6e-3);
  // The lab mill's first stage: an unworn centre beside worn rings; the
  // held centre node costs each ring under 3 % of its depth.
  const std::vector<double> lab = {0, 0.68e-3, 1.47e-3, 0.94e-3};
  const std::vector<double> nl = plate_surface_nodes(lab);
  CHECK(nl[0] == 0);
  double lost_lab = 0;
  for (int j = 0; j < 4; ++j) {
    const double m = ring_mean_numeric(nl, width, j);
    lost_lab += m * M_PI * width * width * (2 * j + 1);
    if (j > 0) CHECK(m == Approx(lab[j]).epsilon(0.03));
  }
  CHECK(lost_lab == Approx(plate_worn_volume(lab, R)).epsilon(1e-6));
}

TEST_CASE("worn plate depths are refused by name where they cannot be", "[plates]") {
  const double R = 0.15, L = 0.1;
  std::array<std::vector<double>, 2> d{std::vector<double>{1e-3, 1e-3, 2e-3, 1e-3},
                                       std::vector<double>{0, 0, 0, 0}};
  CHECK(check_plate_depths(d, 4, R, L).empty());
  CHECK(check_plate_depths(d, 4, R, 0).find("flat end plates") != std::string::npos);
  CHECK(check_plate_depths(d, 5, R, L).find("[0]: 4 depths for 5 rings") != std::string::npos);
  CHECK(check_plate_depths(d, 17, R, L).find("more rings") != std::string::npos);
  auto neg = d;
  neg[1][2] = -1e-4;
  CHECK(check_plate_depths(neg, 4, R, L).find("[1][2]: must be >= 0") != std::string::npos);
  auto steep = d;
  steep[0] = {0, 0, 0.06, 0.06};  // a step well over the 37.5 mm rings' 45°
  CHECK(check_plate_depths(steep, 4, R, L).find("slope by more than 45") != std::string::npos);
  steep[0] = {0, 0, 0.02, 0.02};  // a step of about 30 mm: under 45°
  CHECK(check_plate_depths(steep, 4, R, L).empty());
  auto deep = d;
  deep[1] = {0.1, 0.1, 0.1, 0.1};  // as deep as the mill is long
  CHECK(check_plate_depths(deep, 4, R, L).find("[1][0]: must be >= 0 and less than the mill's length") !=
        std::string::npos);
}

TEST_CASE("the kernels' worn-plate contact is the distance to the dish", "[plates]") {
  DrumSpec spec;
  spec.lifter_rows = 0;
  spec.n_balls = 20;
  Scene sc = make_drum(spec);
  const double R = sc.walls.shell_radius, L = sc.walls.length, width = R / 4;
  sc.walls.plate_depth = {std::vector<double>{2e-3, 2e-3, 9e-3, 5e-3}, std::vector<double>{1e-3, 1e-3, 1e-3, 1e-3}};
  const SceneTables t = scene_tables(sc);
  const f64::SimParams& sp = t.params;
  REQUIRE(sp.plate_nodes == 4);
  const std::vector<double> nodes = plate_surface_nodes(sc.walls.plate_depth[0]);
  CHECK(sp.escape_z0 == Approx(-*std::max_element(nodes.begin(), nodes.end())));
  CHECK(sp.escape_z1 == Approx(L + 1e-3));
  const double r = 0.007;
  // Over each part of the profile (the flat centre, the slopes, the flat rim),
  // a ball whose nearest point of the dish lies on the same straight piece.
  for (double rho : {0.005, 0.03, 0.06, 0.09, 0.12, 0.145}) {
    for (double z : {0.002, -0.001}) {
      const double phi = 0.7;
      f64::real3 n;
      const f64::real3 p = f64::make_real3(rho * std::cos(phi), rho * std::sin(phi), z);
      const double ov = f64::plate_overlap(&sp, 0, p, r, &n);
      const double exact = r - exact_distance(nodes, width, R, rho, z);
      INFO("rho " << rho << " z " << z);
      CHECK(ov == Approx(exact).margin(2e-7));
      CHECK(std::hypot(n.x, n.y, n.z) == Approx(1).margin(1e-12));
      CHECK(n.z > 0.7);  // facing the charge
      double slope = 0;
      plate_surface_depth(nodes, width, rho, &slope);
      // Where the dish deepens outward its face leans out (normal away from the axis).
      CHECK((n.x * std::cos(phi) + n.y * std::sin(phi)) == Approx(slope / std::sqrt(1 + slope * slope)).margin(1e-12));
    }
  }
  // The plate at z = length, worn flat by 1 mm, faces back into the mill.
  f64::real3 n;
  const double ov = f64::plate_overlap(&sp, 1, f64::make_real3(0.05, 0, L - 0.005), r, &n);
  CHECK(ov == Approx(r - 0.006).margin(1e-12));
  CHECK(n.z == -1);
}

TEST_CASE("a ball rests at a worn plate's depth and slides down its slope", "[plates][forces]") {
  DrumSpec spec;
  spec.lifter_rows = 0;
  spec.n_balls = 20;
  spec.mu_slide = 0;
  spec.mu_roll = 0;
  Scene sc = make_drum(spec);
  sc.mill_omega = 0;
  sc.numerics.gravity = {0, 0, -9.81};  // the plate at z = 0 is the floor
  sc.walls.plate_depth = {std::vector<double>{3e-3, 3e-3, 8e-3, 8e-3}, std::vector<double>{0, 0, 0, 0}};
  const std::vector<double> nodes = plate_surface_nodes(sc.walls.plate_depth[0]);
  const double r = 0.007;
  Ball a = sc.balls[0], b = sc.balls[1];
  a.id = 0, b.id = 1, a.radius = b.radius = r;
  a.position = {0.004, 0.0, r + 0.002};         // over the flat centre
  b.position = {0.0, 0.070, r};                 // over the slope between rings 1 and 2
  a.velocity = b.velocity = a.omega = b.omega = {0, 0, 0};
  sc.balls = {a, b};
  auto s = make_solver(context(), sc);
  const long steps = static_cast<long>(0.4 / sc.numerics.dt);
  s->advance(steps);
  const std::vector<BallState> now = s->balls();
  // Resting: the dish's depth there less the ball's radius (its overlap
  // under its weight is below a micrometre at this stiffness).
  CHECK(now[0].position.z == Approx(r - nodes[0]).margin(2e-5));
  CHECK(std::hypot(now[0].velocity.x, now[0].velocity.y, now[0].velocity.z) < 5e-3);
  // Frictionless on a slope that deepens outward: it has slid out and down.
  const double rho_b = std::hypot(now[1].position.x, now[1].position.y);
  std::printf("plates: ball at rest z %.6f m (expected %.6f); sliding ball rho 0.070 -> %.4f m, z %.5f m\n",
              now[0].position.z, r - nodes[0], rho_b, now[1].position.z);
  CHECK(rho_b > 0.075);
  CHECK(now[1].position.z < r - plate_surface_depth(nodes, sc.walls.shell_radius / 4, 0.070));
}

TEST_CASE("the kernels equal the CPU reference against worn plates", "[plates][forces][reference]") {
  for (Precision prec : {Precision::double_, Precision::single}) {
    if (prec == Precision::double_ && !context().info().fp64) continue;
    DrumSpec spec;
    spec.n_balls = 300;
    spec.precision = prec;
    Scene sc = make_drum(spec);
    // The drum's plates are 0.1 m apart: a dish of a few mm at each end.
    sc.walls.plate_depth = {std::vector<double>{1e-3, 2e-3, 5e-3, 3e-3}, std::vector<double>{4e-3, 3e-3, 2e-3, 1e-3}};
    auto pre = make_solver(context(), sc);
    pre->advance(static_cast<long>(0.15 / sc.numerics.dt));
    take_motion(*pre, sc);
    auto dev = make_solver(context(), sc);
    ReferenceSolver ref(sc);
    dev->advance(200);
    ref.advance(200);
    const auto a = dev->balls(), b = ref.balls();
    double dx = 0, vmax = 0, zmin = 1;
    for (std::size_t i = 0; i < a.size(); ++i) {
      dx = std::max(dx, (a[i].position - b[i].position).norm());
      vmax = std::max(vmax, b[i].velocity.norm());
      zmin = std::min(zmin, b[i].position.z - b[i].radius);
    }
    std::printf("plates: kernel vs reference %s: max |dx| %.3g m; lowest ball reaches z %.5f m\n",
                prec == Precision::double_ ? "double" : "float", dx, zmin);
    CHECK(zmin < -0.5e-3);  // balls are in the dish, behind the plate's plane
    CHECK(dx < (prec == Precision::double_ ? 1e-10 : 1e-5));
  }
}

TEST_CASE("worn plate depths in a case: read, written back, refused by name", "[plates][case]") {
  const std::string lab = read_text(mc::io::default_case());
  const std::string key = "liner.plate_depth_mm=[[1.0, 1.5, 4.0, 2.0], [0.5, 1.0, 3.5, 2.5]]";
  const MillCase c = mc::io::parse_case(lab, "lab.toml", {key});
  REQUIRE(c.plate_depth[0].size() == 4);
  CHECK(c.plate_depth[0][2] == Approx(4e-3));
  CHECK(c.plate_depth[1][3] == Approx(2.5e-3));
  const MillCase back = mc::io::parse_case(mc::io::case_to_toml(c), "back.toml");
  CHECK(back.plate_depth == c.plate_depth);
  // The dishes add to the free volume: each ring's depth times its area.
  const MillDerived d0 = derive(mc::io::parse_case(lab, "lab.toml")), d1 = derive(c);
  CHECK(d1.mill_volume - d0.mill_volume ==
        Approx(plate_worn_volume(c.plate_depth[0], 0.5 * c.diameter) + plate_worn_volume(c.plate_depth[1], 0.5 * c.diameter))
            .epsilon(1e-9));
  const Scene s = build_walls(c, d1);
  CHECK(s.walls.plate_depth == c.plate_depth);
  auto refused = [&](const std::vector<std::string>& sets) {
    try {
      mc::io::parse_case(lab, "lab.toml", sets);
    } catch (const mc::io::CaseError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(refused({"liner.plate_depth_mm=[[1.0, 2.0, 3.0], [1.0, 2.0, 3.0, 4.0]]"}).find("liner.plate_depth_mm: [0]: 3 depths for 4 rings") != std::string::npos);
  CHECK(refused({"liner.plate_depth_mm=[1.0, 2.0]"}).find("liner.plate_depth_mm: must be two lists") != std::string::npos);
  CHECK(refused({key, "mill.ends=\"periodic\""}).find("flat end plates") != std::string::npos);
  CHECK(refused({"liner.plate_depth_mm=[[1, 1, 1, 1], [0, 0, -1, 0]]"}).find("[1][2]: must be >= 0") != std::string::npos);
}
