// A typed buffer pairing a host array with its device copy (FluidX3D's habit):
// fill `host`, write_to_device(); run kernels; read_from_device(), read `host`.
// Each buffer reserves its bytes with the Context before it allocates, so a
// run that does not fit the device stops with the bytes needed and available
// (Context::reserve) before the driver is asked.
#pragma once

#include <cstddef>
#include <memory>
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
    // The old device buffer goes first (its reservation with it).
    device_ = cl::Buffer();
    reservation_.reset();
    if (n > (static_cast<std::size_t>(-1) / 2) / sizeof(T))
      throw Error("device out of memory: buffer '" + label_ + "' of " + std::to_string(n) +
                  " elements is larger than any device; " + kOutOfMemoryFix);
    const std::size_t b = (n == 0 ? 1 : n) * sizeof(T);
    reservation_ = ctx_->reserve(b, label_);  // throws when it does not fit
    host.assign(n, T{});
    try {
      device_ = cl::Buffer(ctx_->context(), CL_MEM_READ_WRITE, b);
      // Never what the device last held there (Context::new_buffer_fill).
      const cl_uchar fill = ctx_->new_buffer_fill();
      ctx_->queue().enqueueFillBuffer(device_, fill, 0, b);
    } catch (const cl::Error& e) {
      throw ctx_->error("allocating buffer '" + label_ + "' of " + bytes_text(b), e.err());
    }
  }

  void write_to_device() {
    if (host.empty()) return;
    try {
      ctx_->queue().enqueueWriteBuffer(device_, CL_TRUE, 0, bytes(), host.data());
    } catch (const cl::Error& e) {
      throw ctx_->error("writing buffer '" + label_ + "'", e.err());
    }
  }
  void read_from_device() {
    if (host.empty()) return;
    try {
      ctx_->queue().enqueueReadBuffer(device_, CL_TRUE, 0, bytes(), host.data());
    } catch (const cl::Error& e) {
      throw ctx_->error("reading buffer '" + label_ + "'", e.err());
    }
  }
  // Device-to-device copy of the first n elements of another buffer.
  void copy_from(const Buffer& other, std::size_t n) {
    if (n == 0) return;
    try {
      ctx_->queue().enqueueCopyBuffer(other.device_, device_, 0, 0, n * sizeof(T));
    } catch (const cl::Error& e) {
      throw ctx_->error("copying into buffer '" + label_ + "'", e.err());
    }
  }

 private:
  Context* ctx_ = nullptr;
  std::string label_;
  cl::Buffer device_;
  std::shared_ptr<void> reservation_;  // gives the bytes back to the Context
};

// One int in pinned host memory (CL_MEM_ALLOC_HOST_PTR, mapped once): the
// target of a read that must not wait. A read into pageable memory may
// block the host until it is done (NVIDIA's driver stages it through a
// pinned copy), which keeps the queue from running ahead.
class PinnedInt {
 public:
  PinnedInt() = default;
  explicit PinnedInt(Context& ctx) : ctx_(&ctx) {
    try {
      buffer_ = cl::Buffer(ctx.context(), CL_MEM_READ_WRITE | CL_MEM_ALLOC_HOST_PTR, sizeof(int));
      ptr_ = static_cast<int*>(
          ctx.queue().enqueueMapBuffer(buffer_, CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0, sizeof(int)));
    } catch (const cl::Error& e) {
      throw ctx.error("mapping a pinned status word", e.err());
    }
    *ptr_ = 0;
  }
  PinnedInt(const PinnedInt&) = delete;
  PinnedInt& operator=(const PinnedInt&) = delete;
  ~PinnedInt() {
    if (ptr_ == nullptr) return;
    try {
      ctx_->queue().enqueueUnmapMemObject(buffer_, ptr_);
      ctx_->queue().finish();
    } catch (const cl::Error&) {
    }
  }
  int* get() const { return ptr_; }

 private:
  Context* ctx_ = nullptr;
  cl::Buffer buffer_;
  int* ptr_ = nullptr;
};

}  // namespace mc::compute
