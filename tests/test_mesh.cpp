// Mesh walls (cl/mesh.h, core/wall_mesh.h): a ball on a plate of irregular
// triangles moves as on the analytic end plate; a ball on a shared edge or
// vertex of coplanar triangles feels one contact with the plate's force, in
// a concave corner one per face; the topology and the grid; the lab mill
// with its lifters as an STL against the parametric lifters.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <tuple>

#include "checks.h"
#include "core/drum.h"
#include "core/lifters.h"
#include "core/liner.h"
#include "core/mill_case.h"
#include "core/wall_mesh.h"
#include "helpers.h"
#include "mesh_scene.h"
#include "io/case_file.h"
#include "io/stl.h"
#include "sim/energy_report.h"
#include "core/layout.hpp"
#include "sim/reference.h"
#include "sim/tables.h"
#include "text_file.h"

using namespace mc;
using namespace mc::test;
namespace fs = std::filesystem;

TEST_CASE("closest point on a triangle: face, edges and vertices", "[mesh][geometry]") {
  using namespace mc::f64;
  const real3 a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  int region = -1;
  real3 q = triangle_closest(real3{0.2, 0.3, 0.5}, a, b, c, &region);
  CHECK(region == MC_MESH_FACE);
  CHECK(q.x == Approx(0.2));
  CHECK(q.y == Approx(0.3));
  q = triangle_closest(real3{0.5, -0.4, 0.1}, a, b, c, &region);
  CHECK(region == MC_MESH_EDGE0);  // ab
  CHECK(q.x == Approx(0.5));
  CHECK(q.y == Approx(0.0).margin(1e-15));
  q = triangle_closest(real3{0.8, 0.8, 0}, a, b, c, &region);
  CHECK(region == MC_MESH_EDGE0 + 1);  // bc
  CHECK(q.x == Approx(0.5));
  q = triangle_closest(real3{-0.3, 0.4, 0}, a, b, c, &region);
  CHECK(region == MC_MESH_EDGE0 + 2);  // ca
  triangle_closest(real3{-1, -1, 0}, a, b, c, &region);
  CHECK(region == MC_MESH_VERTEX0);
  triangle_closest(real3{2, -0.1, 0}, a, b, c, &region);
  CHECK(region == MC_MESH_VERTEX0 + 1);
  triangle_closest(real3{-0.1, 2, 0}, a, b, c, &region);
  CHECK(region == MC_MESH_VERTEX0 + 2);
}

TEST_CASE("mesh topology: shared edges and vertices, smooth patches", "[mesh]") {
  Scene s = bare_scene(kSteel, kSteel, Interaction{}, ContactLaw::linear);
  // Two coplanar triangles (one patch) and a third folded up by 90° along
  // the far edge x–xy (its own patch); one vertex written 1e-9 m off, as
  // CAD tools may, is still shared.
  const Vec3 o{0, 0, 0}, x{1, 0, 0}, y{0, 1, 0}, xy{1, 1, 0}, upx{1, 0, 1}, xy_off{1, 1 + 1e-9, 0};
  std::vector<Triangle> t = {{{o, x, xy}}, {{o, xy, y}}, {{x, upx, xy_off}}};
  const MeshTopology topo = mesh_topology({mesh_of(t, s)});
  CHECK(topo.n_triangles == 3);
  CHECK(topo.n_vertices == 5);
  CHECK(topo.n_edges == 3 + 2 + 2);  // the diagonal o–xy and the fold x–xy are shared
  CHECK(topo.edges[0][2] == topo.edges[1][0]);  // ca of the first = ab of the second
  CHECK(topo.patch[0] == topo.patch[1]);
  CHECK(topo.patch[2] != topo.patch[0]);
  CHECK(topo.n_patches == 2);
  // Device order: the turning meshes first.
  WallMesh still = mesh_of(t, s);
  still.turning = false;
  const auto order = mesh_device_order({still, mesh_of(t, s)});
  REQUIRE(order.size() == 6);
  CHECK(order[0].mesh == 1);
  CHECK(order[3].mesh == 0);
}

TEST_CASE("the mesh grid lists every triangle a ball in a cell can touch", "[mesh]") {
  // Random small triangles; for random points, every triangle within the
  // reach of the point must be in the point's cell (host binning; the
  // device's is checked against it through the forces below).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Triangle> tris;
  for (int k = 0; k < 300; ++k) {
    const Vec3 c{u(rng), u(rng), u(rng)};
    tris.push_back({{c, c + Vec3{0.05 * u(rng), 0.08, 0.01}, c + Vec3{0.07, 0.03 * u(rng), -0.02}}});
  }
  const double reach = 0.03;
  const MeshGridSpec g = mesh_grid_spec(tris, reach);
  std::vector<int> starts, cells;
  mesh_bin_host(g, tris, 0, starts, cells);
  int missing = 0, tested = 0;
  for (int q = 0; q < 2000; ++q) {
    const Vec3 p{u(rng), u(rng), u(rng)};
    const int cx = static_cast<int>(std::floor((p.x - g.origin.x) / g.cell));
    const int cy = static_cast<int>(std::floor((p.y - g.origin.y) / g.cell));
    const int cz = static_cast<int>(std::floor((p.z - g.origin.z) / g.cell));
    if (cx < 0 || cy < 0 || cz < 0 || cx >= g.nx || cy >= g.ny || cz >= g.nz) continue;
    const int cell = (cz * g.ny + cy) * g.nx + cx;
    for (int k = 0; k < static_cast<int>(tris.size()); ++k) {
      if ((closest_on_triangle(tris[k], p) - p).norm() >= reach) continue;
      ++tested;
      bool found = false;
      for (int e = starts[cell]; e < starts[cell + 1]; ++e) found = found || cells[e] == k;
      missing += !found;
    }
  }
  CHECK(tested > 50);
  CHECK(missing == 0);
}

