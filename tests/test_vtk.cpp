#include "io/vtk.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <random>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using mc::io::Snapshot;

namespace {

// A fresh folder under the system's temporary folder, removed at the end.
struct TempDir {
  fs::path path;
  TempDir() {
    std::random_device rd;
    const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
    path = fs::temp_directory_path() /
           ("millcharge_vtk_" + std::to_string(::getpid()) + "_" + std::to_string(stamp) + "_" + std::to_string(rd()));
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  REQUIRE(in);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void spit(const fs::path& p, const std::string& s) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  REQUIRE(out);
  out << s;
}

std::uint32_t bits(float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

std::uint64_t bits(double d) {
  std::uint64_t u;
  std::memcpy(&u, &d, 8);
  return u;
}

Snapshot random_snapshot(std::size_t n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-2.5f, 2.5f), vel(-7.f, 7.f), rad(0.005f, 0.08f);
  std::uniform_int_distribution<int> mat(0, 4);
  Snapshot s;
  s.time_s = 12.345678901234567;  // not representable as a float
  for (std::size_t i = 0; i < n; ++i) {
    s.position.push_back({pos(rng), pos(rng), pos(rng)});
    s.velocity.push_back({vel(rng), vel(rng), vel(rng)});
    s.radius.push_back(rad(rng));
    s.material.push_back(mat(rng));
    s.id.push_back(static_cast<int>(1000 + 3 * i));
  }
  if (n >= 4) {  // awkward values that must survive bit for bit
    s.position[0] = {-0.0f, std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::max()};
    s.velocity[1] = {std::numeric_limits<float>::lowest(), 1e-30f, -0.0f};
    s.material[2] = -7;
    s.id[3] = std::numeric_limits<int>::max();
    s.id[2] = std::numeric_limits<int>::min();
  }
  return s;
}

void require_same(const Snapshot& a, const Snapshot& b) {
  REQUIRE(bits(a.time_s) == bits(b.time_s));
  REQUIRE(b.size() == a.size());
  REQUIRE(b.velocity.size() == a.size());
  REQUIRE(b.radius.size() == a.size());
  REQUIRE(b.material.size() == a.size());
  REQUIRE(b.id.size() == a.size());
  std::size_t mismatches = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (bits(a.position[i][k]) != bits(b.position[i][k])) ++mismatches;
      if (bits(a.velocity[i][k]) != bits(b.velocity[i][k])) ++mismatches;
    }
    if (bits(a.radius[i]) != bits(b.radius[i])) ++mismatches;
    if (a.material[i] != b.material[i]) ++mismatches;
    if (a.id[i] != b.id[i]) ++mismatches;
  }
  REQUIRE(mismatches == 0);
}

// Independent of read_vtp: the raw bytes of the appended block of the
// DataArray named `name`, found from its offset attribute.
std::string raw_block(const std::string& file, const std::string& name) {
  std::smatch m;
  const std::regex re("<DataArray[^>]*Name=\"" + name + "\"[^>]*offset=\"([0-9]+)\"");
  const std::string head = file.substr(0, file.find("<AppendedData"));
  REQUIRE(std::regex_search(head, m, re));
  const std::size_t offset = std::stoull(m[1].str());
  const std::size_t app = file.find("<AppendedData encoding=\"raw\">");
  REQUIRE(app != std::string::npos);
  const std::size_t data0 = file.find('_', app) + 1;
  REQUIRE(data0 + offset + 8 <= file.size());
  std::uint64_t bytes = 0;
  for (int i = 7; i >= 0; --i) bytes = (bytes << 8) | static_cast<unsigned char>(file[data0 + offset + i]);
  REQUIRE(data0 + offset + 8 + bytes <= file.size());
  return file.substr(data0 + offset + 8, bytes);
}

template <class T>
std::vector<T> as(const std::string& raw) {
  REQUIRE(raw.size() % sizeof(T) == 0);
  std::vector<T> v(raw.size() / sizeof(T));
  std::memcpy(v.data(), raw.data(), raw.size());  // the test host is little-endian
  return v;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  FAIL("no std::runtime_error thrown");
  return {};
}

}  // namespace

