#include "io/png_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/atomic_file.h"

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include "stb_image_write.h"
#include "stb_easy_font.h"

namespace mc::io {

namespace {

// ------------------------------------------------------------------ canvas --

struct P {
  double x = 0, y = 0;
};

// An RGB picture, white to begin with. Pixel (i, j) covers [i, i+1) × [j, j+1)
// with j growing downwards; shapes are anti-aliased by coverage.
class Canvas {
 public:
  Canvas(int w, int h) : w_(w), h_(h), px_(static_cast<std::size_t>(w) * h * 3, 255) { unclip(); }

  int width() const { return w_; }
  int height() const { return h_; }

  // Drawing is limited to [x0, x1) × [y0, y1).
  void clip(int x0, int y0, int x1, int y1) {
    cx0_ = std::max(0, x0), cy0_ = std::max(0, y0), cx1_ = std::min(w_, x1), cy1_ = std::min(h_, y1);
  }
  void unclip() { cx0_ = 0, cy0_ = 0, cx1_ = w_, cy1_ = h_; }

  // Another canvas's pixels, its top left at (x, y).
  void paste(const Canvas& o, int x, int y) {
    for (int j = 0; j < o.h_; ++j)
      for (int i = 0; i < o.w_; ++i) {
        if (x + i < 0 || x + i >= w_ || y + j < 0 || y + j >= h_) continue;
        for (int c = 0; c < 3; ++c)
          px_[(static_cast<std::size_t>(y + j) * w_ + x + i) * 3 + c] = o.px_[(static_cast<std::size_t>(j) * o.w_ + i) * 3 + c];
      }
  }

  void blend(int x, int y, std::uint32_t rgb, double a) {
    if (x < cx0_ || x >= cx1_ || y < cy0_ || y >= cy1_ || !(a > 0)) return;
    a = std::min(a, 1.0);
    unsigned char* p = &px_[(static_cast<std::size_t>(y) * w_ + x) * 3];
    for (int c = 0; c < 3; ++c) {
      const double src = (rgb >> (16 - 8 * c)) & 0xffu;
      p[c] = static_cast<unsigned char>(std::lround(p[c] + (src - p[c]) * a));
    }
  }
  void set(int x, int y, std::uint32_t rgb) { blend(x, y, rgb, 1.0); }

  // Whole pixels from round(x0) to round(x1) (exclusive), likewise in y.
  void fill_rect(double x0, double y0, double x1, double y1, std::uint32_t rgb, double a = 1) {
    const int i0 = static_cast<int>(std::lround(std::max(x0, -1.0))),
              i1 = static_cast<int>(std::lround(std::min(x1, w_ + 1.0)));
    const int j0 = static_cast<int>(std::lround(std::max(y0, -1.0))),
              j1 = static_cast<int>(std::lround(std::min(y1, h_ + 1.0)));
    for (int j = j0; j < j1; ++j)
      for (int i = i0; i < i1; ++i) blend(i, j, rgb, a);
  }

  // A segment of the given width with round caps.
  void line(P a, P b, std::uint32_t rgb, double width = 2, double alpha = 1) {
    const double r = width / 2 + 0.5;
    const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
    cover(std::min(a.x, b.x) - r, std::min(a.y, b.y) - r, std::max(a.x, b.x) + r,
          std::max(a.y, b.y) + r, rgb, alpha, [&](double x, double y) {
            double t = len2 > 0 ? ((x - a.x) * dx + (y - a.y) * dy) / len2 : 0;
            t = std::clamp(t, 0.0, 1.0);
            return r - std::hypot(x - a.x - t * dx, y - a.y - t * dy);
          });
  }

  void disc(P c, double r, std::uint32_t rgb, double alpha = 1) {
    cover(c.x - r - 1, c.y - r - 1, c.x + r + 1, c.y + r + 1, rgb, alpha,
          [&](double x, double y) { return r + 0.5 - std::hypot(x - c.x, y - c.y); });
  }

  void ring(P c, double r, double width, std::uint32_t rgb) {
    const double o = r + width / 2 + 1;
    cover(c.x - o, c.y - o, c.x + o, c.y + o, rgb, 1, [&](double x, double y) {
      return width / 2 + 0.5 - std::abs(std::hypot(x - c.x, y - c.y) - r);
    });
  }

