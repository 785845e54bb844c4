#include "compute/program.h"

#include <cstdlib>

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <vector>
#include <fstream>
#include <set>
#include <sstream>

namespace mc::compute {

std::string kernel_dir() {
  if (const char* env = std::getenv("MILLCHARGE_KERNEL_DIR")) return env;
  return MC_KERNEL_DIR;
}

BuildOptions& BuildOptions::define(const std::string& name, const std::string& value) {
  defines_.emplace_back(name, value);
  return *this;
}

BuildOptions& BuildOptions::define(const std::string& name, int value) {
  return define(name, std::to_string(value));
}

std::string BuildOptions::str(const std::string& include_dir) const {
  std::ostringstream s;
  s << "-I " << include_dir;
  for (const auto& [name, value] : defines_) {
    s << " -D " << name;
    if (!value.empty()) s << '=' << value;
  }
  return s.str();
}

namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw Error("cannot read kernel file " + path +
                " (set MILLCHARGE_KERNEL_DIR to the folder holding the .cl files)");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Some drivers (PoCL's clang) also print a failed build's diagnostics on
// stderr ("1 error generated."): while the kernels build, stderr goes to a
// temporary file; release() puts it back and returns what was written.
class StderrCapture {
 public:
  StderrCapture() {
    std::fflush(stderr);
    tmp_ = std::tmpfile();
    if (!tmp_) return;
    saved_ = ::dup(2);
    if (saved_ < 0 || ::dup2(::fileno(tmp_), 2) < 0) {
      if (saved_ >= 0) ::close(saved_);
      saved_ = -1;
    }
  }
  std::string release() {
    std::string text;
    if (saved_ >= 0) {
      std::fflush(stderr);
      ::dup2(saved_, 2);
      ::close(saved_);
      saved_ = -1;
      std::rewind(tmp_);
      char buf[4096];
      for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, tmp_)) > 0;) text.append(buf, n);
    }
    if (tmp_) std::fclose(tmp_);
    tmp_ = nullptr;
    return text;
  }
  ~StderrCapture() { release(); }
  StderrCapture(const StderrCapture&) = delete;
  StderrCapture& operator=(const StderrCapture&) = delete;

 private:
  std::FILE* tmp_ = nullptr;
  int saved_ = -1;
};

bool has_error(const std::string& line) {
  return line.find("error:") != std::string::npos || line.find("error :") != std::string::npos;
}

}  // namespace

std::string build_failure_message(const std::string& device, const std::string& dir,
                                  const std::vector<std::string>& files, const std::string& log) {
  // The log's error lines (file:line:col: error: ...), the first few of them,
  // and the files they name; the whole log when it has no such line.
  std::vector<std::string> errors, lines;
  std::set<std::string> named;
  std::istringstream in(log);
  for (std::string line; std::getline(in, line);) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (line.empty()) continue;
    lines.push_back(line);
    if (!has_error(line)) continue;
    errors.push_back(line);
    for (const std::string& f : files)
      if (line.find(f + ":") != std::string::npos) named.insert(f);
  }
  constexpr std::size_t kShown = 8;
  const std::vector<std::string>& shown = errors.empty() ? lines : errors;
  std::string which;
  for (const std::string& f : named.empty() ? std::set<std::string>(files.begin(), files.end()) : named)
    which += (which.empty() ? "" : ", ") + f;
  std::ostringstream m;
  m << "kernel build failed: " << which << " (in " << dir << ") did not compile on " << device;
  if (shown.empty()) {
    m << " (the driver gave no build log)";
  } else {
    m << (errors.empty() ? "; build log:" : "; first errors:");
    for (std::size_t k = 0; k < shown.size() && k < kShown; ++k) m << "\n  " << shown[k];
    if (shown.size() > kShown) m << "\n  ... and " << shown.size() - kShown << " more";
  }
  m << "\nfix: if you edited the kernels, correct the lines above; otherwise make sure " << dir
    << " holds this build's cl/ folder (unset MILLCHARGE_KERNEL_DIR or point it there), update the OpenCL "
       "driver, or try another --device (see `millcharge devices`)";
  return m.str();
}

