// A life study of a mesh liner end to end (app/life_mesh.h): the lab mill
// with its 12 bars from an STL (assets/cases/lab_stl.toml) over two short
// stages. The volume each worn mesh lost, by its own enclosed volume,
// against what its triangles booked in the stage's wear.csv; the next
// stage's case naming the worn mesh; the bars measured across as the
// parametric bar they were cut from; a resumed study; a wear too deep for
// the mesh stopped by name with its stages kept.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/mill_case.h"
#include "core/wall_mesh.h"
#include "io/case_file.h"
#include "io/csv_read.h"
#include "io/stl.h"
#include "life_cli.h"
#include "text_file.h"

namespace fs = std::filesystem;
using namespace life_cli;

TEST_CASE("a mesh liner wears by what its triangles booked, stage by stage", "[life][cli][mesh_wear]") {
  const fs::path a = scratch("mesh"), bars = scratch("bars-25mm.stl");
  // The lab mill's bars as a mesh of faces cut 25 mm across and along
  // (1,344 triangles; vertex rings at mid-length, where they are measured).
  REQUIRE(std::system((std::string(MC_BINARY) + " check --write-lifters '" + bars.string() +
                       "' --lifter-mesh 25 >/dev/null 2>&1")
                          .c_str()) == 0);
  const std::string study = std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --set walls.mesh.0.file='" +
                            bars.string() + "' --stages 2 --hours 4000" + kShort + " --out '" + a.string() + "'";
  std::string err;
  REQUIRE(life(study, &err) == 0);
  INFO(err);
  // The bars stand on the end plates: the plates are held as they are.
  CHECK(nlohmann::json::parse(read_text(a / "life.json"))["request"]["end_plates"] == "held");
  CHECK(!fs::exists(a / "life_plates.csv"));
  const auto meshes = read_csv(a / "life_meshes.csv");
  const auto rows = read_csv(a / "life.csv");
  REQUIRE(meshes.size() == 3);
  REQUIRE(rows.size() == 3);
  const fs::path files[3] = {bars, a / "stage-01" / "liner.stl", a / "stage-02" / "liner.stl"};
  // The new bars as the parametric lab bar (25 mm, 20° faces).
  CHECK(num(meshes[0], "parts") == 12);
  CHECK(num(meshes[0], "mid_height_mm") == Approx(25).margin(1e-3));
  CHECK(num(meshes[0], "mid_leading_angle_deg") == Approx(20).margin(1e-3));
  CHECK(num(meshes[0], "mid_trailing_angle_deg") == Approx(20).margin(1e-3));
  double R[3];
  for (int i = 0; i < 3; ++i) R[i] = 0.5 * num(rows[i], "diameter_m");
  for (int i = 0; i < 2; ++i) {
    INFO("stage " << i);
    const fs::path run = a / ("stage-0" + std::to_string(i));
    const double hours = num(rows[i], "stage_hours");
    CHECK(hours == Approx(2000));
    // Booked: the stage's wear.csv, mesh 0's triangles, each its depth rate
    // (mm per 1000 h, both wears at the case's coefficients) over its area
    // for the stage's hours.
    const mc::io::CsvTable wear = mc::io::read_csv_strict(run / "wear.csv");
    double booked = 0, mesh_kg_h = 0;
    int triangles = 0;
    for (std::size_t k = 0; k < wear.rows.size(); ++k)
      if (wear.rows[k][wear.column("part")] == "mesh") {
        CHECK(wear.number(k, wear.column("row")) == 0);
        booked += wear.number(k, wear.column("wear_mm_per_1000h")) * wear.number(k, wear.column("area_m2")) / 3.6e9 *
                  hours * 3600;
        mesh_kg_h += wear.number(k, wear.column("wear_kg_per_h"));
        ++triangles;
      }
    CHECK(triangles == 1344);
    REQUIRE(booked > 1e-6);
    CHECK(num(meshes[i], "booked_cm3") * 1e-6 == Approx(booked).epsilon(1e-4));
    CHECK(num(meshes[i], "removed_cm3") == Approx(num(meshes[i], "booked_cm3")).epsilon(1e-5));
    // The least-squares move itself removes the booked volume to a few
    // percent: the scale that makes it exact is near 1, no vertex moves
    // far.
    CHECK(std::abs(num(meshes[i], "depth_scale") - 1) < 0.1);
    CHECK(num(meshes[i], "deepest_mm") < 15);
    // Removed: what the closed bars enclose, before against after (the
    // worn mesh as the study wrote it, binary STL in float).
    const auto before = mc::io::read_stl(files[i]).triangles, after = mc::io::read_stl(files[i + 1]).triangles;
    REQUIRE(after.size() == before.size());
    CHECK(mc::closed_mesh_volume(before) - mc::closed_mesh_volume(after) == Approx(booked).epsilon(0.01));
    // Inside the worn shell and between the end plates.
    for (const mc::Triangle& t : after)
      for (const mc::Vec3& v : t.v) {
        CHECK(std::hypot(v.x, v.y) <= R[i + 1] + 1e-6);
        CHECK(v.z >= -1e-6);
        CHECK(v.z <= 0.15 + 1e-6);
      }
    // The shell and lifters' wear: the run's shell part and the mesh's triangles.
    const nlohmann::json summary = nlohmann::json::parse(read_text(run / "summary.json"));
    double shell = 0, shell_mm = 0;
    for (const auto& part : summary.at("liner").at("parts"))
      if (part.at("part") == "shell")
        shell = part.at("wear_kg_per_h").get<double>(), shell_mm = part.at("mean_wear_mm_per_1000h").get<double>();
    CHECK(num(rows[i], "shell_lifters_wear_kg_per_h") == Approx(shell + mesh_kg_h).epsilon(1e-4));
    // The shell falls by its wear over the area the bars leave bare: the
    // run books it over the whole cylinder. The lab bar's feet meet the
    // shell where its 20° faces, 15 mm off the centre at the top, cross the
    // circle: 12 arcs of that width over the circumference.
    double x = 0.03;
    for (int it = 0; it < 50; ++it) x = 0.015 + (0.025 - (R[0] - std::sqrt(R[0] * R[0] - x * x))) * std::tan(20 * M_PI / 180);
    const double covered = 12 * 2 * R[0] * std::asin(x / R[0]) / (2 * M_PI * R[0]);
    CHECK(covered == Approx(0.2).margin(0.01));
    CHECK(num(rows[i + 1], "shell_wear_mm") - num(rows[i], "shell_wear_mm") ==
          Approx(shell_mm * hours / 1000 / (1 - covered)).epsilon(0.01));
    // The next stage's case names the worn mesh, and its run read it.
    for (const fs::path& c : {a / "cases" / ("stage-0" + std::to_string(i + 1) + ".toml"),
                              a / ("stage-0" + std::to_string(i + 1)) / "case.toml"}) {
      const mc::MillCase next = mc::io::read_case(c);
      REQUIRE(next.meshes.size() == 1);
      CHECK(fs::equivalent(next.meshes[0].path, files[i + 1]));
    }
  }
  // The worn bars lower, measured across (above the worn shell, which
  // fell by a fraction of a millimetre), their faces laid back.
  CHECK(num(meshes[2], "mid_height_mm") < 24.9);
  CHECK(num(meshes[2], "mid_leading_angle_deg") > 20.05);
  CHECK(rows[2].at("profile").empty());
  // Resumed: nothing runs again, nothing changes; asked for segments
  // along the mill, it tables them.
  const std::string table = read_text(a / "life_meshes.csv"), stl = read_text(files[2]);
  REQUIRE(life(study + " --axial-segments 2", &err) == 0);
  CHECK(read_text(a / "life_meshes.csv") == table);
  CHECK(read_text(files[2]) == stl);
  const auto seg = read_csv(a / "life_segments.csv");
  REQUIRE(seg.size() == 6);
  for (int i = 0; i < 3; ++i) {
    INFO("stage " << i);
    double booked = 0, smoothed = 0, removed = 0;
    for (int g = 0; g < 2; ++g) {
      const auto& r = seg[2 * i + g];
      CHECK(num(r, "stage") == i);
      CHECK(num(r, "segment") == g);
      CHECK(num(r, "z_from_m") == Approx(0.075 * g));
      CHECK(num(r, "z_to_m") == Approx(0.075 * (g + 1)));
      CHECK(num(r, "bars") == 12);
      if (i == 0) CHECK(num(r, "leading_angle_deg") == Approx(20).margin(1e-3));
      if (i < 2) {
        booked += num(r, "booked_cm3"), smoothed += num(r, "smoothed_cm3"), removed += num(r, "removed_cm3");
        // The move removes each segment's share of the smoothed wear.
        CHECK(num(r, "removed_cm3") == Approx(num(r, "smoothed_cm3")).epsilon(0.01));
      }
    }
    if (i < 2) {
      CHECK(booked == Approx(num(meshes[i], "booked_cm3")).epsilon(1e-4));
      CHECK(smoothed == Approx(booked).epsilon(1e-4));
      CHECK(removed == Approx(num(meshes[i], "removed_cm3")).epsilon(1e-3));
      // What the move recorded in life.json as it moved the mesh (one
      // step, one span: the study ran without segments), against the
      // table's working from the two stages' meshes.
      const nlohmann::json w = nlohmann::json::parse(read_text(a / "life.json"))["stages"][i]["meshes"][0]["wear"];
      CHECK(w.at("steps").get<int>() == 1);
      CHECK(num(meshes[i], "move_steps") == 1);
      REQUIRE(w.at("span_removed_m3").size() == 1);
      CHECK(w["span_removed_m3"][0].get<double>() * 1e6 == Approx(removed).epsilon(1e-4));  // the STL is in floats
      CHECK(w["span_asked_m3"][0].get<double>() * 1e6 == Approx(smoothed).epsilon(1e-6));
      CHECK(w["span_removed_m3"][0].get<double>() + w.at("collapse_m3").get<double>() ==
            Approx(w.at("booked_m3").get<double>()).epsilon(1e-6));
    }
  }
  // Three spans of 50 mm over the shell's two 75 mm elements along the
  // axis: each element's rate goes to the spans it covers by the length
  // in each, so the middle span (half of each) has their mean; the outer
  // ones their own, the area-weighted mean of the stage's shell rows.
  REQUIRE(life(study + " --axial-segments 3", &err) == 0);
  {
    const auto thirds = read_csv(a / "life_segments.csv");
    REQUIRE(thirds.size() == 9);
    const auto shell_rows = read_csv(a / "stage-00" / "wear.csv");
    double rate[2] = {0, 0}, area[2] = {0, 0};
    for (const auto& w : shell_rows) {
      if (w.at("part") != "shell") continue;
      const int bin = num(w, "z_to_m") <= 0.075 + 1e-9 ? 0 : 1;
      rate[bin] += num(w, "wear_mm_per_1000h") * num(w, "area_m2"), area[bin] += num(w, "area_m2");
    }
    REQUIRE(area[0] > 0);
    REQUIRE(area[1] == Approx(area[0]));
    CHECK(num(thirds[0], "shell_wear_mm_per_1000h") == Approx(rate[0] / area[0]).epsilon(1e-4));
    CHECK(num(thirds[2], "shell_wear_mm_per_1000h") == Approx(rate[1] / area[1]).epsilon(1e-4));
    CHECK(num(thirds[1], "shell_wear_mm_per_1000h") ==
          Approx(0.5 * (rate[0] / area[0] + rate[1] / area[1])).epsilon(1e-4));
  }
  // A move made in steps tables what it recorded by span: added up where
  // the table's segments divide the recorded spans, blank where they do
  // not. (Stage 0's move, recorded as two steps over two spans.)
  {
    const std::string kept = read_text(a / "life.json");
    auto write_text = [](const fs::path& p, const std::string& t) { std::ofstream(p, std::ios::binary) << t; };
    nlohmann::json st = nlohmann::json::parse(kept);
    nlohmann::json& w = st["stages"][0]["meshes"][0]["wear"];
    w["steps"] = 2, w["stretch_segments"] = 2;
    w["span_asked_m3"] = {1e-6, 2e-6}, w["span_removed_m3"] = {3e-6, 4e-6};
    write_text(a / "life.json", st.dump(1));
    REQUIRE(life(study + " --axial-segments 2", &err) == 0);
    const auto two = read_csv(a / "life_segments.csv");
    REQUIRE(two.size() == 6);
    CHECK(num(two[0], "smoothed_cm3") == Approx(1.0));
    CHECK(num(two[1], "smoothed_cm3") == Approx(2.0));
    CHECK(num(two[0], "removed_cm3") == Approx(3.0));
    CHECK(num(two[1], "removed_cm3") == Approx(4.0));
    CHECK(two[0].at("booked_cm3") != "");
    REQUIRE(life(study + " --axial-segments 3", &err) == 0);
    const auto three = read_csv(a / "life_segments.csv");
    REQUIRE(three.size() == 9);
    for (int g = 0; g < 3; ++g) {
      CHECK(three[g].at("smoothed_cm3").empty());
      CHECK(three[g].at("removed_cm3").empty());
      CHECK_FALSE(three[g].at("booked_cm3").empty());
    }
    CHECK_FALSE(three[3].at("removed_cm3").empty());  // stage 1's one-step move, worked out from its meshes
    // Not a number of steps a move is made in: refused by name.
    w["steps"] = 3;
    write_text(a / "life.json", st.dump(1));
    CHECK(life(study + " --axial-segments 2", &err) == 2);
    CHECK(err.find("steps: 3: a move is made in 1, 2, 4 or 8 steps") != std::string::npos);
    write_text(a / "life.json", kept);
  }
  // life-compare reads the bars of a mesh study from life_meshes.csv, the
  // rest from life.csv.
  const std::string cmp = std::string(MC_BINARY) + " life-compare '" + a.string() + "' --at 2000,3000 --quiet --out '" +
                          (a / "cmp").string() + "' >/dev/null 2>&1";
  REQUIRE(std::system(cmp.c_str()) == 0);
  const auto compared = read_csv(a / "cmp" / "compare.csv");
  REQUIRE(compared.size() == 2);
  CHECK(num(compared[0], "leading_angle_deg") == Approx(num(meshes[1], "mid_leading_angle_deg")).margin(1e-3));
  CHECK(num(compared[0], "leading_angle_deg_se") == Approx(num(meshes[1], "mid_leading_angle_deg_se")).margin(1e-3));
  CHECK(num(compared[0], "height_mm") == Approx(num(meshes[1], "mid_height_mm")).margin(1e-3));
  CHECK(num(compared[0], "shell_wear_mm") == Approx(num(rows[1], "shell_wear_mm")).margin(1e-3));
  CHECK(num(compared[1], "trailing_angle_deg") ==
        Approx(0.5 * (num(meshes[1], "mid_trailing_angle_deg") + num(meshes[2], "mid_trailing_angle_deg"))).margin(1e-3));
  fs::remove_all(a);
  fs::remove(bars);
}

