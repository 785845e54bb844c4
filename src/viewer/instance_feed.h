// How the balls reach the vertex buffer each frame. With CL-GL interop
// (cl_khr_gl_sharing) the solver's kernel writes the GL buffer itself,
// between acquire and release; otherwise (PoCL with Mesa, for one) the kernel
// writes a device buffer and the host copies it into GL: one copy per frame.
// Any failure of the interop path falls back to the copy, with the reason.
#pragma once

#include <memory>
#include <string>

#include "compute/buffer.h"
#include "compute/gl_buffer.h"
#include "sim/solver.h"
#include "viewer/ball_renderer.h"

namespace mc::viewer {

class InstanceFeed {
 public:
  // `why_not_shared` says why ctx does not share GL objects, when it does not.
  InstanceFeed(compute::Context& ctx, std::string why_not_shared);

  // After the renderer's buffer was (re)sized: binds the GL buffer (interop)
  // or sizes the staging buffer (copy).
  void attach(BallRenderer& balls);
  // Fills the renderer's buffer from the solver; the GL buffer is ready to
  // draw from when this returns.
  void update(Solver& solver, BallRenderer& balls);

  bool interop() const { return shared_ != nullptr; }
  // "CL-GL interop" or "host copy (reason)".
  std::string path() const;

 private:
  void fall_back(const std::string& why);
  compute::Context& ctx_;
  bool try_interop_;
  std::string why_copy_;
  std::unique_ptr<compute::GLBuffer> shared_;
  compute::Buffer<float> staging_;
};

}  // namespace mc::viewer
