#include "io/vtk.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "io/atomic_file.h"

namespace mc::io {

namespace {

static_assert(std::numeric_limits<float>::is_iec559 && sizeof(float) == 4, "needs IEEE float");
static_assert(std::numeric_limits<double>::is_iec559 && sizeof(double) == 8, "needs IEEE double");

// ---------------------------------------------------------------- writing --

// Little-endian bytes whatever the host's order.
void put_u32(std::string& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xffu));
}
void put_u64(std::string& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xffu));
}
void put_f32(std::string& out, float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  put_u32(out, u);
}
void put_f64(std::string& out, double d) {
  std::uint64_t u;
  std::memcpy(&u, &d, 8);
  put_u64(out, u);
}

std::string xml_escape(const std::string& s) {
  std::string r;
  r.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': r += "&amp;"; break;
      case '<': r += "&lt;"; break;
      case '>': r += "&gt;"; break;
      case '"': r += "&quot;"; break;
      case '\'': r += "&apos;"; break;
      default: r.push_back(c);
    }
  }
  return r;
}

// The appended blocks, each a UInt64 byte count then the raw data, and the
// <DataArray .../> tags that point into them.
class Appended {
 public:
  // Starts a block; returns its offset for the tag. `bytes` is the size the
  // caller is about to write.
  std::uint64_t begin(std::uint64_t bytes) {
    const std::uint64_t off = data_.size();
    put_u64(data_, bytes);
    expected_end_ = data_.size() + bytes;
    return off;
  }
  std::string& data() { return data_; }
  void end() const {
    if (data_.size() != expected_end_) throw std::logic_error("write_vtp: appended block size mismatch");
  }

 private:
  std::string data_;
  std::size_t expected_end_ = 0;
};

std::string tag(const char* type, const char* name, int components, std::uint64_t offset) {
  std::string t = "<DataArray type=\"";
  t += type;
  t += "\"";
  if (name) {
    t += " Name=\"";
    t += name;
    t += "\"";
  }
  if (components > 1) t += " NumberOfComponents=\"" + std::to_string(components) + "\"";
  t += " format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
  return t;
}

// ---------------------------------------------------------------- reading --

[[noreturn]] void bad(const std::filesystem::path& p, const std::string& what) {
  throw std::runtime_error("read_vtp: " + p.string() + ": " + what);
}

using Attrs = std::map<std::string, std::string>;