TEST_CASE("a ball on a plate of irregular triangles bounces, slides and rolls as on the analytic end plate",
          "[mesh][physics]") {
  const std::vector<Triangle> plate = irregular_plate(0.6, 24, 0.3, 11);
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    const char* name = law == ContactLaw::linear ? "linear" : "hertz";
    auto a = make_solver(context(), plate_scene(law, nullptr));
    auto m = make_solver(context(), plate_scene(law, &plate));
    const long steps = static_cast<long>(std::lround(0.4 / a->dt()));
    const long chunk = steps / 200;
    double worst = 0, vz_a = -1e9, vz_m = -1e9;
    for (long k = 0; k < steps; k += chunk) {
      a->advance(chunk);
      m->advance(chunk);
      const BallState ba = a->balls()[0], bm = m->balls()[0];
      worst = std::max(worst, (ba.position - bm.position).norm());
      vz_a = std::max(vz_a, ba.velocity.z);  // the rebounds' fastest upward speed
      vz_m = std::max(vz_m, bm.velocity.z);
    }
    const BallState end = a->balls()[0];
    std::printf("irregular plate (%zu triangles), %s: path differs by at most %.3g m over %.2f m; rebound %.6f vs "
                "%.6f m/s (%.2g); end speed %.4f m/s, spin x r / v %.4f\n",
                plate.size(), name, worst, end.position.x - 0.013, vz_m, vz_a, rel_err(vz_m, vz_a),
                std::hypot(end.velocity.x, end.velocity.y),
                std::hypot(end.omega.x, end.omega.y) * 0.02 / std::hypot(end.velocity.x, end.velocity.y));
    INFO(name);
    CHECK(vz_a > 0.1);                         // it bounced
    CHECK(rel_err(vz_m, vz_a) < 1e-3);         // rebound within 0.1 %
    CHECK(worst < 1e-6);                       // path within a micrometre
    CHECK(end.position.x - 0.013 > 0.15);      // it went across many triangles
  }
}

TEST_CASE("a ball on a shared edge or vertex feels one contact with the plate's force, in a corner one per face",
          "[mesh][physics]") {
  // A fan of six irregular triangles about the origin, in z = 0, facing +z.
  std::vector<Triangle> fan;
  const double angles[] = {0, 50, 110, 170, 235, 300, 360};
  for (int k = 0; k < 6; ++k) {
    const double a0 = angles[k] * kPi / 180, a1 = angles[k + 1] * kPi / 180;
    const double r0 = 0.5 + 0.1 * k, r1 = 0.5 + 0.1 * ((k + 1) % 6);
    fan.push_back({{Vec3{0, 0, 0}, Vec3{r0 * std::cos(a0), r0 * std::sin(a0), 0}, Vec3{r1 * std::cos(a1), r1 * std::sin(a1), 0}}});
  }
  const double r = 0.02, delta = 2e-4;
  auto scene_at = [&](Vec3 p, const std::vector<Triangle>* mesh) {
    Scene s = plate_scene(ContactLaw::linear, mesh);
    s.numerics.gravity = {0, 0, 0};
    s.balls[0].position = p;
    s.balls[0].velocity = {};
    s.balls[0].omega = {};
    return s;
  };
  struct Where {
    const char* what;
    Vec3 p;
  } where[] = {{"vertex", {0, 0, r - delta}}, {"edge", {0.3, 0, r - delta}}, {"face", {0.2, 0.1, r - delta}}};
  for (const Where& w : where) {
    const Vec3 fm = force_on(scene_at(w.p, &fan)), fa = force_on(scene_at(w.p, nullptr));
    std::printf("ball on a shared %s: %.0f contact(s), force %.9g N (plate %.9g N, kn delta %.9g N)\n", w.what,
                wall_contacts(scene_at(w.p, &fan)), fm.z, fa.z, 1e5 * delta);
    INFO(w.what);
    CHECK(wall_contacts(scene_at(w.p, &fan)) == 1.0);
    CHECK(fm.z == Approx(fa.z).epsilon(1e-12));
    CHECK(fm.z == Approx(1e5 * delta).epsilon(1e-9));
    CHECK(std::fabs(fm.x) + std::fabs(fm.y) < 1e-9 * fm.z);
  }
  // A convex ridge: the ball beyond both faces touches the edge once, along
  // the line from the edge to its centre.
  const Vec3 a{-1, 0, 0}, b{1, 0, 0};
  std::vector<Triangle> roof = {{{a, b, Vec3{1, 1, -1}}}, {{b, a, Vec3{-1, -1, -1}}}};
  {
    const Vec3 p{0.1, 0.6 * (r - delta), 0.8 * (r - delta)};
    Scene s = scene_at(p, &roof);
    const Vec3 f = force_on(s);
    CHECK(wall_contacts(s) == 1.0);
    CHECK(f.norm() == Approx(1e5 * delta).epsilon(1e-9));
    CHECK(f.y / f.norm() == Approx(0.6).epsilon(1e-9));
    CHECK(f.z / f.norm() == Approx(0.8).epsilon(1e-9));
  }
  // A concave corner: a floor (z = 0) and a wall (x = 0) of two triangles
  // each; the ball pressed into both feels each face.
  const double d1 = 1e-4, d2 = 3e-4;
  std::vector<Triangle> corner = {
      {{Vec3{0, -1, 0}, Vec3{1, -1, 0}, Vec3{1, 1, 0}}}, {{Vec3{0, -1, 0}, Vec3{1, 1, 0}, Vec3{0, 1, 0}}},
      {{Vec3{0, -1, 0}, Vec3{0, 1, 1}, Vec3{0, -1, 1}}}, {{Vec3{0, -1, 0}, Vec3{0, 1, 0}, Vec3{0, 1, 1}}}};
  {
    Scene s = scene_at({r - d1, 0.1, r - d2}, &corner);
    const Vec3 f = force_on(s);
    CHECK(wall_contacts(s) == 2.0);
    CHECK(f.x == Approx(1e5 * d1).epsilon(1e-9));
    CHECK(f.z == Approx(1e5 * d2).epsilon(1e-9));
  }
}