  // Even-odd fill; four scanlines per pixel row, exact coverage along each.
  void polygon(const std::vector<P>& p, std::uint32_t rgb, double alpha = 1) {
    if (p.size() < 3) return;
    double xmin = p[0].x, xmax = p[0].x, ymin = p[0].y, ymax = p[0].y;
    for (const P& q : p) {
      if (!std::isfinite(q.x) || !std::isfinite(q.y)) return;
      xmin = std::min(xmin, q.x), xmax = std::max(xmax, q.x);
      ymin = std::min(ymin, q.y), ymax = std::max(ymax, q.y);
    }
    const int x0 = std::max(cx0_, static_cast<int>(std::floor(xmin)));
    const int x1 = std::min(cx1_, static_cast<int>(std::ceil(xmax)));
    const int y0 = std::max(cy0_, static_cast<int>(std::floor(ymin)));
    const int y1 = std::min(cy1_, static_cast<int>(std::ceil(ymax)));
    if (x0 >= x1 || y0 >= y1) return;
    constexpr int kSub = 4;
    std::vector<double> cov(x1 - x0), xs;
    for (int y = y0; y < y1; ++y) {
      std::fill(cov.begin(), cov.end(), 0.0);
      for (int s = 0; s < kSub; ++s) {
        const double sy = y + (s + 0.5) / kSub;
        xs.clear();
        for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
          if ((p[i].y > sy) != (p[j].y > sy))
            xs.push_back(p[j].x + (sy - p[j].y) * (p[i].x - p[j].x) / (p[i].y - p[j].y));
        std::sort(xs.begin(), xs.end());
        for (std::size_t k = 0; k + 1 < xs.size(); k += 2) {
          const double a = std::clamp(xs[k], double(x0), double(x1));
          const double b = std::clamp(xs[k + 1], double(x0), double(x1));
          for (int i = static_cast<int>(std::floor(a)); i < std::ceil(b); ++i)
            cov[i - x0] += (std::min(b, i + 1.0) - std::max(a, double(i))) / kSub;
        }
      }
      for (int x = x0; x < x1; ++x) blend(x, y, rgb, alpha * cov[x - x0]);
    }
  }

  // stb_easy_font text, top-left at (x, y), `scale` pixels per font unit.
  // `up`: rotated to read bottom to top, starting at (x, y) with the tops of
  // the letters facing left (for a y-axis label).
  void text(double x, double y, const std::string& s, std::uint32_t rgb, int scale = 1,
            bool up = false) {
    std::string t = printable(s);
    std::vector<char> buf(t.size() * 1200 + 64);
    const int quads = stb_easy_font_print(0, 0, t.data(), nullptr, buf.data(), static_cast<int>(buf.size()));
    x = std::round(x), y = std::round(y);
    for (int q = 0; q < quads; ++q) {
      const float* v = reinterpret_cast<const float*>(buf.data() + q * 64);  // 4 × {x, y, z, rgba}
      const double u0 = v[0] * scale, v0 = v[1] * scale, u1 = v[8] * scale, v1 = v[9] * scale;
      if (up)
        fill_rect(x + v0, y - u1, x + v1, y - u0, rgb);
      else
        fill_rect(x + u0, y + v0, x + u1, y + v1, rgb);
    }
  }
  static int text_width(const std::string& s, int scale = 1) {
    std::string t = printable(s);
    return t.empty() ? 0 : stb_easy_font_width(t.data()) * scale;
  }
  static constexpr int kCapHeight = 7;  // font units from the top of a line to the baseline

  // Text with a translucent white box behind it.
  void label(double x, double y, const std::string& s, std::uint32_t rgb, int scale = 1) {
    fill_rect(x - 3, y - 3, x + text_width(s, scale) + 2, y + kCapHeight * scale + 3, 0xffffff, 0.85);
    text(x, y, s, rgb, scale);
  }

  std::string png() const {
    std::string out;
    auto sink = [](void* ctx, void* data, int n) {
      static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), n);
    };
    if (!stbi_write_png_to_func(sink, &out, w_, h_, 3, px_.data(), w_ * 3) || out.empty())
      throw std::runtime_error("PNG encoding failed");
    return out;
  }

