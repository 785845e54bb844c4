// Case files: the shipped cases read and derive what VERIFICATION.md says;
// --set reaches every kind of key; every bad case in tests/data/bad_cases is
// refused by the command line with its message, exit status 2 and no run
// folder.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <unistd.h>
#include <sys/wait.h>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/mill_case.h"
#include "io/case_file.h"

#include "text_file.h"

namespace fs = std::filesystem;
using mc::io::CaseError;

namespace {

std::string error_of(const std::string& text, const std::vector<std::string>& sets = {}) {
  try {
    mc::io::parse_case(text, "case.toml", sets);
  } catch (const CaseError& e) {
    return e.what();
  }
  return "";
}

fs::path temp_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("millcharge_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

}  // namespace

TEST_CASE("the lab mill reads and derives the values of VERIFICATION.md", "[case]") {
  const mc::MillCase c = mc::io::read_case(mc::io::default_case());
  const mc::MillDerived d = mc::derive(c);
  // Nc = 42.3/sqrt(D − d): 45.23 rpm for D = 0.9 m, d = 25.4 mm.
  CHECK(d.critical_rpm == Approx(42.3 / std::sqrt(0.9 - 0.0254)).epsilon(1e-12));
  CHECK(d.critical_rpm == Approx(45.23).margin(0.005));
  CHECK(d.speed_rpm == Approx(0.75 * d.critical_rpm).epsilon(1e-12));
  CHECK(d.omega == Approx(d.speed_rpm * 2 * M_PI / 60).epsilon(1e-12));
  // The ball count reproduces the filling: J (1 − porosity) V = N · π/6 E[d³],
  // diameters uniform on [20, 25.4] mm.
  const double a = 0.020, b = 0.0254;
  const double mean_ball = M_PI / 6 * (std::pow(b, 4) - std::pow(a, 4)) / (4 * (b - a));
  CHECK(d.n_balls == std::lround(0.30 * 0.6 * d.mill_volume / mean_ball));
  CHECK(d.filling_from_counts == Approx(0.30).epsilon(1e-3));
  CHECK(d.n_balls > 1000);
  CHECK(d.n_balls < 5000);
  // Linear law: tc = π sqrt(m*/kn) for the smallest pair; dt = tc / 20.
  const double m = 7800 * M_PI / 6 * std::pow(a, 3);
  CHECK(d.contact_time == Approx(M_PI * std::sqrt(0.5 * m / 1.0e6)).epsilon(1e-9));
  CHECK(d.dt == Approx(d.contact_time / 20).epsilon(1e-12));
  CHECK(d.dt_auto);
}

TEST_CASE("the seed mills A-D have their particle counts within 10 %", "[case]") {
  struct Seed {
    const char* file;
    double rpm, filling;
    long n;
  };
  for (const Seed& s : {Seed{"mill_a.toml", 11.0, 0.41, 212704}, Seed{"mill_b.toml", 10.0, 0.175, 91357},
                        Seed{"mill_c.toml", 11.0, 0.237, 244565}, Seed{"mill_d.toml", 12.2, 0.38, 1259414}}) {
    INFO(s.file);
    const mc::MillCase c = mc::io::read_case(mc::io::case_dir() / s.file);
    const mc::MillDerived d = mc::derive(c);
    CHECK(d.speed_rpm == Approx(s.rpm));
    CHECK(c.filling == Approx(s.filling));
    CHECK(std::abs(d.n_balls - s.n) < 0.10 * s.n);
    CHECK(d.dt == Approx(2e-5));
    CHECK(d.contact_time / d.dt > 15);
  }
}

TEST_CASE("overrides with --set reach values, array entries and strings", "[case]") {
  const std::string lab = read_text(mc::io::default_case());
  const mc::MillCase c = mc::io::parse_case(lab, "lab.toml",
                                            {"mill.speed_fraction=0.6", "charge.size.0.diameter_max=0.03",
                                             "lifters.profile[0].height=0.03", "contact.law=hertz",
                                             "run.precision=double", "run.dt=5e-6", "run.settle=0.2"});
  CHECK(c.speed_fraction == Approx(0.6));
  CHECK(c.sizes[0].diameter_min == Approx(0.02));
  CHECK(c.sizes[0].diameter_max == Approx(0.03));
  CHECK(c.lifter_pattern[0].height == Approx(0.03));
  CHECK(c.law == mc::ContactLaw::hertz);
  CHECK(c.precision == mc::Precision::double_);
  CHECK(c.dt == Approx(5e-6));
  CHECK(c.settle == Approx(0.2));
  // An override names itself in the message.
  CHECK_THAT(error_of(lab, {"mill.length=-1"}), Catch::Contains("--set mill.length=-1: mill.length: must be > 0"));
  CHECK_THAT(error_of(lab, {"charge.size.4.fraction=1"}), Catch::Contains("charge.size has 1 entries"));
  CHECK_THAT(error_of(lab, {"nonsense"}), Catch::Contains("expected KEY=VALUE"));
  CHECK_THAT(error_of(lab, {"mill.diameter.x=1"}), Catch::Contains("is a value, not a table"));
}

TEST_CASE("a case written back reads as the same case", "[case]") {
  for (const char* f : {"lab.toml", "mill_b.toml"}) {
    INFO(f);
    const mc::MillCase a = mc::io::read_case(mc::io::case_dir() / f);
    const mc::MillCase b = mc::io::parse_case(mc::io::case_to_toml(a), f);
    CHECK(b.diameter == a.diameter);
    CHECK(b.speed_fraction == a.speed_fraction);
    CHECK(b.speed_rpm == a.speed_rpm);
    CHECK(b.lifter_rows == a.lifter_rows);
    REQUIRE(b.lifter_pattern.size() == a.lifter_pattern.size());
    CHECK(b.lifter_pattern.back().face_angle_deg == a.lifter_pattern.back().face_angle_deg);
    REQUIRE(b.sizes.size() == a.sizes.size());
    CHECK(b.sizes.back().diameter_max == a.sizes.back().diameter_max);
    CHECK(b.sizes.back().fraction == a.sizes.back().fraction);
    CHECK(b.materials.size() == a.materials.size());
    CHECK(b.pairs.size() == a.pairs.size());
    CHECK(b.contact.kn == a.contact.kn);
    CHECK(b.dt == a.dt);
    CHECK(b.settle == a.settle);
    CHECK(mc::derive(b).n_balls == mc::derive(a).n_balls);
  }
}

TEST_CASE("every bad case is refused with its message, status 2 and no run folder", "[case][cli]") {
  const fs::path corpus = fs::path(MC_TEST_DATA) / "bad_cases";
  const fs::path work = temp_dir("bad_cases");
  fs::create_directories(work);
  int n = 0;
  for (const auto& entry : fs::directory_iterator(corpus)) {
    const fs::path file = entry.path();
    const std::string text = read_text(file);
    REQUIRE(text.rfind("# expect: ", 0) == 0);
    const std::string expect = text.substr(10, text.find('\n') - 10);
    const fs::path out = work / ("run_" + file.stem().string());
    const fs::path err = work / (file.stem().string() + ".err");
    const std::string cmd = std::string(MC_BINARY) + " run '" + file.string() + "' --out '" + out.string() +
                            "' --quiet > /dev/null 2> '" + err.string() + "'";
    const int status = std::system(cmd.c_str());
    const std::string message = read_text(err);
    INFO(file.filename().string() << ": " << message);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 2);
    CHECK_THAT(message, Catch::Contains(expect));
    CHECK_THAT(message, Catch::StartsWith("millcharge: "));
    CHECK(std::count(message.begin(), message.end(), '\n') == 1);  // one message
    CHECK_FALSE(fs::exists(out));
    ++n;
  }
  CHECK(n >= 25);
  fs::remove_all(work);
}