TEST_CASE("a ball pressed deep into a fine mesh feels its plane, not the triangles round it", "[mesh][physics]") {
  // A plate of 5 mm irregular triangles and a 20 mm ball pressed up to 6 mm
  // into it: the contact disc (up to 29 mm across) covers the edges and
  // vertices of the triangles round the one under the centre, whose normals
  // lean away by up to 45°. They lie in the face's plane: one contact, k δ
  // along +z; and a few steps run without the list of candidates
  // overflowing (29 of them, in the order the grid holds them, before the
  // face strikes them), in double and in float.
  const std::vector<Triangle> plate = irregular_plate(0.1, 40, 0.3, 11);
  const double r = 0.02;
  auto pressed = [&](const std::vector<Triangle>& mesh, Vec3 at, double delta) {
    Scene s = plate_scene(ContactLaw::linear, &mesh);
    s.numerics.gravity = {0, 0, 0};
    s.balls[0].position = {at.x, at.y, r - delta};
    s.balls[0].velocity = {};
    s.balls[0].omega = {};
    return s;
  };
  const double depths[] = {2e-4, 3e-3, 6e-3};
  for (const double delta : depths) {
    for (const Vec3 at : {Vec3{0.0013, -0.0021, 0}, Vec3{0.0251, 0.0377, 0}, Vec3{-0.04, 0.0125, 0}}) {
      Scene s = pressed(plate, at, delta);
      const Vec3 f = force_on(s);
      INFO("depth " << delta << " at " << at.x << ", " << at.y);
      CHECK(wall_contacts(s) == 1.0);
      CHECK(f.z == Approx(1e5 * delta).epsilon(1e-9));
      CHECK(std::fabs(f.x) + std::fabs(f.y) < 1e-9 * f.z);
      CHECK_NOTHROW(make_solver(context(), s)->advance(3));
      s.numerics.precision = Precision::single;
      CHECK_NOTHROW(make_solver(context(), s)->advance(3));
    }
  }
  // Not flat: the plate bent into a trough of 5 m radius (a shell seen from
  // inside), or its vertices scattered by up to 0.1 mm (a scan, a worn
  // face). The ball still feels one contact, the nearest face's overlap.
  std::vector<Triangle> trough = plate, rough = plate;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1e-4, 1e-4);
  std::map<std::tuple<double, double>, double> lift;  // one lift per shared vertex
  for (std::size_t t = 0; t < plate.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3 v = plate[t].v[k];
      trough[t].v[k].z = 5.0 - std::sqrt(25.0 - v.x * v.x);
      auto [it, fresh] = lift.try_emplace({v.x, v.y}, 0.0);
      if (fresh) it->second = u(rng);
      rough[t].v[k].z = it->second;
    }
  for (int run = 0; run < 4; ++run) {
    const std::vector<Triangle>* mesh = run % 2 ? &rough : &trough;
    const double delta = run < 2 ? 6e-3 : 2e-4;
    Scene s = pressed(*mesh, {0.0013, -0.0021, 0}, delta);
    const Vec3 f = force_on(s);
    // The nearest point of the surface to the centre (the face under it,
    // or on the rough plate at 0.2 mm a vertex that stands higher).
    const Vec3 q = s.balls[0].position;
    double nearest = 1;
    for (const Triangle& t : *mesh) nearest = std::min(nearest, (q - closest_on_triangle(t, q)).norm());
    REQUIRE(nearest < r);
    INFO((mesh == &trough ? "trough" : "rough") << " " << delta);
    CHECK(wall_contacts(s) == 1.0);
    CHECK(f.norm() == Approx(1e5 * (r - nearest)).epsilon(1e-9));
    CHECK_NOTHROW(make_solver(context(), s)->advance(3));
  }
  // A low step (a strip 2 mm above the plate, of its own surface; two
  // triangles whose diagonal stays out of the ball's reach): a ball on the
  // plate, 6 mm in, that reaches the strip's edge feels both, the edge
  // along the line from it to the centre. The edge lies 2 mm above the
  // plate, within the ball's overlap, but is another surface's. (A face
  // cut finely along such an edge meets the ball there with its segments'
  // vertices too: a limit of the rule, docs/physics.md.)
  std::vector<Triangle> with_bar = plate;
  const double x0 = 0.01, x1 = 0.1, top = 0.002, y0 = -0.1, y1 = 0.1;
  with_bar.push_back({{Vec3{x0, y0, top}, Vec3{x1, y0, top}, Vec3{x0, y1, top}}});
  with_bar.push_back({{Vec3{x1, y0, top}, Vec3{x1, y1, top}, Vec3{x0, y1, top}}});
  for (std::size_t t = plate.size(); t < with_bar.size(); ++t) REQUIRE(triangle_unit_normal(with_bar[t]).z > 0.999);
  {
    const double delta = 6e-3, dx = 0.004;
    Scene s = pressed(with_bar, {x0 - dx, 0.0012, 0}, delta);
    const Vec3 f = force_on(s);
    const double ez = r - delta - top, d = std::hypot(dx, ez);
    CHECK(wall_contacts(s) == 2.0);
    CHECK(f.x == Approx(-1e5 * (r - d) * dx / d).epsilon(1e-9));
    CHECK(f.z == Approx(1e5 * delta + 1e5 * (r - d) * ez / d).epsilon(1e-9));
  }
  // A bar's top of irregular 5 mm triangles (z = 0, x < 0) and its flank
  // (x = 0, falling away), the flank's triangles listed first, so that the
  // crease's edges and vertices take the flank's surface: a ball pressed
  // 5 mm into the top near the crease feels the top alone, wherever it is.
  {
    std::vector<Triangle> bar;
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 10; ++i) {
        const double y0 = -0.025 + 0.005 * j, y1 = y0 + 0.005, z1 = -0.005 * i, z0 = z1 - 0.005;
        bar.push_back({{Vec3{0, y0, z0}, Vec3{0, y1, z1}, Vec3{0, y0, z1}}});
        bar.push_back({{Vec3{0, y0, z0}, Vec3{0, y1, z0}, Vec3{0, y1, z1}}});
      }
    const std::size_t flank = bar.size();
    for (Triangle t : irregular_plate(0.025, 10, 0.3, 23)) {
      for (Vec3& v : t.v) v.x -= 0.025;
      bar.push_back(t);
    }
    for (std::size_t t = 0; t < bar.size(); ++t)
      REQUIRE((t < flank ? triangle_unit_normal(bar[t]).x : triangle_unit_normal(bar[t]).z) > 0.999);
    int placed = 0;
    for (const double x : {-0.0005, -0.0015, -0.003, -0.0045})
      for (const double y : {-0.0101, -0.0049, 0.0003, 0.0052, 0.0098}) {
        Scene s = pressed(bar, {x, y, 0}, 5e-3);
        const Vec3 f = force_on(s);
        INFO("top pressed at " << x << ", " << y);
        CHECK(wall_contacts(s) == 1.0);
        CHECK(f.z == Approx(1e5 * 5e-3).epsilon(1e-9));
        CHECK(std::fabs(f.x) + std::fabs(f.y) < 1e-9 * f.z);
        ++placed;
      }
    CHECK(placed == 20);
  }
  // A concave corner of 5 mm triangles, floor z = 0 and wall x = 0, the
  // ball pressed 3 mm into the floor and 4 mm into the wall: the wall's
  // faces stand in front of the floor's plane, so each face keeps its
  // contact, k δ each, and the crease's edges and vertices add nothing.
  std::vector<Triangle> corner;
  for (int j = 0; j < 20; ++j) {
    const double y0 = -0.05 + 0.005 * j, y1 = y0 + 0.005;
    for (int i = 0; i < 10; ++i) {
      const double a0 = 0.005 * i, a1 = a0 + 0.005;
      corner.push_back({{Vec3{a0, y0, 0}, Vec3{a1, y0, 0}, Vec3{a1, y1, 0}}});
      corner.push_back({{Vec3{a0, y0, 0}, Vec3{a1, y1, 0}, Vec3{a0, y1, 0}}});
      corner.push_back({{Vec3{0, y0, a0}, Vec3{0, y1, a1}, Vec3{0, y0, a1}}});
      corner.push_back({{Vec3{0, y0, a0}, Vec3{0, y1, a0}, Vec3{0, y1, a1}}});
    }
  }
  for (const Triangle& t : corner) {
    const Vec3 n = triangle_unit_normal(t);
    REQUIRE(std::max(n.x, n.z) > 0.999);
  }
  // Listed as built, and listed so that the floor's edges fill the list of
  // candidates before the wall's face comes and the floor's own face comes
  // last (the floor farthest from the ball first): that list is gathered
  // again, faces first, and the run goes on.
  const Vec3 centre{r - 4e-3, 0.0012, r - 6e-3};
  std::vector<Triangle> floor_far_first, walls;
  for (const Triangle& t : corner) (triangle_unit_normal(t).z > 0.5 ? floor_far_first : walls).push_back(t);
  auto away = [&](const Triangle& t) {
    const Vec3 m = (t.v[0] + t.v[1] + t.v[2]) * (1.0 / 3);
    return std::hypot(m.x - centre.x, m.y - centre.y);
  };
  std::sort(floor_far_first.begin(), floor_far_first.end(),
            [&](const Triangle& a, const Triangle& b) { return away(a) > away(b); });
  std::vector<Triangle> late = floor_far_first;
  late.insert(late.end() - 2, walls.begin(), walls.end());
  for (const auto* mesh : {&corner, &late}) {
    Scene s = plate_scene(ContactLaw::linear, mesh);
    s.numerics.gravity = {0, 0, 0};
    s.balls[0].position = centre;
    s.balls[0].velocity = {};
    s.balls[0].omega = {};
    const Vec3 f = force_on(s);
    INFO((mesh == &late ? "the floor's face last" : "as built"));
    CHECK(wall_contacts(s) == 2.0);
    CHECK(f.x == Approx(1e5 * 4e-3).epsilon(1e-9));
    CHECK(f.z == Approx(1e5 * 6e-3).epsilon(1e-9));
    CHECK_NOTHROW(make_solver(context(), s)->advance(3));
  }
}

