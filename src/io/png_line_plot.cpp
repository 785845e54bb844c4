// The line plots of png_plot.h: series against x, reference lines, a
// shaded span and a legend placed where it hides the least; several plots
// stacked in one picture.
#include "io/png_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/atomic_file.h"
#include "io/png_canvas.h"

namespace mc::io {

using draw::Axis;
using draw::Canvas;
using draw::P;
using draw::check_size;
using draw::kLabelPx;
using draw::kLegendPx;
using draw::kTickPx;
using draw::kTitlePx;
using draw::minus;
using draw::nice_axis;
using draw::number;
using draw::superscript;
using draw::tick_label;

namespace {

// A segment drawn as 8-pixel dashes with 5-pixel gaps; `phase` carries the
// pattern from one segment of a polyline to the next.
void dashed_line(Canvas& cv, P a, P b, std::uint32_t rgb, double width, double& phase) {
  constexpr double kOn = 8, kPeriod = 13;
  const double len = std::hypot(b.x - a.x, b.y - a.y);
  if (!(len > 0) || !std::isfinite(len)) return;
  double t = 0;
  while (t < len) {
    const double in = std::fmod(phase + t, kPeriod);
    const double piece = std::min(len - t, in < kOn ? kOn - in : kPeriod - in);
    if (in < kOn) {
      const P p{a.x + (b.x - a.x) * t / len, a.y + (b.y - a.y) * t / len};
      const P q{a.x + (b.x - a.x) * (t + piece) / len, a.y + (b.y - a.y) * (t + piece) / len};
      cv.line(p, q, rgb, width);
    }
    t += piece;
  }
  phase = std::fmod(phase + len, kPeriod);
}

// A tick of a log axis at log10 x = e: 10 with a superscript power for a
// whole power, else the value.
std::string log_tick_label(double e, double step) {
  const double k = std::round(e);
  if (step < 1 || std::abs(e - k) > 1e-6) return number("%.2g", std::pow(10.0, e));
  return "10" + superscript(static_cast<long>(k));
}

// A legend's entry: a line (solid or dashed, with or without a marker) or,
// with `patch`, a filled swatch.
struct LegendEntry {
  std::string label;
  std::uint32_t rgb = 0;
  bool dashed = false, markers = false, patch = false;
  double alpha = 1;
};

// The line plot drawn on a canvas of its own.
Canvas render_line_plot(const LinePlot& given, int width, int height) {
  check_size(width, height);
  Canvas cv(width, height);
  constexpr std::uint32_t kInk = 0x222222, kFrame = 0x444444, kGrid = 0xe6e6e6, kSpan = 0xfbe3b0;
  constexpr double kDataWidth = 1.8;
  // A log x axis: the plot of log10 x, ticks labelled with powers of ten.
  LinePlot plot = given;
  if (plot.log_x) {
    for (PlotSeries& s : plot.series)
      for (double& x : s.x) x = x > 0 ? std::log10(x) : NAN;
    plot.span_from = plot.span_from > 0 ? std::log10(plot.span_from) : NAN;
    plot.span_to = plot.span_to > 0 ? std::log10(plot.span_to) : NAN;
    for (RefLine& r : plot.ref_lines)
      if (r.x_to > r.x_from) {
        r.x_from = r.x_from > 0 ? std::log10(r.x_from) : NAN;
        r.x_to = r.x_to > 0 ? std::log10(r.x_to) : NAN;
      }
  }

  // Data ranges over the finite points and the span.
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const PlotSeries& s : plot.series)
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i]))
        x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]), y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
  for (const PlotSeries& s : plot.series)
    for (std::size_t i = 0; i < std::min({s.x.size(), s.band_lo.size(), s.band_hi.size()}); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.band_lo[i]) && std::isfinite(s.band_hi[i]))
        y0 = std::min(y0, s.band_lo[i]), y1 = std::max(y1, s.band_hi[i]);
  const bool span = plot.span_to > plot.span_from && std::isfinite(plot.span_from) && std::isfinite(plot.span_to);
  if (span) x0 = std::min(x0, plot.span_from), x1 = std::max(x1, plot.span_to);
  for (const RefLine& r : plot.ref_lines)
    if (std::isfinite(r.value)) {
      y0 = std::min(y0, r.value), y1 = std::max(y1, r.value);
      if (r.x_to > r.x_from && std::isfinite(r.x_from) && std::isfinite(r.x_to))
        x0 = std::min(x0, r.x_from), x1 = std::max(x1, r.x_to);
    }
  if (std::isfinite(plot.y_cover_lo)) y0 = std::min(y0, plot.y_cover_lo), y1 = std::max(y1, plot.y_cover_lo);
  if (std::isfinite(plot.y_cover_hi)) y0 = std::min(y0, plot.y_cover_hi), y1 = std::max(y1, plot.y_cover_hi);
  if (!(x0 <= x1)) x0 = 0, x1 = 1;
  if (!(y0 <= y1)) y0 = 0, y1 = 1;
  if (plot.equal_aspect && x1 > x0 && y1 > y0) {
    // Widen the narrower range about its middle to the plot area's shape
    // (the area's size before the labels are placed, near enough).
    const double want = (width - 110.0) / std::max(1.0, height - 110.0);
    const double have = (x1 - x0) / (y1 - y0);
    if (have < want) {
      const double m = 0.5 * (x0 + x1), h = 0.5 * (y1 - y0) * want;
      x0 = m - h, x1 = m + h;
    } else {
      const double m = 0.5 * (y0 + y1), h = 0.5 * (x1 - x0) / want;
      y0 = m - h, y1 = m + h;
    }
  }
  const Axis ax = nice_axis(x0, x1, plot.pad_x ? 0.04 : 0), ay = nice_axis(y0, y1, 0.05);
  auto x_tick_label = [&](int i) {
    return plot.log_x ? log_tick_label(ax.tick(i), ax.step) : tick_label(ax.tick(i), ax.step);
  };

  // Layout: title on top, y tick labels and y label left, x ones below.
  const double title_px = cv.fit(plot.title, kTitlePx, width - 24.0);
  const double tick_cap = cv.cap_height(kTickPx), tick_line = tick_cap + cv.descent(kTickPx);
  const double label_line = cv.cap_height(kLabelPx) + cv.descent(kLabelPx);
  double ytick_w = 0;
  for (int i = 0; i < ay.ticks(); ++i) ytick_w = std::max(ytick_w, cv.text_width(tick_label(ay.tick(i), ay.step), kTickPx));
  const double ylabel_x = 10;  // the y label's cap line
  const int left = static_cast<int>(std::ceil((plot.y_label.empty() ? 10 : ylabel_x + label_line + 10) + ytick_w + 10));
  const int top = plot.title.empty() ? 14 : static_cast<int>(std::ceil(16 + cv.cap_height(title_px) + 16));
  const int bottom = static_cast<int>(std::ceil(10 + tick_line + (plot.x_label.empty() ? 0 : 9 + label_line) + 10));
  double last_w = ax.ticks() > 0 ? cv.text_width(x_tick_label(ax.ticks() - 1), kTickPx) : 0;
  const int right = static_cast<int>(std::max(20.0, std::ceil(last_w / 2 + 8)));
  const int L = std::min(left, width / 2), T = std::min(top, height / 2);
  const int R = std::max(L + 2, width - right), B = std::max(T + 2, height - bottom);
  auto X = [&](double x) { return L + 0.5 + (x - ax.lo) / (ax.hi - ax.lo) * (R - L - 1); };
  auto Y = [&](double y) { return B - 0.5 - (y - ay.lo) / (ay.hi - ay.lo) * (B - T - 1); };

  // Span and grid behind the data.
  cv.clip(L, T, R, B);
  if (span) cv.fill_rect(std::floor(X(plot.span_from)), T, std::ceil(X(plot.span_to)), B, kSpan, 0.6);
  for (int i = 0; i < ax.ticks(); ++i) cv.fill_rect(std::floor(X(ax.tick(i))), T, std::floor(X(ax.tick(i))) + 1, B, kGrid);
  for (int i = 0; i < ay.ticks(); ++i) cv.fill_rect(L, std::floor(Y(ay.tick(i))), R, std::floor(Y(ay.tick(i))) + 1, kGrid);

  // Bands under every line: each run of finite points a translucent
  // polygon, the upper edge out and the lower back.
  for (const PlotSeries& s : plot.series) {
    const std::size_t n = std::min({s.x.size(), s.band_lo.size(), s.band_hi.size()});
    auto ok = [&](std::size_t i) {
      return std::isfinite(s.x[i]) && std::isfinite(s.band_lo[i]) && std::isfinite(s.band_hi[i]);
    };
    for (std::size_t i = 0; i < n;) {
      if (!ok(i)) {
        ++i;
        continue;
      }
      std::size_t j = i;
      while (j < n && ok(j)) ++j;
      std::vector<P> poly;
      for (std::size_t k = i; k < j; ++k) poly.push_back({X(s.x[k]), Y(s.band_hi[k])});
      for (std::size_t k = j; k-- > i;) poly.push_back({X(s.x[k]), Y(s.band_lo[k])});
      if (j - i >= 2) cv.polygon(poly, s.rgb, 0.18);
      i = j;
    }
  }
  // Series: NaN (in x or y) breaks the line; a lone point becomes a dot.
  for (const PlotSeries& s : plot.series) {
    const std::size_t n = std::min(s.x.size(), s.y.size());
    auto ok = [&](std::size_t i) { return i < n && std::isfinite(s.x[i]) && std::isfinite(s.y[i]); };
    double dash = 0;  // where along the dash pattern the line is
    for (std::size_t i = 0; i < n; ++i) {
      if (!ok(i)) continue;
      const P p{X(s.x[i]), Y(s.y[i])};
      if (ok(i + 1) && s.dashed)
        dashed_line(cv, p, {X(s.x[i + 1]), Y(s.y[i + 1])}, s.rgb, kDataWidth, dash);
      else if (ok(i + 1))
        cv.line(p, {X(s.x[i + 1]), Y(s.y[i + 1])}, s.rgb, kDataWidth);
      else if (i == 0 || !ok(i - 1))
        cv.disc(p, 2.5, s.rgb);
      if (s.markers) cv.disc(p, 3.5, s.rgb);
    }
  }
  // Reference lines over the data, each on a white halo so that it shows
  // on lines of its own colour.
  struct Ref {
    const RefLine* line;
    P a, b;  // its ends, in pixels
  };
  std::vector<Ref> refs;
  for (const RefLine& r : plot.ref_lines) {
    const bool part = r.x_to > r.x_from;
    if (!std::isfinite(r.value) || (part && !(std::isfinite(r.x_from) && std::isfinite(r.x_to)))) continue;
    const double y = std::floor(Y(r.value)) + 0.5;  // on a pixel row's centre: sharp
    refs.push_back({&r, {part ? X(r.x_from) : L, y}, {part ? X(r.x_to) : R, y}});
  }
  for (const Ref& r : refs) cv.line(r.a, r.b, 0xffffff, kDataWidth + 3, 0.8);
  for (const Ref& r : refs) {
    double dash = 0;
    if (r.line->dashed) dashed_line(cv, r.a, r.b, r.line->rgb, kDataWidth + 0.4, dash);
    else cv.line(r.a, r.b, r.line->rgb, kDataWidth + 0.4);
  }
  cv.unclip();

  // Frame, ticks and their labels.
  cv.fill_rect(L, T, R, T + 1, kFrame), cv.fill_rect(L, B - 1, R, B, kFrame);
  cv.fill_rect(L, T, L + 1, B, kFrame), cv.fill_rect(R - 1, T, R, B, kFrame);
  for (int i = 0; i < ax.ticks(); ++i) {
    const double x = std::floor(X(ax.tick(i)));
    cv.fill_rect(x, B, x + 1, B + 5, kFrame);
    cv.text(x + 0.5, B + 10, x_tick_label(i), kInk, kTickPx, 0.5, 0);
  }
  for (int i = 0; i < ay.ticks(); ++i) {
    const double y = std::floor(Y(ay.tick(i)));
    cv.fill_rect(L - 5, y, L, y + 1, kFrame);
    cv.text(L - 9, y + 0.5, tick_label(ay.tick(i), ay.step), kInk, kTickPx, 1, 0.5);
  }
  if (!plot.x_label.empty()) {
    const double px = cv.fit(plot.x_label, kLabelPx, width - 16.0);
    cv.text((L + R) / 2.0, B + 10 + tick_line + 9, plot.x_label, kInk, px, 0.5, 0);
  }
  if (!plot.y_label.empty()) {
    const double px = cv.fit(plot.y_label, kLabelPx, B - T + 0.0);
    cv.text(ylabel_x, (T + B) / 2.0, plot.y_label, kInk, px, 0.5, 0, true);
  }
  if (!plot.title.empty()) cv.text(width / 2.0, 16, plot.title, kInk, title_px, 0.5, 0);

  // Legend: the labelled series, the reference lines, then the span, where
  // it hides the least of the lines (matplotlib's "best": the corners
  // first, then the middles of the sides, then the centre).
  std::vector<LegendEntry> entries;
  for (const PlotSeries& s : plot.series)
    if (!s.label.empty()) entries.push_back({s.label, s.rgb, s.dashed, s.markers});
  for (const RefLine& r : plot.ref_lines)
    if (!r.label.empty() && std::isfinite(r.value)) entries.push_back({r.label, r.rgb, r.dashed});
  if (span && !plot.span_label.empty()) entries.push_back({plot.span_label, kSpan, false, false, true, 0.6});
  if (!entries.empty()) {
    double label_w = 0;
    for (const LegendEntry& e : entries) label_w = std::max(label_w, cv.text_width(e.label, kLegendPx));
    const double row = std::round(1.45 * kLegendPx), sample = 28;
    const double lw = std::ceil(10 + sample + 8 + label_w + 10), lh = 8 + row * entries.size() + 4;
    const double xl = L + 10.0, xr = R - 10 - lw, xm = (L + R - lw) / 2;
    const double yt = T + 10.0, yb = B - 10 - lh, ym = (T + B - lh) / 2;
    constexpr int kPlaces = 9;
    const double corners[kPlaces][2] = {{xr, yt}, {xl, yt}, {xl, yb}, {xr, yb}, {xl, ym},
                                        {xr, ym}, {xm, yb}, {xm, yt}, {xm, ym}};
    // What each place would hide: the lines sampled every 2 pixels.
    double hidden[kPlaces] = {};
    auto hide = [&](double px, double py, double weight) {
      for (int c = 0; c < kPlaces; ++c)
        hidden[c] += weight * (px >= corners[c][0] - 4 && px <= corners[c][0] + lw + 4 && py >= corners[c][1] - 4 &&
                               py <= corners[c][1] + lh + 4);
    };
    for (const Ref& r : refs)  // a reference line counts more than data
      for (double px = r.a.x; px <= r.b.x; px += 2) hide(px, r.a.y, 4);
    for (const PlotSeries& s : plot.series) {
      const std::size_t n = std::min(s.x.size(), s.y.size());
      for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
        const P a{X(s.x[i]), Y(s.y[i])};
        const bool next = i + 1 < n && std::isfinite(s.x[i + 1]) && std::isfinite(s.y[i + 1]);
        const P b = next ? P{X(s.x[i + 1]), Y(s.y[i + 1])} : a;
        const int steps = std::clamp(static_cast<int>(std::hypot(b.x - a.x, b.y - a.y) / 2), 1, 1000);
        for (int k = 0; k < steps; ++k) hide(a.x + (b.x - a.x) * k / steps, a.y + (b.y - a.y) * k / steps, 1);
      }
    }
    const int best = static_cast<int>(std::min_element(hidden, hidden + kPlaces) - hidden);
    const double bx = corners[best][0], by = corners[best][1];
    cv.round_box(bx, by, bx + lw, by + lh, 4, 0xffffff, 0.85, 0xcccccc);
    for (std::size_t k = 0; k < entries.size(); ++k) {
      const LegendEntry& e = entries[k];
      const double y = by + 8 + row * k + row / 2 - 1;  // the entry's middle
      const P a{bx + 10, y}, b{bx + 10 + sample, y};
      double dash = 0;
      if (e.patch) {
        cv.fill_rect(a.x, y - 6, b.x, y + 6, e.rgb, e.alpha);
      } else if (e.dashed) {
        dashed_line(cv, a, b, e.rgb, kDataWidth, dash);
      } else {
        cv.line(a, b, e.rgb, kDataWidth);
      }
      if (e.markers) cv.disc({(a.x + b.x) / 2, y}, 3.5, e.rgb);
      cv.text(b.x + 8, y, e.label, kInk, kLegendPx, 0, 0.5);
    }
  }

  return cv;
}

}  // namespace