TEST_CASE("an empty or blank case file is refused as empty, status 2", "[case][cli]") {
  const fs::path work = temp_dir("empty_cases");
  fs::create_directories(work);
  for (const char* text : {"", "\n\n  \t\n", "# only a comment\n"}) {
    const fs::path file = work / "blank.toml";
    std::ofstream(file, std::ios::binary) << text;
    const fs::path err = work / "err.txt";
    const std::string cmd = std::string(MC_BINARY) + " check '" + file.string() + "' > /dev/null 2> '" +
                            err.string() + "'";
    const int status = std::system(cmd.c_str());
    const std::string message = read_text(err);
    INFO("text: '" << text << "' message: " << message);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 2);
    CHECK_THAT(message, Catch::Contains("blank.toml: empty: a case needs the tables"));
  }
  fs::remove_all(work);
}

TEST_CASE("non-ASCII text outside strings and comments is refused before toml++ sees it", "[case]") {
  const std::string lab = read_text(mc::io::default_case());
  auto with = [&](const std::string& from, const std::string& to) {
    std::string t = lab;
    const std::size_t at = t.find(from);
    REQUIRE(at != std::string::npos);
    return t.replace(at, from.size(), to);
  };
  // The fuzzer's finding: "2.ƚ11" reached undefined behaviour in toml++ 3.3.
  CHECK_THAT(error_of(with("youngs_modulus = 2.0e11 # Pa", "youngs_modulus = 2.\xc6\x9a" "11")),
             Catch::Contains("case.toml:64:20: not valid TOML: character U+019A outside a string or comment"));
  CHECK_THAT(error_of(with("diameter = 0.9 ", "diameter = 0.9\xc2\xb5 ")),
             Catch::Contains("case.toml:19:15: not valid TOML: character U+00B5 outside a string or comment"));
  CHECK_THAT(error_of(with("diameter = 0.9 ", "diameter = 0.9\xa5 ")),
             Catch::Contains("not valid TOML: byte 0xA5 (not UTF-8) outside a string or comment"));
  // The second finding: a quote where no string may start ("8n'Ǎ") opens none.
  CHECK_THAT(error_of("title = 8n'\xc7\x8d" "8889tfraction\n"),
             Catch::Contains("case.toml:1:12: not valid TOML: character U+01CD outside a string or comment"));
  // A UTF-8 byte order mark at the start is allowed.
  CHECK(mc::io::parse_case("\xEF\xBB\xBF" + lab, "case.toml").diameter == 0.9);
  // After a backslash in a string (never valid TOML) too.
  CHECK_THAT(error_of(with("title = \"Laboratory", "title = \"\\\xc2\xb5 Laboratory")),
             Catch::Contains("case.toml:16:11: not valid TOML: character U+00B5 after a backslash"));
  CHECK_THAT(error_of(with("title = \"Laboratory ball mill, 0.9 m x 0.15 m, 20-25.4 mm balls\"",
                           "title = \"\"\"a \\  \xc2\xb5\n\"\"\"")),
             Catch::Contains("case.toml:16:17: not valid TOML: character U+00B5 after a backslash"));
  // In strings and comments it is text, as TOML says.
  const mc::MillCase c = mc::io::parse_case(
      with("title = \"Laboratory", "# \xc2\xb5m \xce\xbc \xe3\x80\x80\ntitle = \"\"\"\xc2\xb5 \\\"\xc6\x9a\"\"\"\"  # \xc6\x9a\n#"),
      "case.toml");
  CHECK(c.title == "\xc2\xb5 \"\xc6\x9a\"");
  CHECK(mc::io::parse_case(with("title = \"Laboratory", "title = '''\xc2\xb5''' # \n#"), "case.toml").title == "\xc2\xb5");
  // A --set value with such a character is a string, as any value that is not TOML.
  CHECK_THAT(error_of(lab, {"mill.diameter=0.9\xc2\xb5"}),
             Catch::Contains("mill.diameter: expected a number, got a string"));
}

