// life.png's panels (app/life_picture.h) on a made-up study: what each
// panel holds, its labels, and the power panel drawn, read back pixel by
// pixel.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "app/life_picture.h"
#include "core/lifters.h"
#include "core/scene.h"

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

namespace fs = std::filesystem;
using mc::app::life::LifeAxis;
using mc::app::life::Stage;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Three stages of one or two profiles wearing down (25, 22, 20 mm; the
// second 18, 17, 16 mm), the shell 2 mm a stage, the power 822 to 829 W.
std::vector<Stage> made_up_study(int profiles, double sem) {
  const double heights[2][3] = {{25, 22, 20}, {18, 17, 16}};
  const double faces[3] = {20, 30, 40}, powers[3] = {822, 825, 829}, bare[3] = {0.88, 0.8, 0.7};
  std::vector<Stage> st;
  for (int i = 0; i < 3; ++i) {
    Stage s;
    s.index = i;
    s.case_hours = 1000.0 * i;
    s.shell_wear_m = 0.002 * i;
    s.diameter = 0.9 + 2 * s.shell_wear_m;
    s.filling = 0.3;
    s.ran = true;
    for (int k = 0; k < profiles; ++k) {
      mc::LifterProfile p;
      p.height = heights[k][i] * 1e-3;
      p.top_width = 0.03;
      p.face_angle_deg = faces[i];
      s.outlines.push_back(mc::profile_outline(p));
      s.r.station_m3_s.push_back(std::vector<double>(mc::kWearStations, 1e-12 * (k + 1)));
    }
    s.r.power_W = powers[i];
    s.r.power_sem_W = sem;
    s.r.toe_deg = 240, s.r.shoulder_deg = 40 - 5 * i, s.r.impact_deg = 230 + i;
    s.r.bare_share = bare[i];
    s.r.shell_mm_per_1000h = 0.5;
    st.push_back(s);
  }
  return st;
}

const mc::io::LinePlot* panel(const std::vector<mc::io::LinePlot>& plots, const std::string& title_part) {
  for (const auto& p : plots)
    if (p.title.find(title_part) != std::string::npos) return &p;
  return nullptr;
}

}  // namespace

TEST_CASE("life.png: no error band without standard errors, one legend entry with them", "[life][png]") {
  const auto plots = mc::app::life::life_plots("t", made_up_study(1, kNaN), {1, true, 0.15});
  const auto* power = panel(plots, "power draw");
  REQUIRE(power);
  REQUIRE(power->series.size() == 1);
  CHECK(power->series[0].label == "torque power");
  const auto with = mc::app::life::life_plots("t", made_up_study(1, 1.5), {1, true, 0.15});
  const auto* p2 = panel(with, "power draw");
  REQUIRE(p2);
  REQUIRE(p2->series.size() == 3);  // the power and the band's two edges, one of them in the legend
  int labelled = 0;
  for (const auto& s : p2->series) labelled += !s.label.empty();
  CHECK(labelled == 2);
  CHECK(p2->series[1].y[2] == Approx(829 + 3.0));
  CHECK(p2->series[2].y[2] == Approx(829 - 3.0));
}

TEST_CASE("life.png: every stage's profile is labelled with the height it is drawn at", "[life][png]") {
  for (int profiles : {1, 2}) {
    INFO(profiles << " profiles");
    const std::vector<Stage> st = made_up_study(profiles, kNaN);
    const auto plots = mc::app::life::life_plots("t", st, {1, true, 0.15});
    const mc::io::LinePlot& prof = plots.front();
    CHECK(prof.title.find("lifter profiles") != std::string::npos);
    // Series per profile: a stage each, then the shell arc.
    REQUIRE(prof.series.size() == static_cast<std::size_t>(profiles) * 4);
    for (int i = 0; i < 3; ++i) {
      const mc::io::PlotSeries& s = prof.series[i];  // profile 0, stage i
      // Its legend: every profile's height at this stage, as drawn (the top
      // of each outline, mm above its own shell).
      std::string heights;
      for (int k = 0; k < profiles; ++k) {
        const auto& drawn = prof.series[k * 4 + i].y;
        const double top = *std::max_element(drawn.begin(), drawn.end());
        CHECK(top == Approx(mc::measure_profile(st[i].outlines[k]).height * 1000).margin(1e-9));
        char b[32];
        std::snprintf(b, sizeof b, "%.1f", top);
        heights += (k ? " / " : "") + std::string(b);
      }
      CHECK_THAT(s.label, Catch::Contains(heights + " mm high"));
      // The hours in full (not 1.2e+04), relative at the default coefficient.
      CHECK_THAT(s.label, Catch::StartsWith(std::to_string(1000 * i) + " h (relative):"));
      if (i > 0) CHECK_THAT(s.label, Catch::Contains("shell worn " + std::to_string(2 * i) + ".0 mm"));
    }
    CHECK_FALSE(prof.series[3].label.empty());  // the shell
  }
}

