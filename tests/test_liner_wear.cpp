// Lifter profiles of any shape and the liner moved by its wear
// (core/lifters.h, core/liner_wear.h).
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "core/lifters.h"
#include "core/liner_wear.h"

using Catch::Detail::Approx;
using mc::Vec2;

namespace {

const double kR = 0.45;

std::vector<Vec2> rectangle(double w, double h) { return {{w / 2, 0}, {w / 2, h}, {-w / 2, h}, {-w / 2, 0}}; }

}  // namespace

TEST_CASE("a polygon profile equal to an h x w x 0 bar gives its vertices bit for bit", "[lifters]") {
  mc::LifterProfile bar;
  bar.height = 0.025;
  bar.top_width = 0.03;
  bar.face_angle_deg = 0;
  mc::LifterProfile poly;
  poly.points = {{-0.015, 0}, {-0.015, 0.025}, {0.015, 0.025}, {0.015, 0}};  // either direction
  for (double angle : {0.0, 0.7, 2.5}) {
    const auto a = mc::lifter_polygon(kR, bar, angle), b = mc::lifter_polygon(kR, poly, angle);
    REQUIRE(a.size() == b.size());
    for (std::size_t k = 0; k < a.size(); ++k) {
      CHECK(a[k].x == b[k].x);
      CHECK(a[k].y == b[k].y);
    }
  }
}

TEST_CASE("a trapezoid's outline measures as its height, top width and face angles", "[lifters]") {
  mc::LifterProfile p;
  p.height = 0.025;
  p.top_width = 0.03;
  p.face_angle_deg = 20;
  const mc::ProfileMeasures m = mc::measure_profile(mc::profile_outline(p));
  CHECK(m.height == Approx(0.025).epsilon(1e-12));
  CHECK(m.top_width == Approx(0.03).epsilon(1e-12));
  CHECK(m.leading_angle_deg == Approx(20).epsilon(1e-9));
  CHECK(m.trailing_angle_deg == Approx(20).epsilon(1e-9));
  CHECK(m.area == Approx(0.025 * (0.03 + 0.025 * std::tan(20 * M_PI / 180))).epsilon(1e-12));
  // The stations' path: from where the leading face leaves the shell, over
  // the top, to where the trailing face enters it; as long as the outline
  // inside the shell.
  const auto poly = mc::lifter_polygon(kR, p, 0.0);
  const mc::WearPath w = mc::lifter_wear_path(poly, kR);
  // The circle lies a little above the tangent line at the feet: where the
  // face meets it, (R − y)² + x(y)² = R².
  const double tan20 = std::tan(20 * M_PI / 180);
  double y = 0;
  for (int it = 0; it < 50; ++it) {
    const double x = 0.015 + (0.025 - y) * tan20;
    y = kR - std::sqrt(kR * kR - x * x);
  }
  const double face = (0.025 - y) / std::cos(20 * M_PI / 180);
  CHECK(w.to - w.from == Approx(0.03 + 2 * face).epsilon(1e-9));
}

TEST_CASE("bad lifter outlines are refused with their cause", "[lifters]") {
  auto fault = [](std::vector<Vec2> o) { return mc::profile_outline_fault(o, kR, 0.0254); };
  CHECK(fault(rectangle(0.03, 0.025)).empty());
  CHECK(fault({{0.01, 0}, {-0.01, 0}}).find("at least 3") != std::string::npos);
  CHECK(fault({{0.015, 0.002}, {0, 0.02}, {-0.015, 0}}).find("feet") != std::string::npos);
  CHECK(fault({{0.015, 0}, {0.01, -0.01}, {0, 0.02}, {-0.015, 0}}).find("outside the shell") != std::string::npos);
  CHECK(fault({{15, 0}, {15, 25}, {-15, 25}, {-15, 0}}).find("millimetres") != std::string::npos);
  // Too high in metres, but not a unit slip: no hint.
  const std::string axis = fault({{0.015, 0}, {0, 0.44}, {-0.015, 0}});
  CHECK(axis.find("0.44 m high and reaches the axis") != std::string::npos);
  CHECK(axis.find("millimetres") == std::string::npos);
  CHECK(fault({{0.015, 0}, {0.015, 0.025}, {0, 0.01}, {-0.015, 0.025}, {-0.015, 0}}).find("non-convex") !=
        std::string::npos);
  CHECK(fault({{0.015, 0}, {-0.015, 0.025}, {0.015, 0.025}, {-0.015, 0}}).find("non-convex") != std::string::npos);
  // Needles: feet within the coincidence tolerance, or just past it with no
  // area to speak of (2.5e-10 m² under a 25 mm bar's 6.25e-10).
  CHECK(fault({{1e-10, 0}, {0, 0.025}, {-1e-10, 0}}).find("the feet coincide") != std::string::npos);
  CHECK(fault({{1e-8, 0}, {0, 0.025}, {-1e-8, 0}}).find("no area to speak of") != std::string::npos);
  CHECK(fault({{1e-3, 0}, {0, 0.025}, {-1e-3, 0}}).empty());  // a thin bar is a bar
}

