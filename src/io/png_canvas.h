// The drawing core under the PNG pictures (png_plot.h): the plot font, an
// anti-aliased RGB canvas that draws shapes and text and encodes itself as
// PNG, and the axis and number helpers that several pictures share.
// Internal to the pictures; callers use io/png_plot.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mc::io::draw {

// -------------------------------------------------------------------- font --

// A TrueType font held whole in memory (png_canvas.cpp).
struct Font;

// The font the pictures are drawn in: MILLCHARGE_FONT's file, or the
// built-in one (png_canvas.cpp says when).
std::shared_ptr<const Font> plot_font();

// Sizes of text (em, pixels).
constexpr double kTickPx = 13, kLabelPx = 14, kTitlePx = 17, kLegendPx = 13, kNotePx = 12.5;

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

  // Text in the plot font, anti-aliased. The anchor (x, y) sits at a
  // fraction `ax` of the advance width (0 left, 0.5 centre, 1 right) and a
  // fraction `ay` down the capital height (0 the top of the capitals, 0.5
  // their middle, 1 the baseline); descenders hang below. `px` is the em
  // size in pixels. `up`: rotated to read bottom to top, the tops of the
  // letters facing left (for a y-axis label); the anchor is then taken
  // along the rotated text.
  void text(double x, double y, const std::string& s, std::uint32_t rgb, double px, double ax = 0, double ay = 0,
            bool up = false);
  // The advance width of a line of text, in pixels.
  double text_width(const std::string& s, double px) const;
  // The height of the capitals, of the tallest letters above the baseline
  // and of the descenders below it, in pixels.
  double cap_height(double px) const;
  double ascent(double px) const;
  double descent(double px) const;
  // The largest size up to `px` (and no less than `min_px`) at which `s`
  // fits in `w` pixels.
  double fit(const std::string& s, double px, double w, double min_px = 10) const {
    const double tw = text_width(s, px);
    return tw <= w || !(tw > 0) ? px : std::max(min_px, px * w / tw);
  }

  // `s` broken at spaces into lines no wider than `w` (a word wider than
  // that stays whole on a line of its own).
  std::vector<std::string> wrap(const std::string& s, double px, double w) const {
    std::vector<std::string> lines;
    std::string line;
    std::size_t i = 0;
    while (i < s.size()) {
      const std::size_t j = std::min(s.find(' ', i), s.size());
      const std::string word = s.substr(i, j - i);
      if (!line.empty() && text_width(line + " " + word, px) > w) lines.push_back(line), line.clear();
      line += (line.empty() ? "" : " ") + word;
      i = j + 1;
    }
    if (!line.empty()) lines.push_back(line);
    return lines;
  }

  // Text on a translucent white box, anchored as for text().
  void label(double x, double y, const std::string& s, std::uint32_t rgb, double px, double ax = 0, double ay = 0) {
    const double w = text_width(s, px), cap = cap_height(px);
    const double left = x - ax * w, top = y - ay * cap;
    fill_rect(left - 4, top - 4, left + w + 4, top + cap + descent(px) + 3, 0xffffff, 0.85);
    text(x, y, s, rgb, px, ax, ay);
  }

  // A filled box with rounded corners and a 1-pixel border (a legend's).
  void round_box(double x0, double y0, double x1, double y1, double r, std::uint32_t fill, double alpha,
                 std::uint32_t border) {
    auto sd = [=](double x, double y) {  // signed distance to the box's edge, > 0 outside
      const double qx = std::abs(x - (x0 + x1) / 2) - ((x1 - x0) / 2 - r);
      const double qy = std::abs(y - (y0 + y1) / 2) - ((y1 - y0) / 2 - r);
      return std::hypot(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0) - r;
    };
    cover(x0 - 1, y0 - 1, x1 + 1, y1 + 1, fill, alpha, [&](double x, double y) { return 0.5 - sd(x, y); });
    cover(x0 - 1, y0 - 1, x1 + 1, y1 + 1, border, 1, [&](double x, double y) { return 1.0 - std::abs(sd(x, y) + 0.5); });
  }

  // The picture as a PNG file's bytes.
  std::string png() const;

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
  // The code points of UTF-8 text; a malformed byte or a control character
  // becomes U+FFFD.
  static std::vector<int> utf8(const std::string& s);

  std::shared_ptr<const Font> font_ = plot_font();
  int w_, h_;
  std::vector<unsigned char> px_;
  int cx0_ = 0, cy0_ = 0, cx1_ = 0, cy1_ = 0;
};

// ----------------------------------------------------------------- helpers --

// Throws std::runtime_error for a picture too small or too large to draw.
void check_size(int w, int h);

// The colour a fraction t of the way from a to b (0xRRGGBB).
std::uint32_t mix(std::uint32_t a, std::uint32_t b, double t);

// v printed with a printf format.
std::string format(const char* fmt, double v);

// A number with a true minus sign (U+2212), as typeset.
std::string minus(std::string s);

// An exponent in superscript digits.
std::string superscript(long k);

// A number printed with `fmt` (a %g format), its exponent, if any, typeset:
// 4.7e-05 as 4.7×10⁻⁵, 1e+06 as 10⁶.
std::string number(const char* fmt, double v);

// -------------------------------------------------------------------- axes --

// Axis limits and ticks at multiples of a nice step. `pad` > 0 widens the
// data range by that fraction each side (so no data lies on the frame);
// pad = 0 rounds the limits out to whole steps.
struct Axis {
  double lo = 0, hi = 1, step = 0.2, first = 0;
  int ticks() const { return static_cast<int>(std::floor((hi - first) / step + 1e-9)) + 1; }
  double tick(int i) const { return first + i * step; }
};

Axis nice_axis(double lo, double hi, double pad);

// A tick's label: as many decimals as the step needs, or a typeset
// exponent for very small steps and very large values.
std::string tick_label(double v, double step);

}  // namespace mc::io::draw
