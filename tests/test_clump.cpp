// Clump shapes (src/core/clump.h): the union's volume and inertia against
// closed forms (a sphere, spheres apart, the lens two spheres share) and a
// Monte Carlo integral, the principal frame, scaling, the library, and
// shapes refused by name.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "core/clump.h"

using namespace mc;

namespace {

constexpr double kPi = 3.14159265358979323846;

double sphere_volume(double r) { return 4.0 / 3.0 * kPi * r * r * r; }

// Volume and inertia about the centroid (per unit density) of a union by
// Monte Carlo: n points in the bounding box, a fixed seed.
struct Sampled {
  double volume = 0;
  Vec3 centroid;
  Mat3 inertia{};
};
Sampled monte_carlo(const ClumpShape& s, int n, unsigned seed) {
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const ClumpSphere& b : s.spheres) {
    lo = {std::min(lo.x, b.centre.x - b.radius), std::min(lo.y, b.centre.y - b.radius),
          std::min(lo.z, b.centre.z - b.radius)};
    hi = {std::max(hi.x, b.centre.x + b.radius), std::max(hi.y, b.centre.y + b.radius),
          std::max(hi.z, b.centre.z + b.radius)};
  }
  std::mt19937_64 rng(seed);
  auto u = [&] { return (rng() >> 11) * (1.0 / 9007199254740992.0); };
  const Vec3 ext = hi - lo;
  double inside = 0, mx = 0, my = 0, mz = 0, sxx = 0, syy = 0, szz = 0, sxy = 0, sxz = 0, syz = 0;
  for (int k = 0; k < n; ++k) {
    const Vec3 p{lo.x + u() * ext.x, lo.y + u() * ext.y, lo.z + u() * ext.z};
    bool in = false;
    for (const ClumpSphere& b : s.spheres)
      if ((p - b.centre).dot(p - b.centre) <= b.radius * b.radius) in = true;
    if (!in) continue;
    inside += 1, mx += p.x, my += p.y, mz += p.z;
    sxx += p.x * p.x, syy += p.y * p.y, szz += p.z * p.z, sxy += p.x * p.y, sxz += p.x * p.z, syz += p.y * p.z;
  }
  Sampled r;
  const double box = ext.x * ext.y * ext.z, w = box / n;
  r.volume = inside * w;
  r.centroid = {mx / inside, my / inside, mz / inside};
  const Vec3 c = r.centroid;
  const double V = r.volume;
  const double xx = sxx * w - V * c.x * c.x, yy = syy * w - V * c.y * c.y, zz = szz * w - V * c.z * c.z;
  const double xy = sxy * w - V * c.x * c.y, xz = sxz * w - V * c.x * c.z, yz = syz * w - V * c.y * c.z;
  r.inertia = {{{yy + zz, -xy, -xz}, {-xy, xx + zz, -yz}, {-xz, -yz, xx + yy}}};
  return r;
}

}  // namespace

TEST_CASE("a clump of one sphere: its volume and 2/5 m r^2", "[clump]") {
  const double r = 0.03;
  ClumpShape s{"one", {{{0.1, -0.2, 0.05}, r}}};
  const ClumpMassProperties p = clump_mass_properties(s);
  CHECK(p.volume == Approx(sphere_volume(r)).epsilon(2e-5));
  CHECK(p.centroid.x == Approx(0.1).margin(1e-9));
  CHECK(p.centroid.y == Approx(-0.2).margin(1e-9));
  CHECK(p.centroid.z == Approx(0.05).margin(1e-9));
  const double I = 0.4 * sphere_volume(r) * r * r;
  for (int k = 0; k < 3; ++k) CHECK(p.inertia[k][k] == Approx(I).epsilon(2e-5));
  CHECK(p.inertia[0][1] == Approx(0).margin(1e-6 * I));
  CHECK(p.equivalent_diameter() == Approx(2 * r).epsilon(1e-5));
}