TEST_CASE("vtp round trip of a few hundred balls", "[vtk]") {
  TempDir tmp;
  const fs::path f = tmp.path / "charge_000001.vtp";
  const Snapshot s = random_snapshot(300, 12345);
  mc::io::write_vtp(f, s);
  REQUIRE(fs::exists(f));

  const Snapshot r = mc::io::read_vtp(f);
  require_same(s, r);

  // The file itself, checked without read_vtp.
  const std::string file = slurp(f);
  CHECK(file.find("<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                  "header_type=\"UInt64\">") != std::string::npos);
  CHECK(file.find("NumberOfPoints=\"300\" NumberOfVerts=\"300\"") != std::string::npos);
  const auto pts = as<float>(raw_block(file, "Points"));
  REQUIRE(pts.size() == 900);
  CHECK(bits(pts[3 * 17 + 2]) == bits(s.position[17][2]));
  const auto conn = as<std::int64_t>(raw_block(file, "connectivity"));
  const auto offs = as<std::int64_t>(raw_block(file, "offsets"));
  REQUIRE(conn.size() == 300);
  REQUIRE(offs.size() == 300);
  for (std::size_t i = 0; i < 300; ++i) {
    REQUIRE(conn[i] == static_cast<std::int64_t>(i));
    REQUIRE(offs[i] == static_cast<std::int64_t>(i + 1));
  }
  const auto speed = as<float>(raw_block(file, "speed"));
  REQUIRE(speed.size() == 300);
  const auto& v = s.velocity[5];
  CHECK(speed[5] == Approx(std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])));
  const auto mat = as<std::int32_t>(raw_block(file, "material"));
  REQUIRE(mat.size() == 300);
  CHECK(mat[2] == -7);
  const auto time = as<double>(raw_block(file, "TimeValue"));
  REQUIRE(time.size() == 1);
  CHECK(time[0] == s.time_s);

  // Rewriting in place replaces the file.
  const Snapshot s2 = random_snapshot(50, 999);
  mc::io::write_vtp(f, s2);
  require_same(s2, mc::io::read_vtp(f));
}

TEST_CASE("vtp round trip with no balls", "[vtk]") {
  TempDir tmp;
  const fs::path f = tmp.path / "empty.vtp";
  Snapshot s;
  s.time_s = 0.75;
  mc::io::write_vtp(f, s);
  const std::string file = slurp(f);
  CHECK(file.find("NumberOfPoints=\"0\" NumberOfVerts=\"0\"") != std::string::npos);
  const Snapshot r = mc::io::read_vtp(f);
  CHECK(r.time_s == 0.75);
  CHECK(r.size() == 0);
  CHECK(r.velocity.empty());
  CHECK(r.radius.empty());
  CHECK(r.material.empty());
  CHECK(r.id.empty());
}

TEST_CASE("vtp: a truncated file is refused", "[vtk]") {
  TempDir tmp;
  const fs::path f = tmp.path / "cut.vtp";
  mc::io::write_vtp(f, random_snapshot(300, 7));
  REQUIRE_NOTHROW(mc::io::read_vtp(f));  // whole, it reads
  const auto size = fs::file_size(f);
  fs::resize_file(f, size / 2);
  REQUIRE_THROWS_AS(mc::io::read_vtp(f), std::runtime_error);
  const std::string msg = message_of([&] { mc::io::read_vtp(f); });
  CHECK(msg.find(f.string()) != std::string::npos);
  CHECK(msg.find("truncated") != std::string::npos);

  // Cut just one byte short of the end of the data.
  mc::io::write_vtp(f, random_snapshot(300, 7));
  const std::string whole = slurp(f);
  const std::size_t end_of_data = whole.rfind("\n</AppendedData>");
  REQUIRE(end_of_data != std::string::npos);
  fs::resize_file(f, end_of_data - 1);
  REQUIRE_THROWS_AS(mc::io::read_vtp(f), std::runtime_error);

  // All the data there, but the closing tags cut off.
  spit(f, whole);
  REQUIRE_NOTHROW(mc::io::read_vtp(f));
  fs::resize_file(f, end_of_data + 3);
  REQUIRE_THROWS_AS(mc::io::read_vtp(f), std::runtime_error);
}

