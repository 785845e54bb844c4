#include "io/png_plot.h"

#include <algorithm>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/atomic_file.h"
#include "io/plot_font_data.h"

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include "stb_image_write.h"
#define STBTT_STATIC
#define STB_TRUETYPE_IMPLEMENTATION
#include "stb_truetype.h"

namespace mc::io {

std::filesystem::path plot_font_path() {
  const char* env = std::getenv("MILLCHARGE_FONT");
  return env && *env ? std::filesystem::path(env) : std::filesystem::path();
}

namespace {

// -------------------------------------------------------------------- font --

// A TrueType font held whole in memory, with the metrics the layout uses
// (font units; scale() turns them into pixels). `source` is the file it was
// read from, or empty for the font built into the program.
struct Font {
  std::string source;
  std::vector<unsigned char> file;  // a font read from a file; empty for the built-in one
  const unsigned char* data = nullptr;
  stbtt_fontinfo info{};
  int ascent = 0, descent = 0, cap = 0;

  // The built-in font.
  Font() {
    const auto [bytes, size] = builtin_plot_font();
    init(bytes, size, "the built-in plot font");
  }

  // A font file (MILLCHARGE_FONT).
  explicit Font(std::string path) : source(std::move(path)) {
    std::ifstream in(source, std::ios::binary);
    if (!in) {
      const std::string why = std::strerror(errno);
      throw std::runtime_error("cannot read the plot font " + source + " (MILLCHARGE_FONT): " + why);
    }
    file.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    init(file.data(), file.size(), "the plot font " + source + " (MILLCHARGE_FONT)");
  }
  Font(const Font&) = delete;
  Font& operator=(const Font&) = delete;

  void init(const unsigned char* bytes, std::size_t size, const std::string& what) {
    data = bytes;
    const int offset = size == 0 ? -1 : stbtt_GetFontOffsetForIndex(data, 0);
    if (offset < 0 || !stbtt_InitFont(&info, data, offset))
      throw std::runtime_error(what + " is not a TrueType font");
    int gap = 0;
    stbtt_GetFontVMetrics(&info, &ascent, &descent, &gap);
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    cap = stbtt_GetCodepointBox(&info, 'H', &x0, &y0, &x1, &y1) ? y1 : ascent * 7 / 10;
  }

  float scale(double px) const { return stbtt_ScaleForMappingEmToPixels(&info, static_cast<float>(px)); }

