// A second OpenCL implementation beside PoCL (label `rusticl`: ctest runs
// this with RUSTICL_ENABLE=llvmpipe MILLCHARGE_DEVICE=rusticl, Mesa's rusticl
// on llvmpipe from Debian's mesa-opencl-icd). The same short lab run on the
// device under test and on PoCL: the charge's averages agree, though the two
// runs part ways ball by ball (round-off differs, and a dense charge
// amplifies it). Hidden ([.]): it means something only with MILLCHARGE_DEVICE
// naming another implementation, so only that ctest entry runs it.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "app/commands.h"
#include "compute/context.h"
#include "viewer/gl_sharing.h"

namespace fs = std::filesystem;

namespace {

const char* kPoclPlatform = "Portable Computing Language";

std::string output_of(const std::string& cmd) {
  std::string text;
  if (FILE* p = popen(cmd.c_str(), "r")) {
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) text.append(buf, n);
    pclose(p);
  }
  return text;
}

// A 75 mm slice of the lab mill (half its length, about 1,360 balls),
// settled 0.1 s (not to rest: both devices follow the same collapse of the
// packed charge), then turned 0.2 s with the averages over the last 0.1 s:
// about 15,000 steps.
nlohmann::json short_lab_run(const std::string& device, const fs::path& out) {
  mc::app::RunOptions o;
  o.c.device = device;
  o.c.overrides = {"mill.length=0.075", "run.settle=0.1", "run.warmup=0.1", "run.output_interval=0.025",
                   "run.snapshot_interval=0", "run.checkpoint_interval=0"};
  o.c.duration = 0.2;
  o.out = out.string();
  o.force = true;
  o.quiet = true;
  REQUIRE(mc::app::cmd_run(o) == 0);
  std::ifstream in(out / "summary.json");
  return nlohmann::json::parse(in);
}

}  // namespace