TEST_CASE("a ball over a shallow dish where six triangles meet feels one contact, the nearest", "[mesh][physics]") {
  // Six triangles round the origin, each rising outward at 3° (a worn or
  // scanned surface, one smooth patch): a ball above the vertex is as near
  // to each face, a face contact of each (Hu's rule keeps every face).
  std::vector<Triangle> dish;
  const double tilt = 3 * kPi / 180, R0 = 0.5;
  for (int k = 0; k < 6; ++k) {
    const double a0 = k * kPi / 3, a1 = (k + 1) * kPi / 3;
    dish.push_back({{Vec3{0, 0, 0}, Vec3{R0 * std::cos(a0), R0 * std::sin(a0), R0 * std::tan(tilt)},
                     Vec3{R0 * std::cos(a1), R0 * std::sin(a1), R0 * std::tan(tilt)}}});
  }
  const double r = 0.02, h = r - 2e-4;
  Scene s = plate_scene(ContactLaw::linear, &dish);
  s.numerics.gravity = {0, 0, 0};
  s.balls[0].position = {0, 0, h};
  s.balls[0].velocity = {};
  s.balls[0].omega = {};
  // Each face's plane is h cos(tilt') from the centre, tilt' the face's
  // steepest slope (its normal's angle from the axis): one contact, the
  // nearest face's, with that overlap.
  double nearest = 1;
  for (const Triangle& t : dish) nearest = std::min(nearest, h * triangle_unit_normal(t).z);
  const Vec3 f = force_on(s);
  CHECK(wall_contacts(s) == 1.0);
  CHECK(f.norm() == Approx(1e5 * (r - nearest)).epsilon(1e-9));
  // A steeper fold than a smooth surface's (two patches) keeps both faces.
  std::vector<Triangle> fold = {{{Vec3{0, -1, 0}, Vec3{1, -1, std::tan(0.4)}, Vec3{1, 1, std::tan(0.4)}}},
                                {{Vec3{0, -1, 0}, Vec3{1, 1, std::tan(0.4)}, Vec3{0, 1, 0}}},
                                {{Vec3{0, -1, 0}, Vec3{0, 1, 0}, Vec3{-1, 1, std::tan(0.4)}}},
                                {{Vec3{0, -1, 0}, Vec3{-1, 1, std::tan(0.4)}, Vec3{-1, -1, std::tan(0.4)}}}};
  Scene v = plate_scene(ContactLaw::linear, &fold);
  v.numerics.gravity = {0, 0, 0};
  v.balls[0].position = {0, 0.1, h};
  v.balls[0].velocity = {};
  v.balls[0].omega = {};
  CHECK(wall_contacts(v) == 2.0);
}