TEST_CASE("vtp: files that are not ours are refused", "[vtk]") {
  TempDir tmp;

  const fs::path missing = tmp.path / "nope.vtp";
  REQUIRE_THROWS_AS(mc::io::read_vtp(missing), std::runtime_error);
  CHECK(message_of([&] { mc::io::read_vtp(missing); }).find(missing.string()) != std::string::npos);

  const fs::path text = tmp.path / "notes.vtp";
  spit(text, "these are not the balls you are looking for\n");
  REQUIRE_THROWS_AS(mc::io::read_vtp(text), std::runtime_error);
  CHECK(message_of([&] { mc::io::read_vtp(text); }).find(text.string()) != std::string::npos);

  const fs::path empty = tmp.path / "empty.vtp";
  spit(empty, "");
  REQUIRE_THROWS_AS(mc::io::read_vtp(empty), std::runtime_error);

  // A VTK file, but a collection, not poly data.
  const fs::path pvd = tmp.path / "charge.pvd";
  mc::io::PvdIndex index(pvd);
  index.add(0.0, "a.vtp");
  REQUIRE_THROWS_AS(mc::io::read_vtp(pvd), std::runtime_error);

  // Our own file with an array renamed, or of another type.
  const fs::path good = tmp.path / "good.vtp";
  mc::io::write_vtp(good, random_snapshot(20, 3));
  REQUIRE_NOTHROW(mc::io::read_vtp(good));
  const std::string file = slurp(good);

  auto edited = [&](const std::string& from, const std::string& to) {
    std::string s = file;
    const std::size_t at = s.find(from);
    REQUIRE(at != std::string::npos);
    s.replace(at, from.size(), to);
    const fs::path p = tmp.path / "edited.vtp";
    spit(p, s);
    return p;
  };
  {
    const fs::path p = edited("Name=\"id\"", "Name=\"ix\"");
    REQUIRE_THROWS_AS(mc::io::read_vtp(p), std::runtime_error);
    CHECK(message_of([&] { mc::io::read_vtp(p); }).find("id") != std::string::npos);
  }
  {
    const fs::path p = edited("type=\"Int32\" Name=\"material\"", "type=\"Float32\" Name=\"material\"");
    REQUIRE_THROWS_AS(mc::io::read_vtp(p), std::runtime_error);
    CHECK(message_of([&] { mc::io::read_vtp(p); }).find("material") != std::string::npos);
  }
  {
    const fs::path p = edited("Name=\"TimeValue\"", "Name=\"TimeValve\"");
    REQUIRE_THROWS_AS(mc::io::read_vtp(p), std::runtime_error);
  }
  {
    const fs::path p = edited("type=\"PolyData\"", "type=\"ImageData\"");
    REQUIRE_THROWS_AS(mc::io::read_vtp(p), std::runtime_error);
  }
}

TEST_CASE("pvd index lists every snapshot in order", "[vtk]") {
  TempDir tmp;
  const fs::path pvd = tmp.path / "charge.pvd";
  mc::io::PvdIndex index(pvd);
  CHECK(index.path() == pvd);

  auto dataset_lines = [&] {
    std::vector<std::string> lines;
    std::istringstream in(slurp(pvd));
    for (std::string line; std::getline(in, line);) {
      const auto at = line.find("<DataSet");
      if (at != std::string::npos) lines.push_back(line.substr(at));
    }
    return lines;
  };

  index.add(0.0, "snapshots/charge_000001.vtp");
  CHECK(dataset_lines().size() == 1);
  index.add(1.0 / 3.0, "snapshots/charge_000002.vtp");
  CHECK(dataset_lines().size() == 2);
  index.add(2.5e-3, "snapshots/charge_000003.vtp");

  const std::string text = slurp(pvd);
  CHECK(text.find("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">") != std::string::npos);
  CHECK(text.find("<Collection>") != std::string::npos);
  CHECK(text.find("</Collection>") != std::string::npos);

  const auto lines = dataset_lines();
  REQUIRE(lines.size() == 3);
  CHECK(lines[0] == "<DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"snapshots/charge_000001.vtp\"/>");
  CHECK(lines[1] ==
        "<DataSet timestep=\"0.333333333\" group=\"\" part=\"0\" file=\"snapshots/charge_000002.vtp\"/>");
  CHECK(lines[2] == "<DataSet timestep=\"0.0025\" group=\"\" part=\"0\" file=\"snapshots/charge_000003.vtp\"/>");

  // No temporary files left beside it.
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(tmp.path)) {
    (void)e;
    ++files;
  }
  CHECK(files == 1);
}

TEST_CASE("vtp: vectors of different lengths are refused", "[vtk]") {
  TempDir tmp;
  const fs::path f = tmp.path / "bad.vtp";
  const Snapshot good = random_snapshot(10, 1);
  REQUIRE_NOTHROW(mc::io::write_vtp(tmp.path / "good.vtp", good));

  Snapshot s = good;
  s.velocity.pop_back();
  CHECK_THROWS_AS(mc::io::write_vtp(f, s), std::invalid_argument);
  s = good;
  s.radius.push_back(0.01f);
  CHECK_THROWS_AS(mc::io::write_vtp(f, s), std::invalid_argument);
  s = good;
  s.material.pop_back();
  CHECK_THROWS_AS(mc::io::write_vtp(f, s), std::invalid_argument);
  s = good;
  s.id.clear();
  CHECK_THROWS_AS(mc::io::write_vtp(f, s), std::invalid_argument);
  s = good;
  s.position.pop_back();
  CHECK_THROWS_AS(mc::io::write_vtp(f, s), std::invalid_argument);
  CHECK_FALSE(fs::exists(f));
}
