// The normal-cone test of mesh contacts (cl/mesh.h mesh_in_cone): an edge
// or vertex is a contact only where the ball's centre lies in its normal
// cone. A ball pressed deep into a worn corner of fine strips, onto a
// cube's vertex and edge, and over a triangle turned the wrong way round
// feels one contact: k (r − nearest) along the line from the mesh's nearest
// point to its centre, that point found here by brute force over the
// triangles that face the centre.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/wall_mesh.h"
#include "helpers.h"
#include "mesh_scene.h"

using namespace mc;
using namespace mc::test;

namespace {

constexpr double kStiffness = 1e5;  // plate_scene's kn, linear law

// The nearest point to q of the triangles q is in front of.
struct Nearest {
  Vec3 at;
  double dist = 1e300;
  bool on_face = false;
};
Nearest nearest_on(const std::vector<Triangle>& mesh, const Vec3& q) {
  Nearest best;
  for (const Triangle& t : mesh) {
    const Vec3 n = triangle_unit_normal(t);
    const double h = (q - t.v[0]).dot(n);
    if (!(h > 0)) continue;
    const Vec3 c = closest_on_triangle(t, q);
    const double d = (q - c).norm();
    if (d < best.dist) best = {c, d, std::fabs(h - d) < 1e-12};
  }
  return best;
}

// One ball of radius r at rest at q against the mesh, no gravity: one
// contact, k (r − nearest) along the line from the nearest point to q,
// within tol of the force; and two steps run.
void one_contact(const std::vector<Triangle>& mesh, const Vec3& q, double r, Precision precision, double tol) {
  const Nearest near = nearest_on(mesh, q);
  REQUIRE(near.dist < r);
  Scene s = plate_scene(ContactLaw::linear, &mesh);
  s.numerics.gravity = {0, 0, 0};
  s.numerics.precision = precision;
  s.balls[0].radius = r;
  s.balls[0].position = q;
  s.balls[0].velocity = {};
  s.balls[0].omega = {};
  const Vec3 f = force_on(s);
  const Vec3 expect = (q - near.at) * (kStiffness * (r - near.dist) / near.dist);
  CHECK(wall_contacts(s) == 1.0);
  CHECK((f - expect).norm() < tol * expect.norm());
  CHECK_NOTHROW(make_solver(context(), s)->advance(2));
}

}  // namespace

TEST_CASE("a ball pressed deep into a worn corner of fine strips feels its nearest point once", "[mesh][physics]") {
  // A bar's corner worn round as the life study leaves it: the top (z = R,
  // x < 0) turns through 22 strips of about 4° into the flank (x = R,
  // z < 0), R = 150 mm, so the strips are 10–11 mm wide; the strips' angles
  // differ from row to row of 50 mm along y, so the edges between the rows
  // lean. A 125 mm ball (r = 62.5 mm) pressed 1 to 8 mm into it reaches
  // edges and vertices whose directions to its centre lie 20–30° apart
  // (more than a smooth surface's 20°); of them only the nearest has the
  // centre in its normal cone. One contact: k (r − nearest) along the line
  // from the nearest point to the centre. (Each row of strips as its two
  // rows' convex hull: the chords of both in the order of their normals'
  // angles.) Without the cone test, 59 of these checks fail: two to four
  // contacts, and past four walls the run stops, as the whole SAG mill's
  // worn twin did.
  const double R = 0.15;
  const int rows = 6, strips = 22;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-1.5, 1.5);
  std::vector<std::vector<Vec3>> ring(rows + 1);
  for (int j = 0; j <= rows; ++j) {
    const double y = -0.15 + 0.05 * j;
    ring[j].push_back({-0.2, y, R});
    for (int i = 0; i <= strips; ++i) {
      const double phi = (90.0 * i / strips + (i > 0 && i < strips ? jitter(rng) : 0.0)) * M_PI / 180;
      ring[j].push_back({R * std::sin(phi), y, R * std::cos(phi)});
    }
    ring[j].push_back({R, y, -0.2});
  }
  auto normal_angle = [](const Vec3& p, const Vec3& q) { return std::atan2(-(q.z - p.z), q.x - p.x); };
  std::vector<Triangle> round;
  for (int j = 0; j < rows; ++j) {
    const std::vector<Vec3>&A = ring[j], &B = ring[j + 1];
    std::size_t i = 0, m = 0;
    while (i + 1 < A.size() || m + 1 < B.size()) {
      const bool take_a = m + 1 >= B.size() ||
                          (i + 1 < A.size() && normal_angle(A[i], A[i + 1]) <= normal_angle(B[m], B[m + 1]));
      if (take_a) round.push_back({{A[i], A[i + 1], B[m]}}), ++i;
      else round.push_back({{A[i], B[m + 1], B[m]}}), ++m;
    }
  }
  // Facing out of the corner, and convex but for dents where the rows meet
  // (a strip's chord, its sagitta R (1 − cos 2°) = 0.09 mm, against the next
  // row's vertices between its ends): no vertex of a triangle that shares a
  // vertex with t stands in front of t's plane by more than 0.5 mm.
  double dent = 0;
  auto shares = [](const Triangle& t, const Triangle& u) {
    for (const Vec3& a : t.v)
      for (const Vec3& b : u.v)
        if ((a - b).norm() == 0) return true;
    return false;
  };
  for (const Triangle& t : round) {
    const Vec3 n = triangle_unit_normal(t);
    REQUIRE(n.x + n.z > 0.99);
    for (const Triangle& u : round)
      if (shares(t, u))
        for (const Vec3& v : u.v) dent = std::max(dent, (v - t.v[0]).dot(n));
  }
  REQUIRE(dent < 5e-4);
  // 273 places, 1 to 8 mm in, in double at the origin and in float with
  // the corner moved 4 m off the axis (a SAG mill's shell).
  const double r = 0.0625;
  const Vec3 off{3.9, 0.4, 1.7};
  std::vector<Triangle> far = round;
  for (Triangle& t : far)
    for (Vec3& v : t.v) v = v + off;
  int on_edges = 0;
  for (const double delta : {1e-3, 4e-3, 8e-3})
    for (int a = 0; a <= 12; ++a)
      for (const double y : {-0.1004, -0.0501, -0.0262, 0.0, 0.0013, 0.0497, 0.0731}) {
        const double phi = (-4.0 + 8.1 * a) * M_PI / 180;
        // The centre set so that its nearest point on the mesh is delta in.
        Vec3 q{(R + r) * std::sin(phi), y, (R + r) * std::cos(phi)};
        Nearest near = nearest_on(round, q);
        q = near.at + (q - near.at) * ((r - delta) / near.dist);
        near = nearest_on(round, q);
        REQUIRE(near.dist == Approx(r - delta).epsilon(1e-6));
        on_edges += !near.on_face;
        INFO("delta " << delta << " angle " << phi * 180 / M_PI << " y " << y);
        one_contact(round, q, r, Precision::double_, 1e-6);
        if (a % 3 == 0) one_contact(far, q + off, r, Precision::single, 3e-3);
      }
  CHECK(on_edges > 80);  // of 273, the nearest point on an edge or a vertex (96)
}

