// STL meshes: reading both forms, the lifters written as a mesh, and the
// bad meshes refused with the file and the triangle named.
#include "io/stl.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "core/lifters.h"

using mc::Triangle;
using mc::Vec3;
using mc::io::MeshError;
using mc::io::parse_stl;

namespace {

std::vector<Triangle> two_triangles() {  // a unit square in z = 0, facing +z
  return {{{Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{1, 1, 0}}}, {{Vec3{0, 0, 0}, Vec3{1, 1, 0}, Vec3{0, 1, 0}}}};
}

std::string message_of(const std::string& bytes, const std::string& source = "bad.stl") {
  try {
    parse_stl(bytes, source);
  } catch (const MeshError& e) {
    return e.what();
  }
  return "(accepted)";
}

std::string ascii_facet(const std::string& a, const std::string& b, const std::string& c) {
  return "facet normal 0 0 1\nouter loop\nvertex " + a + "\nvertex " + b + "\nvertex " + c +
         "\nendloop\nendfacet\n";
}

}  // namespace

TEST_CASE("STL: binary and ASCII read back what was written, in metres or millimetres", "[stl]") {
  const auto tris = two_triangles();
  for (const bool binary : {true, false}) {
    const std::string bytes = binary ? mc::io::stl_binary(tris, "solid header of a binary file")
                                     : mc::io::stl_ascii(tris, "square");
    const auto m = parse_stl(bytes, "square.stl", 0.001);
    CHECK(m.binary == binary);
    REQUIRE(m.triangles.size() == 2);
    for (std::size_t k = 0; k < 2; ++k)
      for (int v = 0; v < 3; ++v) {
        CHECK(m.triangles[k].v[v].x == Approx(0.001 * tris[k].v[v].x).margin(1e-12));
        CHECK(m.triangles[k].v[v].y == Approx(0.001 * tris[k].v[v].y).margin(1e-12));
      }
    CHECK(mc::io::triangle_normal(m.triangles[1]).z == Approx(1.0));
  }
  // A binary file whose 80-byte header begins with "solid" (as many CAD
  // tools write it) is still read as binary: its size matches its count.
  CHECK(parse_stl(mc::io::stl_binary(tris, "solid part"), "cad.stl").binary);
}

TEST_CASE("STL: the lab mill's lifters as a closed mesh facing out of each bar", "[stl]") {
  const double radius = 0.45, length = 0.15;
  const auto bars = mc::lifter_rows(radius, 12, {mc::LifterProfile{0.025, 0.03, 20}});
  const auto tris = mc::lifter_triangles(bars, length);
  REQUIRE(tris.size() == 12 * (4 * 2 + 2 * 2));
  double volume = 0;  // divergence theorem: a closed, outward mesh has positive volume
  for (const Triangle& t : tris) {
    const Vec3 n = mc::io::triangle_normal(t);
    const Vec3 c = (t.v[0] + t.v[1] + t.v[2]) * (1.0 / 3.0);
    // Outward: away from the axis of the bar it belongs to (the nearest bar centre).
    const auto& bar = bars[static_cast<std::size_t>(
        std::lround(std::fmod(std::atan2(c.y, c.x) + 2 * M_PI, 2 * M_PI) / (2 * M_PI / 12)) % 12)];
    Vec3 centre{0, 0, 0.5 * length};
    for (const auto& p : bar) centre = centre + Vec3{p.x, p.y, 0} * 0.25;
    CHECK((c - centre).dot(n) > 0);
    const Vec3 e1 = t.v[1] - t.v[0], e2 = t.v[2] - t.v[0];
    volume += t.v[0].dot(Vec3{e1.y * e2.z - e1.z * e2.y, e1.z * e2.x - e1.x * e2.z, e1.x * e2.y - e1.y * e2.x}) / 6;
  }
  // Twelve trapezoids (top 30 mm, 25 mm + 6.25 mm behind the shell, faces at 20°) times the length.
  const double h = 0.025 * 1.25, top = 0.03, base = top + 2 * h * std::tan(20 * M_PI / 180);
  CHECK(volume == Approx(12 * 0.5 * (top + base) * h * length).epsilon(1e-9));
  // Written and read back, the mesh passes the reader's checks.
  CHECK(parse_stl(mc::io::stl_binary(tris), "lifters.stl").triangles.size() == tris.size());
}