TEST_CASE("the contact profile counts balls on mesh lifters and shell, not on mesh ends", "[mesh]") {
  // A ball pressed onto a plate mesh, as a lifter, as the shell and as part of
  // the ends: the toe and shoulder come from the belly's contacts alone.
  std::vector<Triangle> plate = irregular_plate(0.2, 4, 0.2, 3);
  for (MeshPart part : {MeshPart::lifters, MeshPart::shell, MeshPart::ends}) {
    Scene s = plate_scene(ContactLaw::linear, &plate);
    s.walls.meshes[0].part = part;
    s.numerics.gravity = {0, 0, 0};
    s.balls[0].position = {0.013, -0.021, 0.02 - 1e-4};
    s.balls[0].velocity = {};
    s.balls[0].omega = {};
    auto solver = make_solver(context(), s);
    solver->take_contact_profile();
    solver->sample_contact_profile();
    const std::vector<long> prof = solver->take_contact_profile();
    long counts = 0;
    for (long c : prof) counts += c;
    INFO("part " << static_cast<int>(part));
    CHECK(solver->contact_stats().wall_contacts_per_ball == 1);
    CHECK(counts == (part == MeshPart::ends ? 0 : 1));
  }
}

TEST_CASE("mesh lifters in a turning drum: the kernels equal the CPU reference ball by ball", "[mesh][reference]") {
  // The drum's 8 bars as a mesh (cut at the shell), the charge settled on
  // the device, then 200 steps on the device and in the CPU reference,
  // whose mesh cells are binned on the host.
  for (ContactLaw law : {ContactLaw::linear, ContactLaw::hertz}) {
    DrumSpec spec;
    spec.n_balls = 300;
    spec.law = law;
    spec.precision = context().info().fp64 ? Precision::double_ : Precision::single;
    Scene sc = make_drum(spec);
    WallMesh m;
    m.name = "drum lifters";
    m.triangles = lifter_triangles(bars_on_shell(sc.walls.lifters, sc.walls.shell_radius), sc.walls.length);
    m.material = sc.wall_material;
    for (int a = 0; a < sc.wall_index(); ++a) m.interactions.push_back(sc.interaction(a, sc.wall_index()));
    sc.walls.lifters.clear();
    sc.walls.meshes = {m};
    {
      auto pre = make_solver(context(), sc);
      pre->advance(static_cast<long>(0.25 / sc.numerics.dt));
      take_motion(*pre, sc);
    }
    auto dev = make_solver(context(), sc);
    ReferenceSolver ref(sc);
    dev->advance(200);
    ref.advance(200);
    const auto a = dev->balls(), b = ref.balls();
    double dx = 0, vmax = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      dx = std::max(dx, (a[i].position - b[i].position).norm());
      vmax = std::max(vmax, b[i].velocity.norm());
    }
    const double walls = dev->contact_stats().wall_contacts_per_ball;
    std::printf("mesh lifters, kernel vs reference %s %s: max |dx| %.3g m after 200 steps, %.3f wall contacts a "
                "ball, vmax %.3g m/s\n",
                law == ContactLaw::linear ? "linear" : "hertz",
                spec.precision == Precision::double_ ? "double" : "float", dx, walls, vmax);
    CHECK(vmax > 0.05);
    CHECK(walls > 0.05);
    CHECK(dx < (spec.precision == Precision::double_ ? 1e-10 : 1e-4));
  }
}