// Attributes of the tag that starts at `start` (at its '<'); `end` is its '>'.
Attrs parse_attrs(std::string_view text, std::size_t start, std::size_t end) {
  Attrs a;
  std::size_t i = start + 1;
  while (i < end && !std::isspace(static_cast<unsigned char>(text[i])) && text[i] != '/') ++i;  // tag name
  while (i < end) {
    while (i < end && (std::isspace(static_cast<unsigned char>(text[i])) || text[i] == '/')) ++i;
    if (i >= end) break;
    const std::size_t name0 = i;
    while (i < end && text[i] != '=' && !std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    std::string name(text.substr(name0, i - name0));
    while (i < end && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    if (i >= end || text[i] != '=') break;  // attribute without a value: stop
    ++i;
    while (i < end && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    if (i >= end || (text[i] != '"' && text[i] != '\'')) break;
    const char q = text[i++];
    const std::size_t v0 = i;
    while (i < end && text[i] != q) ++i;
    if (i >= end) break;
    a[name] = std::string(text.substr(v0, i - v0));
    ++i;
  }
  return a;
}

// The first tag named `name` (followed by a space, '>' or '/') in [from, limit).
// Returns npos if there is none; `tag_end` gets the position of its '>'.
std::size_t find_tag(std::string_view text, std::string_view name, std::size_t from, std::size_t limit,
                     std::size_t& tag_end) {
  std::string open = "<";
  open += name;
  std::size_t p = from;
  while ((p = text.find(open, p)) != std::string_view::npos && p < limit) {
    const std::size_t after = p + open.size();
    if (after < text.size()) {
      const char c = text[after];
      if (c == '>' || c == '/' || std::isspace(static_cast<unsigned char>(c))) {
        tag_end = text.find('>', after);
        if (tag_end == std::string_view::npos || tag_end >= limit) return std::string_view::npos;
        return p;
      }
    }
    p = after;
  }
  return std::string_view::npos;
}

bool parse_u64(const std::string& s, std::uint64_t& v) {
  if (s.empty() || s.size() > 20) return false;
  std::uint64_t r = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    const std::uint64_t d = static_cast<std::uint64_t>(c - '0');
    if (r > (std::numeric_limits<std::uint64_t>::max() - d) / 10) return false;
    r = r * 10 + d;
  }
  v = r;
  return true;
}

std::uint32_t get_u32(const unsigned char* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
std::uint64_t get_u64(const unsigned char* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
float get_f32(const unsigned char* p) {
  const std::uint32_t u = get_u32(p);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
double get_f64(const unsigned char* p) {
  const std::uint64_t u = get_u64(p);
  double d;
  std::memcpy(&d, &u, 8);
  return d;
}

struct ArrayInfo {
  std::string type;
  int components = 1;
  std::uint64_t offset = 0;
};

}  // namespace

void write_vtp(const std::filesystem::path& path, const Snapshot& s) {
  const std::size_t n = s.position.size();
  if (s.velocity.size() != n || s.radius.size() != n || s.material.size() != n || s.id.size() != n) {
    throw std::invalid_argument("write_vtp: " + path.string() + ": arrays of different lengths (position " +
                                std::to_string(n) + ", velocity " + std::to_string(s.velocity.size()) +
                                ", radius " + std::to_string(s.radius.size()) + ", material " +
                                std::to_string(s.material.size()) + ", id " + std::to_string(s.id.size()) +
                                ")");
  }
  const bool bodies = !s.body.empty();
  if (bodies && (s.body.size() != n || s.orientation.size() != n))
    throw std::invalid_argument("write_vtp: " + path.string() + ": body or orientation arrays of another length");
  const std::uint64_t N = n;
  for (std::size_t i = 0; i < n; ++i) {
    if (s.material[i] < std::numeric_limits<std::int32_t>::min() ||
        s.material[i] > std::numeric_limits<std::int32_t>::max() ||
        s.id[i] < std::numeric_limits<std::int32_t>::min() || s.id[i] > std::numeric_limits<std::int32_t>::max())
      throw std::invalid_argument("write_vtp: " + path.string() + ": material or id out of Int32 range");
  }

  Appended app;
  std::string& d = app.data();
  d.reserve(static_cast<std::size_t>(8 * 8 + N * (12 + 4 + 12 + 4 + 4 + 4 + 12 + 8 + 8)));

  const std::uint64_t off_time = app.begin(8);
  put_f64(d, s.time_s);
  app.end();

  const std::uint64_t off_radius = app.begin(N * 4);
  for (float r : s.radius) put_f32(d, r);
  app.end();

  const std::uint64_t off_vel = app.begin(N * 12);
  for (const auto& v : s.velocity)
    for (float c : v) put_f32(d, c);
  app.end();

  const std::uint64_t off_speed = app.begin(N * 4);
  for (const auto& v : s.velocity) {
    const double sp = std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]);
    put_f32(d, static_cast<float>(sp));
  }
  app.end();

  const std::uint64_t off_mat = app.begin(N * 4);
  for (int m : s.material) put_u32(d, static_cast<std::uint32_t>(static_cast<std::int32_t>(m)));
  app.end();

  const std::uint64_t off_id = app.begin(N * 4);
  for (int i : s.id) put_u32(d, static_cast<std::uint32_t>(static_cast<std::int32_t>(i)));
  app.end();

  std::uint64_t off_body = 0, off_orient = 0;
  if (bodies) {
    off_body = app.begin(N * 4);
    for (int b : s.body) put_u32(d, static_cast<std::uint32_t>(static_cast<std::int32_t>(b)));
    app.end();
    off_orient = app.begin(N * 16);
    for (const auto& q : s.orientation)
      for (float c : q) put_f32(d, c);
    app.end();
  }

  const std::uint64_t off_pos = app.begin(N * 12);
  for (const auto& p : s.position)
    for (float c : p) put_f32(d, c);
  app.end();

  const std::uint64_t off_conn = app.begin(N * 8);
  for (std::uint64_t i = 0; i < N; ++i) put_u64(d, i);
  app.end();

  const std::uint64_t off_offs = app.begin(N * 8);
  for (std::uint64_t i = 1; i <= N; ++i) put_u64(d, i);
  app.end();

  const std::string ns = std::to_string(N);
  std::string x;
  x.reserve(2048 + d.size());
  x += "<?xml version=\"1.0\"?>\n";
  x += "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
  x += "<PolyData>\n";
  x += "<FieldData>\n";
  {
    // FieldData arrays need NumberOfTuples.
    std::string t = tag("Float64", "TimeValue", 1, off_time);
    t.insert(t.find(" format="), " NumberOfTuples=\"1\"");
    x += t;
  }
  x += "</FieldData>\n";
  x += "<Piece NumberOfPoints=\"" + ns + "\" NumberOfVerts=\"" + ns +
       "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n";
  x += "<PointData Scalars=\"radius\" Vectors=\"velocity\">\n";
  x += tag("Float32", "radius", 1, off_radius);
  x += tag("Float32", "velocity", 3, off_vel);
  x += tag("Float32", "speed", 1, off_speed);
  x += tag("Int32", "material", 1, off_mat);
  x += tag("Int32", "id", 1, off_id);
  if (bodies) {
    x += tag("Int32", "body", 1, off_body);
    x += tag("Float32", "orientation", 4, off_orient);
  }
  x += "</PointData>\n";
  x += "<Points>\n";
  x += tag("Float32", "Points", 3, off_pos);
  x += "</Points>\n";
  x += "<Verts>\n";
  x += tag("Int64", "connectivity", 1, off_conn);
  x += tag("Int64", "offsets", 1, off_offs);
  x += "</Verts>\n";
  x += "</Piece>\n";
  x += "</PolyData>\n";
  x += "<AppendedData encoding=\"raw\">\n_";
  x += d;
  x += "\n</AppendedData>\n";
  x += "</VTKFile>\n";

  write_file_atomic(path, x);
}

void write_mesh_vtp(const std::filesystem::path& path, const PolyMesh& m) {
  const std::uint64_t np = m.points.size(), nc = m.polygons.size();
  std::uint64_t corners = 0;
  for (const auto& poly : m.polygons) {
    if (poly.size() < 3) throw std::invalid_argument("write_mesh_vtp: " + path.string() + ": a polygon of " +
                                                     std::to_string(poly.size()) + " points");
    for (int q : poly)
      if (q < 0 || static_cast<std::uint64_t>(q) >= np)
        throw std::invalid_argument("write_mesh_vtp: " + path.string() + ": a polygon names point " +
                                    std::to_string(q) + " of " + std::to_string(np));
    corners += poly.size();
  }
  for (const auto& [name, v] : m.cell_floats)
    if (v.size() != nc) throw std::invalid_argument("write_mesh_vtp: " + path.string() + ": cell array " + name +
                                                    " has " + std::to_string(v.size()) + " values for " +
                                                    std::to_string(nc) + " polygons");
  for (const auto& [name, v] : m.cell_ints)
    if (v.size() != nc) throw std::invalid_argument("write_mesh_vtp: " + path.string() + ": cell array " + name +
                                                    " has " + std::to_string(v.size()) + " values for " +
                                                    std::to_string(nc) + " polygons");
  Appended app;
  std::string& d = app.data();
  std::string cells;
  const std::uint64_t off_time = app.begin(8);
  put_f64(d, m.time_s);
  app.end();
  for (const auto& [name, v] : m.cell_floats) {
    const std::uint64_t off = app.begin(nc * 4);
    for (float x : v) put_f32(d, x);
    app.end();
    cells += tag("Float32", xml_escape(name).c_str(), 1, off);
  }
  for (const auto& [name, v] : m.cell_ints) {
    const std::uint64_t off = app.begin(nc * 4);
    for (int x : v) put_u32(d, static_cast<std::uint32_t>(static_cast<std::int32_t>(x)));
    app.end();
    cells += tag("Int32", xml_escape(name).c_str(), 1, off);
  }
  const std::uint64_t off_pos = app.begin(np * 12);
  for (const auto& p : m.points)
    for (float c : p) put_f32(d, c);
  app.end();
  const std::uint64_t off_conn = app.begin(corners * 8);
  for (const auto& poly : m.polygons)
    for (int q : poly) put_u64(d, static_cast<std::uint64_t>(q));
  app.end();
  const std::uint64_t off_offs = app.begin(nc * 8);
  std::uint64_t end = 0;
  for (const auto& poly : m.polygons) put_u64(d, end += poly.size());
  app.end();

  std::string x;
  x += "<?xml version=\"1.0\"?>\n";
  x += "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
  x += "<PolyData>\n<FieldData>\n";
  std::string t = tag("Float64", "TimeValue", 1, off_time);
  t.insert(t.find(" format="), " NumberOfTuples=\"1\"");
  x += t;
  x += "</FieldData>\n";
  x += "<Piece NumberOfPoints=\"" + std::to_string(np) +
       "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"" + std::to_string(nc) +
       "\">\n";
  x += "<CellData>\n" + cells + "</CellData>\n";
  x += "<Points>\n" + tag("Float32", "Points", 3, off_pos) + "</Points>\n";
  x += "<Polys>\n" + tag("Int64", "connectivity", 1, off_conn) + tag("Int64", "offsets", 1, off_offs) + "</Polys>\n";
  x += "</Piece>\n</PolyData>\n";
  x += "<AppendedData encoding=\"raw\">\n_";
  x += d;
  x += "\n</AppendedData>\n</VTKFile>\n";
  write_file_atomic(path, x);
}

Snapshot read_vtp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) bad(path, "cannot open the file");
  std::string buf((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) bad(path, "cannot read the file");
  const std::string_view text(buf);

  // The XML part ends where the appended data starts; only search tags there,
  // since the raw bytes after it may contain anything.
  std::size_t vtk_end = 0;
  const std::size_t app_limit = text.size();
  std::size_t app_tag_end = 0;
  const std::size_t app_tag = find_tag(text, "AppendedData", 0, app_limit, app_tag_end);
  const std::size_t header_limit = app_tag == std::string_view::npos ? text.size() : app_tag;

  const std::size_t vtk = find_tag(text, "VTKFile", 0, header_limit, vtk_end);
  if (vtk == std::string_view::npos) bad(path, "not a VTK XML file (no <VTKFile> element)");
  const Attrs va = parse_attrs(text, vtk, vtk_end);
  auto attr = [](const Attrs& a, const char* k) {
    auto it = a.find(k);
    return it == a.end() ? std::string() : it->second;
  };
  if (attr(va, "type") != "PolyData") bad(path, "not a VTK PolyData file (type=\"" + attr(va, "type") + "\")");
  if (attr(va, "byte_order") != "LittleEndian")
    bad(path, "unsupported byte_order \"" + attr(va, "byte_order") + "\"");
  if (attr(va, "header_type") != "UInt64")
    bad(path, "unsupported header_type \"" + attr(va, "header_type") + "\"");
  if (attr(va, "compressor") != "") bad(path, "compressed files are not supported");

  if (app_tag == std::string_view::npos) bad(path, "no <AppendedData> element (truncated or not written by write_vtp)");
  const Attrs aa = parse_attrs(text, app_tag, app_tag_end);
  if (attr(aa, "encoding") != "raw") bad(path, "AppendedData encoding is not \"raw\"");
  const std::size_t underscore = text.find('_', app_tag_end + 1);
  if (underscore == std::string_view::npos) bad(path, "truncated data (no '_' after <AppendedData>)");
  for (std::size_t i = app_tag_end + 1; i < underscore; ++i)
    if (!std::isspace(static_cast<unsigned char>(text[i]))) bad(path, "unexpected text before the appended data");
  const std::size_t data0 = underscore + 1;
  const std::uint64_t data_size = text.size() - data0;

  std::size_t piece_end = 0;
  const std::size_t piece = find_tag(text, "Piece", vtk_end, header_limit, piece_end);
  if (piece == std::string_view::npos) bad(path, "no <Piece> element");
  std::size_t dummy = 0;
  if (find_tag(text, "Piece", piece_end, header_limit, dummy) != std::string_view::npos)
    bad(path, "more than one <Piece> is not supported");
  std::uint64_t n = 0;
  if (!parse_u64(attr(parse_attrs(text, piece, piece_end), "NumberOfPoints"), n))
    bad(path, "missing or bad NumberOfPoints");
  if (n > data_size / 12) bad(path, "truncated data (NumberOfPoints " + std::to_string(n) + " does not fit)");

  // Sections, so that arrays are known by section and name.
  auto section = [&](const char* name, std::size_t& b, std::size_t& e) {
    std::size_t te = 0;
    b = find_tag(text, name, vtk_end, header_limit, te);
    if (b == std::string_view::npos) {
      e = b;
      return;
    }
    const std::string close = std::string("</") + name + ">";
    e = text.find(close, te);
    if (e == std::string_view::npos || e > header_limit) e = header_limit;
  };
  struct Sec {
    const char* name;
    std::size_t b, e;
  } secs[] = {{"FieldData", 0, 0}, {"PointData", 0, 0}, {"Points", 0, 0}, {"Verts", 0, 0}};
  for (auto& sc : secs) section(sc.name, sc.b, sc.e);

  std::map<std::string, ArrayInfo> arrays;
  std::size_t p = vtk_end, te = 0;
  while ((p = find_tag(text, "DataArray", p, header_limit, te)) != std::string_view::npos) {
    const Attrs a = parse_attrs(text, p, te);
    std::string sec;
    for (const auto& sc : secs)
      if (sc.b != std::string_view::npos && p > sc.b && p < sc.e) sec = sc.name;
    ArrayInfo info;
    info.type = attr(a, "type");
    const std::string name = attr(a, "Name");
    if (attr(a, "format") != "appended") bad(path, "array \"" + name + "\" is not in appended format");
    if (!parse_u64(attr(a, "offset"), info.offset)) bad(path, "array \"" + name + "\" has a missing or bad offset");
    const std::string nc = attr(a, "NumberOfComponents");
    std::uint64_t c = 1;
    if (!nc.empty() && (!parse_u64(nc, c) || c < 1 || c > 64))
      bad(path, "array \"" + name + "\" has a bad NumberOfComponents");
    info.components = static_cast<int>(c);
    arrays[sec + "/" + (sec == "Points" ? std::string("Points") : name)] = info;
    p = te;
  }

  // Finds an array, checks its type and components, and returns a pointer to
  // its `n * components` values after checking the block is in bounds.
  auto block = [&](const std::string& key, const char* type, int comps, std::uint64_t count,
                   std::size_t elem) -> const unsigned char* {
    auto it = arrays.find(key);
    if (it == arrays.end()) bad(path, "missing array " + key);
    const ArrayInfo& a = it->second;
    if (a.type != type) bad(path, "array " + key + " has type " + a.type + ", expected " + type);
    if (a.components != comps)
      bad(path, "array " + key + " has " + std::to_string(a.components) + " components, expected " +
                    std::to_string(comps));
    if (a.offset > data_size || data_size - a.offset < 8)
      bad(path, "truncated data (array " + key + " starts past the end of the file)");
    const auto* h = reinterpret_cast<const unsigned char*>(text.data() + data0 + a.offset);
    const std::uint64_t bytes = get_u64(h);
    const std::uint64_t want = count * comps * elem;  // n <= data_size / 12, no overflow
    if (bytes != want)
      bad(path, "array " + key + " holds " + std::to_string(bytes) + " bytes, expected " + std::to_string(want));
    if (data_size - a.offset - 8 < bytes) bad(path, "truncated data (array " + key + " runs past the end of the file)");
    return h + 8;
  };

  Snapshot s;
  s.time_s = get_f64(block("FieldData/TimeValue", "Float64", 1, 1, 8));
  const unsigned char* pos = block("Points/Points", "Float32", 3, n, 4);
  const unsigned char* vel = block("PointData/velocity", "Float32", 3, n, 4);
  const unsigned char* rad = block("PointData/radius", "Float32", 1, n, 4);
  const unsigned char* mat = block("PointData/material", "Int32", 1, n, 4);
  const unsigned char* ids = block("PointData/id", "Int32", 1, n, 4);
  block("PointData/speed", "Float32", 1, n, 4);
  const bool has_bodies = arrays.count("PointData/body") > 0;
  const unsigned char* bod = has_bodies ? block("PointData/body", "Int32", 1, n, 4) : nullptr;
  const unsigned char* ori = has_bodies ? block("PointData/orientation", "Float32", 4, n, 4) : nullptr;
  block("Verts/connectivity", "Int64", 1, n, 8);
  block("Verts/offsets", "Int64", 1, n, 8);

  // The data is all there; the file must still end as written, or it was cut.
  std::size_t last = text.size();
  while (last > data0 && std::isspace(static_cast<unsigned char>(text[last - 1]))) --last;
  const std::string_view closing = "</VTKFile>";
  if (last - data0 < closing.size() || text.substr(last - closing.size(), closing.size()) != closing)
    bad(path, "truncated file (it does not end with </VTKFile>)");

  const std::size_t N = static_cast<std::size_t>(n);
  s.position.resize(N);
  s.velocity.resize(N);
  s.radius.resize(N);
  s.material.resize(N);
  s.id.resize(N);
  for (std::size_t i = 0; i < N; ++i) {
    for (int k = 0; k < 3; ++k) {
      s.position[i][k] = get_f32(pos + 4 * (3 * i + k));
      s.velocity[i][k] = get_f32(vel + 4 * (3 * i + k));
    }
    s.radius[i] = get_f32(rad + 4 * i);
    s.material[i] = static_cast<std::int32_t>(get_u32(mat + 4 * i));
    if (has_bodies) {
      s.body.push_back(static_cast<std::int32_t>(get_u32(bod + 4 * i)));
      s.orientation.push_back({get_f32(ori + 16 * i), get_f32(ori + 16 * i + 4), get_f32(ori + 16 * i + 8),
                               get_f32(ori + 16 * i + 12)});
    }
    s.id[i] = static_cast<std::int32_t>(get_u32(ids + 4 * i));
  }
  return s;
}

PvdIndex::PvdIndex(std::filesystem::path pvd_path) : path_(std::move(pvd_path)) {}

void PvdIndex::keep_existing(std::size_t count) {
  entries_.clear();
  if (count == 0) return;
  std::ifstream in(path_);
  std::string line;
  auto attr = [](const std::string& l, const std::string& key, std::string& out) {
    const auto at = l.find(key + "=\"");
    if (at == std::string::npos) return false;
    const auto from = at + key.size() + 2;
    const auto to = l.find('"', from);
    if (to == std::string::npos) return false;
    out = l.substr(from, to - from);
    return true;
  };
  while (entries_.size() < count && std::getline(in, line)) {
    std::string t, f, part;
    if (line.find("<DataSet") == std::string::npos || !attr(line, "timestep", t) || !attr(line, "file", f)) continue;
    if (attr(line, "part", part) && part != "0") continue;  // the snapshots are part 0
    entries_.push_back({std::strtod(t.c_str(), nullptr), f, 0});
  }
  if (entries_.size() < count)
    throw std::runtime_error(path_.string() + ": lists " + std::to_string(entries_.size()) + " snapshots, the checkpoint " +
                             std::to_string(count));
}

std::vector<double> PvdIndex::times(int part) const {
  std::vector<double> t;
  for (const Entry& e : entries_)
    if (e.part == part) t.push_back(e.time_s);
  return t;
}

void PvdIndex::add(double time_s, const std::string& relative_file, int part) {
  if (!std::isfinite(time_s))
    throw std::invalid_argument("PvdIndex::add: " + path_.string() + ": time is not finite");
  entries_.push_back({time_s, relative_file, part});
  std::string x;
  x += "<?xml version=\"1.0\"?>\n";
  x += "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n";
  x += "<Collection>\n";
  char t[64];
  for (const Entry& e : entries_) {
    std::snprintf(t, sizeof t, "%.9g", e.time_s);
    x += "<DataSet timestep=\"";
    x += t;
    x += "\" group=\"\" part=\"" + std::to_string(e.part) + "\" file=\"" + xml_escape(e.file) + "\"/>\n";
  }
  x += "</Collection>\n";
  x += "</VTKFile>\n";
  try {
    write_file_atomic(path_, x);
  } catch (...) {
    entries_.pop_back();  // keep the index as it is on disk
    throw;
  }
}

}  // namespace mc::io