 private:
  // Blends every pixel of the box whose signed coverage f(centre) > 0.
  template <class F>
  void cover(double x0, double y0, double x1, double y1, std::uint32_t rgb, double alpha, F f) {
    if (!(std::isfinite(x0) && std::isfinite(y0) && std::isfinite(x1) && std::isfinite(y1))) return;
    const int i0 = std::max(cx0_, static_cast<int>(std::floor(std::max(x0, -1.0))));
    const int i1 = std::min(cx1_, static_cast<int>(std::ceil(std::min(x1, w_ + 1.0))));
    const int j0 = std::max(cy0_, static_cast<int>(std::floor(std::max(y0, -1.0))));
    const int j1 = std::min(cy1_, static_cast<int>(std::ceil(std::min(y1, h_ + 1.0))));
    for (int j = j0; j < j1; ++j)
      for (int i = i0; i < i1; ++i) {
        const double c = f(i + 0.5, j + 0.5);
        if (c > 0) blend(i, j, rgb, alpha * std::min(c, 1.0));
      }
  }
  static std::string printable(const std::string& s) {
    std::string t = s;
    for (char& c : t)
      if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
    return t;
  }

  int w_, h_;
  std::vector<unsigned char> px_;
  int cx0_ = 0, cy0_ = 0, cx1_ = 0, cy1_ = 0;
};

void check_size(int w, int h) {
  if (w < 16 || h < 16 || w > 16384 || h > 16384)
    throw std::runtime_error("picture size out of range: " + std::to_string(w) + "x" + std::to_string(h));
}

std::uint32_t mix(std::uint32_t a, std::uint32_t b, double t) {
  std::uint32_t out = 0;
  for (int s = 16; s >= 0; s -= 8) {
    const double ca = (a >> s) & 0xffu, cb = (b >> s) & 0xffu;
    out |= static_cast<std::uint32_t>(std::lround(ca + (cb - ca) * t)) << s;
  }
  return out;
}

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// ------------------------------------------------------------- line plot --

// Heckbert's "nice numbers": 1, 2 or 5 × 10^k.
double nice_num(double x, bool round) {
  const double e = std::pow(10.0, std::floor(std::log10(x)));
  const double f = x / e;
  if (round) return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * e;
  return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * e;
}

// Axis limits and ticks at multiples of a nice step. `pad` > 0 widens the
// data range by that fraction each side (so no data lies on the frame);
// pad = 0 rounds the limits out to whole steps.
struct Axis {
  double lo = 0, hi = 1, step = 0.2, first = 0;
  int ticks() const { return static_cast<int>(std::floor((hi - first) / step + 1e-9)) + 1; }
  double tick(int i) const { return first + i * step; }
};

Axis nice_axis(double lo, double hi, double pad) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) lo = 0, hi = 1;
  if (hi - lo <= 1e-12 * std::max(std::abs(lo), std::abs(hi))) {  // constant: give it a range
    const double d = lo != 0 ? 0.1 * std::abs(lo) : 1;
    lo -= d, hi += d;
  }
  Axis a;
  a.step = nice_num(nice_num(hi - lo, false) / 5, true);
  if (pad > 0) {
    const double d = pad * (hi - lo);
    a.lo = lo - d, a.hi = hi + d;
  } else {
    a.lo = std::floor(lo / a.step + 1e-9) * a.step;
    a.hi = std::ceil(hi / a.step - 1e-9) * a.step;
  }
  a.first = std::ceil(a.lo / a.step - 1e-9) * a.step;
  if (!(a.hi > a.lo) || !(a.step > 0) || a.ticks() > 40) a = Axis{lo, hi, hi - lo, lo};
  return a;
}

// A segment drawn as 8-pixel dashes with 5-pixel gaps; `phase` carries the
// pattern from one segment of a polyline to the next.
void dashed_line(Canvas& cv, P a, P b, std::uint32_t rgb, double& phase) {
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
      cv.line(p, q, rgb, 2);
    }
    t += piece;
  }
  phase = std::fmod(phase + len, kPeriod);
}

std::string tick_label(double v, double step) {
  if (std::abs(v) < step * 1e-6) v = 0;
  const double big = std::abs(v);
  if (step >= 1e-4 && big < 1e7) {
    const int digits = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", digits, v);
    return buf;
  }
  return format("%.3g", v);
}

}  // namespace

