// libFuzzer target for the case reader: bytes in, through the entry point the
// command line uses (io::parse_case, which applies --set overrides and calls
// derive()), then the placement of the charge (build_scene) for small
// charges, then the case written back must read again.
//
// Lines of the input that start with "#set " are also given as --set
// overrides (at most 4), so the fuzzer reaches apply_override() too; to TOML
// they are comments.
//
// The documented failures are fine: std::invalid_argument (io::CaseError is
// one), which the CLI prints with exit status 2. Anything else is a bug: a
// crash, a sanitizer report, another exception, a hang, a giant allocation.
// Build and run with scripts/fuzz.sh.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/mill_case.h"
#include "io/case_file.h"

namespace {

std::vector<std::string> set_lines(std::string_view text) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (at < text.size() && out.size() < 4) {
    std::size_t end = text.find('\n', at);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(at, end - at);
    if (line.substr(0, 5) == "#set ") out.emplace_back(line.substr(5));
    at = end + 1;
  }
  return out;
}

[[noreturn]] void bug(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_case_file: BUG: %s: %s\n", what, detail.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > (1u << 20)) return 0;  // read_case refuses files over 1 MiB
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  mc::MillCase c;
  mc::MillDerived d;
  try {
    c = mc::io::parse_case(text, "fuzz.toml", set_lines(text));
    d = mc::derive(c);
  } catch (const std::invalid_argument&) {
    return 0;  // a bad case, refused with a message: fine
  } catch (const std::exception& e) {
    bug("unexpected exception from parse_case/derive", e.what());
  }
  // A valid case: the charge is placed (as `millcharge check` and `run` do)
  // when it is small enough to place quickly.
  double dmin = 1e300;
  for (const mc::SizeClass& k : c.sizes) dmin = std::min(dmin, k.diameter_min);
  const double across = c.diameter / dmin, along = c.length / dmin;
  const double cells = (c.diameter / d.largest_ball_diameter) * (c.diameter / d.largest_ball_diameter) *
                       (c.length / d.largest_ball_diameter);
  if (d.n_balls <= 3000 && across * along < 1e6 && cells < 1e7) {
    try {
      const mc::Scene s = mc::build_scene(c, d);
      if (s.balls.size() != static_cast<std::size_t>(d.n_balls)) bug("build_scene", "wrong ball count");
    } catch (const std::invalid_argument&) {
      // "only N of M balls fit": fine
    } catch (const std::exception& e) {
      bug("unexpected exception from build_scene", e.what());
    }
  }
  // What a run folder keeps (case.toml) must read back as the same case.
  try {
    const mc::MillCase back = mc::io::parse_case(mc::io::case_to_toml(c), "case.toml");
    if (mc::derive(back).n_balls != d.n_balls) bug("case_to_toml round trip", "a different ball count");
  } catch (const std::exception& e) {
    bug("case_to_toml round trip refused", e.what());
  }
  return 0;
}