  double width(const std::vector<int>& cps, float sc) const {
    double w = 0;
    int prev = 0;
    for (int cp : cps) {
      const int g = stbtt_FindGlyphIndex(&info, cp);
      int advance = 0, lsb = 0;
      stbtt_GetGlyphHMetrics(&info, g, &advance, &lsb);
      w += sc * (advance + (prev ? stbtt_GetGlyphKernAdvance(&info, prev, g) : 0));
      prev = g;
    }
    return w;
  }
};

// The font: MILLCHARGE_FONT's file when it is set and can be read, else the
// built-in one (a file that cannot be read is said once, on stderr, and the
// built-in font drawn instead). Kept; looked at again only when
// MILLCHARGE_FONT changes.
struct FontChoice {
  std::shared_ptr<const Font> font;
  std::string warning;  // why MILLCHARGE_FONT's file is not the one in use
};

FontChoice& font_choice() {
  static std::mutex mutex;
  static FontChoice choice;
  static std::string chosen_for = "\x01";  // the MILLCHARGE_FONT value `choice` was made for
  const std::string path = plot_font_path().string();
  std::lock_guard<std::mutex> lock(mutex);
  if (!choice.font || chosen_for != path) {
    chosen_for = path;
    choice.warning.clear();
    if (!path.empty()) {
      try {
        choice.font = std::make_shared<const Font>(path);
        return choice;
      } catch (const std::exception& e) {
        choice.warning = std::string(e.what()) + "; the built-in font is used instead";
        std::fprintf(stderr, "warning: %s\n", choice.warning.c_str());
      }
    }
    static const std::shared_ptr<const Font> builtin = std::make_shared<const Font>();
    choice.font = builtin;
  }
  return choice;
}

std::shared_ptr<const Font> plot_font() { return font_choice().font; }

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
            bool up = false) {
    const std::vector<int> cps = utf8(s);
    if (cps.empty() || !(px > 0) || !std::isfinite(x) || !std::isfinite(y)) return;
    const Font& f = *font_;
    const float sc = f.scale(px);
    const double ua = ax * f.width(cps, sc), va = -f.cap * sc * (1 - ay);  // the anchor: along, down from the baseline
    // The baseline's start on the canvas: (ox + u, oy + v), or (ox + v, oy - u) when up.
    const double ox = up ? std::round(x - va) : x - ua, oy = up ? std::round(y + ua) : std::round(y - va);
    const int oi = static_cast<int>(std::floor(ox)), oj = static_cast<int>(oy);
    double pen = up ? 0 : ox - oi;
    int prev = 0;
    std::vector<unsigned char> bmp;
    for (int cp : cps) {
      const int g = stbtt_FindGlyphIndex(&f.info, cp);
      if (prev) pen += sc * stbtt_GetGlyphKernAdvance(&f.info, prev, g);
      const float shift = static_cast<float>(pen - std::floor(pen));
      int x0, y0, x1, y1;
      stbtt_GetGlyphBitmapBoxSubpixel(&f.info, g, sc, sc, shift, 0, &x0, &y0, &x1, &y1);
      if (x1 > x0 && y1 > y0) {
        const int gw = x1 - x0, gh = y1 - y0;
        bmp.assign(static_cast<std::size_t>(gw) * gh, 0);
        stbtt_MakeGlyphBitmapSubpixel(&f.info, bmp.data(), gw, gh, gw, sc, sc, shift, 0, g);
        const int u0 = static_cast<int>(std::floor(pen)) + x0;
        for (int j = 0; j < gh; ++j)
          for (int i = 0; i < gw; ++i) {
            const unsigned char c = bmp[static_cast<std::size_t>(j) * gw + i];
            if (!c) continue;
            if (up)
              blend(oi + y0 + j, oj - (u0 + i) - 1, rgb, c / 255.0);
            else
              blend(oi + u0 + i, oj + y0 + j, rgb, c / 255.0);
          }
      }
      int advance, lsb;
      stbtt_GetGlyphHMetrics(&f.info, g, &advance, &lsb);
      pen += sc * advance;
      prev = g;
    }
  }
  // The advance width of a line of text, in pixels.
  double text_width(const std::string& s, double px) const { return font_->width(utf8(s), font_->scale(px)); }
  // The height of the capitals, of the tallest letters above the baseline
  // and of the descenders below it, in pixels.
  double cap_height(double px) const { return font_->cap * font_->scale(px); }
  double ascent(double px) const { return font_->ascent * font_->scale(px); }
  double descent(double px) const { return -font_->descent * font_->scale(px); }
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
  // The code points of UTF-8 text; a malformed byte or a control character
  // becomes U+FFFD.
  static std::vector<int> utf8(const std::string& s) {
    std::vector<int> out;
    for (std::size_t i = 0; i < s.size();) {
      const unsigned char c = static_cast<unsigned char>(s[i]);
      const int n = c < 0x80 ? 1 : (c >> 5) == 6 ? 2 : (c >> 4) == 14 ? 3 : (c >> 3) == 30 ? 4 : 0;
      int cp = n == 1 ? c : n == 2 ? c & 0x1f : n == 3 ? c & 0x0f : c & 0x07;
      bool ok = n > 0 && i + n <= s.size();
      for (int k = 1; ok && k < n; ++k) {
        const unsigned char d = static_cast<unsigned char>(s[i + k]);
        ok = (d >> 6) == 2;
        cp = (cp << 6) | (d & 0x3f);
      }
      out.push_back(!ok || cp < 32 || (cp >= 0x7f && cp < 0xa0) ? 0xfffd : cp);
      i += ok ? n : 1;
    }
    return out;
  }

  std::shared_ptr<const Font> font_ = plot_font();
  int w_, h_;
  std::vector<unsigned char> px_;
  int cx0_ = 0, cy0_ = 0, cx1_ = 0, cy1_ = 0;
};

}  // namespace

std::string plot_font_in_use() {
  const auto font = plot_font();
  return font->source.empty() ? "built in" : font->source;
}