namespace {

// The line plot drawn on a canvas of its own.
Canvas render_line_plot(const LinePlot& given, int width, int height) {
  check_size(width, height);
  Canvas cv(width, height);
  constexpr std::uint32_t kInk = 0x222222, kFrame = 0x555555, kGrid = 0xe8e8e8;
  // A log x axis: the plot of log10 x, ticks labelled with powers of ten.
  LinePlot plot = given;
  if (plot.log_x) {
    for (PlotSeries& s : plot.series)
      for (double& x : s.x) x = x > 0 ? std::log10(x) : NAN;
    plot.span_from = plot.span_from > 0 ? std::log10(plot.span_from) : NAN;
    plot.span_to = plot.span_to > 0 ? std::log10(plot.span_to) : NAN;
  }

  // Data ranges over the finite points and the span.
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const PlotSeries& s : plot.series)
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i]))
        x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]), y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
  const bool span = plot.span_to > plot.span_from && std::isfinite(plot.span_from) && std::isfinite(plot.span_to);
  if (span) x0 = std::min(x0, plot.span_from), x1 = std::max(x1, plot.span_to);
  if (!(x0 <= x1)) x0 = 0, x1 = 1;
  if (!(y0 <= y1)) y0 = 0, y1 = 1;
  const Axis ax = nice_axis(x0, x1, plot.pad_x ? 0.04 : 0), ay = nice_axis(y0, y1, 0.05);

  // Layout: title on top, y tick labels and y label left, x ones below.
  int ytick_w = 0;
  for (int i = 0; i < ay.ticks(); ++i)
    ytick_w = std::max(ytick_w, Canvas::text_width(tick_label(ay.tick(i), ay.step)));
  const int left = 12 + (plot.y_label.empty() ? 0 : 16) + ytick_w + 8;
  const int top = plot.title.empty() ? 16 : 44;
  const int bottom = 8 + 14 + (plot.x_label.empty() ? 0 : 18) + 6;
  const int right = 20;
  const int L = std::min(left, width / 2), T = std::min(top, height / 2);
  const int R = std::max(L + 2, width - right), B = std::max(T + 2, height - bottom);
  auto X = [&](double x) { return L + 0.5 + (x - ax.lo) / (ax.hi - ax.lo) * (R - L - 1); };
  auto Y = [&](double y) { return B - 0.5 - (y - ay.lo) / (ay.hi - ay.lo) * (B - T - 1); };

  // Span and grid behind the data.
  cv.clip(L, T, R, B);
  if (span) {
    const double sa = X(plot.span_from), sb = X(plot.span_to);
    cv.fill_rect(std::floor(sa), T, std::ceil(sb), B, 0xfbe3b0, 0.6);
    if (!plot.span_label.empty()) {
      const int tw = Canvas::text_width(plot.span_label);
      const double tx = tw + 8 < sb - sa ? (sa + sb - tw) / 2 : sa + 4;
      cv.text(tx, T + 6, plot.span_label, 0x8a5a00);
    }
  }
  for (int i = 0; i < ax.ticks(); ++i) cv.fill_rect(std::floor(X(ax.tick(i))), T, std::floor(X(ax.tick(i))) + 1, B, kGrid);
  for (int i = 0; i < ay.ticks(); ++i) cv.fill_rect(L, std::floor(Y(ay.tick(i))), R, std::floor(Y(ay.tick(i))) + 1, kGrid);

  // Series: NaN (in x or y) breaks the line; a lone point becomes a dot.
  for (const PlotSeries& s : plot.series) {
    const std::size_t n = std::min(s.x.size(), s.y.size());
    auto ok = [&](std::size_t i) { return i < n && std::isfinite(s.x[i]) && std::isfinite(s.y[i]); };
    double dash = 0;  // where along the dash pattern the line is
    for (std::size_t i = 0; i < n; ++i) {
      if (!ok(i)) continue;
      const P p{X(s.x[i]), Y(s.y[i])};
      if (ok(i + 1) && s.dashed)
        dashed_line(cv, p, {X(s.x[i + 1]), Y(s.y[i + 1])}, s.rgb, dash);
      else if (ok(i + 1))
        cv.line(p, {X(s.x[i + 1]), Y(s.y[i + 1])}, s.rgb, 2);
      else if (i == 0 || !ok(i - 1))
        cv.disc(p, 2.5, s.rgb);
      if (s.markers) cv.disc(p, 3.5, s.rgb);
    }
  }
  cv.unclip();

  // Frame, ticks and their labels.
  cv.fill_rect(L, T, R, T + 1, kFrame), cv.fill_rect(L, B - 1, R, B, kFrame);
  cv.fill_rect(L, T, L + 1, B, kFrame), cv.fill_rect(R - 1, T, R, B, kFrame);
  for (int i = 0; i < ax.ticks(); ++i) {
    const double x = std::floor(X(ax.tick(i)));
    const std::string s = plot.log_x ? format(ax.step >= 1 ? "%.0e" : "%.2g", std::pow(10.0, ax.tick(i)))
                                     : tick_label(ax.tick(i), ax.step);
    cv.fill_rect(x, B, x + 1, B + 5, kFrame);
    cv.text(x + 0.5 - Canvas::text_width(s) / 2.0, B + 9, s, kInk);
  }
  for (int i = 0; i < ay.ticks(); ++i) {
    const double y = std::floor(Y(ay.tick(i)));
    const std::string s = tick_label(ay.tick(i), ay.step);
    cv.fill_rect(L - 5, y, L, y + 1, kFrame);
    cv.text(L - 8 - Canvas::text_width(s), y - 3, s, kInk);
  }
  if (!plot.x_label.empty())
    cv.text((L + R - Canvas::text_width(plot.x_label)) / 2.0, B + 27, plot.x_label, kInk);
  if (!plot.y_label.empty())
    cv.text(10, (T + B + Canvas::text_width(plot.y_label)) / 2.0, plot.y_label, kInk, 1, true);
  if (!plot.title.empty())
    cv.text((width - Canvas::text_width(plot.title, 2)) / 2.0, 14, plot.title, kInk, 2);

  // Legend in the inner corner that covers the fewest data points.
  std::vector<const PlotSeries*> entries;
  int label_w = 0;
  for (const PlotSeries& s : plot.series)
    if (!s.label.empty()) entries.push_back(&s), label_w = std::max(label_w, Canvas::text_width(s.label));
  if (!entries.empty()) {
    const double lw = 8 + 22 + 6 + label_w + 8, lh = 6 + 14.0 * entries.size() + 2;
    const double corners[4][2] = {{R - 8 - lw, T + 8.0}, {L + 8.0, T + 8.0}, {R - 8 - lw, B - 8 - lh}, {L + 8.0, B - 8 - lh}};
    int best = 0;
    std::size_t best_count = SIZE_MAX;
    for (int c = 0; c < 4; ++c) {
      std::size_t count = 0;
      for (const PlotSeries& s : plot.series)
        for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
          const double px = X(s.x[i]), py = Y(s.y[i]);
          count += px >= corners[c][0] && px <= corners[c][0] + lw && py >= corners[c][1] && py <= corners[c][1] + lh;
        }
      if (count < best_count) best = c, best_count = count;
    }
    const double bx = corners[best][0], by = corners[best][1];
    cv.fill_rect(bx, by, bx + lw, by + lh, 0xffffff, 0.9);
    cv.fill_rect(bx, by, bx + lw, by + 1, 0xbbbbbb), cv.fill_rect(bx, by + lh - 1, bx + lw, by + lh, 0xbbbbbb);
    cv.fill_rect(bx, by, bx + 1, by + lh, 0xbbbbbb), cv.fill_rect(bx + lw - 1, by, bx + lw, by + lh, 0xbbbbbb);
    for (std::size_t k = 0; k < entries.size(); ++k) {
      const double y = by + 6 + 14.0 * k;
      double dash = 0;
      if (entries[k]->dashed) dashed_line(cv, {bx + 9, y + 3.5}, {bx + 29, y + 3.5}, entries[k]->rgb, dash);
      else cv.line({bx + 9, y + 3.5}, {bx + 29, y + 3.5}, entries[k]->rgb, 2);
      if (entries[k]->markers) cv.disc({bx + 19, y + 3.5}, 3.5, entries[k]->rgb);
      cv.text(bx + 8 + 22 + 6, y, entries[k]->label, kInk);
    }
  }

  return cv;
}

}  // namespace

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