TEST_CASE("a short lab run on a second OpenCL implementation matches PoCL's", "[.][implementations]") {
  const char* env = std::getenv("MILLCHARGE_DEVICE");
  REQUIRE(env != nullptr);
  const std::string spec = env;
  std::string available;
  for (const auto& d : mc::compute::list_devices()) available += "\n  " + d.label();
  INFO("MILLCHARGE_DEVICE=" << spec << "; the devices here:" << available
                            << "\n(Mesa's rusticl: apt-get install mesa-opencl-icd, as scripts/setup.sh does, and "
                               "RUSTICL_ENABLE=llvmpipe)");
  const mc::compute::DeviceInfo tested = mc::compute::choose_device(spec);
  REQUIRE(tested.platform_name != kPoclPlatform);  // a second implementation, not PoCL again
  const mc::compute::DeviceInfo pocl = mc::compute::choose_device(kPoclPlatform);

  const fs::path dir = fs::temp_directory_path() / ("millcharge_test_implementations_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const nlohmann::json a = short_lab_run(spec, dir / "tested");
  const nlohmann::json b = short_lab_run(kPoclPlatform, dir / "pocl");
  fs::remove_all(dir);

  std::printf("short lab run, %s against %s:\n", tested.label().c_str(), pocl.label().c_str());
  for (const char* k : {"toe_deg", "shoulder_deg", "com_angle_deg", "filling_settled"})
    std::printf("  %-16s %10.4f  %10.4f\n", k, a[k].get<double>(), b[k].get<double>());
  for (const char* k : {"torque", "dissipation", "torque_arm"})
    std::printf("  power %-10s %10.2f  %10.2f W\n", k, a["power_W"][k].get<double>(), b["power_W"][k].get<double>());

  CHECK(a["device"].get<std::string>() == tested.label());
  CHECK(a["precision"] == "float");
  CHECK(a["n_particles"] == b["n_particles"]);
  CHECK(a["steps"] == b["steps"]);
  // The same packing settles to the same bed: the settled filling is
  // measured before the runs have drifted apart.
  CHECK(a["filling_settled"].get<double>() == Approx(b["filling_settled"].get<double>()).margin(1e-3));
  // The charge's averages: within a few per cent and degrees (the two
  // devices measured 0.4 % and 0.6 deg apart; a wrong force or a lost
  // contact moves them by tens).
  const double p = b["power_W"]["torque"].get<double>();
  CHECK(p > 100);
  CHECK(a["power_W"]["torque"].get<double>() == Approx(p).epsilon(0.04));
  CHECK(a["power_W"]["torque_arm"].get<double>() == Approx(b["power_W"]["torque_arm"].get<double>()).epsilon(0.04));
  CHECK(std::fabs(a["toe_deg"].get<double>() - b["toe_deg"].get<double>()) < 4);
  CHECK(std::fabs(a["shoulder_deg"].get<double>() - b["shoulder_deg"].get<double>()) < 4);
  CHECK(std::fabs(a["com_angle_deg"].get<double>() - b["com_angle_deg"].get<double>()) < 1.5);
}

TEST_CASE("millcharge devices lists the second implementation beside PoCL", "[.][implementations]") {
  const char* env = std::getenv("MILLCHARGE_DEVICE");
  REQUIRE(env != nullptr);
  const mc::compute::DeviceInfo tested = mc::compute::choose_device(env);
  REQUIRE(tested.platform_name != kPoclPlatform);
  const std::string out = output_of(std::string(MC_BINARY) + " devices 2>&1");
  INFO(out);
  CHECK_THAT(out, Catch::Contains(std::string("(cpu, ") + kPoclPlatform + ")\n"));
  // The device's line, and below it what it offers (rusticl: no fp64).
  const auto at = out.find(tested.label() + "\n    ");
  REQUIRE(at != std::string::npos);
  const std::string details = out.substr(at + tested.label().size() + 1, out.find('\n', at + tested.label().size() + 1) - at - tested.label().size() - 1);
  CHECK_THAT(details, Catch::Contains(tested.c_version));
  CHECK_THAT(details, Catch::Contains(tested.fp64 ? "fp64 yes" : "fp64 no"));
  CHECK(tested.c_version.rfind("OpenCL C 1.", 0) == 0);  // the kernels are OpenCL C 1.2
}

TEST_CASE("CL-GL interop is tried only with the GL driver of the OpenCL platform's vendor", "[device]") {
  using mc::viewer::same_gl_cl_vendor;
  // Xvfb's software GL on a machine with an NVIDIA GPU: NVIDIA's OpenCL
  // cannot take Mesa's GLX context.
  CHECK_FALSE(same_gl_cl_vendor("Mesa", "llvmpipe (LLVM 15.0.6, 256 bits)", "NVIDIA CUDA"));
  CHECK_FALSE(same_gl_cl_vendor("Mesa", "llvmpipe (LLVM 15.0.6, 256 bits)", "Portable Computing Language"));
  CHECK(same_gl_cl_vendor("Mesa", "llvmpipe (LLVM 15.0.6, 256 bits)", "rusticl"));
  CHECK(same_gl_cl_vendor("NVIDIA Corporation", "NVIDIA H100 80GB HBM3/PCIe/SSE2", "NVIDIA CUDA"));
  CHECK_FALSE(same_gl_cl_vendor("NVIDIA Corporation", "NVIDIA H100 80GB HBM3/PCIe/SSE2", "rusticl"));
  CHECK(same_gl_cl_vendor("AMD", "AMD Radeon RX 7900 XTX", "AMD Accelerated Parallel Processing"));
  // Mesa's Intel GL driver is Mesa's: it shares with rusticl.
  CHECK(same_gl_cl_vendor("Intel", "Mesa Intel(R) UHD Graphics 630", "rusticl"));
  CHECK_FALSE(same_gl_cl_vendor("", "", "NVIDIA CUDA"));
}
