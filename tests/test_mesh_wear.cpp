// A mesh liner worn by its booked wear (life/mesh_wear.h): the volume
// removed against the volume booked, checked by the closed mesh's own
// volume (core/wall_mesh.h), and the worn meshes that are refused.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "core/wall_mesh.h"
#include "life/mesh_wear.h"

using namespace mc;
using mc::life::MeshBounds;
using mc::life::wear_mesh;

namespace {

// A grid of n x n quads, two triangles each, over the square spanned by
// u and v from `origin`, facing u x v.
std::vector<Triangle> grid(const Vec3& origin, const Vec3& u, const Vec3& v, int n) {
  std::vector<Triangle> t;
  auto at = [&](int i, int j) { return origin + u * (static_cast<double>(i) / n) + v * (static_cast<double>(j) / n); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      t.push_back({{at(i, j), at(i + 1, j), at(i + 1, j + 1)}});
      t.push_back({{at(i, j), at(i + 1, j + 1), at(i, j + 1)}});
    }
  return t;
}

// A closed box from `lo` to `hi`, each face an n x n grid facing out; the
// top (+y) face's triangles first.
std::vector<Triangle> box(const Vec3& lo, const Vec3& hi, int n) {
  const double dx = hi.x - lo.x, dy = hi.y - lo.y, dz = hi.z - lo.z;
  std::vector<Triangle> all, f;
  auto add = [&](const std::vector<Triangle>& g) { all.insert(all.end(), g.begin(), g.end()); };
  add(grid({lo.x, hi.y, lo.z}, {0, 0, dz}, {dx, 0, 0}, n));  // top, +y
  add(grid({lo.x, lo.y, lo.z}, {dx, 0, 0}, {0, 0, dz}, n));  // bottom, -y
  add(grid({lo.x, lo.y, lo.z}, {0, dy, 0}, {dx, 0, 0}, n));  // front, -z
  add(grid({lo.x, lo.y, hi.z}, {dx, 0, 0}, {0, dy, 0}, n));  // back, +z
  add(grid({lo.x, lo.y, lo.z}, {0, 0, dz}, {0, dy, 0}, n));  // left, -x
  add(grid({hi.x, lo.y, lo.z}, {0, dy, 0}, {0, 0, dz}, n));  // right, +x
  return all;
}

double area(const Triangle& t) {
  const Vec3 a = t.v[1] - t.v[0], b = t.v[2] - t.v[0];
  const Vec3 c{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
  return 0.5 * c.norm();
}

}  // namespace

TEST_CASE("a plate worn evenly moves every vertex by the depth booked", "[life][mesh_wear]") {
  const std::vector<Triangle> plate = grid({0, 0, 0.5}, {1, 0, 0}, {0, 1, 0}, 8);  // facing +z
  REQUIRE(plate.size() == 128);
  const double d = 1e-3;
  std::vector<double> vol;
  for (const Triangle& t : plate) vol.push_back(area(t) * d);
  const mc::life::MeshWear w = wear_mesh(plate, vol, MeshBounds{});
  CHECK(w.booked_m3 == Approx(1e-3).epsilon(1e-12));
  CHECK(w.removed_m3 == Approx(w.booked_m3).epsilon(1e-10));
  CHECK(w.scale == Approx(1).epsilon(1e-9));
  for (std::size_t t = 0; t < plate.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      CHECK(w.triangles[t].v[k].z == Approx(0.5 - d).epsilon(1e-12));
      CHECK(w.triangles[t].v[k].x == plate[t].v[k].x);
    }
  // No wear, no move.
  const mc::life::MeshWear none = wear_mesh(plate, std::vector<double>(plate.size(), 0.0), MeshBounds{});
  CHECK(none.removed_m3 == 0);
  CHECK(none.triangles[5].v[1].z == plate[5].v[1].z);
}

TEST_CASE("a bar worn on its top loses the booked volume, by its own enclosed volume", "[life][mesh_wear]") {
  // A 50 x 150 x 200 mm bar, 6 x 6 quads a face; 4 mm booked on its top.
  const std::vector<Triangle> bar = box({-0.025, 0, 0}, {0.025, 0.15, 0.2}, 6);
  const double before = closed_mesh_volume(bar);
  REQUIRE(before == Approx(0.05 * 0.15 * 0.2).epsilon(1e-12));
  std::vector<double> vol(bar.size(), 0.0);
  for (int t = 0; t < 72; ++t) vol[t] = area(bar[t]) * 0.004;  // the top's triangles
  const mc::life::MeshWear w = wear_mesh(bar, vol, MeshBounds{});
  CHECK(w.booked_m3 == Approx(0.05 * 0.2 * 0.004).epsilon(1e-12));
  // Independent of the swept volume: the enclosed volume lost.
  CHECK(before - closed_mesh_volume(w.triangles) == Approx(w.booked_m3).epsilon(1e-9));
  CHECK(w.removed_m3 == Approx(w.booked_m3).epsilon(1e-9));
  // Each face keeps its own depth: the top goes down 4 mm all over, edges
  // and corners too, and the sides stay in their planes.
  CHECK(w.scale == Approx(1).epsilon(1e-9));
  for (int t = 0; t < 72; ++t)
    for (int k = 0; k < 3; ++k) CHECK(w.triangles[t].v[k].y == Approx(0.15 - 0.004).epsilon(1e-9));
  for (std::size_t t = 0; t < bar.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      CHECK(w.triangles[t].v[k].x == Approx(bar[t].v[k].x).margin(1e-12));
      CHECK(w.triangles[t].v[k].z == Approx(bar[t].v[k].z).margin(1e-12));
    }
  // The bottom does not move.
  for (int t = 72; t < 144; ++t)
    for (int k = 0; k < 3; ++k) CHECK(w.triangles[t].v[k].y == 0);
  // A finer mesh: a 100 x 150 mm bar, 24 x 24 quads a face (rows of
  // 6.25 mm on its sides): 5 mm off its top leaves it 145 mm high with its
  // sides in place; 15 mm would take the top past the sides' first row,
  // which the mesh cannot follow without new triangles: refused, naming
  // shorter stages.
  const std::vector<Triangle> fine = box({-0.05, 0, 0}, {0.05, 0.15, 0.2}, 24);
  for (const double d : {0.005, 0.015}) {
    std::vector<double> deep(fine.size(), 0.0);
    for (int t = 0; t < 2 * 24 * 24; ++t) deep[t] = area(fine[t]) * d;
    if (d > 0.00625) {
      CHECK_THROWS_WITH(wear_mesh(fine, deep, MeshBounds{}, 0, "bar.stl"),
                        Catch::Contains("turns it over") && Catch::Contains("shorter stages"));
      continue;
    }
    const mc::life::MeshWear f = wear_mesh(fine, deep, MeshBounds{});
    CHECK(closed_mesh_volume(fine) - closed_mesh_volume(f.triangles) == Approx(f.booked_m3).epsilon(1e-9));
    double top = 0, widest = 0;
    for (const Triangle& t : f.triangles)
      for (int k = 0; k < 3; ++k) top = std::max(top, t.v[k].y), widest = std::max(widest, std::abs(t.v[k].x));
    CHECK(top == Approx(0.145).epsilon(1e-9));
    CHECK(widest == Approx(0.05).epsilon(1e-12));
  }
}

TEST_CASE("smoothing evens noisy wear and keeps the volume", "[life][mesh_wear]") {
  const std::vector<Triangle> plate = grid({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 16);
  std::mt19937 rng(57);
  std::uniform_real_distribution<double> u(0.0, 2e-3);
  std::vector<double> vol;
  for (const Triangle& t : plate) vol.push_back(area(t) * u(rng));
  auto roughness = [&](const mc::life::MeshWear& w) {
    double s = 0, s2 = 0;
    int n = 0;
    for (const Triangle& t : w.triangles)
      for (int k = 0; k < 3; ++k) s += t.v[k].z, s2 += t.v[k].z * t.v[k].z, ++n;
    return std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n)));
  };
  const mc::life::MeshWear raw = wear_mesh(plate, vol, MeshBounds{}, 0);
  const mc::life::MeshWear smooth = wear_mesh(plate, vol, MeshBounds{}, 8);
  CHECK(smooth.smoothing == 8);
  CHECK(raw.removed_m3 == Approx(raw.booked_m3).epsilon(1e-9));
  CHECK(smooth.removed_m3 == Approx(smooth.booked_m3).epsilon(1e-9));
  CHECK(roughness(smooth) < 0.5 * roughness(raw));
}

