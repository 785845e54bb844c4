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
#include "core/liner.h"
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
  const int n = 400000;
  for (int k = 0; k <= n; ++k) {
    const double s = (R + 0.02) * k / n;
    const double dz = z + plate_surface_depth(nodes, width, s), dr = rho - s;
    best = std::min(best, std::sqrt(dz * dz + dr * dr));
  }
  return best;
}

}  // namespace

TEST_CASE("a worn plate's face, the metal its rings lost, and a step that never rises", "[plates]") {
  const double R = 0.45, width = R / 4;
  const std::vector<double> depth = {1.5e-3, 1.2e-3, 4.3e-3, 1.9e-3};
  // Flat across each ring's middle half at its depth; straight across the
  // quarter-rings either side of an edge; flat inside and out.
  for (int j = 0; j < 4; ++j) {
    CHECK(plate_surface_depth(depth, width, (j + 0.5) * width) == depth[j]);
    if (j + 1 < 4) CHECK(plate_surface_depth(depth, width, (j + 1) * width) == Approx(0.5 * (depth[j] + depth[j + 1])));
  }
  CHECK(plate_surface_depth(depth, width, 0.0) == depth[0]);
  CHECK(plate_surface_depth(depth, width, R + 0.01) == depth[3]);
  double slope = 0;
  plate_surface_depth(depth, width, 2 * width + 0.1 * width, &slope);
  CHECK(slope == Approx((depth[2] - depth[1]) / (0.5 * width)));
  // Each ring's mean against numeric integration; the volume lost.
  const std::vector<double> mean = plate_ring_means(depth, width);
  double v = 0;
  for (int j = 0; j < 4; ++j) {
    CHECK(mean[j] == Approx(ring_mean_numeric(depth, width, j)).epsilon(1e-6));
    v += ring_mean_numeric(depth, width, j) * M_PI * width * width * (2 * j + 1);
  }
  CHECK(plate_worn_volume(depth, R) == Approx(v).epsilon(1e-6));
  // The deep ring's mean lies under its depth (its edges are shallower),
  // its neighbours' over theirs.
  CHECK(mean[2] < depth[2] - 1e-4);
  CHECK(mean[1] > depth[1] + 1e-4);

  // A step: each ring loses what it booked, measured on the face.
  auto lost = [&](const std::vector<double>& before, const std::vector<double>& after, int j) {
    return ring_mean_numeric(after, width, j) - ring_mean_numeric(before, width, j);
  };
  const std::vector<double> booked = {0.5e-3, 0.4e-3, 1.4e-3, 0.6e-3};
  const std::vector<double> inc = plate_increment(booked);
  std::vector<double> after = depth;
  for (int j = 0; j < 4; ++j) {
    CHECK(inc[j] >= 0);
    after[j] += inc[j];
  }
  for (int j = 0; j < 4; ++j) CHECK(lost(depth, after, j) == Approx(booked[j]).epsilon(1e-5));
  // The lab mill's first stage: a centre that booked almost nothing beside
  // worn rings. Its increment is held at 0; it takes a little of ring 1's
  // metal at their edge; the plate loses its booked volume within 1 %.
  const std::vector<double> lab = {0.05e-3, 1.46e-3, 4.22e-3, 1.87e-3};
  const std::vector<double> il = plate_increment(lab);
  const std::vector<double> zero(4, 0.0);
  CHECK(il[0] == 0);
  double want = 0, got = 0;
  for (int j = 0; j < 4; ++j) {
    want += lab[j] * (2 * j + 1), got += lost(zero, il, j) * (2 * j + 1);
    if (j >= 2) CHECK(lost(zero, il, j) == Approx(lab[j]).epsilon(1e-5));
  }
  std::printf("plates: the lab step: ring 0 lost %.4f mm against 0.05 booked, ring 1 %.4f against 1.46; the plate %.3f %% "
              "over\n",
              lost(zero, il, 0) * 1e3, lost(zero, il, 1) * 1e3, 100 * (got / want - 1));
  CHECK(got == Approx(want).epsilon(0.01));
  // The complementarity conditions on hard bookings, 1 to 16 rings: every
  // increment >= 0, every ring loses at least its booking, exactly where
  // it moves (measured on the face by numeric integration).
  std::uint32_t s2 = 777;
  auto u2 = [&] { return (s2 = s2 * 1664525u + 1013904223u) / 4294967296.0; };
  std::vector<std::vector<double>> cases = {{2.9e-4, 7e-5, 0, 0.303}, {0, 1e-3}, {1e-3}, {0, 0, 5e-3, 0, 0, 1e-4}};
  for (int k = 0; k < 40; ++k) {
    std::vector<double> b(1 + k % 16);
    for (double& x : b) x = u2() < 0.4 ? 0.0 : std::pow(10.0, -6 + 3 * u2());
    cases.push_back(b);
  }
  for (const std::vector<double>& b : cases) {
    const int n = static_cast<int>(b.size());
    const double w = R / n;
    const std::vector<double> x = plate_increment(b), zero_n(n, 0.0);
    double top = 0;
    for (double v : b) top = std::max(top, v);
    for (int j = 0; j < n; ++j) {
      INFO(n << " rings, ring " << j << " booked " << b[j]);
      CHECK(x[j] >= 0);
      const double loss = ring_mean_numeric(x, w, j);
      CHECK(loss >= b[j] - 1e-6 * top);
      if (x[j] > 0) CHECK(loss == Approx(b[j]).margin(1e-6 * top));
    }
  }
  // Many steps of uneven bookings: the face never rises anywhere.
  std::vector<double> d(4, 0.0);
  std::uint32_t seed = 12345;
  auto uniform = [&] { return (seed = seed * 1664525u + 1013904223u) / 4294967296.0; };
  bool rose = false;
  for (int step = 0; step < 200; ++step) {
    std::vector<double> b(4);
    for (double& x : b) x = uniform() < 0.3 ? 0.0 : 1e-3 * uniform();
    const std::vector<double> i = plate_increment(b);
    std::vector<double> next = d;
    for (int j = 0; j < 4; ++j) next[j] += i[j];
    for (int k = 0; k <= 400; ++k)
      rose = rose || plate_surface_depth(next, width, R * k / 400) < plate_surface_depth(d, width, R * k / 400);
    d = next;
  }
  CHECK(!rose);
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
  auto deep = d;
  deep[1] = {0.1, 0.1, 0.1, 0.1};  // as deep as the mill is long
  CHECK(check_plate_depths(deep, 4, R, L).find("[1][0]: must be >= 0 and less than the mill's length") !=
        std::string::npos);
}

