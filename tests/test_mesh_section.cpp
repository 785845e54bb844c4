// Mesh lifter bars measured across (life/mesh_section.h) against the
// parametric bar they were cut from (core/lifters.h measure_profile of its
// own outline), the finer bar mesh of core/lifters.h lifter_triangles,
// and the booked wear spread over a mesh (life/mesh_wear.h smooth_wear).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/lifters.h"
#include "core/wall_mesh.h"
#include "life/mesh_section.h"
#include "life/mesh_wear.h"

using namespace mc;

namespace {

constexpr double R = 0.45;

// Bars of profile p in `rows` rows from angle `first`, cut at the shell,
// as triangles at most max_edge across (0: two per face).
std::vector<Triangle> bars(const LifterProfile& p, int rows, double first, double length, double max_edge) {
  return lifter_triangles(bars_on_shell(lifter_rows(R, rows, {p}, first), R), length, max_edge);
}

double tri_area(const Triangle& t) {
  const Vec3 a = t.v[1] - t.v[0], b = t.v[2] - t.v[0];
  return 0.5 * Vec3{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}.norm();
}

Vec3 unit_normal(const Triangle& t) { return triangle_unit_normal(t); }

}  // namespace

TEST_CASE("a mesh bar cut across measures as the parametric bar it was made from", "[life][mesh_section]") {
  LifterProfile trapezoid;
  trapezoid.height = 0.025, trapezoid.top_width = 0.03, trapezoid.face_angle_deg = 20;
  LifterProfile leaning;  // a worn bar: the leading face laid back to 35°, the trailing at 10°
  const double h = 0.06;
  leaning.points = {{0.05 + h * std::tan(35 * M_PI / 180), 0}, {0.05, h}, {-0.02, h}, {-0.02 - h * std::tan(10 * M_PI / 180), 0}};
  for (const LifterProfile* p : {&trapezoid, &leaning})
    for (double max_edge : {0.0, 0.004}) {
      const std::vector<Triangle> t = bars(*p, 8, 0.3, 0.2, max_edge);
      const auto parts = life::connected_parts(t);
      REQUIRE(parts.size() == 8);
      const ProfileMeasures want = measure_profile(profile_outline(*p));
      for (std::size_t k = 0; k < parts.size(); ++k) {
        const double angle = life::part_angle(t, parts[k]);
        // The row's centre (a symmetric bar) or near it (the leaning one's
        // vertices lie to its leading side).
        if (p == &trapezoid) CHECK(std::remainder(angle - (0.3 + 2 * M_PI * k / 8), 2 * M_PI) == Approx(0).margin(1e-12));
        const double centre = 0.3 + 2 * M_PI * k / 8;
        for (double z : {0.013, 0.1, 0.187}) {
          const std::vector<Vec2> o = life::bar_section(t, parts[k], z, centre, R);
          REQUIRE(o.size() >= 4);
          CHECK(o.front().x > 0);  // from the leading foot
          CHECK(o.back().x < 0);   // to the trailing foot
          const ProfileMeasures m = measure_profile(o);
          CHECK(m.height == Approx(want.height).margin(1e-9));
          CHECK(m.leading_angle_deg == Approx(want.leading_angle_deg).margin(1e-6));
          CHECK(m.trailing_angle_deg == Approx(want.trailing_angle_deg).margin(1e-6));
        }
      }
      // measure_bars in the frames of the rows' centres: every bar, the same figures.
      std::vector<double> centres;
      for (int k = 0; k < 8; ++k) centres.push_back(0.3 + 2 * M_PI * k / 8);
      const life::BarMeasures b = life::measure_bars(t, centres, 0.1, R);
      REQUIRE(b.height.size() == 8);
      for (std::size_t k = 0; k < 8; ++k) {
        CHECK(b.height[k] == Approx(want.height).margin(1e-9));
        CHECK(b.leading_deg[k] == Approx(want.leading_angle_deg).margin(1e-6));
      }
      // A plane beyond the bars' ends cuts nothing.
      CHECK(life::bar_section(t, parts[0], 0.25, 0.3, R).empty());
    }
  // Expected values from the profiles' own geometry (not measure_profile):
  // the trapezoid's 25 mm and 20°, the leaning bar's 35° and 10°.
  const ProfileMeasures lean = measure_profile(profile_outline(leaning));
  CHECK(lean.leading_angle_deg == Approx(35).margin(1e-9));
  CHECK(lean.trailing_angle_deg == Approx(10).margin(1e-9));
  CHECK(measure_profile(profile_outline(trapezoid)).leading_angle_deg == Approx(20).margin(1e-9));
}

