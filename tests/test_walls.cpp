// Wall geometry of cl/walls.h, the very functions the forces kernel calls.
#include <catch2/catch.hpp>

#include "core/lifters.h"
#include "core/layout.hpp"


namespace {

mc::f64::LifterPolygon square() {
  // Unit square [0,1]², counter-clockwise.
  mc::f64::LifterPolygon p{};
  p.n_vertices = 4;
  p.vertices[0] = {0, 0};
  p.vertices[1] = {1, 0};
  p.vertices[2] = {1, 1};
  p.vertices[3] = {0, 1};
  return p;
}

}  // namespace

TEST_CASE("sphere-prism distance: face, edge and centre inside", "[geometry]") {
  const auto poly = square();
  mc::f64::real2 n{};
  SECTION("face: closest point on an edge of the section") {
    const double d = mc::f64::polygon_signed_distance(&poly, {0.5, 1.3}, &n);
    CHECK(d == Approx(0.3).margin(1e-12));
    CHECK(n.x == Approx(0.0).margin(1e-12));
    CHECK(n.y == Approx(1.0));
  }
  SECTION("edge of the prism: closest point is a corner of the section") {
    const double d = mc::f64::polygon_signed_distance(&poly, {1.3, 1.4}, &n);
    CHECK(d == Approx(0.5));
    CHECK(n.x == Approx(0.6));
    CHECK(n.y == Approx(0.8));
  }
  SECTION("centre inside: deepest-face normal, negative distance") {
    const double d = mc::f64::polygon_signed_distance(&poly, {0.9, 0.5}, &n);
    CHECK(d == Approx(-0.1));
    CHECK(n.x == Approx(1.0));
    CHECK(n.y == Approx(0.0).margin(1e-12));
  }
}

TEST_CASE("lifter profile builds the trapezoid of DESIGN.md", "[geometry]") {
  const double R = 1.0;
  const mc::LifterProfile p{0.1, 0.05, 20.0};
  const auto v = mc::lifter_polygon(R, p, 0.0);  // centred on +x
  REQUIRE(v.size() == 4);
  mc::f64::LifterPolygon poly{};
  poly.n_vertices = 4;
  for (int k = 0; k < 4; ++k) poly.vertices[k] = {v[k].x, v[k].y};
  mc::f64::real2 n{};
  // Top face at radius R − h, facing the axis.
  CHECK(mc::f64::polygon_signed_distance(&poly, {0.5, 0.0}, &n) == Approx(0.4));
  CHECK(n.x == Approx(-1.0));
  // Top width w, and at the shell the width w + 2h·tanθ.
  CHECK(v[3].y - v[0].y == Approx(0.05));
  const double tan_f = std::tan(20.0 * M_PI / 180);
  const double half_at = [&](double r) { return 0.025 + (r - 0.9) * tan_f; }(1.0);
  // A point on the shell just outside the face is outside the bar; just inside, inside.
  CHECK(mc::f64::polygon_signed_distance(&poly, {1.0 - 1e-9, half_at + 1e-4}, &n) > 0);
  CHECK(mc::f64::polygon_signed_distance(&poly, {1.0 - 1e-9, half_at - 1e-4}, &n) < 0);
  // The face normal leans θ from the tangential direction.
  mc::f64::polygon_signed_distance(&poly, {0.95, 0.2}, &n);
  CHECK(std::atan2(-n.x, n.y) == Approx(20.0 * M_PI / 180));
  // Bad profiles are refused.
  CHECK_THROWS(mc::lifter_polygon(R, {1.2, 0.05, 0}, 0.0));
  CHECK_THROWS(mc::lifter_polygon(R, {0.1, -0.05, 0}, 0.0));
}

TEST_CASE("shell overlap and the nearest lifter row", "[geometry]") {
  mc::f64::real3 n{};
  CHECK(mc::f64::shell_overlap({0.0, -0.95, 0.3}, 0.06, 1.0, &n) == Approx(0.01));
  CHECK(n.y == Approx(1.0));
  CHECK(mc::f64::shell_overlap({0.3, 0.4, 0.0}, 0.1, 1.0, &n) == Approx(-0.4));
  const double spacing = 2 * M_PI / 8;
  CHECK(mc::f64::nearest_lifter(0.1, 0.0, spacing, 8) == 0);
  CHECK(mc::f64::nearest_lifter(-0.1, 0.0, spacing, 8) == 0);
  CHECK(mc::f64::nearest_lifter(spacing * 2.6, 0.0, spacing, 8) == 3);
  CHECK(mc::f64::nearest_lifter(-spacing * 1.2, 0.0, spacing, 8) == 7);
}