TEST_CASE("the lab mill with its lifters as an STL draws the parametric lab mill's power, toe and shoulder",
          "[mesh][mill][slow]") {
  // assets/cases/lab_stl.toml: lab.toml with its bars from
  // assets/meshes/lab_lifters.stl, which `millcharge check --write-lifters`
  // wrote from lab.toml (the bars cut at the shell). Two revolutions after a
  // 1 s warm-up, as test_mill's lab run.
  const std::vector<std::string> sets = {"run.duration=4.6", "run.warmup=1.0", "run.output_interval=0.02"};
  const checks::LabRun p = checks::case_run(context(), io::default_case(), sets);
  const checks::LabRun m = checks::case_run(context(), io::case_dir() / "lab_stl.toml", sets);
  REQUIRE(m.scene.walls.lifters.empty());
  REQUIRE(m.scene.walls.meshes.size() == 1);
  // The STL is the parametric bars: its triangles, cut at the shell.
  const Scene walls = build_walls(p.c, p.d);
  const auto tris = lifter_triangles(bars_on_shell(walls.walls.lifters, walls.walls.shell_radius), p.c.length);
  REQUIRE(m.scene.walls.meshes[0].triangles.size() == tris.size());
  std::printf("lab mill, parametric lifters: %.2f W, toe %.1f, shoulder %.1f deg (%ld balls); STL lifters (%zu "
              "triangles): %.2f W (%+.2f %%), toe %.1f, shoulder %.1f deg (%ld balls)\n",
              p.s.torque_power_W, p.s.angles.toe_deg, p.s.angles.shoulder_deg, p.d.n_balls, tris.size(),
              m.s.torque_power_W, 100 * (m.s.torque_power_W / p.s.torque_power_W - 1), m.s.angles.toe_deg,
              m.s.angles.shoulder_deg, m.d.n_balls);
  CHECK(m.s.torque_power_W == Approx(p.s.torque_power_W).epsilon(0.03));
  CHECK(std::fabs(m.s.angles.toe_deg - p.s.angles.toe_deg) < 3.0);
  CHECK(std::fabs(m.s.angles.shoulder_deg - p.s.angles.shoulder_deg) < 3.0);
  CHECK(std::abs(m.s.imbalance) < 0.05);
  // The liner books see the mesh: its triangles take the lifters' impacts.
  const LinerLayout layout = liner_layout(m.scene);
  REQUIRE(layout.first_mesh + static_cast<int>(tris.size()) == layout.size());
  double mesh_impacts = 0;
  for (int e = layout.first_mesh; e < layout.size(); ++e) mesh_impacts += m.s.books.liner_at(e, MC_LINER_IMPACTS);
  CHECK(mesh_impacts > 0);
}

TEST_CASE("cone heads and end lifters built from the case face the charge and close the mill", "[mesh][geometry]") {
  EndsSpec e;
  e.cone_angle_deg = 20;
  e.trunnion_diameter = 0.2;
  e.lifter_rows = 8;
  e.lifter_height = 0.02;
  e.lifter_width = 0.03;
  const double R = 0.45, L = 0.15, depth = cone_depth(e, R);
  CHECK(depth == Approx((R - 0.1) * std::tan(20 * kPi / 180)));
  const auto cones = cone_triangles(e, R, L, 96);
  int wrong = 0;
  double zmin = 1e9, zmax = -1e9;
  for (const Triangle& t : cones) {
    const Vec3 c = (t.v[0] + t.v[1] + t.v[2]) * (1.0 / 3.0), n = triangle_unit_normal(t);
    // Into the mill: towards the belly's middle along z, towards the axis.
    const double inward = n.z * (0.5 * L - c.z) - (n.x * c.x + n.y * c.y);
    wrong += !(inward > 0);
    for (const Vec3& v : t.v) {
      zmin = std::min(zmin, v.z);
      zmax = std::max(zmax, v.z);
      CHECK(std::hypot(v.x, v.y) <= R * (1 + 1e-12));
    }
  }
  CHECK(wrong == 0);
  CHECK(zmin == Approx(-depth));
  CHECK(zmax == Approx(L + depth));
  // Each cone with its trunnion disc is a closed surface apart from the
  // ring where it meets the shell: its only open edges lie at radius R.
  Scene s = bare_scene(kSteel, kSteel, Interaction{}, ContactLaw::linear);
  const MeshTopology topo = mesh_topology({mesh_of(cones, s)});
  CHECK(topo.n_patches == 4);  // two cones, two discs
  // End lifters: closed boxes, each face facing out of its box.
  e.cone_angle_deg = 0;  // on flat plates
  const auto bars = end_lifter_triangles(e, R, L);
  CHECK(bars.size() == 2 * 8 * 12);
  for (int b = 0; b < 16; ++b) {
    const std::vector<Triangle> one(bars.begin() + 12 * b, bars.begin() + 12 * (b + 1));
    const double v = closed_mesh_volume(one);
    CHECK(v == Approx(e.lifter_height * e.lifter_width * (R * std::sqrt(1 - std::pow(0.015 / R, 2)) - R / 3)).epsilon(1e-6));
    double v6 = 0;  // signed: positive when the faces point out of the box
    for (const Triangle& t : one) {
      const Vec3 a = t.v[0], bb = t.v[1], c = t.v[2];
      v6 += a.x * (bb.y * c.z - bb.z * c.y) - a.y * (bb.x * c.z - bb.z * c.x) + a.z * (bb.x * c.y - bb.y * c.x);
    }
    CHECK(v6 > 0);
  }
}

TEST_CASE("a ball that goes out through a cone head stops the run, one inside the cone does not", "[mesh][failure]") {
  const MillCase c =
      io::read_case(io::default_case(), {"mill.ends=cones", "mill.cone_angle=20", "mill.trunnion_diameter=0.2"});
  const MillDerived d = derive(c);
  EndsSpec e;
  e.cone_angle_deg = 20;
  e.trunnion_diameter = 0.2;
  const double depth = cone_depth(e, 0.5 * c.diameter);
  REQUIRE(depth > 0.05);
  Scene s = build_scene(c, d);
  REQUIRE_FALSE(s.walls.has_end_plates());
  s.balls.resize(1);
  const double r = s.balls[0].radius;
  // Inside the far cone, past the end of the belly, where a plate used to be.
  s.balls[0].position = {0.0, 0.0, c.length + 0.5 * depth};
  s.balls[0].velocity = {0, 0, 0};
  CHECK_NOTHROW(make_solver(context(), s)->advance(20));
  // Past the trunnion disc of the near cone, wholly outside the mill.
  s.balls[0].position = {0.0, 0.0, -depth - 2 * r};
  auto out = make_solver(context(), s);
  CHECK_THROWS_WITH(out->advance(20), Catch::Contains("left the mill") && Catch::Contains("ball"));
}