TEST_CASE("a finer bar mesh encloses the same bar with faces cut to the size asked", "[life][mesh_section]") {
  LifterProfile p;
  p.height = 0.025, p.top_width = 0.03, p.face_angle_deg = 20;
  const std::vector<Triangle> coarse = bars(p, 12, 0, 0.15, 0), fine = bars(p, 12, 0, 0.15, 0.005);
  CHECK(fine.size() > 20 * coarse.size());
  // The same solid: each bar's cross-section (the polygon's area by the
  // shoelace) times the length, and the closed meshes' volumes alike.
  double area = 0;
  const auto poly = bars_on_shell(lifter_rows(R, 12, {p}, 0), R);
  for (const auto& b : poly)
    for (std::size_t k = 0; k < b.size(); ++k) {
      const Vec2 a = b[k], c = b[(k + 1) % b.size()];
      area += 0.5 * (a.x * c.y - c.x * a.y);
    }
  CHECK(closed_mesh_volume(coarse) == Approx(area * 0.15).epsilon(1e-12));
  CHECK(closed_mesh_volume(fine) == Approx(area * 0.15).epsilon(1e-12));
  // Every side triangle (normal across the axis) at most 5 mm along its
  // edges across and along the mill (its diagonal up to √2 of that).
  int sides = 0;
  for (const Triangle& t : fine) {
    if (std::fabs(unit_normal(t).z) > 0.5) continue;
    ++sides;
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = t.v[(k + 1) % 3] - t.v[k];
      CHECK(e.norm() <= std::sqrt(2.0) * 0.005 + 1e-12);
    }
  }
  CHECK(sides > 0);
}