TEST_CASE("STL: bad meshes are refused with the file and the triangle named", "[stl]") {
  const auto good_binary = mc::io::stl_binary(two_triangles());
  const std::string f1 = ascii_facet("0 0 0", "1 0 0", "1 1 0");
  const std::string f2 = ascii_facet("0 0 0", "1 1 0", "0 1 0");

  CHECK(message_of("") == "bad.stl: empty file, not an STL");
  CHECK_THAT(message_of("PK\x03\x04 a zip file"), Catch::Contains("not an STL") && Catch::Contains("15 bytes"));
  // A binary file cut short: its count no longer matches its size.
  CHECK_THAT(message_of(good_binary.substr(0, good_binary.size() - 7)),
             Catch::Contains("truncated binary STL: its header counts 2 triangles (184 bytes), the file has 177"));
  CHECK_THAT(message_of(good_binary + "extra"), Catch::Contains("not an STL") && Catch::Contains("189 bytes"));
  // ASCII cut in a facet and cut before endsolid.
  CHECK_THAT(message_of("solid s\n" + f1 + "facet normal 0 0 1\nouter loop\nvertex 0 0"),
             Catch::Contains("bad.stl:11: truncated: the file ends in triangle 2"));
  CHECK_THAT(message_of("solid s\n" + f1 + f2), Catch::Contains("ends after 2 triangles without \"endsolid\""));
  CHECK_THAT(message_of("solid s\n" + f1 + ascii_facet("0 0 0", "1 x 0", "0 1 0") + "endsolid\n"),
             Catch::Contains("bad.stl:12: triangle 2: vertex 2 \"x\" is not a number"));
  CHECK_THAT(message_of("solid s\n" + f1 + "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n"),
             Catch::Contains("expected \"vertex\" in triangle 2, got \"endloop\""));
  // Not finite, in both forms.
  CHECK_THAT(message_of("solid s\n" + f1 + ascii_facet("0 0 0", "nan 0 0", "0 1 0") + "endsolid\n"),
             Catch::Contains("bad.stl:9: triangle 2: vertex 2 is not a finite number"));
  {
    std::string b = good_binary;
    const float inf = std::numeric_limits<float>::infinity();
    std::memcpy(&b[84 + 50 + 12 + 12 * 2 + 4], &inf, 4);  // triangle 2, vertex 3, y
    CHECK(message_of(b) == "bad.stl: triangle 2: vertex 3 is not a finite number (0, inf, 0)");
  }
  // A vertex far out of range is named as such, not as a zero-area triangle, in both forms.
  CHECK(message_of("solid s\n" + f1 + ascii_facet("0 0 0", "1 0 0", "0 1e30 0") + "endsolid\n") ==
        "bad.stl:9: triangle 2: vertex 3 is out of range: its y coordinate is 1e+30 m (after scaling), beyond the "
        "limit |y| <= 10000 m (is the file in the units that mesh.scale assumes?)");
  {
    std::string b = good_binary;
    const float far = -2e4f;
    std::memcpy(&b[84 + 12 + 12 * 1], &far, 4);  // triangle 1, vertex 2, x
    CHECK_THAT(message_of(b), Catch::StartsWith("bad.stl: triangle 1: vertex 2 is out of range: its x coordinate is "
                                                "-20000 m") &&
                                  Catch::Contains("limit |x| <= 10000 m"));
  }
  // Zero area: repeated vertices, and three vertices on a line.
  CHECK_THAT(message_of("solid s\n" + f1 + ascii_facet("0 0 0", "1 1 0", "1 1 0") + "endsolid\n"),
             Catch::Contains("triangle 2: has zero area (vertices 2 and 3 coincide)"));
  CHECK_THAT(message_of("solid s\n" + ascii_facet("0 0 0", "1 1 1", "2 2 2") + "endsolid\n"),
             Catch::Contains("triangle 1: has zero area (its vertices lie on a line"));
  // A triangle repeated, its vertices in another order.
  CHECK_THAT(message_of("solid s\n" + f1 + f2 + ascii_facet("1 1 0", "0 0 0", "1 0 0") + "endsolid\n"),
             Catch::Contains("triangle 3: repeats triangle 1"));
  CHECK(message_of("solid empty\nendsolid empty\n") == "bad.stl: the mesh has no triangles");
  CHECK_THAT(message_of("solid s\nfacet normal 0 0 1\nendloop\nendsolid\n"),
             Catch::Contains("expected \"outer\" in triangle 1"));
  // And a file that is not there.
  try {
    mc::io::read_stl("/nonexistent/liner.stl");
    FAIL("accepted a missing file");
  } catch (const MeshError& e) {
    CHECK_THAT(e.what(), Catch::Contains("/nonexistent/liner.stl: cannot be read"));
  }
  // And a directory where a file was meant.
  try {
    mc::io::read_stl(std::filesystem::temp_directory_path());
    FAIL("accepted a directory");
  } catch (const MeshError& e) {
    CHECK(std::string(e.what()) == std::filesystem::temp_directory_path().string() +
                                       ": is a directory, not a file (give the path of an .stl file)");
  }
}
