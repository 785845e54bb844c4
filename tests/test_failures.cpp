// Device failures say what failed and how to fix it, in one line (or a short
// block for a build log), with exit status 1 and no run folder: no OpenCL
// platform, a kernel that does not compile, a device out of memory, a
// --device that matches nothing (and the short names that do match).
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "compute/buffer.h"
#include "compute/context.h"
#include "compute/program.h"
#include "helpers.h"

#include "text_file.h"

namespace fs = std::filesystem;
using mc::compute::Error;

namespace {

fs::path temp_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("millcharge_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

struct Outcome {
  int status = -1;
  std::string err;
};

// The binary with `env` (VAR=value ...) before it; stderr kept.
Outcome run_binary(const std::string& env, const std::string& args, const fs::path& work) {
  const fs::path err = work / "stderr.txt";
  const std::string cmd =
      env + " " + MC_BINARY + " " + args + " > /dev/null 2> '" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  Outcome o;
  o.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  o.err = read_text(err);
  return o;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Sets an environment variable for one scope.
struct ScopedEnv {
  std::string name;
  ScopedEnv(const std::string& n, const std::string& v) : name(n) { ::setenv(n.c_str(), v.c_str(), 1); }
  ~ScopedEnv() { ::unsetenv(name.c_str()); }
};

}  // namespace

TEST_CASE("no OpenCL platform: the message says so and how to fix it, status 1, no run folder", "[device][cli]") {
  // ocl-icd reads the drivers from OCL_ICD_VENDORS: an empty folder has none.
  const fs::path work = temp_dir("no_platform");
  fs::create_directories(work / "vendors");
  const std::string env = "OCL_ICD_VENDORS='" + (work / "vendors").string() + "'";
  const fs::path out = work / "run";
  for (const std::string& args : {"run --quiet --out '" + out.string() + "'", std::string("devices")}) {
    INFO(args);
    const Outcome o = run_binary(env, args, work);
    INFO(o.err);
    CHECK(o.status == 1);
    CHECK_THAT(o.err, Catch::StartsWith("millcharge: OpenCL: no OpenCL platform found: install an OpenCL driver"));
    CHECK_THAT(o.err, Catch::Contains("apt-get install pocl-opencl-icd"));
    CHECK_THAT(o.err, Catch::Contains("check that `millcharge devices` or `clinfo -l` lists a device"));
    CHECK_THAT(o.err, Catch::Contains("OCL_ICD_VENDORS is set to '" + (work / "vendors").string() + "'"));
    CHECK(std::count(o.err.begin(), o.err.end(), '\n') == 1);
  }
  CHECK_FALSE(fs::exists(out));
  fs::remove_all(work);
}

TEST_CASE("a kernel that does not compile: its file, the first errors and the fix", "[device]") {
  const fs::path dir = temp_dir("broken_kernel");
  std::ofstream(dir / "broken.cl") << "// a kernel with two mistakes\n"
                                      "__kernel void broken(__global float* x) {\n"
                                      "  x[0] = undeclared_thing;\n"
                                      "  x[1] = 3 +;\n"
                                      "}\n";
  ScopedEnv env("MILLCHARGE_KERNEL_DIR", dir.string());
  mc::compute::Context& ctx = mc::test::context();
  const std::string m =
      error_of([&] { mc::compute::Program p(ctx, {"broken.cl"}, mc::compute::BuildOptions(), false); });
  INFO(m);
  CHECK_THAT(m, Catch::StartsWith("kernel build failed: broken.cl (in " + dir.string() + ") did not compile on " +
                                  ctx.info().label() + "; first errors:\n"));
  CHECK_THAT(m, Catch::Contains("broken.cl:3:"));
  CHECK_THAT(m, Catch::Contains("undeclared_thing"));
  CHECK_THAT(m, Catch::Contains("broken.cl:4:"));
  CHECK_THAT(m, Catch::Contains("\nfix: if you edited the kernels, correct the lines above; otherwise make sure " +
                                dir.string() + " holds this build's cl/ folder"));
  CHECK(std::count(m.begin(), m.end(), '\n') <= 10);  // a short block, not the whole log
  // A missing file says where it looked and how to point elsewhere.
  CHECK_THAT(error_of([&] { mc::compute::Program p(ctx, {"absent.cl"}, mc::compute::BuildOptions(), false); }),
             Catch::Contains("cannot read kernel file " + (dir / "absent.cl").string() +
                             " (set MILLCHARGE_KERNEL_DIR to the folder holding the .cl files)"));
  fs::remove_all(dir);
}

TEST_CASE("a build log's error lines are picked out, at most 8 of them", "[device]") {
  std::string log;
  for (int k = 1; k <= 20; ++k) log += "forces.cl:" + std::to_string(k) + ":1: error: mistake " + std::to_string(k) + "\n  context line\n";
  const std::string m = mc::compute::build_failure_message("0:0 dev", "/k", {"motion.cl", "forces.cl"}, log);
  CHECK_THAT(m, Catch::StartsWith("kernel build failed: forces.cl (in /k) did not compile on 0:0 dev; first errors:\n"
                                  "  forces.cl:1:1: error: mistake 1\n  forces.cl:2:1: error: mistake 2\n"));
  CHECK_THAT(m, Catch::Contains("  forces.cl:8:1: error: mistake 8\n  ... and 12 more\nfix: "));
  CHECK_THAT(m, !Catch::Contains("mistake 9\n"));
  CHECK_THAT(m, !Catch::Contains("context line"));
  // A log without "error:" lines is shown as it is; no log is said so.
  CHECK_THAT(mc::compute::build_failure_message("d", "/k", {"a.cl"}, "something odd\n"),
             Catch::Contains("a.cl (in /k) did not compile on d; build log:\n  something odd\nfix: "));
  CHECK_THAT(mc::compute::build_failure_message("d", "/k", {"a.cl", "b.cl"}, ""),
             Catch::Contains("a.cl, b.cl (in /k) did not compile on d (the driver gave no build log)\nfix: "));
}

TEST_CASE("a broken kernel folder stops the run with status 1 and no run folder", "[device][cli]") {
  const fs::path work = temp_dir("broken_kernels_cli");
  const fs::path kernels = work / "cl";
  fs::create_directories(kernels);
  for (const auto& e : fs::directory_iterator(fs::path(MC_KERNEL_DIR))) fs::copy_file(e.path(), kernels / e.path().filename());
  {
    std::ofstream f(kernels / "motion.cl", std::ios::app);
    f << "\n__kernel void broken_on_purpose(__global float* x) { x[0] = not_declared; }\n";
  }
  const fs::path out = work / "run";
  const Outcome o = run_binary("MILLCHARGE_KERNEL_DIR='" + kernels.string() + "'",
                               "run --quiet --duration 0.01 --set run.warmup=0 --out '" + out.string() + "'", work);
  INFO(o.err);
  CHECK(o.status == 1);
  // Only the message: the driver's own stderr output (PoCL: "1 error generated.") is held back.
  CHECK_THAT(o.err, Catch::StartsWith("millcharge: OpenCL: kernel build failed: motion.cl (in " + kernels.string() + ")"));
  CHECK_THAT(o.err, Catch::Contains("not_declared"));
  CHECK_THAT(o.err, Catch::Contains("\nfix: "));
  CHECK_FALSE(fs::exists(out));
  fs::remove_all(work);
}

TEST_CASE("a buffer larger than the device allows is refused before any allocation", "[device]") {
  mc::compute::Context& ctx = mc::test::context();
  const std::size_t before = ctx.allocated_bytes();
  const std::size_t too_big = ctx.max_alloc_bytes() + 1;
  const std::string m = error_of([&] { mc::compute::Buffer<char> b(ctx, too_big, "huge"); });
  INFO(m);
  CHECK_THAT(m, Catch::StartsWith("device out of memory: buffer 'huge' needs " + mc::compute::bytes_text(too_big) +
                                  " in one piece, but " + ctx.info().label() + " allows at most " +
                                  mc::compute::bytes_text(ctx.max_alloc_bytes()) +
                                  " per buffer (CL_DEVICE_MAX_MEM_ALLOC_SIZE); fix: fewer balls"));
  CHECK_THAT(m, Catch::EndsWith("another --device with more memory (see `millcharge devices`), or --precision "
                                "float instead of double"));
  CHECK(ctx.allocated_bytes() == before);
  CHECK(mc::compute::bytes_text(1610612736) == "1.50 GiB (1610612736 bytes)");
  CHECK(mc::compute::bytes_text(1000) == "1000 bytes");
}

TEST_CASE("buffers are counted against the device memory and given back", "[device]") {
  ScopedEnv env("MILLCHARGE_DEVICE_MEMORY", "1M");  // this context's device has 1 MiB
  mc::compute::Context ctx;
  CHECK(ctx.memory_bytes() == 1048576);
  CHECK(ctx.max_alloc_bytes() <= 1048576);
  std::string m;
  {
    mc::compute::Buffer<float> a(ctx, 150000, "first");  // 600,000 bytes
    CHECK(ctx.allocated_bytes() == 600000);
    mc::compute::Buffer<float> copy = a;  // shares the device memory
    CHECK(ctx.allocated_bytes() == 600000);
    m = error_of([&] { mc::compute::Buffer<float> b(ctx, 150000, "second"); });
    CHECK(ctx.allocated_bytes() == 600000);
    a.resize(1000);  // the old 600,000 bytes go back (the copy keeps its own)
    CHECK(ctx.allocated_bytes() == 604000);
  }
  CHECK(ctx.allocated_bytes() == 0);
  INFO(m);
  CHECK(m == "device out of memory: the run needs at least 1.1 MiB (1200000 bytes) but " + ctx.info().label() +
                 " has 1.0 MiB (1048576 bytes) (set by MILLCHARGE_DEVICE_MEMORY); buffer 'second' of 585.9 KiB "
                 "(600000 bytes) did not fit on top of 585.9 KiB (600000 bytes) already allocated; " +
                 mc::compute::kOutOfMemoryFix);
  // Now it fits.
  mc::compute::Buffer<float> b(ctx, 150000, "second");
  CHECK(ctx.allocated_bytes() == 600000);
  // The driver's out-of-memory codes get the same fix; other codes their name.
  const std::string oom = ctx.error("writing buffer 'positions'", CL_MEM_OBJECT_ALLOCATION_FAILURE).what();
  CHECK(oom == "device out of memory (CL_MEM_OBJECT_ALLOCATION_FAILURE) writing buffer 'positions': the run's "
               "buffers take 585.9 KiB (600000 bytes) of the 1.0 MiB (1048576 bytes) that " +
                   ctx.info().label() + " has; " + mc::compute::kOutOfMemoryFix);
  CHECK_THAT(ctx.error("launch", CL_OUT_OF_RESOURCES).what(), Catch::StartsWith("device out of memory (CL_OUT_OF_RESOURCES) launch"));
  CHECK_THAT(ctx.error("launch", CL_OUT_OF_HOST_MEMORY).what(), Catch::StartsWith("device out of memory (CL_OUT_OF_HOST_MEMORY) launch"));
  CHECK(std::string(ctx.error("launch", CL_INVALID_VALUE).what()) == "launch: CL_INVALID_VALUE");
}

TEST_CASE("a run that does not fit the device stops with the bytes and the fix, status 1, no run folder",
          "[device][cli]") {
  const fs::path work = temp_dir("oom_cli");
  const fs::path out = work / "run";
  const Outcome o = run_binary("MILLCHARGE_DEVICE_MEMORY=512K",
                               "run --quiet --duration 0.01 --set run.warmup=0 --out '" + out.string() + "'", work);
  INFO(o.err);
  CHECK(o.status == 1);
  CHECK_THAT(o.err, Catch::StartsWith("millcharge: OpenCL: device out of memory: the run needs at least "));
  CHECK_THAT(o.err, Catch::Contains(" has 512.0 KiB (524288 bytes) (set by MILLCHARGE_DEVICE_MEMORY); buffer '"));
  CHECK_THAT(o.err, Catch::Contains("; fix: fewer balls"));
  CHECK(std::count(o.err.begin(), o.err.end(), '\n') == 1);
  CHECK_FALSE(fs::exists(out));
  // A malformed limit is named.
  const Outcome bad = run_binary("MILLCHARGE_DEVICE_MEMORY=lots", "run --quiet --out '" + out.string() + "'", work);
  CHECK(bad.status == 1);
  CHECK_THAT(bad.err, Catch::Contains("MILLCHARGE_DEVICE_MEMORY='lots': expected bytes, e.g. 512M or 2G"));
  CHECK_FALSE(fs::exists(out));
  fs::remove_all(work);
}

TEST_CASE("device choice: short names find the implementation, case-insensitively", "[device]") {
  const std::vector<mc::compute::DeviceInfo> all = mc::compute::list_devices();
  const auto pocl = std::find_if(all.begin(), all.end(), [](const mc::compute::DeviceInfo& d) {
    return d.platform_name == "Portable Computing Language";
  });
  if (pocl == all.end()) {
    WARN("no PoCL device here (scripts/setup.sh installs pocl-opencl-icd): `pocl` not checked");
    return;
  }
  // PoCL's platform is "Portable Computing Language", its vendor "The pocl
  // project": `pocl` finds it by either, whatever the case.
  for (const char* spec : {"pocl", "PoCL", "POCL"}) {
    INFO(spec);
    const mc::compute::DeviceInfo d = mc::compute::choose_device(spec);
    CHECK(d.platform_name == "Portable Computing Language");
    CHECK(d.label() == pocl->label());
  }
  CHECK(pocl->platform_vendor.find("pocl") != std::string::npos);
  CHECK_FALSE(pocl->vendor.empty());
  // Part of a name as before, and the indices.
  CHECK(mc::compute::choose_device("portable").label() == pocl->label());
  CHECK(mc::compute::choose_device(std::to_string(pocl->platform_index) + ":" + std::to_string(pocl->device_index))
            .label() == pocl->label());
  // Every short name either finds a device whose platform or device names
  // it, or fails with the list.
  for (const std::string& n : mc::compute::device_short_names()) {
    INFO(n);
    try {
      const mc::compute::DeviceInfo d = mc::compute::choose_device(n);
      std::string text = d.platform_name + " " + d.platform_vendor + " " + d.name + " " + d.vendor;
      std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
      const bool named = n == "pocl"   ? text.find("portable computing language") != std::string::npos
                         : n == "cuda" ? text.find("nvidia") != std::string::npos
                         : n == "mesa" ? text.find("mesa") != std::string::npos
                         : n == "amd"  ? text.find("amd") != std::string::npos ||
                                            text.find("advanced micro devices") != std::string::npos
                                       : text.find(n) != std::string::npos;
      CHECK(named);
    } catch (const Error& e) {
      CHECK_THAT(e.what(), Catch::Contains("'" + n + "' matches no OpenCL device"));
    }
  }
}

TEST_CASE("device choice: a spec that matches nothing names itself, the devices and the short names", "[device][cli]") {
  if (mc::compute::list_devices().empty()) return;  // the no-platform message instead (above)
  const std::string msg = error_of([] { mc::compute::choose_device("No-Such-Device-42"); });
  INFO(msg);
  CHECK_THAT(msg, Catch::StartsWith("--device 'No-Such-Device-42' matches no OpenCL device; available:\n"));
  for (const mc::compute::DeviceInfo& d : mc::compute::list_devices()) CHECK_THAT(msg, Catch::Contains("\n  " + d.label()));
  CHECK_THAT(msg, Catch::Contains("a short name (pocl, nvidia, cuda, amd, intel, rusticl, mesa)"));
  CHECK_THAT(msg, Catch::EndsWith("or part of a device or platform name"));

  // The same from the command line: status 1, no run folder; and
  // `millcharge devices` runs to the end with MILLCHARGE_DEVICE=pocl.
  const fs::path work = temp_dir("no_such_device");
  const fs::path out = work / "run";
  const Outcome o = run_binary("", "run --quiet --device no-such-device-42 --out '" + out.string() + "'", work);
  INFO(o.err);
  CHECK(o.status == 1);
  CHECK_THAT(o.err, Catch::Contains("--device 'no-such-device-42' matches no OpenCL device"));
  CHECK_THAT(o.err, Catch::Contains("pocl, nvidia, cuda, amd, intel, rusticl, mesa"));
  CHECK_FALSE(fs::exists(out));
  const Outcome d = run_binary("MILLCHARGE_DEVICE=pocl", "devices", work);
  INFO(d.err);
  CHECK(d.status == 0);
  fs::remove_all(work);
}