TEST_CASE("absurd sizes are refused by derive() with the key, before anything is allocated", "[case]") {
  const std::string lab = read_text(mc::io::default_case());
  // 2^32 lifter rows is not 0 rows.
  CHECK_THAT(error_of(lab, {"lifters.rows=4294967296"}), Catch::Contains("lifters.rows: must be in [0, 400]"));
  // A mill of 1.09e12 balls: the count is refused, not rounded into a long.
  CHECK_THAT(error_of(lab, {"mill.diameter=400", "mill.length=300"}),
             Catch::Contains("charge: the case needs 1.09251e+12 balls"));
  CHECK_THAT(error_of(lab, {"mill.diameter=1e300"}), Catch::Contains("mill.diameter: must be at most 1000 m (got 1e+300)"));
  CHECK_THAT(error_of(lab, {"mill.length=1001"}), Catch::Contains("mill.length: must be at most 1000 m (got 1001)"));
  CHECK_THAT(error_of(lab, {"mill.diameter=1000", "mill.length=1000", "charge.size.0.diameter_min=2.5e-8",
                            "charge.size.0.diameter_max=2.5e-8"}),
             Catch::Contains("more than the 50 million supported"));
  // Few balls in a huge mill: the packing's columns would be absurd.
  CHECK_THAT(error_of(lab, {"mill.diameter=400", "mill.length=300", "charge.filling=1e-9"}),
             Catch::Contains("charge.size: the mill (400 m x 300 m) is too large for its smallest balls (0.02 m): "
                             "placing them needs 2.88321e+08 columns"));
  // Just inside the limits the same case derives (1 ball per class at least).
  const mc::MillCase ok = mc::io::parse_case(lab, "lab.toml", {"mill.diameter=20", "mill.length=3", "charge.filling=1e-9"});
  CHECK(mc::derive(ok).n_balls == 1);
  // A contact so stiff that the run would be 3e152 steps.
  CHECK_THAT(error_of(lab, {"contact.stiffness=1e300"}), Catch::Contains("steps, more than 1e11"));
  CHECK_THAT(error_of(lab, {"run.snapshot_interval=1e-5"}), Catch::Contains("600000 snapshots, more than 100000"));
  CHECK_THAT(error_of(lab, {"run.duration=inf"}), Catch::Contains("run.duration: must be a finite number"));
  CHECK_THAT(error_of(lab, {"mill.diameter=nan"}), Catch::Contains("mill.diameter: must be a finite number"));
}