TEST_CASE("the booked wear spread over a mesh keeps its volume and its creases", "[life][mesh_section]") {
  LifterProfile p;
  p.height = 0.025, p.top_width = 0.03, p.face_angle_deg = 20;
  const std::vector<Triangle> t = bars(p, 4, 0, 0.15, 0.003);
  const std::vector<std::vector<int>> parts = life::connected_parts(t);
  REQUIRE(parts.size() == 4);
  // Bar 0's top (normal pointing in, towards the axis, at angle 0: -x).
  auto on_top = [&](int i) { return unit_normal(t[i]).x < -0.99; };
  std::vector<double> spike(t.size(), 0.0);
  int top_count = 0, spiked = -1;
  for (int i : parts[0])
    if (on_top(i)) {
      ++top_count;
      const Vec3 c = (t[i].v[0] + t[i].v[1] + t[i].v[2]) * (1.0 / 3);
      if (spiked < 0 && std::fabs(c.z - 0.075) < 0.003 && std::fabs(c.y) < 0.003) spiked = i;
    }
  REQUIRE(top_count > 50);
  REQUIRE(spiked >= 0);
  spike[spiked] = 1e-6;
  auto sum = [](const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return s;
  };
  // Uneven wear on two bars: each bar's and each face's volume kept, none
  // carried over a crease (the faces at 70° to the top) or to another bar.
  {
    std::vector<double> uneven(t.size(), 0.0);
    std::uint32_t x = 12345;
    auto face_of = [&](int i) {  // 0 top, 1 and 2 the sides, 3 the base, 4 the ends
      const Vec3 n = unit_normal(t[i]);
      if (std::fabs(n.z) > 0.5) return 4;
      const Vec3 c = (t[i].v[0] + t[i].v[1] + t[i].v[2]) * (1.0 / 3);
      const double r = std::hypot(c.x, c.y), nr = (n.x * c.x + n.y * c.y) / r;
      return nr < -0.99 ? 0 : nr > 0.99 ? 3 : (n.y * c.x - n.x * c.y) / r > 0 ? 1 : 2;
    };
    for (int bar : {0, 2})
      for (int i : parts[bar]) {
        x = x * 1664525u + 1013904223u;  // a fixed pseudo-random depth, 0 to 2 mm
        uneven[i] = face_of(i) < 3 ? tri_area(t[i]) * 2e-3 * (x >> 8) / double(1u << 24) : 0.0;
      }
    const std::vector<double> e = life::smooth_wear(t, uneven, 0.005, 0.02);
    REQUIRE(e.size() == t.size());
    for (std::size_t bar = 0; bar < parts.size(); ++bar)
      for (int face = 0; face < 5; ++face) {
        double before = 0, after = 0;
        for (int i : parts[bar])
          if (face_of(i) == face) before += uneven[i], after += e[i];
        INFO("bar " << bar << ", face " << face);
        CHECK(after == Approx(before).epsilon(1e-12).margin(1e-18));
      }
    // And it is smoother: the spread of the depths on bar 0's top falls.
    double m0 = 0, m1 = 0, s0 = 0, s1 = 0;
    int n = 0;
    for (int i : parts[0])
      if (face_of(i) == 0) m0 += uneven[i] / tri_area(t[i]), m1 += e[i] / tri_area(t[i]), ++n;
    m0 /= n, m1 /= n;
    for (int i : parts[0])
      if (face_of(i) == 0)
        s0 += std::pow(uneven[i] / tri_area(t[i]) - m0, 2), s1 += std::pow(e[i] / tri_area(t[i]) - m1, 2);
    CHECK(std::sqrt(s1) < 0.3 * std::sqrt(s0));
  }
  // One triangle's wear spread as a Gaussian: 5 mm across, 20 mm along.
  const std::vector<double> s = life::smooth_wear(t, spike, 0.005, 0.02);
  CHECK(sum(s) == Approx(1e-6).epsilon(1e-12));
  CHECK(s[spiked] < 0.5e-6);  // spread: the triangle keeps a part of it
  const Vec3 c0 = (t[spiked].v[0] + t[spiked].v[1] + t[spiked].v[2]) * (1.0 / 3);
  double far_along = 0, far_across = 0, near = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (s[i] == 0) continue;
    CHECK(on_top(static_cast<int>(i)));
    const Vec3 c = (t[i].v[0] + t[i].v[1] + t[i].v[2]) * (1.0 / 3);
    const double depth = s[i] / tri_area(t[i]);
    if (std::fabs(c.z - c0.z) < 0.002 && std::fabs(c.y - c0.y) < 0.002) near = std::max(near, depth);
    if (std::fabs(c.z - c0.z) > 0.03 && std::fabs(c.y - c0.y) < 0.002) far_along = std::max(far_along, depth);
    if (std::fabs(c.y - c0.y) > 0.012 && std::fabs(c.z - c0.z) < 0.002) far_across = std::max(far_across, depth);
  }
  // Gaussian falls: at 30 mm along (1.5 sd) to exp(-1.125) = 0.32 of the
  // centre at most; at 12 mm across (2.4 sd) to exp(-2.88) = 0.056.
  CHECK(near > 0);
  CHECK(far_along < 0.4 * near);
  CHECK(far_along > 0.1 * near);
  CHECK(far_across < 0.1 * near);
  // across <= 0: unchanged.
  CHECK(life::smooth_wear(t, spike, 0, 0) == spike);
}
