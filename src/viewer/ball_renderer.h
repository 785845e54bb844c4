// The balls as instanced, lit, depth-correct sphere impostors: one square per
// ball, its data in a vertex buffer laid out as cl/instances.h, which the
// OpenCL kernel fills directly (interop) or the host copies into.
#pragma once

#include <glm/glm.hpp>

#include "viewer/gl.h"
#include "viewer/shader.h"

namespace mc::viewer {

enum class ColourBy { speed = 0, size = 1, material = 2, impact = 3 };

struct BallStyle {
  ColourBy colour_by = ColourBy::speed;
  glm::vec2 range{0, 1};  // cold and hot ends (impact: log10 W)
  bool slab = false;
  float slab_from = 0, slab_to = 0;  // m along the axis
};

class BallRenderer {
 public:
  BallRenderer();
  ~BallRenderer();
  BallRenderer(const BallRenderer&) = delete;
  BallRenderer& operator=(const BallRenderer&) = delete;

  // Storage for n balls (contents undefined until written).
  void resize(int n);
  int count() const { return n_; }
  GLuint vertex_buffer() const { return instances_; }
  // The host path: n × MC_INSTANCE_FLOATS floats.
  void upload(const float* data);

  void draw(const glm::mat4& view, const glm::mat4& projection, bool orthographic, const BallStyle& style);

 private:
  ShaderProgram shader_;
  GLuint vao_ = 0, corners_ = 0, instances_ = 0;
  int n_ = 0;
};

}  // namespace mc::viewer
