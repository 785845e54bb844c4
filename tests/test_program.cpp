// The kernel build's options and log: the compiler-cache key holds the
// headers (a hash of cl/ in the options), and MILLCHARGE_BUILD_LOG keeps a
// good build's log.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "compute/program.h"
#include "helpers.h"

namespace fs = std::filesystem;
using namespace mc;

namespace {

// The MC_SOURCE_HASH of a build of scan.cl from `dir`, read back from the
// build log that MILLCHARGE_BUILD_LOG asks for.
std::string built_hash(const fs::path& dir, const fs::path& log) {
  fs::remove(log);
  ::setenv("MILLCHARGE_KERNEL_DIR", dir.c_str(), 1);
  ::setenv("MILLCHARGE_BUILD_LOG", log.c_str(), 1);
  compute::BuildOptions opts;
  opts.define("MC_SCAN_WG", 64);
  compute::Program program(test::context(), {"scan.cl"}, opts, false);
  ::unsetenv("MILLCHARGE_KERNEL_DIR");
  ::unsetenv("MILLCHARGE_BUILD_LOG");
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  std::smatch m;
  const std::string s = text.str();
  INFO("build log: " << s);
  REQUIRE(s.find("== options:") != std::string::npos);
  REQUIRE(std::regex_search(s, m, std::regex("-DMC_SOURCE_HASH=0x([0-9a-f]{16})")));
  return m[1];
}

}  // namespace

TEST_CASE("the kernels' build options hold a hash of every file in cl/, so an edited header is a new build",
          "[device]") {
  const fs::path tmp = fs::temp_directory_path() / ("mc-program-" + std::to_string(::getpid()));
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  fs::copy(compute::kernel_dir(), tmp / "cl", fs::copy_options::recursive);
  const fs::path log = tmp / "build.log";
  const std::string first = built_hash(tmp / "cl", log);
  CHECK(built_hash(tmp / "cl", log) == first);  // the same files, the same key
  {
    // A comment added to a header that scan.cl includes: its source string is
    // the same, its build is not.
    std::ofstream shim(tmp / "cl" / "mc_shim.h", std::ios::app);
    shim << "/* edited */\n";
  }
  const std::string edited = built_hash(tmp / "cl", log);
  CHECK(edited != first);
  fs::remove_all(tmp);
}