TEST_CASE("life.png: each axis one quantity, the reline criteria drawn, uncalibrated hours called relative",
          "[life][png]") {
  const std::vector<Stage> st = made_up_study(2, 1.0);
  const auto rel = mc::app::life::life_plots("t", st, {1, true, 0.15});
  for (const auto& p : rel) {
    INFO(p.title);
    CHECK(p.y_label.find(" or ") == std::string::npos);
    if (p.title.find("profiles") == std::string::npos)
      CHECK(p.x_label == "hours (relative: wear coefficient not calibrated)");
  }
  const auto* height = panel(rel, "height");
  const auto* faces = panel(rel, "face angles");
  REQUIRE(height);
  REQUIRE(faces);
  CHECK(height->y_label == "height above the shell (mm)");
  CHECK(height->series.size() == 2);
  CHECK(height->series[1].y[2] == Approx(16.0).margin(1e-9));
  CHECK(faces->series.size() == 4);
  // Small changes do not fill a panel: the height from the shell up, the
  // angles over at least 10 degrees about their middle.
  CHECK(height->y_cover_lo == 0);
  CHECK(faces->y_cover_hi - faces->y_cover_lo >= 10 - 1e-9);
  for (const char* angles : {"where the charge lands", "leaves the shell"}) {
    const auto* p = panel(rel, angles);
    REQUIRE(p);
    CHECK(p->y_cover_hi - p->y_cover_lo >= 10 - 1e-9);
  }
  const auto* bare = panel(rel, "bare liner");
  REQUIRE(bare);
  CHECK(bare->series[0].y == std::vector<double>{88, 80, 70});
  CHECK(bare->y_cover_lo == 0);
  CHECK(bare->y_cover_hi == 100);
  const auto* rate = panel(rel, "wear rate");
  REQUIRE(rate);
  CHECK_THAT(rate->y_label, Catch::Contains("(relative)"));
  CHECK(rate->series.back().y[0] == Approx(0.5));  // the shell's mean, as booked
  // Calibrated: operating hours, scaled by the factor (hours / 4, rates x 4).
  const auto cal = mc::app::life::life_plots("t", st, {4, false, 0.15});
  const auto* rate4 = panel(cal, "wear rate");
  REQUIRE(rate4);
  CHECK(rate4->x_label == "operating hours");
  CHECK(rate4->series.back().x[2] == Approx(500));
  CHECK(rate4->series.back().y[0] == Approx(2.0));
  CHECK(rate4->y_label.find("relative") == std::string::npos);
  CHECK_THAT(cal.front().series[2].label, Catch::StartsWith("500 h:"));
}

TEST_CASE("life.png: a 1 % change of power fills a tenth of its panel, not all of it", "[life][png]") {
  const auto plots = mc::app::life::life_plots("t", made_up_study(1, kNaN), {1, true, 0.15});
  const auto* power = panel(plots, "power draw");
  REQUIRE(power);
  // The axis spans at least ±5 % of the mean (825.3 W): 784 to 867 W.
  CHECK(power->y_cover_lo == Approx(0.95 * 825.333).epsilon(1e-5));
  CHECK(power->y_cover_hi == Approx(1.05 * 825.333).epsilon(1e-5));
  const fs::path file = fs::temp_directory_path() / ("millcharge-life-power-" + std::to_string(::getpid()) + ".png");
  mc::io::write_line_plot_png(file, *power, 960, 400);
  int w = 0, h = 0, n = 0;
  unsigned char* px = stbi_load(file.string().c_str(), &w, &h, &n, 3);
  REQUIRE(px);
  // The line's pixels (its blue, 0x1f77b4, away from the legend's sample at
  // the panel's edges): their rows span 7 W of an axis of at least 83 W,
  // less than 9 % of the plot's height plus the markers' 8 pixels.
  int top = h, bottom = -1, frame_top = h, frame_bottom = -1;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const unsigned char* p = px + (static_cast<std::size_t>(y) * w + x) * 3;
      if (std::abs(p[0] - 0x1f) <= 12 && std::abs(p[1] - 0x77) <= 12 && std::abs(p[2] - 0xb4) <= 12 && x > 200 &&
          x < 760)
        top = std::min(top, y), bottom = std::max(bottom, y);
      if (p[0] == 0x44 && p[1] == 0x44 && p[2] == 0x44 && x == w / 2)  // the frame
        frame_top = std::min(frame_top, y), frame_bottom = std::max(frame_bottom, y);
    }
  stbi_image_free(px);
  fs::remove(file);
  REQUIRE(bottom > top);
  REQUIRE(frame_bottom - frame_top > 200);
  CHECK(bottom - top < 0.09 * (frame_bottom - frame_top) + 8);
  CHECK(bottom - top > 0.04 * (frame_bottom - frame_top));  // and not flattened away
}

