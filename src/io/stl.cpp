#include "io/stl.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include <fmt/format.h>

namespace mc::io {

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "STL is little-endian; this reader assumes a little-endian host"
#endif

namespace {

constexpr std::size_t kHeader = 84;  // 80 bytes of text, then the count
constexpr std::size_t kFacet = 50;   // normal, three vertices (floats), 2 bytes

Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

bool starts_with_solid(std::string_view s) {
  std::size_t i = 0;
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  if (s.size() - i < 5) return false;
  for (int k = 0; k < 5; ++k)
    if (std::tolower(static_cast<unsigned char>(s[i + k])) != "solid"[k]) return false;
  return i + 5 == s.size() || std::isspace(static_cast<unsigned char>(s[i + 5]));
}

std::uint32_t binary_count(std::string_view b) {
  std::uint32_t n = 0;
  std::memcpy(&n, b.data() + 80, 4);
  return n;
}

std::string printable(std::string_view s, std::size_t max = 24) {
  std::string out;
  for (char ch : s.substr(0, max)) out += std::isprint(static_cast<unsigned char>(ch)) ? ch : '?';
  return s.size() > max ? out + "..." : out;
}

// Reads whitespace-separated words with their line numbers.
class Words {
 public:
  Words(std::string_view text, const std::string& source) : t_(text), source_(source) {}
  bool next(std::string_view& w) {
    while (p_ < t_.size() && std::isspace(static_cast<unsigned char>(t_[p_]))) {
      if (t_[p_] == '\n') ++line_;
      ++p_;
    }
    if (p_ >= t_.size()) return false;
    const std::size_t b = p_;
    while (p_ < t_.size() && !std::isspace(static_cast<unsigned char>(t_[p_]))) ++p_;
    w = t_.substr(b, p_ - b);
    word_line_ = line_;
    return true;
  }
  // The rest of the current line (the solid's name).
  std::string_view rest_of_line() {
    const std::size_t b = p_;
    while (p_ < t_.size() && t_[p_] != '\n') ++p_;
    std::string_view r = t_.substr(b, p_ - b);
    while (!r.empty() && std::isspace(static_cast<unsigned char>(r.front()))) r.remove_prefix(1);
    while (!r.empty() && std::isspace(static_cast<unsigned char>(r.back()))) r.remove_suffix(1);
    return r;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw MeshError(fmt::format("{}:{}: {}", source_, word_line_, what));
  }
  int line() const { return word_line_; }

