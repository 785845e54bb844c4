#include "viewer/instance_feed.h"

#include <iostream>

#include "../../cl/instances.h"

namespace mc::viewer {

InstanceFeed::InstanceFeed(compute::Context& ctx, std::string why_not_shared)
    : ctx_(ctx), try_interop_(ctx.shares_gl()), why_copy_(std::move(why_not_shared)) {}

std::string InstanceFeed::path() const {
  if (interop()) return "CL-GL interop (kernel writes the GL buffer)";
  return "host copy (" + why_copy_ + ")";
}

void InstanceFeed::fall_back(const std::string& why) {
  std::cerr << "millcharge view: CL-GL interop failed, copying through the host: " << why << '\n';
  shared_.reset();
  try_interop_ = false;
  why_copy_ = "interop failed: " + why;
}

void InstanceFeed::attach(BallRenderer& balls) {
  shared_.reset();
  if (try_interop_) {
    try {
      glFinish();
      shared_ = std::make_unique<compute::GLBuffer>(ctx_, balls.vertex_buffer());
      return;
    } catch (const compute::Error& e) {
      fall_back(e.what());
    }
  }
  const std::size_t floats = static_cast<std::size_t>(balls.count()) * MC_INSTANCE_FLOATS;
  if (staging_.size() != floats) staging_ = compute::Buffer<float>(ctx_, floats, "view instances");
}

void InstanceFeed::update(Solver& solver, BallRenderer& balls) {
  if (shared_) {
    try {
      glFinish();  // GL is done with the buffer before OpenCL takes it
      shared_->acquire();
      // Released however the kernel ends: a buffer still acquired must not
      // be destroyed (the fall-back below, or the feed's end).
      struct Release {
        compute::GLBuffer& b;
        compute::Context& ctx;
        bool done = false;
        ~Release() {
          if (done) return;
          try {
            b.release();
            ctx.finish();
          } catch (...) {  // already failing: the first error is the one reported
          }
        }
      } guard{*shared_, ctx_};
      solver.write_instances(shared_->device());
      guard.done = true;
      shared_->release();
      ctx_.finish();  // the kernel is done before GL draws
      return;
    } catch (const compute::Error& e) {
      fall_back(e.what());
      attach(balls);
    }
  }
  solver.write_instances(staging_.device());
  staging_.read_from_device();  // blocking: waits for the kernel
  balls.upload(staging_.host.data());
}

}  // namespace mc::viewer