TEST_CASE("a mesh worn too deep in a stage stops the study by name and keeps its stages", "[life][cli][mesh_wear]") {
  const fs::path a = scratch("mesh-deep");
  std::string err;
  // A thousand times the hours: the bars are worn through in the one stage.
  CHECK(life(std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --stages 1 --hours 4000000" + kShort + " --out '" +
                 a.string() + "'",
             &err) == 2);
  INFO(err);
  CHECK(err.find("walls.mesh[0] worn from stage 0 to 1: ") != std::string::npos);
  CHECK(err.find("the study stops at stage 0") != std::string::npos);
  CHECK_FALSE(fs::exists(a / "stage-01" / "liner.stl"));
  const nlohmann::json state = nlohmann::json::parse(read_text(a / "life.json"));
  CHECK(state.at("stages").size() == 1);
  CHECK(state.at("stopped").get<std::string>().find("walls.mesh[0]") != std::string::npos);
  CHECK(read_csv(a / "life_meshes.csv").size() == 1);
  fs::remove_all(a);
}

TEST_CASE("a mesh whose corners are not welded is refused before a study starts", "[life][cli][mesh_wear]") {
  // The lab bars with each triangle's corners its own (moved by a few
  // tenths of a micrometre to 14 µm, a different amount per triangle): no two
  // triangles share a corner.
  std::vector<mc::Triangle> t =
      mc::io::read_stl(fs::path(MC_ASSET_DIR) / "meshes" / "lab_lifters.stl").triangles;
  for (std::size_t i = 0; i < t.size(); ++i)
    for (mc::Vec3& v : t[i].v) {
      const double r = std::hypot(v.x, v.y), shrink = 1 - 1e-7 * (1 + i) / r;  // inward, off the shell
      v = {v.x * shrink, v.y * shrink, v.z};
    }
  const fs::path loose = scratch("loose.stl"), a = scratch("loose-study");
  {
    std::ofstream f(loose, std::ios::binary);
    f << mc::io::stl_binary(t);
  }
  std::string err;
  CHECK(life(std::string(MC_ASSET_DIR) + "/cases/lab_stl.toml --set walls.mesh.0.file='" + loose.string() +
                 "' --stages 1 --hours 10 --out '" + a.string() + "'",
             &err) == 2);
  INFO(err);
  CHECK(err.find("walls.mesh[0]: 144 of its 144 triangles share no corner with another") != std::string::npos);
  CHECK_FALSE(fs::exists(a));
  fs::remove(loose);
}