// MILLCHARGE_BUILD_LOG=FILE: a good build's log (NVIDIA's register and
// spill counts under -cl-nv-verbose, PoCL's vectoriser notes) appended to
// FILE with the device and the options, since a good build shows none.
void Program::keep_build_log(Context& ctx, const std::string& opts) {
  const char* path = std::getenv("MILLCHARGE_BUILD_LOG");
  if (!path || !*path) return;
  std::string log;
  try {
    log = program_.getBuildInfo<CL_PROGRAM_BUILD_LOG>(ctx.device());
  } catch (const cl::Error&) {
    log = "(the driver gave no build log)";
  }
  if (std::FILE* f = std::fopen(path, "a")) {
    std::fprintf(f, "== %s (%s)\n== options: %s\n%s\n", ctx.info().label().c_str(), double_ ? "double" : "float",
                 opts.c_str(), log.c_str());
    std::fclose(f);
  }
}

// MILLCHARGE_PROGRAM_DUMP=DIR: what the driver built, for a look at the
// code a GPU runs: the program binary (PTX text on NVIDIA, which
// `ptxas -v` turns into registers and spills per kernel, docs/gpu.md) as
// DIR/program-float.ptx (or .bin), and each kernel's figures the driver
// reports (private and local memory, the largest and the preferred
// work-group size) as DIR/kernels-float.txt; -double for double precision.
void Program::dump_program(Context& ctx, const std::string& opts) {
  const char* dir = std::getenv("MILLCHARGE_PROGRAM_DUMP");
  if (!dir || !*dir) return;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const std::string tag = double_ ? "double" : "float";
  try {
    const std::vector<std::vector<unsigned char>> binaries = program_.getInfo<CL_PROGRAM_BINARIES>();
    if (!binaries.empty() && !binaries[0].empty()) {
      const std::vector<unsigned char>& b = binaries[0];
      const std::string head(b.begin(), b.begin() + std::min<std::size_t>(b.size(), 4096));
      const bool ptx = head.find(".version") != std::string::npos && head.find(".target") != std::string::npos;
      std::ofstream(std::string(dir) + "/program-" + tag + (ptx ? ".ptx" : ".bin"), std::ios::binary)
          .write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
    }
  } catch (const cl::Error&) {
  }
  std::ofstream t(std::string(dir) + "/kernels-" + tag + ".txt");
  t << "# " << ctx.info().label() << " (" << tag << "); options: " << opts << "\n";
  t << "# kernel private_bytes local_bytes max_work_group preferred_multiple\n";
  try {
    std::vector<cl::Kernel> kernels;
    program_.createKernels(&kernels);
    std::vector<std::string> lines;
    for (cl::Kernel& k : kernels) {
      std::ostringstream l;
      l << k.getInfo<CL_KERNEL_FUNCTION_NAME>() << ' '
        << k.getWorkGroupInfo<CL_KERNEL_PRIVATE_MEM_SIZE>(ctx.device()) << ' '
        << k.getWorkGroupInfo<CL_KERNEL_LOCAL_MEM_SIZE>(ctx.device()) << ' '
        << k.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(ctx.device()) << ' '
        << k.getWorkGroupInfo<CL_KERNEL_PREFERRED_WORK_GROUP_SIZE_MULTIPLE>(ctx.device());
      lines.push_back(l.str());
    }
    std::sort(lines.begin(), lines.end());
    for (const std::string& l : lines) t << l << '\n';
  } catch (const cl::Error& e) {
    t << "# the driver did not say: " << error_name(e.err()) << '\n';
  }
}

// A hash (FNV-1a) of every file in the kernel folder, names and contents.
// A driver's compiler cache may key on the source string alone, which names
// the headers but does not hold them: an edited header would then reuse the
// old binary. The hash goes into the options, and so into the key.
static std::string kernel_folder_hash(const std::string& dir) {
  std::vector<std::filesystem::path> paths;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file()) paths.push_back(e.path());
  std::sort(paths.begin(), paths.end());
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const std::string& bytes) {
    for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  };
  for (const auto& p : paths) {
    mix(p.filename().string());
    mix(read_file(p.string()));
  }
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