// -------------------------------------------------------------- end view --

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

  // Toe and shoulder: radius from the centre to the shell, labelled outside.
  auto mark = [&](double deg, const char* name, std::uint32_t rgb) {
    if (!(deg >= 0) || !std::isfinite(deg)) return;
    const double a = deg * (3.14159265358979323846 / 180), ca = std::cos(a), sa = std::sin(a);
    cv.line(centre, map(shell * ca, shell * sa), rgb, 2.5);
    const std::string s = std::string(name) + " " + format("%.0f", deg) + " deg";
    const double tw = Canvas::text_width(s), th = Canvas::kCapHeight;
    const P p{centre.x + (rpx + 10) * ca, centre.y - (rpx + 10) * sa};
    double x = ca > 0.3 ? p.x : ca < -0.3 ? p.x - tw : p.x - tw / 2;
    double y = sa > 0.3 ? p.y - th : sa < -0.3 ? p.y : p.y - th / 2;
    x = std::clamp(x, 4.0, size - 4 - tw), y = std::clamp(y, 4.0, size - 4 - th);
    cv.label(x, y, s, rgb);
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
    cv.text(x0 - 6 - Canvas::text_width(hi), y0, hi, kInk);
    cv.text(x0 - 6 - Canvas::text_width("0"), y1 - Canvas::kCapHeight, "0", kInk);
    cv.text(x1 - Canvas::text_width("speed"), y0 - 16, "speed", kInk);
  }
  if (!view.title.empty()) cv.text((size - Canvas::text_width(view.title, 2)) / 2.0, 12, view.title, kInk, 2);

  write_file_atomic(path, cv.png());
}