 private:
  std::string_view t_;
  const std::string& source_;
  std::size_t p_ = 0;
  int line_ = 1, word_line_ = 1;
};

void expect(Words& w, std::string_view want, std::string_view where) {
  std::string_view got;
  if (!w.next(got)) w.fail(fmt::format("truncated: the file ends {} (expected \"{}\")", where, want));
  if (got != want) w.fail(fmt::format("expected \"{}\" {}, got \"{}\"", want, where, printable(got)));
}

double number(Words& w, std::string_view what, std::size_t triangle) {
  std::string_view got;
  if (!w.next(got)) w.fail(fmt::format("truncated: the file ends in triangle {} (expected {})", triangle, what));
  double x = 0;
  const auto [end, ec] = std::from_chars(got.data(), got.data() + got.size(), x);
  if (ec != std::errc() || end != got.data() + got.size())
    w.fail(fmt::format("triangle {}: {} \"{}\" is not a number", triangle, what, printable(got)));
  return x;
}

TriangleMesh parse_ascii(std::string_view text, const std::string& source, double scale,
                         std::vector<int>& lines) {
  TriangleMesh m;
  Words w(text, source);
  expect(w, "solid", "at the start");
  m.name = std::string(w.rest_of_line());
  std::string_view word;
  for (;;) {
    if (!w.next(word))
      w.fail(fmt::format("truncated: the file ends after {} triangles without \"endsolid\"", m.triangles.size()));
    if (word == "endsolid") break;
    const std::size_t k = m.triangles.size() + 1;
    if (word != "facet")
      w.fail(fmt::format("expected \"facet\" or \"endsolid\" after triangle {}, got \"{}\"{}", k - 1,
                         printable(word),
                         std::any_of(text.begin(), text.end(), [](char c) { return c == '\0'; })
                             ? " (the file holds binary bytes: a binary STL whose size does not match its count?)"
                             : ""));
    const int line = w.line();
    expect(w, "normal", fmt::format("in triangle {}", k));
    for (int c = 0; c < 3; ++c) number(w, "its normal", k);
    expect(w, "outer", fmt::format("in triangle {}", k));
    expect(w, "loop", fmt::format("in triangle {}", k));
    Triangle t;
    for (int v = 0; v < 3; ++v) {
      expect(w, "vertex", fmt::format("in triangle {}", k));
      const std::string what = fmt::format("vertex {}", v + 1);
      t.v[v] = Vec3{number(w, what, k), number(w, what, k), number(w, what, k)} * scale;
    }
    expect(w, "endloop", fmt::format("in triangle {} (a facet has three vertices)", k));
    expect(w, "endfacet", fmt::format("in triangle {}", k));
    m.triangles.push_back(t);
    lines.push_back(line);
  }
  return m;
}

TriangleMesh parse_binary(std::string_view b, double scale) {
  TriangleMesh m;
  m.binary = true;
  std::string head(b.substr(0, 80));
  head.erase(std::find(head.begin(), head.end(), '\0'), head.end());
  while (!head.empty() && std::isspace(static_cast<unsigned char>(head.back()))) head.pop_back();
  m.name = head;
  const std::uint32_t n = binary_count(b);
  m.triangles.resize(n);
  for (std::uint32_t k = 0; k < n; ++k) {
    float f[12];
    std::memcpy(f, b.data() + kHeader + std::size_t(k) * kFacet, sizeof f);
    for (int v = 0; v < 3; ++v) m.triangles[k].v[v] = Vec3{f[3 + 3 * v], f[4 + 3 * v], f[5 + 3 * v]} * scale;
  }
  return m;
}

// No mill part is 10 km across: a coordinate beyond this is a corrupt or mis-scaled file.
constexpr double kMaxCoordinate = 1e4;

void check(const TriangleMesh& m, const std::string& source, const std::vector<int>& lines) {
  auto where = [&](std::size_t k) {
    return lines.empty() ? fmt::format("{}: triangle {}", source, k + 1)
                         : fmt::format("{}:{}: triangle {}", source, lines[k], k + 1);
  };
  if (m.triangles.empty()) throw MeshError(fmt::format("{}: the mesh has no triangles", source));
  std::map<std::array<std::tuple<double, double, double>, 3>, std::size_t> seen;
  for (std::size_t k = 0; k < m.triangles.size(); ++k) {
    const Triangle& t = m.triangles[k];
    for (int v = 0; v < 3; ++v)
      if (!std::isfinite(t.v[v].x) || !std::isfinite(t.v[v].y) || !std::isfinite(t.v[v].z))
        throw MeshError(fmt::format("{}: vertex {} is not a finite number ({}, {}, {})", where(k), v + 1, t.v[v].x,
                                    t.v[v].y, t.v[v].z));
    for (int v = 0; v < 3; ++v) {
      const double c[3] = {t.v[v].x, t.v[v].y, t.v[v].z};
      for (int d = 0; d < 3; ++d)
        if (std::abs(c[d]) > kMaxCoordinate)
          throw MeshError(fmt::format(
              "{}: vertex {} is out of range: its {} coordinate is {:.6g} m (after scaling), beyond the limit "
              "|{}| <= {:g} m (is the file in the units that mesh.scale assumes?)",
              where(k), v + 1, "xyz"[d], c[d], "xyz"[d], kMaxCoordinate));
    }
    for (int a = 0; a < 3; ++a)
      for (int c = a + 1; c < 3; ++c)
        if ((t.v[a] - t.v[c]).norm() == 0)
          throw MeshError(fmt::format("{}: has zero area (vertices {} and {} coincide)", where(k), a + 1, c + 1));
    double longest = 0;
    for (int a = 0; a < 3; ++a) longest = std::max(longest, (t.v[(a + 1) % 3] - t.v[a]).norm());
    const double twice_area = cross(t.v[1] - t.v[0], t.v[2] - t.v[0]).norm();
    if (twice_area <= 1e-9 * longest * longest)
      throw MeshError(fmt::format("{}: has zero area (its vertices lie on a line; longest edge {:.6g} m)", where(k),
                                  longest));
    std::array<std::tuple<double, double, double>, 3> key;
    for (int v = 0; v < 3; ++v) key[v] = {t.v[v].x, t.v[v].y, t.v[v].z};
    std::sort(key.begin(), key.end());
    const auto [it, fresh] = seen.emplace(key, k);
    if (!fresh) throw MeshError(fmt::format("{}: repeats triangle {}", where(k), it->second + 1));
  }
}

void put_float(std::string& out, double x) {
  const float f = static_cast<float>(x);
  char b[4];
  std::memcpy(b, &f, 4);
  out.append(b, 4);
}

}  // namespace

Vec3 triangle_normal(const Triangle& t) {
  const Vec3 n = cross(t.v[1] - t.v[0], t.v[2] - t.v[0]);
  const double len = n.norm();
  return len > 0 ? n * (1.0 / len) : Vec3{};
}

TriangleMesh parse_stl(std::string_view bytes, const std::string& source, double scale) {
  if (bytes.empty()) throw MeshError(fmt::format("{}: empty file, not an STL", source));
  std::vector<int> lines;
  TriangleMesh m;
  const bool solid = starts_with_solid(bytes);
  if (bytes.size() >= kHeader &&
      bytes.size() == kHeader + kFacet * static_cast<std::uint64_t>(binary_count(bytes))) {
    m = parse_binary(bytes, scale);
  } else if (solid) {
    m = parse_ascii(bytes, source, scale, lines);
  } else if (bytes.size() < kHeader) {
    throw MeshError(fmt::format(
        "{}: not an STL: {} bytes that neither begin with \"solid\" (ASCII STL) nor hold a binary STL's "
        "84-byte header",
        source, bytes.size()));
  } else {
    const std::uint64_t n = binary_count(bytes);
    const std::uint64_t want = kHeader + kFacet * n;
    throw MeshError(
        bytes.size() < want
            ? fmt::format("{}: truncated binary STL: its header counts {} triangles ({} bytes), the file has {} bytes",
                          source, n, want, bytes.size())
            : fmt::format("{}: not an STL: it does not begin with \"solid\" (ASCII STL), and as binary STL its "
                          "header counts {} triangles ({} bytes) but the file has {} bytes",
                          source, n, want, bytes.size()));
  }
  check(m, source, lines);
  return m;
}

TriangleMesh read_stl(const std::filesystem::path& path, double scale) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw MeshError(fmt::format("{}: is a directory, not a file (give the path of an .stl file)", path.string()));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshError(fmt::format("{}: cannot be read (no such file, or no permission)", path.string()));
  std::ostringstream buf;
  buf << in.rdbuf();
  if (in.bad()) throw MeshError(fmt::format("{}: read error", path.string()));
  return parse_stl(buf.str(), path.string(), scale);
}