TEST_CASE("life.png along the mill: a line per worn mesh and segment, gaps for figures not measured, the widest "
          "spread over stages with every bin", "[life][png]") {
  const fs::path dir = fs::temp_directory_path() / ("millcharge-along-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  // Two worn meshes of bars (0 and 2) and one without (1, a shell), two
  // segments, stages 0 and 1; one standard error not measured (empty).
  std::string csv =
      "stage,hours,case_hours,mesh,segment,z_from_m,z_to_m,bars,height_mm,height_mm_se,leading_angle_deg,"
      "leading_angle_deg_se,trailing_angle_deg,trailing_angle_deg_se,shell_wear_mm_per_1000h,booked_cm3,"
      "smoothed_cm3,removed_cm3,wear_basis\n";
  for (int stage = 0; stage < 2; ++stage)
    for (int mesh = 0; mesh < 3; ++mesh)
      for (int seg = 0; seg < 2; ++seg) {
        const int bars = mesh == 1 ? 0 : 6;
        const double face = 20 + 10 * stage + mesh + 0.5 * seg;
        const std::string se = stage == 1 && mesh == 2 && seg == 1 ? "" : "0.25";
        csv += std::to_string(stage) + "," + std::to_string(1000 * stage) + "," + std::to_string(1000 * stage) + "," +
               std::to_string(mesh) + "," + std::to_string(seg) + "," + (seg ? "0.075,0.15," : "0,0.075,") +
               std::to_string(bars) + ",25,0.1," + (bars ? std::to_string(face) : std::string()) + "," + se +
               ",20,0.1,1,1,1,1,relative\n";
      }
  std::ofstream(dir / "life_segments.csv") << csv;
  // The impact points: stage 0 two bins 5 deg apart; stage 1 one bin
  // without a point (not counted for the spread, whatever its other bin);
  // no summary for stage 2 or 3 (not run).
  fs::create_directories(dir / "stage-00");
  fs::create_directories(dir / "stage-01");
  std::ofstream(dir / "stage-00" / "summary.json")
      << R"({"liner": {"impact_point_along": [{"z0_m": 0, "z1_m": 0.075, "impact_point_deg": 230.5},
                                             {"z0_m": 0.075, "z1_m": 0.15, "impact_point_deg": 235.5}]}})";
  std::ofstream(dir / "stage-01" / "summary.json")
      << R"({"liner": {"impact_point_along": [{"z0_m": 0, "z1_m": 0.075, "impact_point_deg": 221.5},
                                             {"z0_m": 0.075, "z1_m": 0.15, "impact_point_deg": null}]}})";
  const auto plots = mc::app::life::along_plots("fixture", dir, true);
  REQUIRE(plots.size() == 3);
  // Four lines: meshes 0 and 2, two segments each; the shell mesh left out.
  REQUIRE(plots[0].series.size() == 4);
  CHECK(plots[0].series[0].label == "mesh 0, 0 to 0.075 m");
  CHECK(plots[0].series[3].label == "mesh 2, 0.075 to 0.15 m");
  for (const auto& s : plots[0].series) REQUIRE(s.y.size() == 2);
  CHECK(plots[0].series[2].y[1] == Approx(32));  // stage 1, mesh 2, segment 0: 20 + 10 + 2
  CHECK(plots[0].series[2].band_hi[1] - plots[0].series[2].y[1] == Approx(0.5));
  CHECK(std::isnan(plots[0].series[3].band_hi[1]));  // its standard error not measured
  // The impact point: stage 1's second bin has none, so the widest spread
  // is stage 0's, 5 deg (not stage 1's lone bin).
  REQUIRE(plots[2].series.size() == 2);
  CHECK(plots[2].series[1].y.size() == 1);
  CHECK_THAT(plots[2].title, Catch::Contains("widest spread 5.0 deg, at 0 h, relative"));
  // A summary without the bins (a run of an older build) is passed over.
  std::ofstream(dir / "stage-01" / "summary.json") << R"({"liner": {}})";
  CHECK(mc::app::life::along_plots("fixture", dir, false)[2].series[0].y.size() == 1);
  fs::remove_all(dir);
}