bool draw_or_warn(const std::filesystem::path& file, const std::function<void()>& draw) {
  try {
    draw();
    return true;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "warning: %s not drawn: %s\n", file.string().c_str(), e.what());
    return false;
  }
}

std::string plot_font_warning() {
  font_choice();
  return font_choice().warning;
}

namespace {

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

// A number with a true minus sign (U+2212), as typeset.
std::string minus(std::string s) {
  if (!s.empty() && s[0] == '-') s.replace(0, 1, "\u2212");
  return s;
}

// An exponent in superscript digits.
std::string superscript(long k) {
  static const char* const sup[] = {"\u2070", "\u00b9", "\u00b2", "\u00b3", "\u2074",
                                    "\u2075", "\u2076", "\u2077", "\u2078", "\u2079"};
  std::string s;
  for (char c : std::to_string(k)) s += c == '-' ? "\u207b" : sup[c - '0'];
  return s;
}

// A number printed with `fmt` (a %g format), its exponent, if any, typeset:
// 4.7e-05 as 4.7×10⁻⁵, 1e+06 as 10⁶.
std::string number(const char* fmt, double v) {
  const std::string s = format(fmt, v);
  const std::size_t e = s.find_first_of("eE");
  if (e == std::string::npos || !std::isfinite(v)) return minus(s);
  const std::string mantissa = s.substr(0, e);
  const std::string power = "10" + superscript(std::strtol(s.c_str() + e + 1, nullptr, 10));
  if (mantissa == "1" || mantissa == "-1") return minus(mantissa == "1" ? power : "-" + power);
  return minus(mantissa + "\u00d7" + power);
}

std::string tick_label(double v, double step) {
  if (std::abs(v) < step * 1e-6) v = 0;
  const double big = std::abs(v);
  if (step >= 1e-4 && big < 1e7) {
    const int digits = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", digits, v);
    return minus(buf);
  }
  return number("%.3g", v);
}

// A tick of a log axis at log10 x = e: 10 with a superscript power for a
// whole power, else the value.
std::string log_tick_label(double e, double step) {
  const double k = std::round(e);
  if (step < 1 || std::abs(e - k) > 1e-6) return number("%.2g", std::pow(10.0, e));
  return "10" + superscript(static_cast<long>(k));
}

}  // namespace

namespace {

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
  const bool span = plot.span_to > plot.span_from && std::isfinite(plot.span_from) && std::isfinite(plot.span_to);
  if (span) x0 = std::min(x0, plot.span_from), x1 = std::max(x1, plot.span_to);
  for (const RefLine& r : plot.ref_lines)
    if (std::isfinite(r.value)) {
      y0 = std::min(y0, r.value), y1 = std::max(y1, r.value);
      if (r.x_to > r.x_from && std::isfinite(r.x_from) && std::isfinite(r.x_to))
        x0 = std::min(x0, r.x_from), x1 = std::max(x1, r.x_to);
    }
  if (!(x0 <= x1)) x0 = 0, x1 = 1;
  if (!(y0 <= y1)) y0 = 0, y1 = 1;
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
    const std::string s = std::string(name) + " " + format("%.0f", deg) + "\u00b0";
    const double tw = cv.text_width(s, kNotePx), th = cv.cap_height(kNotePx);
    const P p{centre.x + (rpx + 12) * ca, centre.y - (rpx + 12) * sa};
    double x = ca > 0.3 ? p.x : ca < -0.3 ? p.x - tw : p.x - tw / 2;
    double y = sa > 0.3 ? p.y - th : sa < -0.3 ? p.y : p.y - th / 2;
    x = std::clamp(x, 6.0, size - 6 - tw), y = std::clamp(y, 6.0, size - 8 - th);
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

// ------------------------------------------------------------- heat maps --

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
  for (const auto& [mx, label] : m.marks_x)
    if (std::isfinite(mx)) cv.line({X(mx), double(T)}, {X(mx), double(B)}, 0xc51b8a, 2);
  int nth = 0;
  for (const auto& [mx, label] : m.marks_x) {
    if (!std::isfinite(mx)) continue;
    const double tw = cv.text_width(label, kNotePx);
    const double tx = X(mx) + 6 + tw > R - 4 ? X(mx) - 6 - tw : X(mx) + 6;
    cv.label(tx, T + 10 + 22 * nth++, label, 0xc51b8a, kNotePx);
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