TEST_CASE("a lifter worn by a uniform depth loses the booked area and its height by that depth", "[lifters]") {
  const std::vector<Vec2> o = rectangle(0.03, 0.025);
  const mc::WearPath path = mc::lifter_wear_path(mc::lifter_polygon(kR, mc::LifterProfile{0, 0, 0, o}, 0.0), kR);
  const double span = path.to - path.from, d = 0.001;
  std::vector<double> area(mc::kWearStations, d * span / mc::kWearStations);
  const mc::WornLifter w = mc::wear_lifter(o, kR, area, 0.0);
  REQUIRE_FALSE(w.worn_away);
  CHECK(w.removed_area == Approx(w.booked_area).epsilon(1e-4));
  CHECK(w.scale == Approx(1.0).margin(0.1));
  const mc::ProfileMeasures m = mc::measure_profile(w.outline);
  CHECK(m.height == Approx(0.025 - d).margin(2e-4));
  CHECK(m.top_width == Approx(0.03 - 2 * d).margin(5e-4));
}

TEST_CASE("no wear leaves the outline, and shell wear alone raises the lifter", "[lifters]") {
  const std::vector<Vec2> o = rectangle(0.03, 0.025);
  const std::vector<double> none(mc::kWearStations, 0.0);
  const mc::WornLifter w = mc::wear_lifter(o, kR, none, 0.0);
  CHECK(mc::measure_profile(w.outline).area == Approx(mc::measure_profile(o).area).epsilon(1e-9));
  const mc::WornLifter s = mc::wear_lifter(o, kR, none, 0.002);
  CHECK(mc::measure_profile(s.outline).height == Approx(0.027).epsilon(1e-9));
  CHECK(s.removed_area == Approx(0.0).margin(1e-12));
}

TEST_CASE("wear on the leading top corner rounds it and lays the face back", "[lifters]") {
  const std::vector<Vec2> o = rectangle(0.03, 0.025);
  std::vector<double> area(mc::kWearStations, 0.0);
  // Stations run from the leading foot over the top: the leading corner is
  // about a third of the way.
  for (int j = 8; j <= 11; ++j) area[j] = 2e-5;
  const mc::WornLifter w = mc::wear_lifter(o, kR, area, 0.0);
  REQUIRE_FALSE(w.worn_away);
  CHECK(w.removed_area == Approx(8e-5).epsilon(1e-4));
  const mc::ProfileMeasures m = mc::measure_profile(w.outline);
  CHECK(m.leading_angle_deg > 5);
  CHECK(std::fabs(m.trailing_angle_deg) < 0.5);
  CHECK(w.outline.size() > 4);
}

TEST_CASE("uneven wear of any pattern removes the booked area within 1e-5 and leaves a valid outline", "[lifters]") {
  // Patterns of station wear as a run books them: a worn leading corner,
  // a worn top, both faces, with and without shell wear; a bar with a face
  // angle and one already rounded.
  const std::vector<std::vector<Vec2>> bars = {
      rectangle(0.03, 0.025),
      {{0.024, 0}, {0.015, 0.025}, {-0.015, 0.025}, {-0.024, 0}},
      {{0.03, 0}, {0.022, 0.012}, {0.008, 0.02}, {-0.015, 0.022}, {-0.018, 0}}};
  int cases = 0;
  for (const auto& o : bars)
    for (int pattern = 0; pattern < 4; ++pattern)
      for (double shell : {0.0, 0.0015}) {
        std::vector<double> area(mc::kWearStations, 0.0);
        unsigned seed = 12345u + 97u * static_cast<unsigned>(pattern);
        for (int j = 0; j < mc::kWearStations; ++j) {
          seed = seed * 1103515245u + 12345u;
          const double noise = 0.5 + (seed >> 16 & 0x7fff) / 32768.0;
          const double centre = pattern == 0 ? 10 : pattern == 1 ? 16 : pattern == 2 ? 24 : 6;
          area[j] = 4e-6 * noise * std::exp(-0.5 * std::pow((j - centre) / (pattern == 3 ? 12.0 : 3.0), 2));
        }
        const mc::WornLifter w = mc::wear_lifter(o, kR, area, shell);
        INFO("bar " << &o - &bars[0] << ", pattern " << pattern << ", shell " << shell);
        REQUIRE_FALSE(w.worn_away);
        CHECK(w.removed_area == Approx(w.booked_area).epsilon(1e-5));
        CHECK(mc::profile_outline_fault(w.outline, kR + shell, 0.0) == "");
        CHECK(static_cast<int>(w.outline.size()) <= mc::kLifterMaxPoints);
        CHECK(mc::measure_profile(w.outline).height < mc::measure_profile(o).height + shell);
        ++cases;
      }
  CHECK(cases == 24);
}