std::string value_with_error(double value, double sem, const std::string& unit) {
  char buf[128];
  const std::string u = unit.empty() ? "" : " " + unit;
  if (!std::isfinite(value)) return "n/a" + u;
  if (!(sem > 0) || !std::isfinite(sem)) {
    std::snprintf(buf, sizeof buf, "%.1f", value);
    return minus(buf) + u;
  }
  const int digits = std::clamp(1 - static_cast<int>(std::floor(std::log10(sem))), 0, 9);
  std::snprintf(buf, sizeof buf, "%.*f \u00b1 %.*f", digits, value, digits, sem);
  return minus(buf) + u;
}

void write_line_plot_png(const std::filesystem::path& path, const LinePlot& plot, int width, int height) {
  write_file_atomic(path, render_line_plot(plot, width, height).png());
}

void write_line_plots_png(const std::filesystem::path& path, const std::vector<LinePlot>& plots, int width,
                          int height_each) {
  if (plots.empty()) throw std::invalid_argument("write_line_plots_png: no plots");
  check_size(width, height_each * static_cast<int>(plots.size()));
  Canvas all(width, height_each * static_cast<int>(plots.size()));
  for (std::size_t k = 0; k < plots.size(); ++k)
    all.paste(render_line_plot(plots[k], width, height_each), 0, static_cast<int>(k) * height_each);
  write_file_atomic(path, all.png());
}

}  // namespace mc::io