Program::Program(Context& ctx, const std::vector<std::string>& files,
                 BuildOptions options, bool double_precision)
    : ctx_(ctx), double_(double_precision) {
  if (double_ && !ctx.info().fp64)
    throw Error("--precision double needs a device with cl_khr_fp64; " + ctx.info().label() +
                " has none: use --precision float");
  const std::string dir = kernel_dir();
  // One translation unit; #line keeps the file names in the build log.
  std::string source;
  for (const std::string& f : files)
    source += "#line 1 \"" + f + "\"\n" + read_file(dir + "/" + f) + "\n";
  if (double_) options.define("MC_DOUBLE");
  std::string opts = options.str(dir) + " -DMC_SOURCE_HASH=0x" + kernel_folder_hash(dir);
  // Extra compiler options for tuning and for drivers that need them, e.g.
  // MILLCHARGE_CL_OPTIONS="-cl-mad-enable".
  if (const char* extra = std::getenv("MILLCHARGE_CL_OPTIONS")) opts += std::string(" ") + extra;
  try {
    program_ = cl::Program(ctx.context(), source);
  } catch (const cl::Error& e) {
    throw Error("cannot create OpenCL program: " + error_name(e.err()));
  }
  StderrCapture driver_output;
  try {
    program_.build({ctx.device()}, opts.c_str());
    // A good build: whatever the driver printed goes out as before.
    const std::string printed = driver_output.release();
    if (!printed.empty()) std::fputs(printed.c_str(), stderr);
    keep_build_log(ctx, opts);
    dump_program(ctx, opts);
  } catch (const cl::Error& e) {
    const std::string printed = driver_output.release();  // the build log has it too
    std::string log;
    try {
      log = program_.getBuildInfo<CL_PROGRAM_BUILD_LOG>(ctx.device());
    } catch (const cl::Error&) {
    }
    if (log.find_first_not_of(" \n\r\t") == std::string::npos) log = printed;
    if (e.err() != CL_BUILD_PROGRAM_FAILURE && log.empty())
      throw ctx.error("building the kernels in " + dir + " on " + ctx.info().label(), e.err());
    throw Error(build_failure_message(ctx.info().label(), dir, files, log));
  }
}

Kernel::Kernel(Program& program, const std::string& name) : program_(program), name_(name) {
  try {
    kernel_ = cl::Kernel(program.get(), name.c_str());
  } catch (const cl::Error& e) {
    throw Error("kernel '" + name + "' not found in the program: " + error_name(e.err()));
  }
}

void Kernel::fail(const std::string& what, const cl::Error& e) const {
  throw program_.ctx().error("kernel '" + name_ + "': " + what, e.err());
}

void Kernel::set(cl_uint index, double value) {
  try {
    if (program_.double_precision())
      kernel_.setArg(index, value);
    else
      kernel_.setArg(index, static_cast<float>(value));
  } catch (const cl::Error& e) {
    fail("argument " + std::to_string(index), e);
  }
}

void Kernel::set(cl_uint index, int value) {
  try {
    kernel_.setArg(index, static_cast<cl_int>(value));
  } catch (const cl::Error& e) {
    fail("argument " + std::to_string(index), e);
  }
}

void Kernel::set(cl_uint index, const LocalBytes& local) {
  try {
    kernel_.setArg(index, cl::Local(local.bytes));
  } catch (const cl::Error& e) {
    fail("argument " + std::to_string(index), e);
  }
}

void Kernel::set_mem(cl_uint index, const cl::Buffer& mem) {
  try {
    kernel_.setArg(index, mem);
  } catch (const cl::Error& e) {
    fail("argument " + std::to_string(index), e);
  }
}

void Kernel::launch(std::size_t global, std::size_t local) {
  if (global == 0) return;
  // Left to itself, PoCL runs a launch of a few thousand items as one
  // work-group on one core; 64 spreads it over all cores and suits GPUs.
  // (Every kernel checks its index against its count.)
  if (local == 0 && global >= 256) local = 64;
  if (local > 0) global = (global + local - 1) / local * local;
  try {
    program_.ctx().queue().enqueueNDRangeKernel(
        kernel_, cl::NullRange, cl::NDRange(global),
        local > 0 ? cl::NDRange(local) : cl::NullRange);
  } catch (const cl::Error& e) {
    fail("launch of " + std::to_string(global) + " items failed", e);
  }
}

}  // namespace mc::compute
