// PNG pictures: written, read back with stb_image, and checked pixel by pixel
// where the geometry is known.
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/png_plot.h"

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

namespace fs = std::filesystem;
using namespace mc::io;

namespace {

// A fresh folder under the system temporary one, removed at the end.
struct TempDir {
  fs::path path;
  TempDir() {
    std::random_device rd;
    const auto t = std::chrono::steady_clock::now().time_since_epoch().count();
    path = fs::temp_directory_path() /
           ("millcharge_png_" + std::to_string(t) + "_" + std::to_string(rd()));
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

struct Rgb {
  int r = 0, g = 0, b = 0;
};

struct Image {
  int w = 0, h = 0;
  std::vector<unsigned char> px;
  Rgb at(int x, int y) const {
    const unsigned char* p = &px[(static_cast<std::size_t>(y) * w + x) * 3];
    return {p[0], p[1], p[2]};
  }
};

Image load(const fs::path& p) {
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(p.string().c_str(), &w, &h, &n, 3);
  REQUIRE(data != nullptr);
  Image im{w, h, std::vector<unsigned char>(data, data + static_cast<std::size_t>(w) * h * 3)};
  stbi_image_free(data);
  return im;
}

bool near(Rgb c, std::uint32_t rgb, int tol) {
  return std::abs(c.r - int((rgb >> 16) & 0xff)) <= tol && std::abs(c.g - int((rgb >> 8) & 0xff)) <= tol &&
         std::abs(c.b - int(rgb & 0xff)) <= tol;
}
bool white(Rgb c) { return c.r >= 250 && c.g >= 250 && c.b >= 250; }

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The ink of a line plot's title: pixels off white above the plot area's
// frame (the first row more than half dark from the top), in the middle half
// of the width, where a centred title lies and no tick label reaches.
int title_ink(const Image& im) {
  int frame = -1;
  for (int y = 0; y < im.h && frame < 0; ++y) {
    int dark = 0;
    for (int x = 0; x < im.w; ++x) dark += im.at(x, y).r < 160;
    if (dark > im.w / 2) frame = y;
  }
  REQUIRE(frame > 0);
  int ink = 0;
  for (int y = 0; y < frame - 1; ++y)
    for (int x = im.w / 4; x < im.w * 3 / 4; ++x) ink += !white(im.at(x, y));
  return ink;
}

}  // namespace

TEST_CASE("line plot: size, content in the plot area, series colours", "[png]") {
  TempDir dir;
  LinePlot plot;
  plot.title = "Power draw";
  plot.x_label = "time (s)";
  plot.y_label = "power (kW)";
  PlotSeries a{"shell", {}, {}, 0xd62728}, b{"lifters", {}, {}, 0x1f77b4};
  for (int i = 0; i <= 200; ++i) {
    const double t = 0.05 * i;
    a.x.push_back(t), a.y.push_back(3 + std::sin(t));
    b.x.push_back(t), b.y.push_back(1 + 0.5 * std::cos(2 * t));
  }
  plot.series = {a, b};
  plot.span_from = 4, plot.span_to = 8, plot.span_label = "average";
  const fs::path file = dir.path / "power.png";
  write_line_plot_png(file, plot, 640, 360);

  const Image im = load(file);
  REQUIRE(im.w == 640);
  REQUIRE(im.h == 360);
  int non_white = 0, red = 0, blue = 0, total = 0;
  for (int y = im.h * 15 / 100; y < im.h * 85 / 100; ++y)
    for (int x = im.w * 15 / 100; x < im.w * 85 / 100; ++x, ++total) {
      const Rgb c = im.at(x, y);
      non_white += !white(c);
      red += near(c, 0xd62728, 30);
      blue += near(c, 0x1f77b4, 30);
    }
  CHECK(non_white > total / 100);  // lines, grid and span are there …
  CHECK(non_white < total * 6 / 10);  // … but it is not a filled block
  CHECK(red > 400);  // ~450 px of 2 px line in the central box, at least
  CHECK(blue > 400);
  // The title is drawn in the top margin, dark, around the middle.
  int dark_top = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = im.w / 4; x < im.w * 3 / 4; ++x) dark_top += im.at(x, y).r < 100;
  CHECK(dark_top > 50);
}

TEST_CASE("line plot: NaN breaks the line, and constant data gets a range", "[png]") {
  TempDir dir;
  LinePlot plot;
  PlotSeries s{"", {}, {}, 0x00a000};  // no label: no legend in the way
  for (int i = 0; i <= 100; ++i) {
    s.x.push_back(i);
    s.y.push_back(i > 40 && i < 60 ? kNaN : 2.0);
  }
  plot.series = {s};
  const fs::path file = dir.path / "constant.png";
  write_line_plot_png(file, plot, 500, 300);
  const Image im = load(file);
  REQUIRE(im.w == 500);
  REQUIRE(im.h == 300);

  std::set<int> cols, rows;
  for (int y = 0; y < im.h; ++y)
    for (int x = 0; x < im.w; ++x)
      if (near(im.at(x, y), 0x00a000, 40)) cols.insert(x), rows.insert(y);
  REQUIRE(cols.size() > 100);
  // A horizontal line, 2 px thick, well inside the picture (a zero y range
  // would have put it on the frame or nowhere).
  CHECK(*rows.rbegin() - *rows.begin() <= 3);
  CHECK(*rows.begin() > im.h / 5);
  CHECK(*rows.rbegin() < im.h * 4 / 5);
  // It spans most of the width, with a gap of about a fifth of it where the
  // values are NaN.
  const int first = *cols.begin(), last = *cols.rbegin();
  CHECK(last - first > im.w / 2);
  int gap = 0, prev = first;
  for (int c : cols) gap = std::max(gap, c - prev), prev = c;
  CHECK(gap > (last - first) * 15 / 100);
  CHECK(gap < (last - first) * 25 / 100);
}

TEST_CASE("line plot: empty series, all-NaN series and a single point", "[png]") {
  TempDir dir;
  LinePlot plot;
  plot.title = "odd data";
  plot.series = {PlotSeries{"empty", {}, {}, 0x1f77b4}, PlotSeries{"nan", {1, 2}, {kNaN, kNaN}, 0xff7f0e},
                 PlotSeries{"", {3.0}, {7.0}, 0x00a000}};
  const fs::path file = dir.path / "odd.png";
  REQUIRE_NOTHROW(write_line_plot_png(file, plot, 320, 240));
  const Image im = load(file);
  CHECK(im.w == 320);
  CHECK(im.h == 240);
  int green = 0;
  for (int y = 0; y < im.h; ++y)
    for (int x = 0; x < im.w; ++x) green += near(im.at(x, y), 0x00a000, 40);
  CHECK(green >= 9);  // the lone point is a dot
  CHECK(green < 60);

  LinePlot none;
  const fs::path blank = dir.path / "none.png";
  REQUIRE_NOTHROW(write_line_plot_png(blank, none, 200, 150));
  CHECK(load(blank).w == 200);
}

TEST_CASE("end view: balls, painter's order, toe and shoulder, lifters", "[png]") {
  TempDir dir;
  const int size = 400;
  EndView view;
  view.shell_radius = 1.0;

  // The shell alone: its outline fixes the centre and scale in pixels.
  const fs::path shell_file = dir.path / "shell.png";
  write_end_view_png(shell_file, view, size);
  const Image shell = load(shell_file);
  REQUIRE(shell.w == size);
  REQUIRE(shell.h == size);
  int x0 = size, x1 = -1, y0 = size, y1 = -1;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      if (shell.at(x, y).r < 128) x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  REQUIRE(x1 > x0);
  const double cx = (x0 + x1 + 1) / 2.0, cy = (y0 + y1 + 1) / 2.0;
  const double rpx = (x1 - x0 + 1) / 2.0;
  CHECK(std::abs((y1 - y0) - (x1 - x0)) <= 1);  // a circle
  CHECK(rpx > size / 4);
  auto px = [&](double x, double y) {  // lab frame (m) to a pixel, y up
    return std::pair<int, int>{int(std::floor(cx + x * rpx)), int(std::floor(cy - y * rpx))};
  };

  // Two balls at the same place: the near one (larger z) is fast (yellow)
  // and comes first in the list, the far one is at rest (dark purple).
  view.balls = {EndViewBall{0.5, -0.5, 0.1, 0.08, 2.0}, EndViewBall{0.5, -0.5, -0.1, 0.08, 0.0}};
  view.max_speed = 2.0;
  view.lifters = {{{-0.1, -0.98}, {0.1, -0.98}, {0.1, -0.8}, {-0.1, -0.8}}};
  view.toe_deg = 180;
  view.shoulder_deg = 90;
  const fs::path file = dir.path / "view.png";
  write_end_view_png(file, view, size);
  const Image im = load(file);
  REQUIRE(im.w == size);
  REQUIRE(im.h == size);

  auto [bx, by] = px(0.5, -0.5);
  CHECK(near(im.at(bx, by), 0xfde725, 12));  // viridis at the top of the scale
  auto [ex, ey] = px(-0.5, 0.5);
  CHECK(white(im.at(ex, ey)));  // nothing there
  auto [rx, ry] = px(0.5, 0.0);
  CHECK(white(im.at(rx, ry)));  // no marker at 0°
  auto [tx, ty] = px(-0.5, 0.0);  // toe at 180°: left of the centre
  const Rgb toe = im.at(tx, ty);
  CHECK(toe.r > 150);
  CHECK(toe.g < 110);
  auto [sx, sy] = px(0.0, 0.5);  // shoulder at 90°: above the centre
  CHECK(!white(im.at(sx, sy)));
  auto [dx, dy] = px(0.0, -0.5);
  CHECK(white(im.at(dx, dy)));  // and not below it
  auto [lx, ly] = px(0.0, -0.89);  // inside the lifter: grey
  const Rgb lifter = im.at(lx, ly);
  CHECK(std::abs(lifter.r - lifter.g) < 8);
  CHECK(std::abs(lifter.g - lifter.b) < 8);
  CHECK(lifter.r > 110);
  CHECK(lifter.r < 200);

  // The far ball on its own shows the bottom of the scale; with max_speed 0
  // the scale comes from the balls (max 0 here), so speed 0 is still purple.
  view.balls = {EndViewBall{0.5, -0.5, -0.1, 0.08, 0.0}};
  view.max_speed = 0;
  view.toe_deg = view.shoulder_deg = -1;
  view.has_com = true, view.com_x = 0.0, view.com_y = -0.5;
  write_end_view_png(file, view, size);
  const Image far = load(file);
  CHECK(near(far.at(bx, by), 0x440154, 12));
  CHECK(white(far.at(tx, ty)));  // toe not marked any more
  auto [mx, my] = px(0.0, -0.25);  // on the line to the centre of mass
  CHECK(far.at(mx, my).r < 100);
}

TEST_CASE("pictures into a missing folder throw", "[png]") {
  TempDir dir;
  const fs::path missing = dir.path / "no" / "such" / "folder";
  LinePlot plot;
  plot.series = {PlotSeries{"a", {0, 1}, {0, 1}}};
  CHECK_THROWS_AS(write_line_plot_png(missing / "plot.png", plot), std::runtime_error);
  EndView view;
  view.shell_radius = 1;
  CHECK_THROWS_AS(write_end_view_png(missing / "view.png", view), std::runtime_error);
  CHECK_FALSE(fs::exists(missing));
}

TEST_CASE("text: anti-aliased, the y label reads upwards", "[png]") {
  TempDir dir;
  LinePlot plot;
  plot.title = "Power draw of the mill";
  plot.x_label = "time since the mill started (s)";
  plot.y_label = "power drawn by the mill (W)";
  plot.series = {PlotSeries{"", {0, 1, 2}, {1, 3, 2}, 0x1f77b4}};
  const fs::path file = dir.path / "text.png";
  write_line_plot_png(file, plot, 640, 400);
  const Image im = load(file);

  // The title: grey levels between ink and paper on its edges, not just the
  // two of a bitmap font.
  std::set<int> greys;
  int ink = 0, coloured = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = im.w / 4; x < im.w * 3 / 4; ++x) {
      const Rgb c = im.at(x, y);
      coloured += std::abs(c.r - c.g) > 2 || std::abs(c.g - c.b) > 2;
      if (c.r < 80) ++ink;
      if (c.r >= 80 && c.r <= 200) greys.insert(c.r);
    }
  CHECK(ink > 40);
  CHECK(greys.size() > 30);
  CHECK(coloured == 0);  // grey ink on white: no colour fringes