TEST_CASE("a worn mesh that leaves the mill or is worn through is refused by name", "[life][mesh_wear]") {
  // A liner patch 2 mm inside a 1 m shell, facing the axis (-x), worn 5 mm.
  const std::vector<Triangle> patch = grid({0.998, -0.02, 0.1}, {0, 0, 0.1}, {0, 0.04, 0}, 4);
  std::vector<double> vol;
  for (const Triangle& t : patch) vol.push_back(area(t) * 0.005);
  CHECK_THROWS_WITH(wear_mesh(patch, vol, MeshBounds{1.0, 0, 1}, 0, "liner.stl"),
                    Catch::Contains("liner.stl: triangle") && Catch::Contains("beyond the shell") &&
                        Catch::Contains("worn through"));
  // 1 mm is fine.
  for (double& v : vol) v *= 0.2;
  CHECK_NOTHROW(wear_mesh(patch, vol, MeshBounds{1.0, 0, 1}));
  // An end liner 10 mm from the end plate z = 0, facing +z, worn 20 mm.
  const std::vector<Triangle> end = grid({0.1, 0.1, 0.01}, {0.1, 0, 0}, {0, 0.1, 0}, 4);
  std::vector<double> deep;
  for (const Triangle& t : end) deep.push_back(area(t) * 0.02);
  CHECK_THROWS_WITH(wear_mesh(end, deep, MeshBounds{1.0, 0, 1}, 0, "end.stl"),
                    Catch::Contains("end.stl: triangle") && Catch::Contains("beyond the mill's ends"));
  // A bar worn deeper on its top than its grid: the top's edge turns over.
  const std::vector<Triangle> bar = box({-0.025, 0, 0}, {0.025, 0.03, 0.2}, 6);
  std::vector<double> top(bar.size(), 0.0);
  for (int t = 0; t < 72; ++t) top[t] = area(bar[t]) * 0.05;
  CHECK_THROWS_WITH(wear_mesh(bar, top, MeshBounds{}, 0, "bar.stl"),
                    Catch::Contains("bar.stl: triangle") && Catch::Contains("shorter stages"));
  // Bad volumes.
  CHECK_THROWS_WITH(wear_mesh(end, {1.0}, MeshBounds{}), Catch::Contains("1 wear volumes for 32 triangles"));
  std::vector<double> bad = deep;
  bad[3] = -1e-9;
  CHECK_THROWS_WITH(wear_mesh(end, bad, MeshBounds{}), Catch::Contains("triangle 4: wear volume"));
  bad[3] = NAN;
  CHECK_THROWS_WITH(wear_mesh(end, bad, MeshBounds{}), Catch::Contains("triangle 4: wear volume"));
}