TEST_CASE("a ball on a cube's vertex, edge or face feels one contact, along the line from the nearest point",
          "[mesh][physics]") {
  // A closed 0.2 m cube, normals out; a 62.5 mm ball 3 mm into it over a
  // vertex (the contact along the diagonal), over an edge, and over the top
  // face next to an edge, where the top's other triangle lists its diagonal
  // too. A guard that the cone test keeps what Hu's rule alone already got
  // right: one contact on a convex vertex, edge and face.
  const double h = 0.1, r = 0.0625, delta = 3e-3;
  const Vec3 p[8] = {{-h, -h, -h}, {h, -h, -h}, {h, h, -h}, {-h, h, -h},
                     {-h, -h, h},  {h, -h, h},  {h, h, h},  {-h, h, h}};
  const int quads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  std::vector<Triangle> cube;
  for (const auto& f : quads) {
    cube.push_back({{p[f[0]], p[f[1]], p[f[2]]}});
    cube.push_back({{p[f[0]], p[f[2]], p[f[3]]}});
  }
  for (const Triangle& t : cube) {
    const Vec3 c = (t.v[0] + t.v[1] + t.v[2]) * (1.0 / 3);
    REQUIRE(triangle_unit_normal(t).dot(c) > 0);  // faces out
  }
  const double d = r - delta;
  const Vec3 at_vertex = p[6] + Vec3{1, 1, 1} * (d / std::sqrt(3.0));
  const Vec3 at_edge = Vec3{h, 0.031, h} + Vec3{1, 0, 1} * (d / std::sqrt(2.0));
  const Vec3 at_face = Vec3{h - 0.004, -0.017, h + d};
  for (const Vec3& q : {at_vertex, at_edge, at_face}) {
    REQUIRE(nearest_on(cube, q).dist == Approx(d).epsilon(1e-9));
    INFO("centre " << q.x << ", " << q.y << ", " << q.z);
    one_contact(cube, q, r, Precision::double_, 1e-9);
    one_contact(cube, q, r, Precision::single, 1e-4);
  }
}

TEST_CASE("a triangle turned the wrong way round leaves no hole: its neighbours' edges hold the ball",
          "[mesh][physics]") {
  // A plate of 10 mm triangles, one of them turned over (normal −z: a scan
  // or a CAD export with a flipped facet). A ball over it, 1.5 or 7.5 mm
  // into the plate's plane, is behind that triangle, which gives no
  // contact; the rim's edges must: the triangle behind the ball vetoes
  // none of them. One contact, k (r − nearest rim point).
  std::vector<Triangle> plate = irregular_plate(0.1, 20, 0.3, 7);
  const Vec3 under{0.013, -0.021, 0};
  std::size_t flipped = plate.size();
  for (std::size_t t = 0; t < plate.size() && flipped == plate.size(); ++t)
    if ((closest_on_triangle(plate[t], under) - under).norm() < 1e-12) flipped = t;
  REQUIRE(flipped < plate.size());
  std::swap(plate[flipped].v[1], plate[flipped].v[2]);
  REQUIRE(triangle_unit_normal(plate[flipped]).z < -0.999);
  const Triangle& hole = plate[flipped];
  const Vec3 centroid = (hole.v[0] + hole.v[1] + hole.v[2]) * (1.0 / 3);
  const double r = 0.0625;
  for (const double delta : {1.5e-3, 7.5e-3}) {
    const Vec3 q{centroid.x, centroid.y, r - delta};
    const Nearest near = nearest_on(plate, q);
    REQUIRE(!near.on_face);        // the nearest point is on the rim
    REQUIRE(near.dist > r - delta);  // farther than the plane, within reach
    INFO("delta " << delta);
    one_contact(plate, q, r, Precision::double_, 1e-6);
  }
}