// ------------------------------------------------------------- heat maps --

namespace {

// The heat scale: dark blue through teal and yellow to red, t in [0, 1].
std::uint32_t heat(double t) {
  static const std::uint32_t table[] = {0x2c3e9e, 0x2a8fbd, 0x3fb67b, 0xb5d334, 0xfdb92e, 0xe2401c};
  t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) * 5 : 0;
  const int i = std::min(4, static_cast<int>(t));
  return mix(table[i], table[i + 1], t - i);
}

void draw_heat_map(Canvas& cv, const HeatMap& m, int x, int y, int w, int h) {
  constexpr std::uint32_t kInk = 0x222222, kFrame = 0x555555, kEmpty = 0xdddddd;
  double hi = 0;
  for (const HeatCell& c : m.cells)
    if (std::isfinite(c.value)) hi = std::max(hi, c.value);
  const int L = x + 56, T = y + 28, R = x + w - 110, B = y + h - 40;
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
      for (auto [p, q] : {std::pair{a, b}, {b, d}, {d, e}, {e, a}}) cv.line(p, q, 0x111111, 1);
    }
  int nth = 0;  // labels one under the other, so that near marks stay legible
  for (const auto& [mx, label] : m.marks_x) {
    if (!std::isfinite(mx)) continue;
    cv.line({X(mx), double(T)}, {X(mx), double(B)}, 0xc51b8a, 2);
    const double tx = X(mx) + 4 + Canvas::text_width(label) > R ? X(mx) - 4 - Canvas::text_width(label) : X(mx) + 4;
    cv.label(tx, T + 6 + 16 * nth++, label, 0xc51b8a);
  }
  cv.unclip();
  cv.fill_rect(L, T, R, T + 1, kFrame), cv.fill_rect(L, B - 1, R, B, kFrame);
  cv.fill_rect(L, T, L + 1, B, kFrame), cv.fill_rect(R - 1, T, R, B, kFrame);
  const Axis ax = nice_axis(m.x_lo, m.x_hi, 0), ay = nice_axis(m.y_lo, m.y_hi, 0);
  for (int i = 0; i < ax.ticks(); ++i) {
    const double v = ax.tick(i);
    if (v < m.x_lo - 1e-9 || v > m.x_hi + 1e-9) continue;
    const std::string s = tick_label(v, ax.step);
    cv.fill_rect(std::floor(X(v)), B, std::floor(X(v)) + 1, B + 5, kFrame);
    cv.text(X(v) - Canvas::text_width(s) / 2.0, B + 9, s, kInk);
  }
  for (int i = 0; i < ay.ticks(); ++i) {
    const double v = ay.tick(i);
    if (v < m.y_lo - 1e-9 || v > m.y_hi + 1e-9) continue;
    const std::string s = tick_label(v, ay.step);
    cv.fill_rect(L - 5, std::floor(Y(v)), L, std::floor(Y(v)) + 1, kFrame);
    cv.text(L - 8 - Canvas::text_width(s), Y(v) - 3, s, kInk);
  }
  if (!m.x_label.empty()) cv.text((L + R - Canvas::text_width(m.x_label)) / 2.0, B + 24, m.x_label, kInk);
  if (!m.y_label.empty()) cv.text(x + 8, (T + B + Canvas::text_width(m.y_label)) / 2.0, m.y_label, kInk, 1, true);
  if (!m.title.empty()) cv.text(L, y + 6, m.title, kInk, 2);
  // The colour bar: the top decade labelled, log steps below it.
  const double bx0 = R + 24, bx1 = R + 38;
  for (int j = 0; j < B - T; ++j) cv.fill_rect(bx0, T + j, bx1, T + j + 1, heat(1 - (j + 0.5) / (B - T)));
  cv.fill_rect(bx0 - 1, T - 1, bx1 + 1, T, kFrame), cv.fill_rect(bx0 - 1, B, bx1 + 1, B + 1, kFrame);
  for (int d = 0; d <= static_cast<int>(m.decades); ++d) {
    const double v = hi * std::pow(10.0, -d);
    const double yy = T + (B - T) * d / m.decades;
    cv.text(bx1 + 4, yy - 3, hi > 0 ? format("%.2g", v) : "0", kInk);
  }
  cv.text(bx0, T - 14, m.unit, kInk);
}