TEST_CASE("the kernels' worn-plate contact is the distance to the dish, corners included", "[plates]") {
  DrumSpec spec;
  spec.lifter_rows = 0;
  spec.n_balls = 20;
  Scene sc = make_drum(spec);
  const double R = sc.walls.shell_radius, L = sc.walls.length, width = R / 4;
  sc.walls.plate_depth = {std::vector<double>{2e-3, 2e-3, 9e-3, 5e-3}, std::vector<double>{1e-3, 4e-3, 2e-3, 6e-3}};
  const SceneTables t = scene_tables(sc);
  const f64::SimParams& sp = t.params;
  REQUIRE(sp.plate_nodes == 4);
  CHECK(sp.escape_z0 == Approx(-9e-3));
  CHECK(sp.escape_z1 == Approx(L + 6e-3));
  const double r = 0.007;
  for (int plate = 0; plate < 2; ++plate) {
    const std::vector<double>& depth = sc.walls.plate_depth[plate];
    // Across the flats, the ramps and every corner (a quarter-ring either
    // side of an edge), just before, on and after it, and a ball's slope away.
    std::vector<double> rhos = {0.004, 0.02, 0.06, 0.1, 0.145};
    for (int e = 1; e < 4; ++e)
      for (double c : {e * width - 0.25 * width, e * width + 0.25 * width})
        for (double dr : {-3e-3, -1e-4, -1e-6, 0.0, 1e-6, 1e-4, 3e-3}) rhos.push_back(c + dr);
    for (double rho : rhos)
      for (double h : {0.004, 0.0015, -0.0005}) {  // the centre's height above the plate's plane
        const double phi = 0.7;
        const double z = plate == 0 ? h : L - h;
        f64::real3 n;
        const double ov = f64::plate_overlap(&sp, plate, f64::make_real3(rho * std::cos(phi), rho * std::sin(phi), z), r, &n);
        const double exact = r - exact_distance(depth, width, R, rho, h);
        INFO("plate " << plate << " rho " << rho << " height " << h);
        CHECK(ov == Approx(exact).margin(3e-7));
        CHECK(std::hypot(n.x, n.y, n.z) == Approx(1).margin(1e-12));
        CHECK((plate == 0 ? n.z : -n.z) > 0.5);  // facing the charge
      }
  }
  // On a ramp that deepens outward the face leans out: the normal's radial
  // part is the slope's, on either plate (ring 2 to 3 on plate 1 rises).
  for (int plate = 0; plate < 2; ++plate) {
    const double rho = 1.1 * width, h = 0.002;
    double slope = 0;
    plate_surface_depth(sc.walls.plate_depth[plate], width, rho, &slope);
    f64::real3 n;
    f64::plate_overlap(&sp, plate, f64::make_real3(rho, 0, plate == 0 ? h : L - h), r, &n);
    CHECK(n.x == Approx(slope / std::sqrt(1 + slope * slope)).margin(1e-9));
  }
  // The overlap runs on across a corner: no jump between neighbouring points.
  const double corner = 2 * width - 0.25 * width;
  double last = NAN, jump = 0;
  for (int k = -200; k <= 200; ++k) {
    f64::real3 n;
    const double ov = f64::plate_overlap(&sp, 0, f64::make_real3(corner + k * 1e-5, 0, 0.0), r, &n);
    if (std::isfinite(last)) jump = std::max(jump, std::fabs(ov - last));
    last = ov;
  }
  CHECK(jump < 2e-5);  // 1e-5 m apart, slopes under 1
  // 1, 2 and 16 rings, and centres behind the face (deeper than the plate
  // there): the overlap is the radius plus the distance back to the face.
  for (int rings : {1, 2, 16}) {
    Scene s2 = sc;
    s2.liner.plate_rings = rings;
    std::vector<double> d0(rings), d1(rings);
    for (int j = 0; j < rings; ++j) d0[j] = 1e-3 * (1 + (j * 7) % 5), d1[j] = 1e-3 * (1 + (j * 3) % 4);
    s2.walls.plate_depth = {d0, d1};
    const SceneTables t2 = scene_tables(s2);
    const double w2 = R / rings;
    for (int plate = 0; plate < 2; ++plate)
      for (double rho : {0.003, 0.5 * w2, 0.75 * w2 + 1e-4, 1.26 * w2, 0.11, 0.149})
        for (double h : {0.003, -0.0005, -0.0045}) {
          if (rho > R) continue;  // inside the shell only
          const std::vector<double>& depth = plate == 0 ? d0 : d1;
          const double face = -plate_surface_depth(depth, w2, rho);
          f64::real3 n2;
          const double ov = f64::plate_overlap(&t2.params, plate, f64::make_real3(0, rho, plate == 0 ? h : L - h), r, &n2);
          const double dist = exact_distance(depth, w2, R, rho, h);
          INFO(rings << " rings, plate " << plate << " rho " << rho << " height " << h);
          CHECK(ov == Approx(h < face ? r + dist : r - dist).margin(3e-7));
          CHECK((plate == 0 ? n2.z : -n2.z) > 0);
        }
  }
  // The plate at z = length, flat where it is 1 mm deep, faces back into the mill.
  f64::real3 n;
  const double ov = f64::plate_overlap(&sp, 1, f64::make_real3(0.005, 0, L - 0.005), r, &n);
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
  const std::vector<double>& nodes = sc.walls.plate_depth[0];
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

TEST_CASE("liner.vtp draws a worn plate on its dish, bends included", "[plates][outputs]") {
  DrumSpec spec;
  spec.lifter_rows = 0;
  spec.n_balls = 20;
  Scene sc = make_drum(spec);
  const double R = sc.walls.shell_radius, L = sc.walls.length, w = R / 2;
  sc.liner.plate_rings = 2;
  sc.liner.plate_sectors = 6;
  // Feed plate 1 mm deep in its inner ring, 3 mm in its outer; the
  // discharge plate 0 and 0.5 mm. The dish (by hand): each ring's own
  // depth across its middle half, straight between the two over the
  // quarter-rings either side of their edge at R/2.
  sc.walls.plate_depth = {std::vector<double>{1e-3, 3e-3}, std::vector<double>{0, 0.5e-3}};
  auto dish = [&](int plate, double rho) {
    const double a = plate == 0 ? 1e-3 : 0.0, b = plate == 0 ? 3e-3 : 0.5e-3;
    if (rho <= 0.75 * w) return a;
    if (rho >= 1.25 * w) return b;
    return a + (rho - 0.75 * w) / (0.5 * w) * (b - a);
  };
  const LinerLayout layout = liner_layout(sc);
  int plates = 0, bends = 0;
  for (const LinerElement& e : layout.elements) {
    if (e.part != LinerPart::plate) continue;
    ++plates;
    INFO("plate " << e.row << ", ring " << e.bin);
    for (const Vec3& p : e.outline) {
      const double rho = std::hypot(p.x, p.y);
      const double expected = e.row == 0 ? -dish(0, rho) : L + dish(1, rho);
      CHECK(p.z == Approx(expected).margin(1e-12));
      bends += std::abs(rho - 0.75 * w) < 1e-12 || std::abs(rho - 1.25 * w) < 1e-12;
    }
  }
  CHECK(plates == 2 * 2 * 6);
  // Each element has its ring's bend on both radial sides: 2 plates x 2
  // rings x 6 sectors x 2 sides.
  CHECK(bends == 48);
  // The feed plate's edge at the shell lies 3 mm behind its plane, its
  // centre 1 mm; new plates are drawn on their planes.
  sc.walls.plate_depth = {};
  for (const LinerElement& e : liner_layout(sc).elements)
    if (e.part == LinerPart::plate)
      for (const Vec3& p : e.outline) CHECK(p.z == (e.row == 0 ? 0.0 : L));
}

TEST_CASE("the window's plate face follows the dish: every vertex at its depth, facing the mill, covering the disc",
          "[plates][outputs]") {
  // Three rings of 0.1 m: 4, 1 and 6 mm deep. The dish (by hand): each
  // ring's depth across its middle half, straight between neighbours over
  // the quarter-rings either side of their edges at 0.1 and 0.2 m.
  const double R = 0.3, w = 0.1;
  const std::vector<double> depth = {4e-3, 1e-3, 6e-3};
  auto dish = [&](double rho) {
    if (rho <= 0.075) return 4e-3;
    if (rho < 0.125) return 4e-3 + (rho - 0.075) / (0.5 * w) * (1e-3 - 4e-3);
    if (rho <= 0.175) return 1e-3;
    if (rho < 0.225) return 1e-3 + (rho - 0.175) / (0.5 * w) * (6e-3 - 1e-3);
    return 6e-3;
  };
  const int segments = 60;
  const std::vector<Triangle> face = plate_face_triangles(depth, R, segments);
  // Rings between 0, the four bends and R: a triangle at the axis and two
  // per sector in each of the other four.
  REQUIRE(face.size() == static_cast<std::size_t>(segments * (1 + 2 * 4)));
  double area = 0;
  int bends = 0;
  for (const Triangle& t : face) {
    const Vec3 e1 = t.v[1] - t.v[0], e2 = t.v[2] - t.v[0];
    const double nz = e1.x * e2.y - e1.y * e2.x;  // twice the area projected on the plate's plane, + facing +z
    CHECK(nz > 0);
    area += 0.5 * nz;
    for (const Vec3& p : t.v) {
      const double rho = std::hypot(p.x, p.y);
      CHECK(p.z == Approx(-dish(rho)).margin(1e-12));
      for (double b : {0.075, 0.125, 0.175, 0.225}) bends += std::abs(rho - b) < 1e-12;
    }
  }
  // The regular 60-gon of radius R, covered once.
  CHECK(area == Approx(0.5 * segments * R * R * std::sin(2 * M_PI / segments)).epsilon(1e-12));
  CHECK(bends > 0);
  // A new plate: its plane.
  for (const Triangle& t : plate_face_triangles({}, R, segments))
    for (const Vec3& p : t.v) CHECK(p.z == 0.0);
}
