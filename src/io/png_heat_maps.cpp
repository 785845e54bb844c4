// The heat maps of png_plot.h: rectangles coloured on a log scale (the
// liner unrolled) with marked angles, and a bar chart beneath them.
#include "io/png_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "io/atomic_file.h"
#include "io/png_canvas.h"

namespace mc::io {

using draw::Axis;
using draw::Canvas;
using draw::P;
using draw::check_size;
using draw::kLabelPx;
using draw::kNotePx;
using draw::kTickPx;
using draw::kTitlePx;
using draw::mix;
using draw::nice_axis;
using draw::number;
using draw::tick_label;

namespace {

// The heat scale: dark blue through teal and yellow to red, t in [0, 1].
std::uint32_t heat(double t) {
  static const std::uint32_t table[] = {0x2c3e9e, 0x2a8fbd, 0x3fb67b, 0xb5d334, 0xfdb92e, 0xe2401c};
  t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) * 5 : 0;
  const int i = std::min(4, static_cast<int>(t));
  return mix(table[i], table[i + 1], t - i);
}

// The frame of a panel inside (x, y, w, h): a title on top, y ticks and a
// y label on the left, x ticks and an x label (wrapped to the panel's
// width) below, `right` pixels kept on the right.
struct Panel {
  int L = 0, T = 0, R = 0, B = 0;
  double title_px = kTitlePx;
  std::vector<std::string> x_label;
};

Panel panel(const Canvas& cv, int x, int y, int w, int h, const std::string& title, const std::string& x_label,
            bool y_label, double ytick_w, int right, bool x_ticks = true) {
  Panel p;
  const double label_line = cv.cap_height(kLabelPx) + cv.descent(kLabelPx);
  p.L = x + static_cast<int>(std::ceil(std::max(60.0, (y_label ? 10 + label_line + 10 : 10) + ytick_w + 10)));
  p.R = x + w - right;
  p.title_px = cv.fit(title, kTitlePx, p.R - p.L);
  p.T = y + (title.empty() ? 12 : static_cast<int>(std::ceil(10 + cv.cap_height(p.title_px) + 14)));
  if (!x_label.empty()) p.x_label = cv.wrap(x_label, kLabelPx, p.R - p.L);
  const double below = (x_ticks ? 10 + cv.cap_height(kTickPx) + cv.descent(kTickPx) : 6) +
                       (p.x_label.empty() ? 0 : 9 + 1.25 * kLabelPx * (p.x_label.size() - 1) + label_line) + 10;
  p.B = y + h - static_cast<int>(std::ceil(below));
  p.B = std::max(p.B, p.T + 20);
  return p;
}

void draw_panel_labels(Canvas& cv, const Panel& p, int x, const std::string& title, const std::string& y_label,
                       bool x_ticks = true) {
  constexpr std::uint32_t kInk = 0x222222;
  const double tick_line = x_ticks ? 10 + cv.cap_height(kTickPx) + cv.descent(kTickPx) : 6;
  for (std::size_t k = 0; k < p.x_label.size(); ++k)
    cv.text((p.L + p.R) / 2.0, p.B + tick_line + 9 + 1.25 * kLabelPx * k, p.x_label[k], kInk, kLabelPx, 0.5, 0);
  if (!y_label.empty())
    cv.text(x + 10, (p.T + p.B) / 2.0, y_label, kInk, cv.fit(y_label, kLabelPx, p.B - p.T), 0.5, 0, true);
  if (!title.empty()) cv.text(p.L, p.T - 14 - cv.cap_height(p.title_px), title, kInk, p.title_px, 0, 0);
}

void draw_heat_map(Canvas& cv, const HeatMap& m, int x, int y, int w, int h) {
  constexpr std::uint32_t kInk = 0x222222, kFrame = 0x444444, kEmpty = 0xdddddd;
  double hi = 0;
  for (const HeatCell& c : m.cells)
    if (std::isfinite(c.value)) hi = std::max(hi, c.value);
  const Axis ax = nice_axis(m.x_lo, m.x_hi, 0), ay = nice_axis(m.y_lo, m.y_hi, 0);
  double ytick_w = 0;
  for (int i = 0; i < ay.ticks(); ++i) ytick_w = std::max(ytick_w, cv.text_width(tick_label(ay.tick(i), ay.step), kTickPx));
  const Panel p = panel(cv, x, y, w, h, m.title, m.x_label, !m.y_label.empty(), ytick_w, 120);
  const int L = p.L, T = p.T, R = p.R, B = p.B;
  auto X = [&](double v) { return L + (v - m.x_lo) / (m.x_hi - m.x_lo) * (R - L); };
  auto Y = [&](double v) { return B - (v - m.y_lo) / (m.y_hi - m.y_lo) * (B - T); };
  cv.clip(L, T, R, B);
  cv.fill_rect(L, T, R, B, 0xf4f4f4);
  for (const HeatCell& c : m.cells) {
    const bool some = hi > 0 && c.value > 0 && std::isfinite(c.value);
    const double t = some ? 1 + std::log10(c.value / hi) / m.decades : 0;
    const std::uint32_t col = some ? heat(t) : kEmpty;
    cv.polygon({{X(c.x0), Y(c.y1)}, {X(c.x1), Y(c.y1)}, {X(c.x1), Y(c.y0)}, {X(c.x0), Y(c.y0)}}, col);
  }
  for (const HeatCell& c : m.cells)
    if (c.outline) {
      const P a{X(c.x0), Y(c.y0)}, b{X(c.x1), Y(c.y0)}, d{X(c.x1), Y(c.y1)}, e{X(c.x0), Y(c.y1)};
      for (auto [p0, q] : {std::pair{a, b}, {b, d}, {d, e}, {e, a}}) cv.line(p0, q, 0x111111, 1);
    }
  // The marks, then their labels over them, one under the other so that
  // near marks stay legible.
  for (std::size_t k = 1; k < m.curve.size(); ++k)
    cv.line({X(m.curve[k - 1].first), Y(m.curve[k - 1].second)}, {X(m.curve[k].first), Y(m.curve[k].second)},
            kInk, 2);
  for (const HeatMap::Mark& mk : m.marks_x)
    if (std::isfinite(mk.x)) {  // in its colour, edged in ink so that it shows on any cell
      cv.line({X(mk.x), double(T)}, {X(mk.x), double(B)}, kInk, 6);
      cv.line({X(mk.x), double(T)}, {X(mk.x), double(B)}, mk.rgb, 3);
    }
  int nth = 0;
  for (const HeatMap::Mark& mk : m.marks_x) {
    if (!std::isfinite(mk.x)) continue;
    const double tw = cv.text_width(mk.label, kNotePx);
    const double tx = X(mk.x) + 6 + tw > R - 4 ? X(mk.x) - 6 - tw : X(mk.x) + 6;
    cv.label(tx, T + 10 + 22 * nth++, mk.label, mk.rgb, kNotePx);
  }
  if (!m.curve.empty() && !m.curve_label.empty()) {
    const double tw = cv.text_width(m.curve_label, kNotePx);
    cv.label(R - 8 - tw, B - 18, m.curve_label, kInk, kNotePx);
  }
  cv.unclip();
  cv.fill_rect(L, T, R, T + 1, kFrame), cv.fill_rect(L, B - 1, R, B, kFrame);
  cv.fill_rect(L, T, L + 1, B, kFrame), cv.fill_rect(R - 1, T, R, B, kFrame);
  for (int i = 0; i < ax.ticks(); ++i) {
    const double v = ax.tick(i);
    if (v < m.x_lo - 1e-9 || v > m.x_hi + 1e-9) continue;
    cv.fill_rect(std::floor(X(v)), B, std::floor(X(v)) + 1, B + 5, kFrame);
    cv.text(std::floor(X(v)) + 0.5, B + 10, tick_label(v, ax.step), kInk, kTickPx, 0.5, 0);
  }
  for (int i = 0; i < ay.ticks(); ++i) {
    const double v = ay.tick(i);
    if (v < m.y_lo - 1e-9 || v > m.y_hi + 1e-9) continue;
    cv.fill_rect(L - 5, std::floor(Y(v)), L, std::floor(Y(v)) + 1, kFrame);
    cv.text(L - 9, std::floor(Y(v)) + 0.5, tick_label(v, ay.step), kInk, kTickPx, 1, 0.5);
  }
  draw_panel_labels(cv, p, x, m.title, m.y_label);
  // The colour bar: the top decade labelled, log steps below it.
  const double bx0 = R + 20, bx1 = R + 34;
  for (int j = 0; j < B - T; ++j) cv.fill_rect(bx0, T + j, bx1, T + j + 1, heat(1 - (j + 0.5) / (B - T)));
  cv.fill_rect(bx0 - 1, T - 1, bx1 + 1, T, kFrame), cv.fill_rect(bx0 - 1, B, bx1 + 1, B + 1, kFrame);
  cv.fill_rect(bx0 - 1, T, bx0, B, kFrame), cv.fill_rect(bx1, T, bx1 + 1, B, kFrame);
  for (int d = 0; d <= static_cast<int>(m.decades); ++d) {
    const double v = hi * std::pow(10.0, -d);
    const double yy = std::floor(T + (B - T) * d / m.decades);
    cv.fill_rect(bx1, yy, bx1 + 4, yy + 1, kFrame);
    cv.text(bx1 + 7, yy + 0.5, hi > 0 ? number("%.2g", v) : "0", kInk, kTickPx, 0, 0.5);
  }
  cv.text(bx0, T - 9, m.unit, kInk, kTickPx, 0, 1);
}

void draw_bars(Canvas& cv, const BarChart& b, int x, int y, int w, int h) {
  constexpr std::uint32_t kInk = 0x222222, kFrame = 0x444444;
  double hi = 0;
  for (const auto& [name, v] : b.bars)
    if (std::isfinite(v)) hi = std::max(hi, v);
  const Axis ay = nice_axis(0, hi > 0 ? 1.08 * hi : 1, 0);  // room for the values above the bars
  double ytick_w = 0;
  for (int i = 0; i < ay.ticks(); ++i) ytick_w = std::max(ytick_w, cv.text_width(tick_label(ay.tick(i), ay.step), kTickPx));
  const Panel p = panel(cv, x, y, w, h, b.title, "", !b.y_label.empty(), ytick_w, 120);
  const int L = p.L, T = p.T, R = p.R, B = p.B;
  auto Y = [&](double v) { return B - v / ay.hi * (B - T); };
  for (int i = 0; i < ay.ticks(); ++i) {
    const double v = ay.tick(i);
    cv.fill_rect(L, std::floor(Y(v)), R, std::floor(Y(v)) + 1, 0xe6e6e6);
    cv.fill_rect(L - 5, std::floor(Y(v)), L, std::floor(Y(v)) + 1, kFrame);
    cv.text(L - 9, std::floor(Y(v)) + 0.5, tick_label(v, ay.step), kInk, kTickPx, 1, 0.5);
  }
  const int n = static_cast<int>(b.bars.size());
  for (int k = 0; k < n; ++k) {
    const double slot = static_cast<double>(R - L) / n;
    const double x0 = L + slot * (k + 0.2), x1 = L + slot * (k + 0.8);
    const double v = std::isfinite(b.bars[k].second) ? b.bars[k].second : 0;
    cv.fill_rect(x0, Y(v), x1, B, b.rgb);
    cv.text((x0 + x1) / 2, Y(v) - 6, number("%.3g", v), kInk, kTickPx, 0.5, 1);
    cv.text((x0 + x1) / 2, B + 10, b.bars[k].first, kInk, cv.fit(b.bars[k].first, kTickPx, slot - 6), 0.5, 0);
  }
  cv.fill_rect(L, B - 1, R, B, kFrame), cv.fill_rect(L, T, L + 1, B, kFrame);
  draw_panel_labels(cv, p, x, b.title, b.y_label);
}

}  // namespace

void write_heat_maps_png(const std::filesystem::path& path, const std::vector<HeatMap>& maps, const BarChart& bars,
                         int width) {
  const int map_h = 320, bar_h = bars.bars.empty() ? 0 : 270;
  const int height = static_cast<int>(maps.size()) * map_h + bar_h;
  check_size(width, height);
  Canvas cv(width, height);
  for (std::size_t k = 0; k < maps.size(); ++k) draw_heat_map(cv, maps[k], 0, static_cast<int>(k) * map_h, width, map_h);
  if (!bars.bars.empty()) draw_bars(cv, bars, 0, static_cast<int>(maps.size()) * map_h, width, bar_h);
  write_file_atomic(path, cv.png());
}

}  // namespace mc::io
