#include "io/png_canvas.h"

#include "io/atomic_file.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <mutex>
#include <stdexcept>

#include "io/plot_font_data.h"
#include "io/png_plot.h"

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

namespace draw {

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

namespace {

// The font: MILLCHARGE_FONT's file when it is set and can be read, else the
// built-in one (a file that cannot be read is said once, on stderr, and the
// built-in font drawn instead). Kept; looked at again only when
// MILLCHARGE_FONT changes.
struct FontChoice {
  std::shared_ptr<const Font> font;
  std::string warning;  // why MILLCHARGE_FONT's file is not the one in use
};

FontChoice font_choice() {
  static std::mutex mutex;
  static FontChoice choice;
  static std::string chosen_for;  // the MILLCHARGE_FONT value `choice` was made for
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

}  // namespace

std::shared_ptr<const Font> plot_font() { return font_choice().font; }

// ------------------------------------------------------------------ canvas --

void Canvas::text(double x, double y, const std::string& s, std::uint32_t rgb, double px, double ax, double ay,
                  bool up) {
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

double Canvas::text_width(const std::string& s, double px) const { return font_->width(utf8(s), font_->scale(px)); }
double Canvas::cap_height(double px) const { return font_->cap * font_->scale(px); }
double Canvas::ascent(double px) const { return font_->ascent * font_->scale(px); }
double Canvas::descent(double px) const { return -font_->descent * font_->scale(px); }

std::string Canvas::png() const {
  std::string out;
  auto sink = [](void* ctx, void* data, int n) {
    static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), n);
  };
  if (!stbi_write_png_to_func(sink, &out, w_, h_, 3, px_.data(), w_ * 3) || out.empty())
    throw std::runtime_error("PNG encoding failed");
  return out;
}

std::vector<int> Canvas::utf8(const std::string& s) {
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

// ----------------------------------------------------------------- helpers --

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

std::string minus(std::string s) {
  if (!s.empty() && s[0] == '-') s.replace(0, 1, "\u2212");
  return s;
}

std::string superscript(long k) {
  static const char* const sup[] = {"\u2070", "\u00b9", "\u00b2", "\u00b3", "\u2074",
                                    "\u2075", "\u2076", "\u2077", "\u2078", "\u2079"};
  std::string s;
  for (char c : std::to_string(k)) s += c == '-' ? "\u207b" : sup[c - '0'];
  return s;
}

std::string number(const char* fmt, double v) {
  const std::string s = format(fmt, v);
  const std::size_t e = s.find_first_of("eE");
  if (e == std::string::npos || !std::isfinite(v)) return minus(s);
  const std::string mantissa = s.substr(0, e);
  const std::string power = "10" + superscript(std::strtol(s.c_str() + e + 1, nullptr, 10));
  if (mantissa == "1" || mantissa == "-1") return minus(mantissa == "1" ? power : "-" + power);
  return minus(mantissa + "\u00d7" + power);
}

// -------------------------------------------------------------------- axes --

namespace {

// Heckbert's "nice numbers": 1, 2 or 5 × 10^k.
double nice_num(double x, bool round) {
  const double e = std::pow(10.0, std::floor(std::log10(x)));
  const double f = x / e;
  if (round) return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * e;
  return (f <= 1 ? 1 : f <= 2 ? 2 : f <= 5 ? 5 : 10) * e;
}

}  // namespace

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

}  // namespace draw

std::string plot_font_in_use() {
  const auto font = draw::plot_font();
  return font->source.empty() ? "built in" : font->source;
}

bool draw_or_warn(const std::filesystem::path& file, const std::function<void()>& draw) {
  return write_or_warn(file, draw, "drawn");
}

std::string plot_font_warning() {
  return draw::font_choice().warning;
}

}  // namespace mc::io