  // The y label, left of the tick labels: taller than wide.
  int x0 = im.w, x1 = -1, y0 = im.h, y1 = -1;
  for (int y = 0; y < im.h; ++y)
    for (int x = 0; x < 30; ++x)
      if (im.at(x, y).r < 128) x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  REQUIRE(x1 >= x0);
  CHECK(y1 - y0 > 100);        // the label's length, along y
  CHECK(x1 - x0 < 20);         // one line's height, along x
  CHECK(std::abs((y0 + y1) / 2 - im.h / 2) < 40);  // centred on the plot area

  // The x label under the plot, centred.
  int xl0 = im.w, xl1 = -1;
  for (int y = im.h - 24; y < im.h; ++y)
    for (int x = 0; x < im.w; ++x)
      if (im.at(x, y).r < 128) xl0 = std::min(xl0, x), xl1 = std::max(xl1, x);
  REQUIRE(xl1 > xl0);
  CHECK(xl1 - xl0 > 150);
  CHECK(std::abs((xl0 + xl1) / 2 - im.w / 2) < 40);
}

TEST_CASE("the plot font is built in: MILLCHARGE_FONT that cannot be read is a warning, never a lost picture",
          "[png]") {
  TempDir dir;
  struct Restore {  // MILLCHARGE_FONT as it was
    std::string old;
    bool had = false;
    Restore() {
      if (const char* v = std::getenv("MILLCHARGE_FONT")) old = v, had = true;
    }
    ~Restore() {
      if (had) setenv("MILLCHARGE_FONT", old.c_str(), 1);
      else unsetenv("MILLCHARGE_FONT");
    }
  } restore;
  LinePlot plot;
  plot.title = "font";
  plot.x_label = "x (s)";
  plot.series = {PlotSeries{"a", {0, 1}, {0, 1}}};
  auto bytes = [](const fs::path& f) {
    std::ifstream in(f, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };

  // Unset: the built-in font, no warning.
  unsetenv("MILLCHARGE_FONT");
  CHECK(plot_font_path().empty());
  CHECK(plot_font_in_use() == "built in");
  CHECK(plot_font_warning().empty());
  write_line_plot_png(dir.path / "builtin.png", plot);
  const std::string builtin = bytes(dir.path / "builtin.png");
  REQUIRE(builtin.size() > 1000);
  // Text drawn: the title's box holds ink (210 pixels for "font" at
  // 17 px), and none when the title is empty, so the count can fail.
  const int ink = title_ink(load(dir.path / "builtin.png"));
  std::printf("the built-in font's title \"font\": %d pixels of ink\n", ink);
  CHECK(ink > 100);  // measured 210
  LinePlot untitled = plot;
  untitled.title.clear();
  write_line_plot_png(dir.path / "untitled.png", untitled);
  CHECK(title_ink(load(dir.path / "untitled.png")) == 0);

  // A file that is not there, and one that is not a TrueType font: each is
  // named in a warning, and the picture is drawn in the built-in font, the
  // same bytes.
  const std::string missing = (dir.path / "no-such-font.ttf").string();
  const fs::path junk = dir.path / "junk.ttf";
  { std::ofstream(junk) << "not a font"; }
  using Catch::Matchers::Contains;
  for (const std::string& bad : {missing, junk.string()}) {
    INFO(bad);
    setenv("MILLCHARGE_FONT", bad.c_str(), 1);
    CHECK(plot_font_path() == fs::path(bad));
    CHECK(plot_font_in_use() == "built in");
    CHECK_THAT(plot_font_warning(), Contains(bad) && Contains("MILLCHARGE_FONT") && Contains("built-in font"));
    write_line_plot_png(dir.path / "fallback.png", plot);
    CHECK(bytes(dir.path / "fallback.png") == builtin);
  }
  setenv("MILLCHARGE_FONT", junk.string().c_str(), 1);
  CHECK_THAT(plot_font_warning(), Contains("not a TrueType font"));

  // Another font that can be read is drawn in: other pixels.
  const char* other = "/usr/share/fonts/truetype/dejavu/DejaVuSerif.ttf";
  if (fs::exists(other)) {
    setenv("MILLCHARGE_FONT", other, 1);
    CHECK(plot_font_in_use() == other);
    CHECK(plot_font_warning().empty());
    write_line_plot_png(dir.path / "serif.png", plot);
    CHECK(bytes(dir.path / "serif.png") != builtin);
  }
}

TEST_CASE("a picture that cannot be written is a warning naming the file, and the rest goes on", "[png]") {
  TempDir dir;
  LinePlot plot;
  plot.series = {PlotSeries{"a", {0, 1}, {0, 1}}};
  const fs::path blocked = dir.path / "not-a-folder";
  { std::ofstream(blocked) << "a file where a folder should be"; }
  const fs::path file = blocked / "plot.png";
  CHECK_FALSE(draw_or_warn(file, [&] { write_line_plot_png(file, plot); }));
  CHECK(draw_or_warn(dir.path / "plot.png", [&] { write_line_plot_png(dir.path / "plot.png", plot); }));
  CHECK(fs::exists(dir.path / "plot.png"));
}

TEST_CASE("line plot: reference lines across the averaging window, in the legend", "[png]") {
  TempDir dir;
  LinePlot plot;
  plot.title = "reference lines";
  PlotSeries lo{"", {}, {}, 0x1f77b4}, hi{"", {}, {}, 0xd62728};
  for (int i = 0; i <= 100; ++i) lo.x.push_back(0.1 * i), lo.y.push_back(0), hi.x.push_back(0.1 * i), hi.y.push_back(10);
  plot.series = {lo, hi};
  plot.span_from = 4, plot.span_to = 8;
  const std::uint32_t mean_rgb = 0x7b00d4, dash_rgb = 0x00a060;
  plot.ref_lines = {{5.0, 4, 8, mean_rgb, false, ""}, {7.5, 4, 8, dash_rgb, true, ""}};
  // First without labels: no legend.
  const fs::path file = dir.path / "ref.png";
  write_line_plot_png(file, plot, 800, 480);
  const Image im = load(file);

  // The rows of the two series (0 and 10) fix the y scale: 5 lies halfway.
  auto rows_of = [&](std::uint32_t rgb, int x) {
    std::vector<int> rows;
    for (int y = 0; y < im.h; ++y)
      if (near(im.at(x, y), rgb, 40)) rows.push_back(y);
    return rows;
  };
  const std::vector<int> r0 = rows_of(0x1f77b4, im.w / 2), r10 = rows_of(0xd62728, im.w / 2);
  REQUIRE(!r0.empty());
  REQUIRE(!r10.empty());
  const double y0 = (r0.front() + r0.back()) / 2.0, y10 = (r10.front() + r10.back()) / 2.0;
  const int mean_row = static_cast<int>(std::lround((y0 + y10) / 2 - 0.5));
  const int dash_row = static_cast<int>(std::lround(y0 + (y10 - y0) * 0.75 - 0.5));

  // The span's columns, from its shading halfway between the lines.
  const int probe = (mean_row + dash_row) / 2;
  int sa = im.w, sb = -1;
  for (int x = 0; x < im.w; ++x)
    if (near(im.at(x, probe), 0xfbe3b0, 25) || near(im.at(x, probe), 0xfdeed0, 12)) sa = std::min(sa, x), sb = std::max(sb, x);
  REQUIRE(sb - sa > im.w / 5);

  // The mean: in its colour at its row in every column of the span, and
  // nowhere in that band outside the span.
  auto has = [&](int x, int row, std::uint32_t rgb) {
    for (int y = row - 1; y <= row + 1; ++y)
      if (near(im.at(x, y), rgb, 30)) return true;
    return false;
  };
  int across = 0, outside = 0, dashed = 0;
  for (int x = sa + 2; x <= sb - 2; ++x) across += has(x, mean_row, mean_rgb), dashed += has(x, dash_row, dash_rgb);
  for (int x = 0; x < im.w; ++x)
    if (x < sa - 3 || x > sb + 3) outside += has(x, mean_row, mean_rgb) + has(x, dash_row, dash_rgb);
  CHECK(across == sb - sa - 3);
  CHECK(outside == 0);
  // The dashed one: dashes and gaps.
  CHECK(dashed > (sb - sa) * 45 / 100);
  CHECK(dashed < (sb - sa) * 85 / 100);

  // With labels, each is in the legend: more pixels of its colour.
  auto count = [](const Image& m, std::uint32_t rgb) {
    int n = 0;
    for (int y = 0; y < m.h; ++y)
      for (int x = 0; x < m.w; ++x) n += near(m.at(x, y), rgb, 30);
    return n;
  };
  plot.ref_lines[0].label = "mean 5.0 \u00b1 0.1";
  plot.ref_lines[1].label = "dashed 7.5";
  const fs::path labelled = dir.path / "ref_labelled.png";
  write_line_plot_png(labelled, plot, 800, 480);
  const Image lm = load(labelled);
  CHECK(count(lm, mean_rgb) > count(im, mean_rgb) + 20);
  CHECK(count(lm, dash_rgb) > count(im, dash_rgb) + 10);
}

TEST_CASE("a value with its standard error", "[png]") {
  CHECK(value_with_error(874.43, 2.83, "W") == "874.4 \u00b1 2.8 W");
  CHECK(value_with_error(871.7, 6.3, "W") == "871.7 \u00b1 6.3 W");
  CHECK(value_with_error(0.123456, 0.00123, "") == "0.1235 \u00b1 0.0012");
  CHECK(value_with_error(1234567.8, 2345, "W") == "1234568 \u00b1 2345 W");
  CHECK(value_with_error(-5.0, 0.12, "W") == "\u22125.00 \u00b1 0.12 W");
  CHECK(value_with_error(871.66, kNaN, "W") == "871.7 W");
  CHECK(value_with_error(871.66, 0, "W") == "871.7 W");
}

TEST_CASE("heat map: coloured marks over the cells, and a curve on the map's y axis", "[png]") {
  // One row of cells of one value (the colour bar's top), a mark in cyan
  // at x = 0.5, a curve along y = 0.5 in ink. The mark's colour stands in
  // a column the height of the map; the curve adds a row of ink across it.
  TempDir dir;
  auto map = [](bool marks, bool curve) {
    HeatMap m;
    m.title = "strip";
    m.y_label = "covered";
    m.unit = "W/deg";
    for (int k = 0; k < 100; ++k) m.cells.push_back({k / 100.0, (k + 1) / 100.0, 0, 1, 1.0, false});
    if (marks) m.marks_x.push_back({0.5, "toe", 0x1ca3c4});
    if (curve)
      for (int k = 0; k <= 100; ++k) m.curve.push_back({k / 100.0, 0.25});
    return m;
  };
  auto count = [&](const fs::path& p, std::uint32_t rgb, int tol) {
    const Image im = load(p);
    int n = 0;
    for (int y = 0; y < im.h; ++y)
      for (int x = 0; x < im.w; ++x) n += near(im.at(x, y), rgb, tol);
    return n;
  };
  write_heat_maps_png(dir.path / "bare.png", {map(false, false)}, BarChart{}, 800);
  write_heat_maps_png(dir.path / "marked.png", {map(true, false)}, BarChart{}, 800);
  write_heat_maps_png(dir.path / "curved.png", {map(false, true)}, BarChart{}, 800);
  const int cyan_bare = count(dir.path / "bare.png", 0x1ca3c4, 20), cyan = count(dir.path / "marked.png", 0x1ca3c4, 20);
  const int ink_bare = count(dir.path / "bare.png", 0x222222, 30), ink = count(dir.path / "curved.png", 0x222222, 30);
  INFO("cyan pixels " << cyan_bare << " -> " << cyan << ", ink " << ink_bare << " -> " << ink);
  // (The colour bar's ramp passes near cyan.)
  CHECK(cyan - cyan_bare >= 2 * 150);  // a 3 px line the map's height (at least 150 px), and its label
  CHECK(ink - ink_bare >= 500);  // a 2 px curve across a map over 500 px wide
  // Where they are: in a column at 30 % of the picture's width the map's
  // cells run from its top to its bottom, and the curve at y = 0.25 lies a
  // quarter of the way up; the mark's column is at the map's middle.
  const Image bare = load(dir.path / "bare.png"), curved = load(dir.path / "curved.png"),
              marked = load(dir.path / "marked.png");
  const int col = bare.w * 3 / 10;
  const Rgb cell = bare.at(col, bare.h / 2);
  int top = -1, bottom = -1, ink_row = -1;
  for (int y = 0; y < bare.h; ++y)
    if (near(bare.at(col, y), (cell.r << 16) | (cell.g << 8) | cell.b, 10)) {
      if (top < 0) top = y;
      bottom = y;
    }
  for (int y = top; y <= bottom && ink_row < 0; ++y)
    if (near(curved.at(col, y), 0x222222, 40)) ink_row = y;
  REQUIRE(top >= 0);
  REQUIRE(ink_row >= 0);
  INFO("map rows " << top << " to " << bottom << ", curve at row " << ink_row);
  CHECK((bottom - ink_row) / double(bottom - top) == Approx(0.25).margin(0.02));
  int left = -1, right = -1;
  for (int x = 0; x < marked.w; ++x)
    if (near(marked.at(x, (top + bottom) / 2), 0x1ca3c4, 20)) {
      if (left < 0) left = x;
      right = x;
    }
  int map_left = -1, map_right = -1;
  for (int x = 0; x < bare.w; ++x)
    if (near(bare.at(x, (top + bottom) / 2), (cell.r << 16) | (cell.g << 8) | cell.b, 10)) {
      if (map_left < 0) map_left = x;
      map_right = x;
    }
  REQUIRE(left >= 0);
  CHECK(0.5 * (left + right) == Approx(0.5 * (map_left + map_right)).margin(3));
}

TEST_CASE("end view: an impact point beside the toe is labelled clear of the toe's label", "[png]") {
  // Toe at 232 deg, impact point at 234: their labels would lie on each
  // other; each must keep as much ink as when the impact point is far off.
  TempDir dir;
  auto ink = [&](double impact, std::uint32_t rgb) {
    EndView view;
    view.shell_radius = 1.0;
    view.toe_deg = 232;
    view.shoulder_deg = 40;
    view.impact_deg = impact;
    const fs::path f = dir.path / ("v" + std::to_string(static_cast<int>(impact)) + ".png");
    write_end_view_png(f, view, 600);
    const Image im = load(f);
    // Outside the shell (the marks' lines end at it): the labels.
    int n = 0;
    for (int y = 0; y < im.h; ++y)
      for (int x = 0; x < im.w; ++x) {
        const double dx = x - im.w / 2.0, dy = y - im.h / 2.0;
        if (std::hypot(dx, dy) > 0.42 * im.w) n += near(im.at(x, y), rgb, 60);
      }
    return n;
  };
  const int toe_near = ink(234, 0xd62728), toe_far = ink(320, 0xd62728);
  const int impact_near = ink(234, 0xc51b8a), impact_far = ink(320, 0xc51b8a);
  INFO("toe label ink " << toe_near << " (impact far: " << toe_far << "), impact " << impact_near << " ("
                        << impact_far << ")");
  REQUIRE(toe_far > 20);
  REQUIRE(impact_far > 20);
  CHECK(toe_near >= 0.85 * toe_far);
  CHECK(impact_near >= 0.85 * impact_far);
}