TEST_CASE("a lab mill with cone heads: the cones take collisions and the power books close",
          "[mesh][mill][slow]") {
  const checks::LabRun r = checks::case_run(
      context(), io::default_case(),
      {"mill.ends=cones", "mill.cone_angle=20", "mill.trunnion_diameter=0.2", "run.duration=2.8", "run.warmup=1.0",
       "run.output_interval=0.02"});
  std::printf("lab mill with 20 deg cone heads (%ld balls, %.4g m3 with the cones): torque %.2f W, dissipation "
              "%.2f W (imbalance %+.2f %%), toe %.1f, shoulder %.1f deg\n",
              r.d.n_balls, r.d.mill_volume, r.s.torque_power_W, r.s.dissipation_power_W, 100 * r.s.imbalance,
              r.s.angles.toe_deg, r.s.angles.shoulder_deg);
  REQUIRE(r.scene.walls.meshes.size() == 1);
  CHECK_FALSE(r.scene.walls.has_end_plates());
  CHECK(r.d.mill_volume > 1.5 * kPi * 0.45 * 0.45 * 0.15);  // the cones add their volume
  CHECK(std::abs(r.s.imbalance) < 0.05);
  CHECK(r.s.torque_power_W > 800);
  // The cones (the "ends" rows of the spectra) take their share of the
  // collisions.
  const mc::SpectraReport sp = mc::spectra_report(r.scene, r.s.books, r.s.window_s, r.s.open_loss_start_J,
                                                  r.s.open_loss_end_J, r.s.dissipated_J);
  double ends_W = 0;
  for (const auto& t : sp.types) {
    CHECK(t.pair.find("end plate") == std::string::npos);  // there are none
    if (t.pair.size() > 5 && t.pair.compare(t.pair.size() - 5, 5, "-ends") == 0) ends_W += t.power_W;
  }
  CHECK(ends_W > 0.02 * sp.dissipation_W);
  // Along the mill: the axial bins divide the length between the cones'
  // bases (no end plates, so not the plates' spacing), each with its share.
  const mc::LinerLayout layout = mc::liner_layout(r.scene);
  const mc::LinerReport lr = mc::liner_report(r.scene, layout, r.s.books, r.s.window_s, r.s.profile, r.s.angles);
  REQUIRE(lr.impact_W_by_axial.size() == static_cast<std::size_t>(layout.axial_bins));
  REQUIRE(layout.axial_bins >= 2);
  double along_W = 0;
  for (double w : lr.impact_W_by_axial) along_W += w;
  for (double w : lr.impact_W_by_axial) CHECK(w > 0.2 * along_W / layout.axial_bins);
}

TEST_CASE("a mesh with more triangles than the device can hold is refused with the count, status 2, no run folder",
          "[mesh][cli]") {
  // 2 × 180² = 64,800 triangles (a 0.5 m square just off the feed end of the lab
  // mill) need some 6 MiB; the device is given 4 MiB, which the balls fit.
  const fs::path work = fs::temp_directory_path() / "millcharge_mesh_memory";
  fs::remove_all(work);
  fs::create_directories(work);
  std::vector<Triangle> tris;
  const int n = 180;
  const double h = 0.25, step = 2 * h / n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const Vec3 a{-h + i * step, -h + j * step, 0.002}, b = a + Vec3{step, 0, 0}, c = a + Vec3{step, step, 0},
                 d = a + Vec3{0, step, 0};
      tris.push_back({{a, b, c}});
      tris.push_back({{a, c, d}});
    }
  std::ofstream(work / "big.stl", std::ios::binary) << io::stl_binary(tris);
  std::string text = read_text(io::default_case());
  text += "\n[[walls.mesh]]\nfile = \"big.stl\"\npart = \"ends\"\n";
  std::ofstream(work / "big.toml") << text;
  const fs::path out = work / "run", err = work / "err.txt";
  const std::string cmd = "MILLCHARGE_DEVICE_MEMORY=4M " + std::string(MC_BINARY) + " run '" +
                          (work / "big.toml").string() + "' --quiet --out '" + out.string() + "' > /dev/null 2> '" +
                          err.string() + "'";
  const int status = std::system(cmd.c_str());
  const std::string message = read_text(err);
  INFO(message);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 2);
  CHECK_THAT(message, Catch::StartsWith("millcharge: walls.mesh: 64800 triangles need "));
  CHECK_THAT(message, Catch::Contains("use coarser meshes (fewer triangles)"));
  CHECK(std::count(message.begin(), message.end(), '\n') == 1);
  CHECK_FALSE(fs::exists(out));
  fs::remove_all(work);
}

