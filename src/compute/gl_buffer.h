// An OpenGL buffer object seen by OpenCL (cl_khr_gl_sharing): kernels write
// it directly, between acquire() and release(), so the data never leave the
// device (the Khronos OpenCL-SDK nbody's habit).
#pragma once

#include "compute/context.h"

namespace mc::compute {

class GLBuffer {
 public:
  // `gl_buffer` is the name of a GL buffer object with its storage already
  // allocated; `ctx` must share objects with the current GL context. Throws
  // Error when the driver refuses.
  GLBuffer(Context& ctx, unsigned gl_buffer);

  // Enqueued on the context's queue; OpenGL must have finished with the
  // buffer before acquire(), and the queue must be finished after release()
  // before OpenGL draws from it.
  void acquire();
  void release();
  const cl::Buffer& device() const { return buffer_; }

 private:
  Context* ctx_;
  cl::BufferGL buffer_;
};

}  // namespace mc::compute