std::string stl_binary(const std::vector<Triangle>& triangles, std::string_view header) {
  std::string out(80, ' ');
  std::copy_n(header.begin(), std::min<std::size_t>(header.size(), 80), out.begin());
  const std::uint32_t n = static_cast<std::uint32_t>(triangles.size());
  char b[4];
  std::memcpy(b, &n, 4);
  out.append(b, 4);
  out.reserve(kHeader + kFacet * triangles.size());
  for (const Triangle& t : triangles) {
    const Vec3 nrm = triangle_normal(t);
    put_float(out, nrm.x), put_float(out, nrm.y), put_float(out, nrm.z);
    for (const Vec3& v : t.v) put_float(out, v.x), put_float(out, v.y), put_float(out, v.z);
    out.append(2, '\0');
  }
  return out;
}

std::string stl_ascii(const std::vector<Triangle>& triangles, std::string_view name) {
  std::string out = fmt::format("solid {}\n", name);
  for (const Triangle& t : triangles) {
    const Vec3 n = triangle_normal(t);
    out += fmt::format("  facet normal {:.9g} {:.9g} {:.9g}\n    outer loop\n", n.x, n.y, n.z);
    for (const Vec3& v : t.v) out += fmt::format("      vertex {:.9g} {:.9g} {:.9g}\n", v.x, v.y, v.z);
    out += "    endloop\n  endfacet\n";
  }
  return out + fmt::format("endsolid {}\n", name);
}

}  // namespace mc::io