TEST_CASE("a liner mesh, or a part of one, wound inside out is refused by name, and cone heads are not held to it",
          "[mesh][geometry]") {
  // The lab mill's bars as a closed mesh (faces out of each bar), and a
  // scanned shell as an open sheet 5 mm inside the shell facing the axis.
  const double R = 0.45, L = 0.15;
  LifterProfile lab;
  lab.height = 0.025, lab.top_width = 0.03, lab.face_angle_deg = 20;
  const auto bars = lifter_rows(R, 12, {lab});
  std::vector<Triangle> sheet;
  const int n = 48;
  for (int k = 0; k < n; ++k) {
    const double a0 = 2 * kPi * k / n, a1 = 2 * kPi * (k + 1) / n, r = R - 0.005;
    const Vec3 p0{r * std::cos(a0), r * std::sin(a0), 0}, p1{r * std::cos(a1), r * std::sin(a1), 0};
    const Vec3 q0 = p0 + Vec3{0, 0, L}, q1 = p1 + Vec3{0, 0, L};
    sheet.push_back({{p0, q1, p1}});  // (q1 - p0) x (p1 - p0) points to the axis
    sheet.push_back({{p0, q0, q1}});
  }
  auto turned = [](std::vector<Triangle> t) {
    for (Triangle& x : t) std::swap(x.v[1], x.v[2]);
    return t;
  };
  auto walls = [&](const std::vector<Triangle>& t, MeshPart part) {
    Walls w;
    w.shell_radius = R + 0.01, w.length = L;  // the bars' feet reach 6.25 mm behind the shell
    WallMesh m;
    m.name = "liner.stl", m.part = part, m.triangles = t;
    w.meshes.push_back(m);
    return w;
  };
  // The sheet's inward facing, checked by hand: each triangle's normal
  // against the direction to the axis from its centroid.
  for (const Triangle& t : sheet) {
    const Vec3 c = (t.v[0] + t.v[1] + t.v[2]) * (1.0 / 3.0);
    REQUIRE(triangle_unit_normal(t).dot(Vec3{-c.x, -c.y, 0}) > 0);
  }
  for (const auto& [t, part] : {std::pair{lifter_triangles(bars, L), MeshPart::lifters}, std::pair{sheet, MeshPart::shell}}) {
    CHECK_NOTHROW(check_meshes(walls(t, part)));
    CHECK_THROWS_WITH(check_meshes(walls(turned(t), part)),
                      Catch::StartsWith("liner.stl: its triangles face away from the axis where the mesh comes nearest "
                                        "it") &&
                          Catch::Contains("wound inside out") && Catch::Contains("flip"));
    // As part of the ends (a cone head's inside faces the charge along the
    // axis as much as across it) it is not checked.
    CHECK_NOTHROW(check_meshes(walls(turned(t), MeshPart::ends)));
  }
  // One bar of twelve turned round (bodies exported one by one): each
  // connected part is checked, and the message says it is one part.
  std::vector<Triangle> one = lifter_triangles(bars, L);
  REQUIRE(one.size() == 12 * 12);
  for (std::size_t k = 5 * 12; k < 6 * 12; ++k) std::swap(one[k].v[1], one[k].v[2]);
  CHECK_THROWS_WITH(check_meshes(walls(one, MeshPart::lifters)),
                    Catch::Contains("where 1 of its 12 parts comes nearest it") &&
                        Catch::Contains("export those parts the other way round"));
  // A part reaching to within a thousandth of the shell's radius of the
  // axis (a trunnion's plate) has no direction to the axis there: either
  // way round it passes.
  // (A fan of two triangles 0.2 mm from it, facing the axis as a bar's
  // top would, turned: refused 1 mm out.)
  auto fan = [](double x0) {
    return std::vector<Triangle>{{{Vec3{x0, 0, 0.05}, Vec3{0.1, 0, 0.1}, Vec3{0.1, 0.05, 0.05}}},
                                 {{Vec3{x0, 0, 0.05}, Vec3{0.1, 0.05, 0.05}, Vec3{0.1, 0, 0.0}}}};
  };
  CHECK_NOTHROW(check_meshes(walls(fan(0.0002), MeshPart::lifters)));
  CHECK_NOTHROW(check_meshes(walls(turned(fan(0.0002)), MeshPart::lifters)));
  const std::vector<Triangle> out_fan = fan(0.001);
  for (const Triangle& t : out_fan) REQUIRE(triangle_unit_normal(t).x < 0);  // toward the axis, as given
  CHECK_NOTHROW(check_meshes(walls(out_fan, MeshPart::lifters)));
  CHECK_THROWS_WITH(check_meshes(walls(turned(out_fan), MeshPart::lifters)), Catch::Contains("wound inside out"));
  // An open sheet whose innermost vertex is a corner of one triangle (a
  // scan's arc, nearer the axis at one end), turned: refused.
  std::vector<Triangle> arc;
  for (int k = 0; k < 8; ++k) {
    const double a0 = 0.1 * k, a1 = 0.1 * (k + 1), r0 = R - 0.005 - 0.001 * k, r1 = R - 0.006 - 0.001 * k;
    const Vec3 p0{r0 * std::cos(a0), r0 * std::sin(a0), 0}, p1{r1 * std::cos(a1), r1 * std::sin(a1), 0};
    arc.push_back({{p0, p1 + Vec3{0, 0, L}, p1}});
    arc.push_back({{p0, p0 + Vec3{0, 0, L}, p1 + Vec3{0, 0, L}}});
  }
  CHECK_NOTHROW(check_meshes(walls(arc, MeshPart::shell)));
  CHECK_THROWS_WITH(check_meshes(walls(turned(arc), MeshPart::shell)), Catch::Contains("wound inside out"));
  // A lone triangle (a file whose triangles share no corner, refused by a
  // life study on its own grounds) has no surface round its corner: it
  // passes either way round.
  CHECK_NOTHROW(check_meshes(walls({sheet[0]}, MeshPart::shell)));
  CHECK_NOTHROW(check_meshes(walls(turned({sheet[0]}), MeshPart::shell)));
  // From a case: the lab mill's STL bars given flip = true are refused,
  // status 2, naming the key and the flip; nothing written.
  const fs::path work = fs::temp_directory_path() / "mc-inside-out", out = work / "run", err = work / "err.txt";
  fs::remove_all(work);
  fs::create_directories(work);
  const std::string cmd = std::string(MC_BINARY) + " run '" + std::string(MC_ASSET_DIR) +
                          "/cases/lab_stl.toml' --set walls.mesh.0.flip=true --quiet --out '" + out.string() +
                          "' > /dev/null 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  const std::string message = read_text(err);
  INFO(message);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 2);
  CHECK_THAT(message, Catch::Contains("walls.mesh[0]") && Catch::Contains("wound inside out") &&
                          Catch::Contains("toggle the mesh's flip key"));
  CHECK(std::count(message.begin(), message.end(), '\n') == 1);
  CHECK_FALSE(fs::exists(out));
  fs::remove_all(work);
}
