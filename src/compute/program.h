// Building the kernels in cl/ into one OpenCL program, with -D constants, and
// the kernel objects that launch them.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "compute/buffer.h"
#include "compute/context.h"

namespace mc::compute {

// Folder of the .cl files: $MILLCHARGE_KERNEL_DIR, else the source tree's cl/.
std::string kernel_dir();

// The message of a failed build: the files that failed, the build log's first
// error lines and what to do. `device` is DeviceInfo::label(), `dir` the
// kernel folder, `log` the driver's build log.
std::string build_failure_message(const std::string& device, const std::string& dir,
                                  const std::vector<std::string>& files, const std::string& log);

// Compile-time constants handed to the kernels as -D options, built in one
// place (FluidX3D's habit).
class BuildOptions {
 public:
  BuildOptions& define(const std::string& name, const std::string& value = "");
  BuildOptions& define(const std::string& name, int value);
  std::string str(const std::string& include_dir) const;

 private:
  std::vector<std::pair<std::string, std::string>> defines_;
};

class Program {
 public:
  // Builds the listed files of kernel_dir() as one program. `double_precision`
  // says whether `real` is double in these kernels (-D MC_DOUBLE is added).
  // A build failure throws Error with the build log (file:line messages).
  Program(Context& ctx, const std::vector<std::string>& files,
          BuildOptions options, bool double_precision);

  Context& ctx() { return ctx_; }
  cl::Program& get() { return program_; }
  bool double_precision() const { return double_; }

 private:
  void keep_build_log(Context& ctx, const std::string& opts);
  void dump_program(Context& ctx, const std::string& opts);
  Context& ctx_;
  cl::Program program_;
  bool double_;
};

// Local memory of a given size, as a kernel argument.
struct LocalBytes {
  std::size_t bytes;
};

// One kernel of a program; arguments are bound in order with args(...), a
// floating-point scalar becomes the kernel's `real`. Errors name the kernel.
class Kernel {
 public:
  Kernel(Program& program, const std::string& name);

  template <class... Args>
  Kernel& args(const Args&... a) {
    cl_uint index = 0;
    (set(index++, a), ...);
    return *this;
  }
  // Enqueues without waiting. `global` is rounded up to a multiple of `local`
  // (0 = let the driver choose); kernels check their range.
  void launch(std::size_t global, std::size_t local = 0);
  const std::string& name() const { return name_; }

 private:
  void set(cl_uint index, double value);
  void set(cl_uint index, float value) { set(index, static_cast<double>(value)); }
  void set(cl_uint index, int value);
  void set(cl_uint index, const LocalBytes& local);
  template <class T>
  void set(cl_uint index, const Buffer<T>& buffer) {
    set_mem(index, buffer.device());
  }
  // A buffer the caller owns (a GL buffer shared with OpenCL, for example).
  void set(cl_uint index, const cl::Buffer& mem) { set_mem(index, mem); }
  void set_mem(cl_uint index, const cl::Buffer& mem);
  [[noreturn]] void fail(const std::string& what, const cl::Error& e) const;

  Program& program_;
  std::string name_;
  cl::Kernel kernel_;
};

}  // namespace mc::compute