TEST_CASE("spheres apart: volumes add and the parallel axis theorem holds", "[clump]") {
  const double r = 1, d = 3;  // centres 3 apart along a diagonal of the x-y plane
  const Vec3 e{d / std::sqrt(2.0) / 2, d / std::sqrt(2.0) / 2, 0};
  ClumpShape s{"two", {{e * -1.0, r}, {e, r}}};
  const ClumpMassProperties p = clump_mass_properties(s, 1024);
  const double V1 = sphere_volume(r);
  CHECK(p.volume == Approx(2 * V1).epsilon(2e-5));
  // About the axis through both centres: 2 · 2/5 V r²; across it, plus
  // 2 V (d/2)².
  CHECK(p.principal.x == Approx(2 * 0.4 * V1 * r * r).epsilon(1e-4));
  CHECK(p.principal.y == Approx(2 * (0.4 * V1 * r * r + V1 * (d / 2) * (d / 2))).epsilon(1e-4));
  CHECK(p.principal.z == Approx(p.principal.y).epsilon(1e-4));
  // The least moment's axis lies along the line of centres.
  const Vec3 a{p.axes[0][0], p.axes[1][0], p.axes[2][0]};
  CHECK(std::fabs(a.dot(e) / e.norm()) == Approx(1).epsilon(1e-6));
}

TEST_CASE("overlapping spheres count once: the lens, and a Monte Carlo integral", "[clump]") {
  // Two unit spheres with centres one radius apart share a lens of volume
  // pi (4r + d)(2r - d)^2 / 12.
  const ClumpShape peanut = library_shape("peanut");
  const ClumpMassProperties p = clump_mass_properties(peanut, 1024);
  const double r = 1, d = 1;
  const double lens = kPi * (4 * r + d) * (2 * r - d) * (2 * r - d) / 12;
  CHECK(p.volume == Approx(2 * sphere_volume(r) - lens).epsilon(2e-5));
  CHECK(p.volume < 2 * sphere_volume(r) * 0.9);  // the sum would count the lens twice

  // Every library shape, and an irregular one, against 4·10⁶ samples: the
  // sampling's relative error is about 1e-3.
  std::vector<ClumpShape> shapes = {peanut, library_shape("flat4"), library_shape("rod5"), library_shape("rock")};
  shapes.push_back({"odd", {{{0, 0, 0}, 1.0}, {{0.9, 0.4, 0.2}, 0.6}, {{-0.3, 0.8, -0.5}, 0.8}}});
  for (const ClumpShape& s : shapes) {
    INFO(s.name);
    const ClumpMassProperties q = clump_mass_properties(s, 512);
    const Sampled mc = monte_carlo(s, 4'000'000, 7);
    CHECK(q.volume == Approx(mc.volume).epsilon(4e-3));
    const double scale = q.inertia[0][0] + q.inertia[1][1] + q.inertia[2][2];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        INFO("I[" << i << "][" << j << "]");
        CHECK(q.inertia[i][j] == Approx(mc.inertia[i][j]).margin(6e-3 * scale));
      }
  }
}

TEST_CASE("a shape normalised: its volume-equivalent diameter, centred, on its principal axes", "[clump]") {
  // A rod turned off the axes and moved: the normalised shape has its least
  // moment along x and no products of inertia.
  ClumpShape rod = library_shape("rod5");
  const double a = 0.6, b = 0.3;
  for (ClumpSphere& s : rod.spheres) {
    const Vec3 c = s.centre;
    const Vec3 turned{c.x * std::cos(a) * std::cos(b), c.x * std::sin(a) * std::cos(b), c.x * std::sin(b)};
    s.centre = turned + Vec3{5, -2, 1};
  }
  const ClumpShape n = normalised_shape(rod, 0.08);
  const ClumpMassProperties p = clump_mass_properties(n);
  CHECK(p.equivalent_diameter() == Approx(0.08).epsilon(1e-5));
  const double L = 0.08;
  CHECK(p.centroid.norm() < 1e-6 * L);
  const double Imax = p.principal.z;
  CHECK(std::fabs(p.inertia[0][1]) < 1e-5 * Imax);
  CHECK(std::fabs(p.inertia[0][2]) < 1e-5 * Imax);
  CHECK(std::fabs(p.inertia[1][2]) < 1e-5 * Imax);
  CHECK(p.inertia[0][0] < p.inertia[1][1]);
  // The rod's spheres lie along x.
  for (const ClumpSphere& s : n.spheres) CHECK(std::hypot(s.centre.y, s.centre.z) < 1e-5 * L);
}

