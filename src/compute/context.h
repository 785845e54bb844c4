// Device choice and the command queue: the OpenCL context a solver runs in.
#pragma once

#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
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
  std::string platform_vendor;  // CL_PLATFORM_VENDOR, e.g. "The pocl project", "Mesa/X.org"
  std::string name;
  std::string vendor;  // CL_DEVICE_VENDOR, e.g. "NVIDIA Corporation", "GenuineIntel"
  std::string type;  // "gpu", "cpu", "accelerator", "other"
  std::string version;
  std::string c_version;  // CL_DEVICE_OPENCL_C_VERSION, e.g. "OpenCL C 1.2"
  bool fp64 = false;
  bool gl_sharing = false;
  std::size_t global_mem_bytes = 0;
  std::size_t max_alloc_bytes = 0;
  int compute_units = 0;
  std::string label() const;  // "P:D name (type, platform)"
};

// All devices of all platforms; empty when there is no OpenCL platform.
std::vector<DeviceInfo> list_devices();

// The platforms that offer no device, by index and name: a driver installed
// for hardware that is not there, or Mesa's rusticl, which offers none until
// RUSTICL_ENABLE names a driver.
std::vector<std::pair<int, std::string>> platforms_without_devices();

// What to print when list_devices() is empty: no platform (or platforms
// without devices), and how to fix it.
std::string no_device_message();

// The short names of OpenCL implementations and vendors that choose_device
// knows: pocl, nvidia, cuda, amd, intel, rusticl, mesa.
std::vector<std::string> device_short_names();

// Picks a device from a spec, case-insensitively: "" or "auto" (a GPU when
// there is one, else the first device), "gpu", "cpu", "accelerator", "P:D"
// (platform and device index), a short name (device_short_names(): the first
// device whose platform's name or vendor fits it, else the first whose own
// name or vendor does; "pocl" finds "Portable Computing Language"), or a
// part of the device's or platform's name (or, failing that, vendor). Throws
// Error naming the spec, listing the devices and the short names when none
// matches.
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

  // Device memory. Every Buffer reserves its bytes here before it allocates:
  // a buffer larger than max_alloc_bytes() or one that would take the total
  // over memory_bytes() throws Error ("device out of memory: ... needs ...,
  // ... available; fix: ...") instead of failing somewhere in the driver.
  // The reservation is given back when the last copy of the token goes.
  std::shared_ptr<void> reserve(std::size_t bytes, const std::string& label);
  std::size_t allocated_bytes() const;
  // CL_DEVICE_GLOBAL_MEM_SIZE, or MILLCHARGE_DEVICE_MEMORY (bytes, with an
  // optional K, M or G suffix) when that is smaller: the memory a run may use.
  std::size_t memory_bytes() const { return memory_bytes_; }
  // CL_DEVICE_MAX_MEM_ALLOC_SIZE (capped at memory_bytes()).
  std::size_t max_alloc_bytes() const;

  // The byte every new device buffer is filled with before any kernel
  // runs: 0, or 0xFF (a NaN in every real, -1 in every int) with
  // MILLCHARGE_POISON=1 in the environment or after set_new_buffer_fill.
  // A device does not clear the memory it hands out, so a kernel that reads
  // what no kernel wrote sees the last program's data on a GPU; under the
  // poison such a read changes a result (tests/test_poison.cpp).
  unsigned char new_buffer_fill() const { return new_buffer_fill_; }
  void set_new_buffer_fill(unsigned char byte) { new_buffer_fill_ = byte; }

  // The error for an OpenCL call that failed while doing `what` (e.g.
  // "writing buffer 'positions'"): the out-of-memory codes
  // (CL_MEM_OBJECT_ALLOCATION_FAILURE, CL_OUT_OF_RESOURCES,
  // CL_OUT_OF_HOST_MEMORY) give the bytes in use and available and the fix.
  Error error(const std::string& what, int code) const;

 private:
  void choose(const std::string& spec);
  struct Ledger;
  std::shared_ptr<Ledger> ledger_;
  std::size_t memory_bytes_ = 0;
  bool shares_gl_ = false;
  unsigned char new_buffer_fill_ = 0;
  DeviceInfo info_;
  cl::Device device_;
  cl::Context context_;
  cl::CommandQueue queue_;
};

// Text of an OpenCL error code, for messages.
std::string error_name(int code);

// True for the codes that mean the device (or the host) ran out of memory.
bool is_out_of_memory(int code);

// "1.50 GiB (1610612736 bytes)", for messages.
std::string bytes_text(std::size_t bytes);

// The fix printed with every out-of-memory message.
inline constexpr const char* kOutOfMemoryFix =
    "fix: fewer balls (a lower charge.filling or larger balls), a smaller case, another --device with more "
    "memory (see `millcharge devices`), or --precision float instead of double";

}  // namespace mc::compute
