// Device choice and the command queue: the OpenCL context a solver runs in.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "compute/opencl.hpp"

namespace mc::compute {

// Every failure of the OpenCL layer: the message names what failed and how to
// fix it where there is a fix.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct DeviceInfo {
  int platform_index = 0;
  int device_index = 0;
  std::string platform_name;
  std::string name;
  std::string type;  // "gpu", "cpu", "accelerator", "other"
  std::string version;
  bool fp64 = false;
  bool gl_sharing = false;
  std::size_t global_mem_bytes = 0;
  std::size_t max_alloc_bytes = 0;
  int compute_units = 0;
  std::string label() const;  // "P:D name (type, platform)"
};

// All devices of all platforms; empty when there is no OpenCL platform.
std::vector<DeviceInfo> list_devices();

// Picks a device from a spec: "" or "auto" (a GPU when there is one, else the
// first device), "gpu", "cpu", "P:D" (platform and device index), or a part
// of the device or platform name. Throws Error naming the spec and listing the
// devices when none matches.
DeviceInfo choose_device(const std::string& spec);

class Context {
 public:
  // spec as for choose_device; when empty, MILLCHARGE_DEVICE is read.
  explicit Context(const std::string& spec = "");
  // A context that shares objects with an OpenGL context (cl_khr_gl_sharing):
  // `gl_properties` name the GL context, e.g. {CL_GL_CONTEXT_KHR, glx_context,
  // CL_GLX_DISPLAY_KHR, display}; the platform and the closing 0 are added.
  // Throws Error when the device lacks the extension, is not the device that
  // runs the GL context, or the driver refuses.
  Context(const std::string& spec, const std::vector<cl_context_properties>& gl_properties);

  const DeviceInfo& info() const { return info_; }
  cl::Context& context() { return context_; }
  cl::Device& device() { return device_; }
  cl::CommandQueue& queue() { return queue_; }
  void finish();
  bool shares_gl() const { return shares_gl_; }

 private:
  bool shares_gl_ = false;
  DeviceInfo info_;
  cl::Device device_;
  cl::Context context_;
  cl::CommandQueue queue_;
};

// Text of an OpenCL error code, for messages.
std::string error_name(int code);

}  // namespace mc::compute
