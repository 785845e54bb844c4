#include "compute/gl_buffer.h"

#include <vector>

namespace mc::compute {

GLBuffer::GLBuffer(Context& ctx, unsigned gl_buffer) : ctx_(&ctx) {
  if (!ctx.shares_gl()) throw Error("the OpenCL context does not share objects with OpenGL");
  try {
    buffer_ = cl::BufferGL(ctx.context(), CL_MEM_WRITE_ONLY, gl_buffer);
  } catch (const cl::Error& e) {
    throw Error("clCreateFromGLBuffer failed: " + error_name(e.err()));
  }
}

void GLBuffer::acquire() {
  const std::vector<cl::Memory> objects{buffer_};
  try {
    ctx_->queue().enqueueAcquireGLObjects(&objects);
  } catch (const cl::Error& e) {
    throw Error("acquiring the GL buffer failed: " + error_name(e.err()));
  }
}

void GLBuffer::release() {
  const std::vector<cl::Memory> objects{buffer_};
  try {
    ctx_->queue().enqueueReleaseGLObjects(&objects);
  } catch (const cl::Error& e) {
    throw Error("releasing the GL buffer failed: " + error_name(e.err()));
  }
}

}  // namespace mc::compute
