// A typed buffer pairing a host array with its device copy (FluidX3D's habit):
// fill `host`, write_to_device(); run kernels; read_from_device(), read `host`.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "compute/context.h"

namespace mc::compute {

template <class T>
class Buffer {
 public:
  Buffer() = default;
  Buffer(Context& ctx, std::size_t n, std::string label) : ctx_(&ctx), label_(std::move(label)) {
    resize(n);
  }

  std::vector<T> host;

  std::size_t size() const { return host.size(); }
  std::size_t bytes() const { return host.size() * sizeof(T); }
  const std::string& label() const { return label_; }
  const cl::Buffer& device() const { return device_; }

  // New size on both sides; device contents are not kept.
  void resize(std::size_t n) {
    host.assign(n, T{});
    const std::size_t b = (n == 0 ? 1 : n) * sizeof(T);
    try {
      device_ = cl::Buffer(ctx_->context(), CL_MEM_READ_WRITE, b);
    } catch (const cl::Error& e) {
      throw Error("cannot allocate device buffer '" + label_ + "' of " + std::to_string(b) +
                  " bytes: " + error_name(e.err()));
    }
  }

  void write_to_device() {
    if (host.empty()) return;
    try {
      ctx_->queue().enqueueWriteBuffer(device_, CL_TRUE, 0, bytes(), host.data());
    } catch (const cl::Error& e) {
      throw Error("writing buffer '" + label_ + "' failed: " + error_name(e.err()));
    }
  }
  void read_from_device() {
    if (host.empty()) return;
    try {
      ctx_->queue().enqueueReadBuffer(device_, CL_TRUE, 0, bytes(), host.data());
    } catch (const cl::Error& e) {
      throw Error("reading buffer '" + label_ + "' failed: " + error_name(e.err()));
    }
  }
  // Device-to-device copy of the first n elements of another buffer.
  void copy_from(const Buffer& other, std::size_t n) {
    if (n == 0) return;
    try {
      ctx_->queue().enqueueCopyBuffer(other.device_, device_, 0, 0, n * sizeof(T));
    } catch (const cl::Error& e) {
      throw Error("copying into buffer '" + label_ + "' failed: " + error_name(e.err()));
    }
  }

 private:
  Context* ctx_ = nullptr;
  std::string label_;
  cl::Buffer device_;
};

}  // namespace mc::compute
