// `life --axial-segments N` on a mill of [lifters] bars wears their mesh
// twin (life/bar_twin.h): the twin against the bars it stands for (its
// enclosed volume against the bars' cross-sections by the shoelace formula
// times the length), and a study of the lab mill through the twin against
// the same study given the bars as the STL `check --write-lifters` writes,
// figure for figure; what the twin cannot do, refused by name.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "core/lifters.h"
#include "core/mill_case.h"
#include "core/wall_mesh.h"
#include "io/case_file.h"
#include "io/stl.h"
#include "app/life_picture.h"
#include "life/bar_twin.h"
#include "life_cli.h"
#include "text_file.h"

namespace fs = std::filesystem;
using namespace life_cli;

TEST_CASE("the bars' mesh twin encloses the bars' volume and replaces [lifters]", "[life][mesh_wear]") {
  const mc::MillCase c = mc::io::read_case(mc::io::default_case());
  const mc::MillDerived d = mc::derive(c);
  const std::vector<mc::Triangle> twin = mc::life::bar_twin_triangles(c, d, 0.01);
  // The bars cut at the shell, each cross-section's area by the shoelace
  // formula, times the mill's length.
  const mc::Scene w = mc::build_walls(c, d);
  const auto bars = mc::bars_on_shell(w.walls.lifters, w.walls.shell_radius);
  REQUIRE(bars.size() == 12);
  double area = 0;
  for (const auto& p : bars)
    for (std::size_t i = 0; i < p.size(); ++i) {
      const mc::Vec2 a = p[i], b = p[(i + 1) % p.size()];
      area += 0.5 * (a.x * b.y - b.x * a.y);
    }
  CHECK(mc::closed_mesh_volume(twin) == Approx(area * c.length).epsilon(1e-5));
  // And by the profile alone: each bar h (top + h tan θ) on the tangent
  // at its foot (the case's derived lifter volume), less what lies beyond
  // the shell (a³/3R, a the foot's half-width) and the sliver between the
  // chord that closes the cut bar and the shell (2a³/3R), to order (a/R)².
  const double a = 0.5 * c.lifter_pattern[0].top_width +
                   c.lifter_pattern[0].height * std::tan(c.lifter_pattern[0].face_angle_deg * M_PI / 180);
  const double cut = c.lifter_rows * c.length * a * a * a / (0.5 * c.diameter);
  std::printf("twin %.9g m3, shoelace %.9g m3, profile %.9g m3 less %.4g m3 cut at the shell\n",
              mc::closed_mesh_volume(twin), area * c.length, d.lifter_volume, cut);
  CHECK(cut > 0.02 * d.lifter_volume);
  CHECK(mc::closed_mesh_volume(twin) == Approx(d.lifter_volume - cut).epsilon(2e-3));
  // Every coordinate is a 32-bit float, as the STL holds it; no triangle
  // runs more than 10 mm along the mill.
  bool floats = true;
  for (const mc::Triangle& t : twin)
    for (const mc::Vec3& v : t.v)
      for (const double x : {v.x, v.y, v.z}) floats = floats && x == static_cast<double>(static_cast<float>(x));
  CHECK(floats);
  double longest = 0;
  for (const mc::Triangle& t : twin)
    for (int k = 0; k < 3; ++k) longest = std::max(longest, std::fabs(t.v[k].z - t.v[(k + 1) % 3].z));
  CHECK(longest <= 0.01 + 1e-6);
  const mc::MillCase t = mc::life::with_bar_twin(c, twin, "/tmp/bars.stl");
  CHECK(t.lifter_rows == 0);
  REQUIRE(t.meshes.size() == c.meshes.size() + 1);
  CHECK(t.meshes.back().part == mc::MeshPart::lifters);
  CHECK(t.meshes.back().turning);
  CHECK(t.meshes.back().path == "/tmp/bars.stl");
  CHECK(t.meshes.back().triangles.size() == twin.size());
  // The default size: the largest ball's radius, at most half a segment.
  CHECK(mc::life::default_twin_edge(0.0254, 0.15, 2) == Approx(0.0127));
  CHECK(mc::life::default_twin_edge(0.0254, 0.15, 6) == Approx(0.0125));
  CHECK(mc::life::default_twin_edge(0.15, 4.189, 5) == Approx(0.075));
}

