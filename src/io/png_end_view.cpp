// The end view of png_plot.h: the mill's cross-section seen along its axis,
// balls coloured by speed, toe, shoulder, impact point and centre of mass
// marked.
#include "io/png_plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
#include <vector>

#include "io/atomic_file.h"
#include "io/png_canvas.h"

namespace mc::io {

using draw::Canvas;
using draw::P;
using draw::check_size;
using draw::format;
using draw::kNotePx;
using draw::kTitlePx;
using draw::mix;

namespace {

// Viridis sampled at 0, 0.1, …, 1.
std::uint32_t viridis(double t) {
  static const std::uint32_t table[] = {0x440154, 0x482475, 0x414487, 0x355f8d, 0x2a788e, 0x21918c,
                                        0x22a884, 0x44bf70, 0x7ad151, 0xbddf26, 0xfde725};
  t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) * 10 : 0;
  const int i = std::min(9, static_cast<int>(t));
  return mix(table[i], table[i + 1], t - i);
}

}  // namespace

void write_end_view_png(const std::filesystem::path& path, const EndView& view, int size) {
  check_size(size, size);
  Canvas cv(size, size);
  constexpr std::uint32_t kInk = 0x222222, kShell = 0x333333, kToe = 0xd62728, kShoulder = 0xe6700a;

  // Scale: the shell fills the square below the title, with room for labels.
  double shell = view.shell_radius;
  if (!(shell > 0) || !std::isfinite(shell)) {
    shell = 0;
    for (const EndViewBall& b : view.balls) shell = std::max(shell, std::hypot(b.x, b.y) + b.radius);
    for (const auto& poly : view.lifters)
      for (const Vec2& v : poly) shell = std::max(shell, std::hypot(v.x, v.y));
    if (!(shell > 0) || !std::isfinite(shell)) shell = 1;
  }
  const double top = view.title.empty() ? 0 : 36, pad = std::max(24.0, 0.06 * size);
  const double rpx = std::max(1.0, (size - top - 2 * pad) / 2);
  const P centre{size / 2.0, top + pad + rpx};
  const double k = rpx / shell;
  auto map = [&](double x, double y) { return P{centre.x + x * k, centre.y - y * k}; };  // y up

  for (const auto& poly : view.lifters) {
    std::vector<P> pts;
    for (const Vec2& v : poly) pts.push_back(map(v.x, v.y));
    cv.polygon(pts, 0xa3a3a3);
    for (std::size_t i = 0; i < pts.size() && pts.size() > 2; ++i) cv.line(pts[i], pts[(i + 1) % pts.size()], 0x6e6e6e, 1);
  }

  // Balls far to near: the viewer looks along −z, so a larger z is nearer and
  // is drawn later (on top).
  double vmax = view.max_speed;
  if (!(vmax > 0) || !std::isfinite(vmax)) {
    vmax = 0;
    for (const EndViewBall& b : view.balls)
      if (std::isfinite(b.speed)) vmax = std::max(vmax, b.speed);
    if (!(vmax > 0)) vmax = 1;
  }
  std::vector<std::size_t> order(view.balls.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return view.balls[a].z < view.balls[b].z; });
  for (std::size_t i : order) {
    const EndViewBall& b = view.balls[i];
    if (!std::isfinite(b.x) || !std::isfinite(b.y)) continue;
    const P c = map(b.x, b.y);
    const double r = std::max(b.radius * k, 0.6);
    const std::uint32_t fill = viridis(std::isfinite(b.speed) ? b.speed / vmax : 0);
    if (r >= 2.5) {
      cv.disc(c, r, mix(fill, 0x000000, 0.45));
      cv.disc(c, r - 1.1, fill);
    } else {
      cv.disc(c, r, fill);
    }
  }
  cv.ring(centre, rpx, 3, kShell);

  // Toe and shoulder: radius from the centre to the shell, labelled outside;
  // a label that would cover one already placed moves along its ray (out,
  // then in), as the viewer's do (viewer/label_layout.h).
  std::vector<std::array<double, 4>> taken;  // x0, y0, x1, y1
  auto mark = [&](double deg, const char* name, std::uint32_t rgb) {
    if (!(deg >= 0) || !std::isfinite(deg)) return;
    const double a = deg * (3.14159265358979323846 / 180), ca = std::cos(a), sa = std::sin(a);
    cv.line(centre, map(shell * ca, shell * sa), rgb, 2.5);
    const std::string s = std::string(name) + " " + format("%.0f", deg) + "\u00b0";
    const double tw = cv.text_width(s, kNotePx), th = cv.cap_height(kNotePx);
    double x = 0, y = 0;
    for (int k = 0; k < 9; ++k) {
      const double out = 12 + 14.0 * (k % 2 == 1 ? (k + 1) / 2 : -(k / 2) * 0.5);
      const P p{centre.x + (rpx + out) * ca, centre.y - (rpx + out) * sa};
      x = ca > 0.3 ? p.x : ca < -0.3 ? p.x - tw : p.x - tw / 2;
      y = sa > 0.3 ? p.y - th : sa < -0.3 ? p.y : p.y - th / 2;
      x = std::clamp(x, 6.0, size - 6 - tw), y = std::clamp(y, 6.0, size - 8 - th);
      bool clear = true;
      for (const auto& t : taken)
        clear = clear && (x + tw + 6 < t[0] || t[2] < x - 6 || y + th + 6 < t[1] || t[3] < y - 6);
      if (clear) break;
    }
    taken.push_back({x, y, x + tw, y + th});
    cv.label(x, y, s, rgb, kNotePx);
  };
  mark(view.toe_deg, "toe", kToe);
  mark(view.shoulder_deg, "shoulder", kShoulder);
  mark(view.impact_deg, "impact", 0xc51b8a);

  if (view.has_com && std::isfinite(view.com_x) && std::isfinite(view.com_y)) {
    const P c = map(view.com_x, view.com_y);
    cv.line(centre, c, 0xffffff, 4), cv.line(centre, c, kInk, 1.5);
    for (int s : {-1, 1}) cv.line({c.x - 7, c.y - 7.0 * s}, {c.x + 7, c.y + 7.0 * s}, 0xffffff, 4.5);
    for (int s : {-1, 1}) cv.line({c.x - 7, c.y - 7.0 * s}, {c.x + 7, c.y + 7.0 * s}, kInk, 2);
  }
  cv.disc(centre, 2.5, kInk);

  // Colour bar in the bottom-right corner (outside the shell).
  if (!view.balls.empty()) {
    const double bw = 12, bh = std::min(160.0, 0.25 * size), x1 = size - 16.0, y1 = size - 16.0;
    const double x0 = x1 - bw, y0 = y1 - bh;
    for (int j = 0; j < static_cast<int>(bh); ++j) cv.fill_rect(x0, y0 + j, x1, y0 + j + 1, viridis(1 - (j + 0.5) / bh));
    cv.fill_rect(x0 - 1, y0 - 1, x1 + 1, y0, kShell), cv.fill_rect(x0 - 1, y1, x1 + 1, y1 + 1, kShell);
    cv.fill_rect(x0 - 1, y0, x0, y1, kShell), cv.fill_rect(x1, y0, x1 + 1, y1, kShell);
    const std::string hi = format("%.3g m/s", vmax);
    cv.fill_rect(x0 - 4, y0, x0 - 1, y0 + 1, kShell), cv.fill_rect(x0 - 4, y1 - 1, x0 - 1, y1, kShell);
    cv.text(x0 - 7, y0 + 0.5, hi, kInk, kNotePx, 1, 0.5);
    cv.text(x0 - 7, y1 - 0.5, "0", kInk, kNotePx, 1, 0.5);
    cv.text(x1, y0 - 12, "speed", kInk, kNotePx, 1, 1);
  }
  if (!view.title.empty())
    cv.text(size / 2.0, 14, view.title, kInk, cv.fit(view.title, kTitlePx, size - 24.0), 0.5, 0);

  write_file_atomic(path, cv.png());
}

}  // namespace mc::io