TEST_CASE("a shape in any unit: radii of 1e-200 or 1e200 normalise as radii of 1 do", "[clump]") {
  const ClumpShape one{"pebble", {{{0, 0, 0}, 1.0}, {{0.9, 0, 0}, 0.8}, {{0.4, 0.6, 0}, 0.7}}};
  const ClumpShape ref = normalised_shape(one, 0.05);
  for (double unit : {1e-200, 1e200}) {
    INFO(unit);
    ClumpShape s = one;
    for (ClumpSphere& b : s.spheres) b.centre = b.centre * unit, b.radius *= unit;
    CHECK_NOTHROW(check_shape(s, "charge.shape[0].spheres"));
    const ClumpShape n = normalised_shape(s, 0.05);
    REQUIRE(n.spheres.size() == ref.spheres.size());
    for (std::size_t k = 0; k < n.spheres.size(); ++k) {
      CHECK(n.spheres[k].radius == Approx(ref.spheres[k].radius).epsilon(1e-9));
      CHECK((n.spheres[k].centre - ref.spheres[k].centre).norm() < 1e-9 * 0.05);
    }
  }
}

TEST_CASE("the shape library: each shape valid, a rock as flat as its ellipsoid", "[clump]") {
  for (const std::string& name : library_shape_names()) {
    INFO(name);
    const ClumpShape s = library_shape(name);
    CHECK_NOTHROW(check_shape(s, "shapes." + name));
    CHECK(clump_mass_properties(s).volume > 0);
  }
  CHECK(library_shape("rock").spheres.size() == 12);
  // A rock of 1 : 0.8 : 0.5 has the moments of its ellipsoid's order, and
  // stays inside the ellipsoid (to the sampling of its surface).
  const ClumpShape rock = rock_shape(15, 0.8, 0.5, 3);
  REQUIRE(rock.spheres.size() == 15);
  for (const ClumpSphere& s : rock.spheres) {
    const Vec3 c = s.centre;
    CHECK(c.x * c.x + c.y * c.y / 0.64 + c.z * c.z / 0.25 < 1);
  }
  const ClumpMassProperties p = clump_mass_properties(rock);
  const double ellipsoid = 4.0 / 3.0 * kPi * 1 * 0.8 * 0.5;
  CHECK(p.volume < ellipsoid * 1.01);
  CHECK(p.volume > ellipsoid * 0.6);
  // About the longest axis the least moment; about the shortest the most.
  const Vec3 least{p.axes[0][0], p.axes[1][0], p.axes[2][0]};
  const Vec3 most{p.axes[0][2], p.axes[1][2], p.axes[2][2]};
  CHECK(std::fabs(least.x) > 0.9);
  CHECK(std::fabs(most.z) > 0.9);
  // The same seed, the same rock.
  const ClumpShape again = rock_shape(15, 0.8, 0.5, 3);
  for (std::size_t k = 0; k < rock.spheres.size(); ++k) CHECK(again.spheres[k].radius == rock.spheres[k].radius);
  CHECK_THROWS_WITH(library_shape("cube"), Catch::Contains("the library has sphere, peanut, flat4, rod5, rock"));
  CHECK_THROWS_WITH(rock_shape(1, 0.8, 0.5), Catch::Contains("2 to 64 spheres"));
  CHECK_THROWS_WITH(rock_shape(8, 0.8, 0.9), Catch::Contains("1 >= b >= c > 0.2"));
}

TEST_CASE("a shape that cannot be a body is refused, naming the key and the sphere", "[clump]") {
  const std::string key = "shapes.chip";
  CHECK_THROWS_WITH(check_shape(ClumpShape{"chip", {}}, key), Catch::Contains("shapes.chip: the shape has no spheres"));
  CHECK_THROWS_WITH(check_shape(ClumpShape{"chip", {{{0, 0, 0}, 1}, {{1, 0, 0}, -0.5}}}, key),
                    Catch::Contains("sphere 1's radius must be > 0"));
  CHECK_THROWS_WITH(check_shape(ClumpShape{"chip", {{{0, 0, 0}, 0}}}, key), Catch::Contains("sphere 0's radius"));
  CHECK_THROWS_WITH(check_shape(ClumpShape{"chip", {{{0, std::nan(""), 0}, 1}}}, key),
                    Catch::Contains("sphere 0's centre is not a finite point"));
  CHECK_THROWS_WITH(check_shape(ClumpShape{"chip", {{{0, 0, 0}, 0.01}, {{5, 0, 0}, 0.01}}}, key),
                    Catch::Contains("sphere 1 lies 5 from sphere 0, more than 100 times the largest radius"));
}
