// A worn mesh kept fit to wear again (life/mesh_collapse.h, the
// relaxation in life/mesh_wear.h): short edges collapsed with their wear
// kept, a plane's area kept, an end plane's vertices kept on it; and a bar
// whose worn corner has drawn a strip a millimetre wide, which the next
// move turns over as it stands and wears once its strip is collapsed.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <stdexcept>
#include <vector>

#include "life/mesh_collapse.h"
#include "life/mesh_wear.h"

using namespace mc;

namespace {

Vec3 cross3(const Vec3& a, const Vec3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
Vec3 area2(const Triangle& t) { return cross3(t.v[1] - t.v[0], t.v[2] - t.v[0]); }
double area(const Triangle& t) { return 0.5 * area2(t).norm(); }

// Rows of points (each row a line across, the rows along `v`), two
// triangles per quad, facing (row direction) x v.
std::vector<Triangle> sheet(const std::vector<Vec3>& across, const Vec3& v, int n) {
  std::vector<Triangle> t;
  for (std::size_t i = 0; i + 1 < across.size(); ++i)
    for (int j = 0; j < n; ++j) {
      const Vec3 a = across[i] + v * j, b = across[i + 1] + v * j, c = across[i + 1] + v * (j + 1),
                 d = across[i] + v * (j + 1);
      t.push_back({{a, b, c}});
      t.push_back({{a, c, d}});
    }
  return t;
}

// A lifter bar 25 mm high on the shell plane y = 0, extruded along z from
// 0 to 60 mm in 10 mm rows: its leading face x = 0 in three rows, a strip
// of `strip` mm at 45° where the top meets it (what the wear of earlier
// stages draws), the top at y = 25 mm and the trailing face at x = 30 mm.
// Its surface faces out of the bar, towards the charge.
std::vector<Triangle> worn_bar(double strip) {
  const double s = strip / std::sqrt(2.0);
  const std::vector<Vec3> profile = {{30e-3, 0, 0},      {30e-3, 12.5e-3, 0}, {30e-3, 25e-3, 0},
                                     {20e-3, 25e-3, 0},  {10e-3, 25e-3, 0},   {s * 1e-3, 25e-3, 0},
                                     {0, (25 - s) * 1e-3, 0}, {0, 16e-3, 0},   {0, 8e-3, 0},
                                     {0, 0, 0}};
  return sheet(profile, {0, 0, 10e-3}, 6);
}

// The same bar closed: its base on the shell plane (facing -y) and its
// two ends (facing -z at z = 0 and +z at z = 60 mm), each end a fan from
// the profile's centroid; the solid's volume is then the enclosed one.
std::vector<Triangle> closed_bar(double strip) {
  std::vector<Triangle> t = worn_bar(strip);
  const double s = strip / std::sqrt(2.0);
  const std::vector<Vec3> profile = {{30e-3, 0, 0},      {30e-3, 12.5e-3, 0}, {30e-3, 25e-3, 0},
                                     {20e-3, 25e-3, 0},  {10e-3, 25e-3, 0},   {s * 1e-3, 25e-3, 0},
                                     {0, (25 - s) * 1e-3, 0}, {0, 16e-3, 0},   {0, 8e-3, 0},
                                     {0, 0, 0}};
  const Vec3 dz{0, 0, 10e-3};
  for (int j = 0; j < 6; ++j) {  // the base, from (0,0) to (30,0)
    const Vec3 a = profile.back() + dz * j, b = profile.front() + dz * j, c = profile.front() + dz * (j + 1),
               d = profile.back() + dz * (j + 1);
    t.push_back({{a, b, c}});
    t.push_back({{a, c, d}});
  }
  Vec3 centre{};
  for (const Vec3& p : profile) centre = centre + p * (1.0 / profile.size());
  for (std::size_t i = 0; i < profile.size(); ++i) {
    const Vec3& a = profile[i];
    const Vec3& b = profile[(i + 1) % profile.size()];
    t.push_back({{centre, b, a}});                             // z = 0 (the profile runs anticlockwise)
    t.push_back({{centre + dz * 6, a + dz * 6, b + dz * 6}});  // z = 60 mm
  }
  return t;
}

}  // namespace

TEST_CASE("short edges collapse with their wear kept, a plane's area kept and nothing folded",
          "[life][mesh_wear][collapse]") {
  // A plane of 8 x 8 mm cells facing +z, its fifth row of vertices drawn
  // to within 0.4 mm of the fourth.
  std::vector<Vec3> across;
  for (int i = 0; i <= 8; ++i) across.push_back({i * 8e-3, 0, 0});
  across[5].x = across[4].x + 0.4e-3;
  const std::vector<Triangle> plane = sheet(across, {0, 8e-3, 0}, 8);
  REQUIRE(area2(plane[0]).z > 0);
  std::vector<double> volume;
  for (std::size_t t = 0; t < plane.size(); ++t) volume.push_back(1e-9 * (1 + t % 7));
  const double booked = std::accumulate(volume.begin(), volume.end(), 0.0);
  const double total_area = 64e-3 * 64e-3;

  const life::Collapsed c = life::collapse_short_edges(plane, volume, 0, 0);
  // The strip's cross edges inside the plane (7 of its 9; the two on its
  // border have one triangle each) collapse, two triangles each.
  CHECK(c.edges == 7);
  CHECK(c.triangles.size() == plane.size() - 14);
  CHECK(std::accumulate(c.volume_m3.begin(), c.volume_m3.end(), 0.0) == Approx(booked).epsilon(1e-12));
  double a = 0;
  for (const Triangle& t : c.triangles) {
    CHECK(area2(t).z > 0);  // none folded
    a += area(t);
  }
  CHECK(a == Approx(total_area).epsilon(1e-12));
  // Nothing short: nothing changes.
  std::vector<Vec3> even;
  for (int i = 0; i <= 8; ++i) even.push_back({i * 8e-3, 0, 0});
  const std::vector<Triangle> flat = sheet(even, {0, 8e-3, 0}, 8);
  const life::Collapsed none = life::collapse_short_edges(flat, std::vector<double>(flat.size(), 1e-9), 0, 0);
  CHECK(none.edges == 0);
  CHECK(none.triangles.size() == flat.size());

  // A plane across the axis's end: a vertex on the end plane z = 0 keeps
  // its place, its short edge's other end comes to it.
  std::vector<Vec3> rows;  // along z from the end plane: 0, 0.3, 8, 16 ... mm
  const std::vector<double> zs = {0, 0.3e-3, 8e-3, 16e-3, 24e-3};
  std::vector<Triangle> end_sheet;
  for (std::size_t i = 0; i + 1 < zs.size(); ++i)
    for (int j = 0; j < 4; ++j) {
      const Vec3 p{j * 8e-3, 0.4, zs[i]}, q{(j + 1) * 8e-3, 0.4, zs[i]}, r{(j + 1) * 8e-3, 0.4, zs[i + 1]},
          u{j * 8e-3, 0.4, zs[i + 1]};
      end_sheet.push_back({{p, r, q}});
      end_sheet.push_back({{p, u, r}});
    }
  const life::Collapsed e = life::collapse_short_edges(end_sheet, std::vector<double>(end_sheet.size(), 1e-9), 0, 1);
  CHECK(e.edges == 3);  // the three inner ones of the 0.3 mm row (its two on the border have one triangle)
  std::set<double> left;  // x of the points still 0.3 mm from the plane
  for (const Triangle& t : e.triangles)
    for (const Vec3& p : t.v) {
      CHECK((p.z == 0 || p.z == 0.3e-3 || p.z >= 8e-3 - 1e-12));  // to the plane, not halfway
      if (p.z == 0.3e-3) left.insert(p.x);
    }
  CHECK(left == std::set<double>{0.0, 32e-3});
}

TEST_CASE("a closed part of four vertices is not collapsed into a two-sided sheet", "[life][mesh_wear][collapse]") {
  // A tetrahedron with one edge 0.1 mm long, the others 10 mm: collapsing
  // it would leave two triangles of the same corners, facing apart.
  const Vec3 a{0, 0, 0}, b{0.1e-3, 0, 0}, c{0.05e-3, 10e-3, 0}, d{0.05e-3, 3e-3, 9e-3};
  std::vector<Triangle> tet = {{{a, c, b}}, {{a, b, d}}, {{b, c, d}}, {{a, d, c}}};
  double v6 = 0;
  for (const Triangle& t : tet) v6 += t.v[0].dot(cross3(t.v[1], t.v[2]));
  REQUIRE(v6 > 0);  // facing out
  const life::Collapsed k = life::collapse_short_edges(tet, std::vector<double>(4, 1e-9), 0, 0, 0.5);
  CHECK(k.edges == 0);
  CHECK(k.triangles.size() == 4);
}

TEST_CASE("a bar whose worn corner drew a thin strip: turned over as it stands, kept by relaxation or by "
          "collapsing the strip", "[life][mesh_wear][collapse]") {
  const std::vector<Triangle> bar = worn_bar(0.8);
  // The corner's wear: the strip, and the top's and the face's rows next
  // to it, 2 mm deep; the rest of the top 0.5 mm.
  std::vector<double> volume;
  for (std::size_t t = 0; t < bar.size(); ++t) {
    const std::size_t segment = t / 12;  // of the profile: 6 quads along z, 2 triangles each
    const double depth = segment >= 4 && segment <= 6 ? 2e-3 : segment == 2 || segment == 3 ? 0.5e-3 : 0.0;
    volume.push_back(area(bar[t]) * depth);
  }
  const double booked = std::accumulate(volume.begin(), volume.end(), 0.0);
  const life::MeshBounds bounds{0, -1e-6, 60e-3 + 1e-6};
  // Moved as it stands: the strip's two rows move along their own faces'
  // normals and past each other.
  CHECK_THROWS_WITH(life::wear_mesh(bar, volume, bounds, 0, "bar", false), Catch::Contains("bar: triangle") &&
                                                                             Catch::Contains("turns it over"));
  // Relaxed: the strip's vertices (their faces within 50° of one
  // another) slide apart along the surface; the booked volume removed.
  const life::MeshWear r = life::wear_mesh(bar, volume, bounds, 0, "bar");
  CHECK(r.relaxed > 0);
  CHECK(r.removed_m3 == Approx(booked).epsilon(1e-6));
  for (std::size_t t = 0; t < bar.size(); ++t) {
    CHECK(area2(r.triangles[t]).dot(area2(bar[t])) > 0);
    for (int k = 0; k < 3; ++k) {
      const Vec3& was = bar[t].v[k];
      const Vec3& now = r.triangles[t].v[k];
      // The feet (an open edge on the shell) and the unworn trailing face
      // (three or more rings from the spoiled strip) stay where they were.
      if (was.y == 0 || (was.x == 30e-3 && was.y < 25e-3)) {
        CHECK(now.x == was.x);
        CHECK(now.y == was.y);
        CHECK(now.z == was.z);
      }
    }
  }
  // Collapsed first, as a study does: the strip's five inner cross edges
  // go (its two at the mesh's open ends have one triangle each, and stay),
  // its wear kept; the worn mesh is one, with the booked volume removed.
  const life::Collapsed c = life::collapse_short_edges(bar, volume, 0, 60e-3);
  CHECK(c.edges == 5);
  CHECK(c.triangles.size() == bar.size() - 10);
  CHECK(std::accumulate(c.volume_m3.begin(), c.volume_m3.end(), 0.0) == Approx(booked).epsilon(1e-12));
  const life::MeshWear w = life::wear_mesh(c.triangles, c.volume_m3, bounds, 0, "bar");
  CHECK(w.removed_m3 == Approx(booked).epsilon(1e-6));
  for (std::size_t t = 0; t < w.triangles.size(); ++t) CHECK(area2(w.triangles[t]).dot(area2(c.triangles[t])) > 0);
}

// Six times the signed volume a surface encloses with the origin: for two
// surfaces with the same rim, their difference is the volume between them.
double volume6(const std::vector<Triangle>& m) {
  double v = 0;
  for (const Triangle& t : m) v += t.v[0].dot(cross3(t.v[1], t.v[2]));
  return v;
}

// Closed and consistently wound: each directed edge (by coordinates) once,
// and its reverse once.
bool closed(const std::vector<Triangle>& m) {
  std::map<std::pair<std::array<double, 3>, std::array<double, 3>>, int> uses;
  for (const Triangle& t : m)
    for (int k = 0; k < 3; ++k) {
      const Vec3 &a = t.v[k], &b = t.v[(k + 1) % 3];
      ++uses[{{a.x, a.y, a.z}, {b.x, b.y, b.z}}];
    }
  for (const auto& [e, n] : uses)
    if (n != 1 || !uses.count({e.second, e.first})) return false;
  return true;
}

TEST_CASE("a stage's mesh kept fit: no collapse where none is needed, the first share that keeps it one, the "
          "collapse's own volume counted, a spoiled move named, other refusals at once",
          "[life][mesh_wear][collapse]") {
  const life::MeshBounds bounds{0, -1e-6, 60e-3 + 1e-6};
  // The closed bar with a 2.5 mm strip; wear on its corner (the strip and
  // the rows of the top and the face next to it), none on its base and ends.
  const std::vector<Triangle> bar = closed_bar(2.5);
  REQUIRE(volume6(bar) / 6 == Approx((30e-3 * 25e-3 - 0.5 * std::pow(2.5e-3 / std::sqrt(2.0), 2)) * 60e-3));
  auto corner_wear = [&](double depth) {
    std::vector<double> volume;
    for (std::size_t t = 0; t < bar.size(); ++t) {
      const std::size_t segment = t / 12;  // the profile's sheet first: 9 segments of 12 triangles
      volume.push_back(area(bar[t]) * (t < 108 && segment >= 4 && segment <= 6 ? depth : 0.0));
    }
    return volume;
  };
  // 2 mm: the plain move keeps the mesh one; nothing collapsed.
  std::vector<double> volume = corner_wear(2e-3);
  const life::FitWear plain = life::wear_kept_fit(bar, volume, bounds, 0, 0, "bar");
  CHECK(plain.share == 0);
  CHECK(plain.collapsed.edges == 0);
  CHECK(plain.collapsed.triangles.size() == bar.size());
  CHECK((volume6(bar) - volume6(plain.wear.triangles)) / 6 ==
        Approx(std::accumulate(volume.begin(), volume.end(), 0.0)).epsilon(1e-6));
  // 6 mm: the plain move spoils it; collapsed at a quarter of the median
  // edge (the strip's seven cross edges) it wears. The collapse took metal
  // of its own (the closed meshes' enclosed volumes, before and after);
  // the move removes the rest, so the solid loses the volume booked.
  volume = corner_wear(6e-3);
  const double booked = std::accumulate(volume.begin(), volume.end(), 0.0);
  const life::FitWear f = life::wear_kept_fit(bar, volume, bounds, 0, 0, "bar");
  CHECK(f.share == 0.25);
  CHECK(f.collapsed.edges == 7);
  const double taken = (volume6(bar) - volume6(f.collapsed.triangles)) / 6;
  CHECK(taken > 0.01 * booked);  // a chamfer's worth: not nothing
  CHECK(f.collapsed.removed_m3 == Approx(taken).epsilon(1e-9));
  CHECK((volume6(bar) - volume6(f.wear.triangles)) / 6 == Approx(booked).epsilon(1e-6));
  // 60 mm off a 25 mm bar's corner: no share keeps it, nor 8 steps; the
  // last one's refusal, a spoiled mesh, named.
  volume = corner_wear(60e-3);
  CHECK_THROWS_AS(life::wear_kept_fit(bar, volume, bounds, 0, 0, "bar"), life::MeshSpoiled);
  // A bar past the mill's end: refused as it is, not as a spoiled mesh.
  volume = corner_wear(2e-3);
  const life::MeshBounds short_mill{0, -1e-6, 50e-3};
  try {
    life::wear_kept_fit(bar, volume, short_mill, 0, 0, "bar");
    FAIL("no refusal");
  } catch (const life::MeshSpoiled& e) {
    FAIL(std::string("refused as spoiled: ") + e.what());
  } catch (const std::invalid_argument& e) {
    CHECK_THAT(e.what(), Catch::Contains("beyond the mill's ends"));
  }
}

TEST_CASE("a collapse's own volume is booked where it was taken, and the move is asked the rest there",
          "[life][mesh_wear][collapse]") {
  const std::vector<Triangle> bar = closed_bar(2.5);
  std::vector<double> volume;
  for (std::size_t t = 0; t < bar.size(); ++t) {
    const std::size_t segment = t / 12;
    volume.push_back(area(bar[t]) * (t < 108 && segment >= 4 && segment <= 6 ? 6e-3 : 0.5e-3));
  }
  const double booked = std::accumulate(volume.begin(), volume.end(), 0.0);
  const life::Collapsed c = life::collapse_short_edges(bar, volume, 0, 60e-3, 0.25);
  REQUIRE(c.edges == 7);
  REQUIRE(c.taken_m3.size() == c.triangles.size());
  // The locals add up to the whole, measured independently as the closed
  // bar's enclosed volume before and after.
  const double whole = (volume6(bar) - volume6(c.triangles)) / 6;
  REQUIRE(whole > 0.01 * 6e-3 * 2.5e-3 * 60e-3);
  CHECK(std::accumulate(c.taken_m3.begin(), c.taken_m3.end(), 0.0) == Approx(whole).epsilon(1e-9));
  // Taken only round the strip (the corner line at x 0.9, y 24.1 mm): no
  // triangle whose corners all lie further than one 10 mm ring from it.
  double near = 0;
  for (std::size_t t = 0; t < c.triangles.size(); ++t) {
    double closest = 1;
    for (const Vec3& v : c.triangles[t].v) closest = std::min(closest, std::hypot(v.x - 0.9e-3, v.y - 24.1e-3));
    if (closest > 11e-3) CHECK(c.taken_m3[t] == 0);
    else near += c.taken_m3[t];
  }
  CHECK(near == Approx(whole).epsilon(1e-9));
  // Unspread, the move is asked each triangle's booked less what the
  // collapse took from it, and the whole the booked less the collapse's.
  const std::vector<double> asked = life::asked_volumes(c, 0, 0);
  double sum = 0;
  for (std::size_t t = 0; t < asked.size(); ++t) {
    sum += asked[t];
    if (c.volume_m3[t] > c.taken_m3[t]) CHECK(asked[t] == Approx(c.volume_m3[t] - c.taken_m3[t]).epsilon(1e-9));
  }
  CHECK(sum == Approx(booked - whole).epsilon(1e-12));
  // The same bar 5 m off the axis (a plant mill's liner): the same
  // collapse, and each triangle takes the same volume.
  std::vector<Triangle> far = bar;
  for (Triangle& t : far)
    for (Vec3& v : t.v) v.x += 5.0;
  const life::Collapsed cf = life::collapse_short_edges(far, volume, 0, 60e-3, 0.25);
  REQUIRE(cf.taken_m3.size() == c.taken_m3.size());
  for (std::size_t t = 0; t < c.taken_m3.size(); ++t) CHECK(cf.taken_m3[t] == Approx(c.taken_m3[t]).margin(1e-6 * whole));
  // A collapse with nothing to take leaves the asked volumes as booked.
  const life::Collapsed none{bar, volume, 0, 0.0, {}};
  const std::vector<double> plain = life::asked_volumes(none, 0, 0);
  for (std::size_t t = 0; t < bar.size(); ++t) CHECK(plain[t] == Approx(volume[t]).epsilon(1e-12));
}

TEST_CASE("a move removes what each stretch was asked, not only the whole: a worn corner and a worn top "
          "side by side", "[life][mesh_wear][collapse]") {
  // Two closed bars 100 mm apart, one mesh: the first worn 3 mm on its
  // corner (convex: moving its faces by their depths removes less than
  // depth times area), the second 1 mm on its top.
  const std::vector<Triangle> a = closed_bar(2.5);
  std::vector<Triangle> mesh = a;
  for (Triangle t : a) {
    for (Vec3& v : t.v) v.x += 0.1;
    mesh.push_back(t);
  }
  const std::size_t n = a.size();
  std::vector<double> volume(mesh.size(), 0.0);
  for (std::size_t t = 0; t < n && t < 108; ++t) {
    const std::size_t segment = t / 12;
    if (segment >= 4 && segment <= 6) volume[t] = area(mesh[t]) * 3e-3;
    if (segment >= 2 && segment <= 4) volume[n + t] = area(mesh[n + t]) * 1e-3;
  }
  double booked_a = 0, booked_b = 0;
  for (std::size_t t = 0; t < n; ++t) booked_a += volume[t], booked_b += volume[n + t];
  const life::MeshBounds bounds{0, -1e-6, 60e-3 + 1e-6};
  // Each bar's volume lost, from its own closed surface before and after.
  auto lost = [&](const std::vector<Triangle>& worn, std::size_t from) {
    const std::vector<Triangle> b0(mesh.begin() + from, mesh.begin() + from + n);
    const std::vector<Triangle> b1(worn.begin() + from, worn.begin() + from + n);
    return (volume6(b0) - volume6(b1)) / 6;
  };
  // Spread 6 mm across, 20 mm along (within each bar: they are two parts).
  const std::vector<double> asked = life::smooth_wear(mesh, volume, 6e-3, 20e-3);
  // One depth scale for the whole: the whole is right, the bars are not.
  const life::MeshWear global = life::wear_mesh(mesh, asked, bounds, 0, "bars");
  REQUIRE(lost(global.triangles, 0) + lost(global.triangles, n) == Approx(booked_a + booked_b).epsilon(1e-6));
  const double off = std::abs(lost(global.triangles, 0) / booked_a - 1);
  INFO("one scale: the corner bar off by " << off);
  REQUIRE(off > 0.01);
  // Kept fit, corrected stretch by stretch: each bar loses what it booked.
  const life::FitWear f = life::wear_kept_fit(mesh, volume, bounds, 6e-3, 20e-3, "bars");
  INFO("passes " << f.local_passes << ", misfit " << f.local_misfit);
  CHECK(f.share == 0);
  CHECK(f.local_passes >= 1);
  CHECK(f.local_misfit <= life::kLocalTolerance);
  CHECK(lost(f.wear.triangles, 0) == Approx(booked_a).epsilon(0.003));
  CHECK(lost(f.wear.triangles, n) == Approx(booked_b).epsilon(0.003));
  CHECK(f.wear.removed_m3 == Approx(booked_a + booked_b).epsilon(1e-6));
  // One bar alone is one stretch: its one scale is already right.
  const std::vector<double> only_a(volume.begin(), volume.begin() + n);
  const life::FitWear g = life::wear_kept_fit(a, only_a, bounds, 6e-3, 20e-3, "bar");
  CHECK(g.local_passes == 0);
  CHECK(g.local_misfit < 1e-6);
}

TEST_CASE("a bar worn on its corner in one half of the mill and on its top in the other: each half removes what "
          "it was asked, given the segments", "[life][mesh_wear][collapse]") {
  const std::vector<Triangle> bar = closed_bar(2.5);
  // The profile's sheet: 9 segments of 6 rows of 10 mm along z, two
  // triangles a quad; rows 0-2 (z < 30 mm) worn 3 mm on the corner,
  // rows 3-5 1 mm on the top.
  std::vector<double> volume(bar.size(), 0.0);
  double booked[2] = {0, 0};
  for (std::size_t t = 0; t < 108; ++t) {
    const std::size_t segment = t / 12, row = (t % 12) / 2;
    if (row < 3 && segment >= 4 && segment <= 6) volume[t] = area(bar[t]) * 3e-3;
    if (row >= 3 && segment >= 2 && segment <= 4) volume[t] = area(bar[t]) * 1e-3;
    booked[row < 3 ? 0 : 1] += volume[t];
  }
  const life::MeshBounds bounds{0, -1e-6, 60e-3 + 1e-6};
  auto halves = [&](const life::FitWear& f) {
    const std::vector<double> swept = life::swept_volumes(f.collapsed.triangles, f.wear.triangles);
    std::array<double, 2> h{0, 0};
    for (std::size_t t = 0; t < swept.size(); ++t) {
      const auto& v = f.collapsed.triangles[t].v;
      h[(v[0].z + v[1].z + v[2].z) / 3 < 30e-3 ? 0 : 1] += swept[t];
    }
    return h;
  };
  // Unspread (across 0: each triangle moves its own volume); as one
  // stretch, the corner half is cut short.
  const life::FitWear one = life::wear_kept_fit(bar, volume, bounds, 0, 0, "bar");
  CHECK(one.local_passes == 0);
  const std::array<double, 2> h1 = halves(one);
  INFO("one stretch: " << h1[0] / booked[0] << ", " << h1[1] / booked[1]);
  REQUIRE(std::abs(h1[0] / booked[0] - 1) > 0.01);
  CHECK(h1[0] + h1[1] == Approx(booked[0] + booked[1]).epsilon(1e-6));
  // In two segments, each half is its own stretch.
  const life::FitWear two = life::wear_kept_fit(bar, volume, bounds, 0, 0, "bar", 2);
  INFO("passes " << two.local_passes << ", misfit " << two.local_misfit);
  CHECK(two.local_passes >= 1);
  const std::array<double, 2> h2 = halves(two);
  CHECK(h2[0] == Approx(booked[0]).epsilon(0.003));
  CHECK(h2[1] == Approx(booked[1]).epsilon(0.003));
  CHECK((volume6(bar) - volume6(two.wear.triangles)) / 6 == Approx(booked[0] + booked[1]).epsilon(1e-6));
}

TEST_CASE("a corner worn too deep for one move is worn in steps, each collapsed and moved on the last one's "
          "mesh: the solid loses what was booked, span by span", "[life][mesh_wear][collapse]") {
  const std::vector<Triangle> bar = closed_bar(2.5);
  // 15 mm off the corner of a 25 mm bar (the strip and the rows of the top
  // and the face beside it): rows 0-2 (z < 30 mm) and rows 3-5 alike.
  std::vector<double> volume(bar.size(), 0.0);
  double booked = 0;
  for (std::size_t t = 0; t < 108; ++t) {
    const std::size_t segment = t / 12;
    if (segment >= 4 && segment <= 6) volume[t] = area(bar[t]) * 15e-3;
    booked += volume[t];
  }
  const life::MeshBounds bounds{0, -1e-6, 60e-3 + 1e-6};
  // In one move no share keeps the mesh one.
  CHECK_THROWS_AS(life::wear_kept_fit(bar, volume, bounds, 0, 0, "bar", 2, 1), life::MeshSpoiled);
  const life::FitWear f = life::wear_kept_fit(bar, volume, bounds, 0, 0, "bar", 2);
  INFO("steps " << f.steps << ", edges " << f.edges << ", collapse " << f.collapse_m3 / booked << ", passes "
                 << f.local_passes << ", misfit " << f.local_misfit);
  CHECK(f.steps > 1);
  CHECK(f.edges > 0);
  // The closed solid's volume lost, against what the steps recorded.
  CHECK((volume6(bar) - volume6(f.wear.triangles)) / 6 == Approx(booked).epsilon(1e-6));
  CHECK(f.removed_m3 == Approx(booked).epsilon(1e-6));
  REQUIRE(f.span_asked_m3.size() == 2);
  REQUIRE(f.span_removed_m3.size() == 2);
  CHECK(f.span_removed_m3[0] + f.span_removed_m3[1] + f.collapse_m3 == Approx(booked).epsilon(1e-6));
  // The halves booked alike and were asked alike; each removed its ask.
  CHECK(f.span_asked_m3[0] == Approx(f.span_asked_m3[1]).epsilon(0.02));
  for (int g = 0; g < 2; ++g) CHECK(f.span_removed_m3[g] == Approx(f.span_asked_m3[g]).epsilon(0.003));
  // The mesh is one (closed: every edge between two triangles, each edge
  // run once each way; none crushed), and the worn bar lies within the new one: its rear face,
  // base and ends where they were, its worn face at most 0.5 mm outside
  // (a relaxed vertex slid within the mean plane round it), the corner
  // cut back at least 5 mm along its diagonal.
  double least_x = 1, least_y = 1, most_x = -1, corner = 1;
  CHECK(closed(f.wear.triangles));
  for (const Triangle& t : f.wear.triangles) {
    CHECK(area(t) > 1e-10);
    for (const Vec3& v : t.v) {
      least_x = std::min(least_x, v.x), least_y = std::min(least_y, v.y), most_x = std::max(most_x, v.x);
      CHECK(v.z >= -1e-9);
      CHECK(v.z <= 60e-3 + 1e-9);
      corner = std::min(corner, (std::hypot(v.x, 25e-3 - v.y)));  // nearest to the sharp corner's place
    }
  }
  CHECK(least_x > -0.5e-3);
  CHECK(least_y > -1e-6);
  CHECK(most_x == Approx(30e-3).margin(1e-9));
  CHECK(corner > 5e-3);
}

TEST_CASE("a corner worn deep in one half of the mill and hardly in the other: the steps remove the booked, "
          "each half its own ask", "[life][mesh_wear][collapse]") {
  const std::vector<Triangle> bar = closed_bar(2.5);
  const life::MeshBounds bounds{0, -1e-6, 60e-3 + 1e-6};
  // Rows 0-2 (z < 30 mm) worn 15 mm on the corner; rows 3-5 `light` on the top.
  for (const double light : {0.0, 0.1e-3, 1e-3}) {
    std::vector<double> volume(bar.size(), 0.0);
    double booked = 0;
    for (std::size_t t = 0; t < 108; ++t) {
      const std::size_t segment = t / 12, row = (t % 12) / 2;
      if (row < 3 && segment >= 4 && segment <= 6) volume[t] = area(bar[t]) * 15e-3;
      if (row >= 3 && segment >= 2 && segment <= 4) volume[t] = area(bar[t]) * light;
      booked += volume[t];
    }
    const life::FitWear f = life::wear_kept_fit(bar, volume, bounds, 0, 0, "bar", 2);
    INFO("light " << light * 1e3 << " mm: steps " << f.steps << ", collapse " << f.collapse_m3 / booked
                  << ", spans asked " << f.span_asked_m3[0] << ", " << f.span_asked_m3[1] << ", removed "
                  << f.span_removed_m3[0] << ", " << f.span_removed_m3[1] << ", misfit " << f.local_misfit);
    CHECK(f.steps > 1);
    // The closed solid loses the booked volume, whatever one half could not carry on.
    CHECK((volume6(bar) - volume6(f.wear.triangles)) / 6 == Approx(booked).epsilon(1e-6));
    CHECK(f.removed_m3 == Approx(booked).epsilon(1e-6));
    CHECK(f.span_removed_m3[0] + f.span_removed_m3[1] + f.collapse_m3 == Approx(booked).epsilon(1e-6));
    // What was asked of the halves, with the collapses', is the booked (each
    // step's scale makes its own whole; a shortfall counted twice shows in
    // the halves below, not here).
    CHECK(f.span_asked_m3[0] + f.span_asked_m3[1] + f.collapse_m3 == Approx(booked).epsilon(1e-6));
    // Each half its own ask where the wear steps down by a fifteenth
    // between them. (Where it drops to nothing, the row of vertices on the
    // boundary moves with the worn half and the unworn triangles beside it
    // are cut on a ramp half a row long: no correction undoes that, and
    // the halves are not held to their asks.)
    if (light >= 1e-3)
      for (int g = 0; g < 2; ++g) CHECK(f.span_removed_m3[g] == Approx(f.span_asked_m3[g]).epsilon(0.03));
    CHECK(closed(f.wear.triangles));
  }
}