void draw_bars(Canvas& cv, const BarChart& b, int x, int y, int w, int h) {
  constexpr std::uint32_t kInk = 0x222222, kFrame = 0x555555;
  double hi = 0;
  for (const auto& [name, v] : b.bars)
    if (std::isfinite(v)) hi = std::max(hi, v);
  const Axis ay = nice_axis(0, hi > 0 ? hi : 1, 0);
  const int L = x + 56, T = y + 28, R = x + w - 110, B = y + h - 40;
  auto Y = [&](double v) { return B - v / ay.hi * (B - T); };
  for (int i = 0; i < ay.ticks(); ++i) {
    const double v = ay.tick(i);
    cv.fill_rect(L, std::floor(Y(v)), R, std::floor(Y(v)) + 1, 0xe8e8e8);
    const std::string s = tick_label(v, ay.step);
    cv.text(L - 8 - Canvas::text_width(s), Y(v) - 3, s, kInk);
  }
  const int n = static_cast<int>(b.bars.size());
  for (int k = 0; k < n; ++k) {
    const double slot = static_cast<double>(R - L) / n;
    const double x0 = L + slot * (k + 0.2), x1 = L + slot * (k + 0.8);
    const double v = std::isfinite(b.bars[k].second) ? b.bars[k].second : 0;
    cv.fill_rect(x0, Y(v), x1, B, b.rgb);
    const std::string val = format("%.3g", v);
    cv.text((x0 + x1 - Canvas::text_width(val)) / 2, Y(v) - 12, val, kInk);
    cv.text((x0 + x1 - Canvas::text_width(b.bars[k].first)) / 2, B + 9, b.bars[k].first, kInk);
  }
  cv.fill_rect(L, B - 1, R, B, kFrame), cv.fill_rect(L, T, L + 1, B, kFrame);
  if (!b.y_label.empty()) cv.text(x + 8, (T + B + Canvas::text_width(b.y_label)) / 2.0, b.y_label, kInk, 1, true);
  if (!b.title.empty()) cv.text(L, y + 6, b.title, kInk, 2);
}

}  // namespace

void write_heat_maps_png(const std::filesystem::path& path, const std::vector<HeatMap>& maps, const BarChart& bars,
                         int width) {
  const int map_h = 300, bar_h = bars.bars.empty() ? 0 : 260;
  const int height = static_cast<int>(maps.size()) * map_h + bar_h;
  check_size(width, height);
  Canvas cv(width, height);
  for (std::size_t k = 0; k < maps.size(); ++k) draw_heat_map(cv, maps[k], 0, static_cast<int>(k) * map_h, width, map_h);
  if (!bars.bars.empty()) draw_bars(cv, bars, 0, static_cast<int>(maps.size()) * map_h, width, bar_h);
  write_file_atomic(path, cv.png());
}

}  // namespace mc::io