TEST_CASE("two worn meshes, one in millimetres and turned, are carried through a stage placed", "[life][cli][mesh_wear]") {
  // The lab bars split in two STL files: bars 0-5 in metres as they are,
  // bars 6-11 in millimetres and turned back by 180° (the case turns them
  // forward again with angle = 180).
  const std::vector<mc::Triangle> all =
      mc::io::read_stl(fs::path(MC_ASSET_DIR) / "meshes" / "lab_lifters.stl").triangles;
  REQUIRE(all.size() == 144);
  std::vector<mc::Triangle> first(all.begin(), all.begin() + 72), second;
  for (auto it = all.begin() + 72; it != all.end(); ++it) {
    mc::Triangle t = *it;
    for (mc::Vec3& v : t.v) v = {-v.x * 1000, -v.y * 1000, v.z * 1000};
    second.push_back(t);
  }
  const fs::path dir = scratch("two-meshes"), a = scratch("two-meshes-study");
  fs::create_directories(dir);
  std::ofstream(dir / "a.stl", std::ios::binary) << mc::io::stl_binary(first);
  std::ofstream(dir / "b.stl", std::ios::binary) << mc::io::stl_binary(second);
  // lab_stl.toml with its one mesh replaced by the two.
  std::string text = read_text(fs::path(MC_ASSET_DIR) / "cases" / "lab_stl.toml");
  const std::size_t at = text.find("\n[[walls.mesh]]") + 1, end = text.find("\n[charge]") + 1;
  REQUIRE(at > 0);
  REQUIRE(end > at);
  text = text.substr(0, at) +
         "[[walls.mesh]]\nfile = \"a.stl\"\npart = \"lifters\"\n\n"
         "[[walls.mesh]]\nfile = \"b.stl\"\nunits = \"mm\"\nangle = 180.0\npart = \"lifters\"\n\n" +
         text.substr(end);
  std::ofstream(dir / "two.toml") << text;
  std::string err;
  const int rc = life("'" + (dir / "two.toml").string() + "' --stages 1 --hours 2000" + kShort + " --out '" +
                      a.string() + "'",
                      &err);
  INFO(err);
  REQUIRE(rc == 0);
  const auto rows = read_csv(a / "life_meshes.csv");
  REQUIRE(rows.size() == 4);  // two stages, two meshes
  for (const auto& r : rows) CHECK(num(r, "parts") == 6);
  CHECK(rows[2].at("file") == "stage-01/liner-0.stl");
  CHECK(rows[3].at("file") == "stage-01/liner-1.stl");
  // The next case names both, in metres, placed.
  const mc::MillCase next = mc::io::read_case(a / "cases" / "stage-01.toml");
  REQUIRE(next.meshes.size() == 2);
  CHECK(fs::equivalent(next.meshes[1].path, a / "stage-01" / "liner-1.stl"));
  CHECK(next.meshes[1].units == "m");
  CHECK(next.meshes[1].angle_deg == 0);
  // The second mesh's worn triangles where the original bars 6-11 were:
  // an end cap (no wear) is where it was to float precision, every vertex
  // within a wear's depth of the original.
  const std::vector<mc::Triangle> worn = mc::io::read_stl(a / "stage-01" / "liner-1.stl").triangles;
  REQUIRE(worn.size() == 72);
  double farthest = 0;
  for (std::size_t i = 0; i < 72; ++i)
    for (int k = 0; k < 3; ++k) {
      const mc::Vec3 d = worn[i].v[k] - all[72 + i].v[k];
      farthest = std::max(farthest, d.norm());
    }
  CHECK(farthest > 1e-5);   // worn
  CHECK(farthest < 0.015);  // and where the bars are, not turned or scaled away
  const double booked = num(rows[1], "booked_cm3") * 1e-6;
  CHECK(mc::closed_mesh_volume(second) * 1e-9 - mc::closed_mesh_volume(worn) == Approx(booked).epsilon(0.01));
  fs::remove_all(dir);
  fs::remove_all(a);
}