TEST_CASE("life --axial-segments on bars of [lifters] is the study of their STL, figure for figure",
          "[life][cli][mesh_wear]") {
  const fs::path a = scratch("twin"), b = scratch("twin-stl"), bars = scratch("twin-25mm.stl");
  REQUIRE(std::system((std::string(MC_BINARY) + " check --write-lifters '" + bars.string() +
                       "' --lifter-mesh 25 >/dev/null 2>&1")
                          .c_str()) == 0);
  const std::string span = " --stages 1 --hours 4000 --axial-segments 2" + kShort;
  std::string err;
  REQUIRE(life(span + " --lifter-mesh 25 --out '" + a.string() + "'", &err) == 0);
  INFO(err);
  REQUIRE(life(std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --set walls.mesh.0.file='" + bars.string() + "'" +
                   span + " --out '" + b.string() + "'",
               &err) == 0);
  // The twin is check --write-lifters' mesh, and stage 0's case wears it.
  const auto written = mc::io::read_stl(bars).triangles, twin = mc::io::read_stl(a / "new-bars.stl").triangles;
  REQUIRE(twin.size() == written.size());
  bool same = true;
  for (std::size_t i = 0; i < twin.size(); ++i)
    for (int k = 0; k < 3; ++k) same = same && (twin[i].v[k] - written[i].v[k]).norm() == 0;
  CHECK(same);
  const mc::MillCase s0 = mc::io::read_case(a / "cases" / "stage-00.toml");
  CHECK(s0.lifter_rows == 0);
  REQUIRE(s0.meshes.size() == 1);
  CHECK(fs::equivalent(s0.meshes[0].path, a / "new-bars.stl"));
  CHECK(nlohmann::json::parse(read_text(a / "life.json"))["request"]["bars_as_mesh_mm"] == 25.0);
  // The two studies, figure for figure: each stage's mesh, each segment.
  for (const char* table : {"life_meshes.csv", "life_segments.csv"}) {
    const auto ta = read_csv(a / table), tb = read_csv(b / table);
    REQUIRE(ta.size() == tb.size());
    REQUIRE(ta.size() >= 2);
    for (std::size_t i = 0; i < ta.size(); ++i)
      for (const auto& [key, value] : tb[i]) {
        if (key == "file") continue;  // stage 0's: new-bars.stl against the STL given
        INFO(table << " row " << i << " " << key);
        CHECK(ta[i].at(key) == value);
      }
  }
  CHECK(read_csv(a / "life_meshes.csv")[0].at("booked_cm3") != "0");
  const auto worn_a = mc::io::read_stl(a / "stage-01" / "liner.stl").triangles;
  const auto worn_b = mc::io::read_stl(b / "stage-01" / "liner.stl").triangles;
  REQUIRE(worn_a.size() == worn_b.size());
  double apart = 0, moved = 0;
  for (std::size_t i = 0; i < worn_a.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      apart = std::max(apart, (worn_a[i].v[k] - worn_b[i].v[k]).norm());
      if (i < written.size()) moved = std::max(moved, (worn_a[i].v[k] - written[i].v[k]).norm());
    }
  CHECK(apart == 0);
  CHECK(moved > 1e-5);  // worn
  // life.png's panels along the mill: the bars per segment, a point per
  // stage, and the impact point per liner bin with its widest spread.
  const auto along = mc::app::life::along_plots("lab", a, true);
  REQUIRE(along.size() == 3);
  for (int p = 0; p < 2; ++p) {
    REQUIRE(along[p].series.size() == 2);
    CHECK(along[p].series[0].label == "0 to 0.075 m");
    CHECK(along[p].series[1].label == "0.075 to 0.15 m");
    CHECK(along[p].series[1].y.size() == 2);
  }
  CHECK(along[0].series[0].y[0] == Approx(20).margin(1e-3));  // the new bar's face
  CHECK(along[2].series.size() >= 2);  // the liner's axial bins
  CHECK(err.find("life.png") == std::string::npos);  // drawn, panels along the mill included
  CHECK(fs::exists(a / "life.png"));
  CHECK(mc::app::life::along_plots("lab", b / "cases", true).empty());  // no segments there
  // Resumed, it wears the same twin and runs nothing again.
  const std::string twin_bytes = read_text(a / "new-bars.stl"), table_a = read_text(a / "life_meshes.csv");
  REQUIRE(life(span + " --lifter-mesh 25 --out '" + a.string() + "'", &err) == 0);
  CHECK(read_text(a / "new-bars.stl") == twin_bytes);
  CHECK(read_text(a / "life_meshes.csv") == table_a);
  CHECK_FALSE(fs::exists(a / "stage-02"));
  // Another triangle size is another study.
  CHECK(life(span + " --lifter-mesh 20 --out '" + a.string() + "'", &err) == 2);
  CHECK(err.find("bars_as_mesh_mm") != std::string::npos);
  fs::remove_all(a);
  fs::remove_all(b);
  fs::remove(bars);
}
