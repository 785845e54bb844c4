// A bar's leading face, top and trailing face by their place along its
// outline (core/lifters.h lifter_face_split), on the host's liner elements
// and in the kernels' books, for every outline the case reader accepts.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "app/commands.h"
#include "core/lifters.h"
#include "core/layout.hpp"
#include "core/liner.h"
#include "helpers.h"
#include "io/case_file.h"

using Catch::Detail::Approx;
using namespace mc;
using namespace mc::test;

namespace {

const double kR = 0.45;

// A bar's exposed outline from its leading foot to its trailing foot, in its
// own frame (x ahead, y up from the tangent), measured apart from the code:
// where each side meets the circle, by bisection on the side's line.
double side_to_circle(Vec2 top, Vec2 foot) {
  // Points top + t (foot − top), t in [0, 1]; in the mill frame the bar's
  // centre is on +x: (R − y, x). Inside the shell while (R − y)² + x² < R².
  auto inside = [&](double t) {
    const double x = top.x + t * (foot.x - top.x), y = top.y + t * (foot.y - top.y);
    return (kR - y) * (kR - y) + x * x < kR * kR;
  };
  double lo = 0, hi = 1;
  for (int it = 0; it < 200; ++it) (inside(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
  return lo * std::hypot(foot.x - top.x, foot.y - top.y);
}

std::vector<Vec2> bar(const LifterProfile& p) { return lifter_polygon(kR, p, 0.0); }

FaceSplit split_of(const LifterProfile& p) { return lifter_face_split(bar(p), kR, Vec2{1, 0}); }

LifterProfile points(std::vector<Vec2> pts) {
  LifterProfile p;
  p.points = std::move(pts);
  return p;
}

}  // namespace

TEST_CASE("a trapezoid's faces are its sides and its top is its top face, at any face angle", "[lifters][faces]") {
  for (double angle : {0.0, 20.0, 44.0, 50.0, 59.0}) {
    LifterProfile p;
    p.height = 0.025;
    p.top_width = 0.03;
    p.face_angle_deg = angle;
    const FaceSplit f = split_of(p);
    const double tn = std::tan(angle * M_PI / 180);
    const double half_base = 0.015 + 0.025 * tn;
    const double side = side_to_circle({0.015, 0.025}, {half_base + 0.025 * tn, -0.025});
    INFO("face angle " << angle);
    CHECK(f.top_from - f.from == Approx(side).epsilon(1e-9));
    CHECK(f.top_to - f.top_from == Approx(0.03).epsilon(1e-12));
    CHECK(f.to - f.top_to == Approx(side).epsilon(1e-9));
  }
}

TEST_CASE("a pointed bar's top is its tip above 90 % of its height, and a ramp keeps its leading face",
          "[lifters][faces]") {
  // A triangle whose faces lay back 50 degrees: the top is the tenth of each
  // side nearest the apex.
  const FaceSplit t = split_of(points({{0.03, 0}, {0.0, 0.025}, {-0.03, 0}}));
  const double side = std::hypot(0.03, 0.025);
  CHECK(t.top_to - t.top_from == Approx(0.2 * side).epsilon(1e-9));
  CHECK(t.top_from - t.from == Approx(side_to_circle({0.0, 0.025}, {0.03, 0.0}) - 0.1 * side).epsilon(1e-9));
  CHECK(t.to - t.top_to == Approx(t.top_from - t.from).epsilon(1e-9));
  // A worn bar that has become a ramp: its whole leading side laid back to
  // 63 degrees stays the leading face, the flat 10 mm at the top is the top.
  const FaceSplit r = split_of(points({{0.03, 0}, {-0.02, 0.025}, {-0.03, 0.025}, {-0.03, 0}}));
  CHECK(r.top_from - r.from == Approx(side_to_circle({-0.02, 0.025}, {0.03, 0.0})).epsilon(1e-9));
  CHECK(r.top_to - r.top_from == Approx(0.01).epsilon(1e-12));
  CHECK(r.to - r.top_to == Approx(side_to_circle({-0.03, 0.025}, {-0.03, 0.0})).epsilon(1e-9));
}

TEST_CASE("every outline the reader accepts gives three faces of positive length that cover it", "[lifters][faces]") {
  // Random convex outlines: points on an upper half-ellipse of random
  // half-widths and heights, some lopsided, 3 to 16 points.
  unsigned seed = 2026u;
  auto uniform = [&] {
    seed = seed * 1103515245u + 12345u;
    return (seed >> 8 & 0xffffff) / 16777216.0;
  };
  int accepted = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 3 + static_cast<int>(uniform() * 14);
    const double a = 0.005 + 0.04 * uniform(), h = 0.003 + 0.06 * uniform(), skew = -0.8 + 1.6 * uniform();
    std::vector<double> ts{0.0, M_PI};
    for (int k = 0; k + 2 < n; ++k) ts.push_back(M_PI * (0.02 + 0.96 * uniform()));
    std::sort(ts.begin(), ts.end());
    std::vector<Vec2> pts;
    for (double t : ts) {
      const double y = h * std::sin(t);
      pts.push_back({a * std::cos(t) + skew * y, y});
    }
    if (profile_outline_fault(pts, kR, 0.02) != "") continue;
    ++accepted;
    Scene sc;
    sc.walls.shell_radius = kR;
    sc.walls.length = 0.1;
    sc.walls.lifters = lifter_rows(kR, 6, {points(pts)}, 0.3);
    sc.walls.lifter_first_angle = 0.3;
    const LinerLayout L = liner_layout(sc);
    const WearPath path = lifter_wear_path(sc.walls.lifters[0], kR);
    double faces = 0;
    for (int f = 0; f < 3; ++f) {
      const LinerElement& e = L.elements[L.first_lifter + f * L.axial_bins];
      INFO("trial " << trial << ", face " << f << ", " << n << " points");
      CHECK(e.outline.size() >= 4);
      CHECK(e.area_m2 > 0);
      faces += e.area_m2 / (e.z1 - e.z0);
    }
    CHECK(faces == Approx(path.to - path.from).epsilon(1e-9));
    // The top holds the summit, and lies above half the height; the leading
    // face starts at the leading foot, ahead of where the trailing face ends.
    auto height = [&](const Vec3& p) {
      const double c = std::cos(0.3), sn = std::sin(0.3);
      return kR - (p.x * c + p.y * sn);
    };
    double summit = 0, top_max = 0, top_min = 1e300;
    for (int f = 0; f < 3; ++f)
      for (const Vec3& p : L.elements[L.first_lifter + f * L.axial_bins].outline) {
        summit = std::max(summit, height(p));
        if (f == 1) top_max = std::max(top_max, height(p)), top_min = std::min(top_min, height(p));
      }
    CHECK(top_max == Approx(summit).epsilon(1e-9));
    CHECK(top_min >= 0.5 * summit * (1 - 1e-9));
    const auto& lead = L.elements[L.first_lifter].outline;
    const auto& trail = L.elements[L.first_lifter + 2 * L.axial_bins].outline;
    const double ahead_lead = -lead.front().x * std::sin(0.3) + lead.front().y * std::cos(0.3);
    const Vec3& trail_foot = trail[trail.size() / 2 - 1];  // its strip's last point at z0
    const double ahead_trail = -trail_foot.x * std::sin(0.3) + trail_foot.y * std::cos(0.3);
    CHECK(ahead_lead > ahead_trail);
  }
  CHECK(accepted > 200);
}

TEST_CASE("the kernels book a collision on the face it strikes, however far the face lays back", "[lifters][faces][books]") {
  // One bar at angle 0 whose faces lay back 50 degrees; a ball thrown at
  // the middle of each face and at the top's centre books one impact there.
  LifterProfile p;
  p.height = 0.03;
  p.top_width = 0.02;
  p.face_angle_deg = 50;
  const double tn = std::tan(50 * M_PI / 180), cs = std::cos(50 * M_PI / 180), sn = std::sin(50 * M_PI / 180);
  const Material steel{"steel", 7800, 2e11, 0.3};
  Interaction in;
  in.kn = 1e6;
  const double r = 0.008;
  // Targets in the bar's frame (x ahead, y up), with their outward normals.
  struct Target {
    Vec2 at, normal;
    int face;
  };
  const std::vector<Target> targets = {{{0.01 + 0.015 * tn, 0.015}, {cs, sn}, static_cast<int>(LifterFace::leading)},
                                       {{0.0, 0.03}, {0, 1}, static_cast<int>(LifterFace::top)},
                                       {{-0.01 - 0.015 * tn, 0.015}, {-cs, sn}, static_cast<int>(LifterFace::trailing)}};
  // And a triangle whose sides lay back 50 degrees: its tip is its top.
  LifterProfile tri = points({{0.03, 0}, {0.0, 0.03 / std::tan(50 * M_PI / 180)}, {-0.03, 0}});
  const double apex = tri.points[1].y;
  const std::vector<std::pair<LifterProfile, Target>> shots = {
      {p, targets[0]}, {p, targets[1]}, {p, targets[2]},
      {tri, {{0.015, 0.5 * apex}, {cs, sn}, static_cast<int>(LifterFace::leading)}},
      {tri, {{0.0, apex}, {0, 1}, static_cast<int>(LifterFace::top)}},
      {tri, {{-0.015, 0.5 * apex}, {-cs, sn}, static_cast<int>(LifterFace::trailing)}}};
  for (const auto& [bar_profile, t] : shots) {
    Scene sc = bare_scene(steel, steel, in, ContactLaw::linear);
    sc.walls.shell_radius = kR;
    sc.walls.length = 0.1;
    sc.walls.lifters = lifter_rows(kR, 8, {bar_profile}, 0.0);
    sc.numerics.dt = 1e-5;
    // Bar frame (x, y) to the mill frame: (R − y, x).
    const Vec2 c{t.at.x + (r + 0.001) * t.normal.x, t.at.y + (r + 0.001) * t.normal.y};
    Ball b;
    b.radius = r;
    b.position = {kR - c.y, c.x, 0.05};
    b.velocity = {0.5 * t.normal.y, -0.5 * t.normal.x, 0};  // towards the face
    sc.balls = {b};
    const LinerLayout L = liner_layout(sc);
    auto s = make_solver(context(), sc);
    s->advance(1000);  // 10 ms: in, bounced and gone
    const BookSums books = s->read_books();
    INFO("face " << t.face);
    for (int f = 0; f < 3; ++f) {
      double impacts = 0;
      for (int a = 0; a < L.axial_bins; ++a) impacts += books.liner_at(L.first_lifter + f * L.axial_bins + a, MC_LINER_IMPACTS);
      CHECK(impacts == (f == t.face ? 1 : 0));
    }
  }
}

namespace {

std::string read_all(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A short run of the lab mill (a 60 mm length of it) with `lifters` as its
// [[lifters.profile]] tables, into `out`.
int short_run(const std::filesystem::path& out, const std::string& lifters, std::vector<std::string> sets = {}) {
  std::string text = read_all(io::default_case());
  const std::size_t a = text.find("\n[[lifters.profile]]") + 1, b = text.find("\n[charge]") + 1;
  REQUIRE(a > 0);
  REQUIRE(b > a);
  text = text.substr(0, a) + lifters + text.substr(b);
  const std::filesystem::path file = out.parent_path() / (out.filename().string() + ".toml");
  std::ofstream(file) << text;
  app::RunOptions o;
  o.c.case_path = file.string();
  o.c.overrides = {"mill.length=0.06", "run.settle=0.05", "run.warmup=0.1", "run.snapshot_interval=0.1"};
  for (const std::string& s : sets) o.c.overrides.push_back(s);
  o.c.duration = 0.3;
  o.out = out.string();
  o.quiet = true;
  return app::cmd_run(o);
}

// wear.csv's lifter rows of row 0: face name to area, over all axial bins.
std::map<std::string, double> faces_of_row0(const std::filesystem::path& wear_csv) {
  std::map<std::string, double> out;
  std::ifstream in(wear_csv);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    if (f.size() > 12 && f[1] == "lifter" && f[2] == "0") out[f[3]] += std::stod(f[12]);
  }
  return out;
}

}  // namespace

TEST_CASE("a triangle and a ramp run whole, and a mesh that cannot be written after the run is a warning",
          "[lifters][faces][cli]") {
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / ("millcharge_test_triangle_" + std::to_string(::getpid()));
  std::filesystem::remove_all(out);
  // liner.vtp cannot be written: a folder holding a file stands in its place.
  std::filesystem::create_directories(out / "liner.vtp");
  std::ofstream(out / "liner.vtp" / "keep") << "x";
  const std::string lifters =
      "[[lifters.profile]]\npoints = [[0.03, 0.0], [0.0, 0.025], [-0.03, 0.0]]\nunits = \"m\"\n\n"
      "[[lifters.profile]]\npoints = [[0.03, 0.0], [-0.02, 0.025], [-0.03, 0.025], [-0.03, 0.0]]\nunits = \"m\"\n\n";
  REQUIRE(short_run(out, lifters) == 0);
  for (const char* f : {"summary.json", "timeseries.csv", "spectra.csv", "wear.csv", "lifter_wear.csv",
                        "checkpoint.bin", "liner.png", "snapshots/liner_000000.vtp"}) {
    INFO(f);
    CHECK(std::filesystem::is_regular_file(out / f));
  }
  CHECK(std::filesystem::is_directory(out / "liner.vtp"));
  // The triangle's tip: a tenth of each 39 mm side, over the 60 mm length.
  const auto faces = faces_of_row0(out / "wear.csv");
  REQUIRE(faces.size() == 3);
  CHECK(faces.at("top") == Approx(0.2 * std::hypot(0.03, 0.025) * 0.06).epsilon(1e-5));
  CHECK(faces.at("leading") > 0.0015);
  CHECK(faces.at("trailing") == Approx(faces.at("leading")).epsilon(1e-5));
  std::filesystem::remove_all(out);
  std::filesystem::remove(out.parent_path() / (out.filename().string() + ".toml"));
}

TEST_CASE("a bar with faces laid back 50 degrees runs whole and books its faces", "[lifters][faces][cli]") {
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / ("millcharge_test_face50_" + std::to_string(::getpid()));
  std::filesystem::remove_all(out);
  const std::string lifters = "[[lifters.profile]]\nheight = 0.025\ntop_width = 0.03\nface_angle = 50.0\n\n";
  REQUIRE(short_run(out, lifters) == 0);
  CHECK(std::filesystem::is_regular_file(out / "summary.json"));
  CHECK(std::filesystem::file_size(out / "liner.vtp") > 1000);
  const auto faces = faces_of_row0(out / "wear.csv");
  REQUIRE(faces.size() == 3);
  CHECK(faces.at("top") == Approx(0.03 * 0.06).epsilon(1e-5));
  CHECK(faces.at("leading") > 0.025 * 0.06);
  std::filesystem::remove_all(out);
  std::filesystem::remove(out.parent_path() / (out.filename().string() + ".toml"));
}

TEST_CASE("the bare shell between lopsided bars is the mill's arc less each bar's footprint", "[lifters][faces]") {
  // A worn ramp: its leading foot 30 mm ahead of its row's centre, its
  // trailing foot 30 mm behind, its top leaning back. Its footprint is the
  // arc between where its two foot edges cross the shell, found here by
  // bisection along each edge.
  const std::vector<Vec2> ramp{{0.03, 0}, {-0.02, 0.025}, {-0.03, 0.025}, {-0.03, 0}};
  auto crossing_angle = [](Vec2 top, Vec2 foot) {
    double lo = 0, hi = 1;
    auto at = [&](double t) { return Vec2{top.x + t * (foot.x - top.x), top.y + t * (foot.y - top.y)}; };
    for (int it = 0; it < 200; ++it) {
      const Vec2 p = at(0.5 * (lo + hi));
      ((kR - p.y) * (kR - p.y) + p.x * p.x < kR * kR ? lo : hi) = 0.5 * (lo + hi);
    }
    const Vec2 p = at(lo);
    return std::atan2(p.x, kR - p.y);  // from the row's centre, counter-clockwise positive
  };
  const double lead = crossing_angle({-0.02, 0.025}, {0.03 + 0.05 * 0.25, -0.025 * 0.25});
  const double trail = -crossing_angle({-0.03, 0.025}, {-0.03, -0.025});
  const int rows = 10;
  Scene sc;
  sc.walls.shell_radius = kR;
  sc.walls.length = 0.2;
  sc.walls.lifters = lifter_rows(kR, rows, {points(ramp)}, 0.0);
  const LinerLayout L = liner_layout(sc);
  double shell = 0;
  for (const LinerElement& e : L.elements)
    if (e.part == LinerPart::shell) shell += e.area_m2;
  CHECK(L.lifter_lead_angle[3] == Approx(lead).epsilon(1e-9));
  CHECK(L.lifter_trail_angle[3] == Approx(trail).epsilon(1e-9));
  CHECK(shell == Approx(kR * 0.2 * (2 * M_PI - rows * (lead + trail))).epsilon(1e-9));
}