TEST_CASE("a stage that wears a lifter through says so", "[lifters]") {
  const std::vector<Vec2> o = rectangle(0.03, 0.025);
  std::vector<double> area(mc::kWearStations, 1e-4);  // far more than the bar holds
  CHECK(mc::wear_lifter(o, kR, area, 0.0).worn_away);
}

TEST_CASE("a laid-back foot over a worn shell follows its face down to the worn shell", "[lifters]") {
  // Faces laid back 72 and 79 degrees from the radial, the latter so wide
  // that its foot lies behind the curved shell: with no wear on the bar the
  // outline only rises by the shell's depth, its feet carried along its
  // faces to the worn shell (the face line y = h (x_foot - x) / run meets
  // y = -depth at x_foot + depth run / h).
  struct Bar {
    std::vector<Vec2> o;
    double run, h;  // the leading face's horizontal run and rise
  };
  const std::vector<Bar> bars = {{{{0.05, 0}, {-0.01, 0.02}, {-0.02, 0.02}, {-0.02, 0}}, 0.06, 0.02},
                                 {{{0.06, 0}, {0.0, 0.012}, {-0.01, 0.012}, {-0.03, 0}}, 0.06, 0.012}};
  for (const Bar& b : bars)
    for (double shell : {0.0, 0.005, 0.02}) {
      INFO("bar " << &b - &bars[0] << ", shell worn " << shell << " m");
      const mc::WornLifter w = mc::wear_lifter(b.o, kR, std::vector<double>(mc::kWearStations, 0.0), shell);
      REQUIRE_FALSE(w.worn_away);
      CHECK(std::fabs(w.removed_area) < 1e-12);
      REQUIRE(w.outline.size() == b.o.size());
      CHECK(w.outline.front().x == Approx(b.o.front().x + shell * b.run / b.h).margin(1e-9));
      for (std::size_t k = 1; k + 1 < b.o.size(); ++k) {  // the bar above the old shell, risen by its depth
        CHECK(w.outline[k].x == Approx(b.o[k].x).margin(1e-9));
        CHECK(w.outline[k].y == Approx(b.o[k].y + shell).margin(1e-9));
      }
    }
}

TEST_CASE("the hours a bar takes to lose a height: the shell's wear adds to its height hour for hour", "[lifters][life]") {
  // The shell falling away under a bar at q raises the bar's height above
  // it by q t and leaves the bar itself as it wears without it: so the
  // hours t_q to lose L with the shell wearing satisfy
  // h0 - H(t_q) - q t_q = L, H the height worn with the shell still.
  const double len = 0.15;
  const std::vector<Vec2> o = rectangle(0.03, 0.025);
  const double h0 = 0.025, r = 1e-6;  // m per hour of depth on every station
  mc::BarWearRates still;
  still.length = len;
  still.station_m3_s.assign(mc::kWearStations, r / 3600 * (0.0795 / mc::kWearStations) * len);
  for (double q_over_r : {0.0, 0.3}) {
    mc::BarWearRates rates = still;
    rates.shell_m_per_h = q_over_r * r;
    for (double loss : {0.001, 0.005}) {
      const double t = mc::hours_to_lose(o, kR, rates, loss);
      INFO("q/r " << q_over_r << ", loss " << loss << " m: " << t << " h");
      REQUIRE(t > 0);
      const double H = mc::measure_profile(mc::wear_for_hours(o, kR, still, t).outline).height;
      CHECK(h0 - H - rates.shell_m_per_h * t == Approx(loss).epsilon(1e-6));
      // The top wears about r an hour: a small loss comes in about loss / r.
      if (q_over_r == 0 && loss < 0.002) CHECK(t == Approx(loss / r).epsilon(0.05));
    }
  }
  // No wear on the bar, or nothing to lose: no hours.
  mc::BarWearRates shell_only;
  shell_only.length = len;
  shell_only.station_m3_s.assign(mc::kWearStations, 0.0);
  shell_only.shell_m_per_h = r;
  CHECK(mc::hours_to_lose(o, kR, shell_only, 0.001) < 0);
  CHECK(mc::hours_to_lose(o, kR, still, 0.0) < 0);
}
