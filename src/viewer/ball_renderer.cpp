#include "viewer/ball_renderer.h"

#include <cstdint>

#include "../../cl/instances.h"

namespace mc::viewer {

namespace {
constexpr GLsizei kStride = MC_INSTANCE_FLOATS * sizeof(float);
}

BallRenderer::BallRenderer() : shader_("balls.vert", "balls.frag") {
  const float corners[8] = {-1, -1, 1, -1, -1, 1, 1, 1};
  glGenVertexArrays(1, &vao_);
  glGenBuffers(1, &corners_);
  glGenBuffers(1, &instances_);
  glBindVertexArray(vao_);
  glBindBuffer(GL_ARRAY_BUFFER, corners_);
  glBufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
  glBindBuffer(GL_ARRAY_BUFFER, instances_);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, kStride, nullptr);
  glVertexAttribDivisor(1, 1);
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, kStride, reinterpret_cast<const void*>(std::uintptr_t{16}));
  glVertexAttribDivisor(2, 1);
  glBindVertexArray(0);
}

BallRenderer::~BallRenderer() {
  glDeleteBuffers(1, &instances_);
  glDeleteBuffers(1, &corners_);
  glDeleteVertexArrays(1, &vao_);
}

void BallRenderer::resize(int n) {
  n_ = n;
  glBindBuffer(GL_ARRAY_BUFFER, instances_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(n > 0 ? n : 1) * kStride, nullptr, GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void BallRenderer::upload(const float* data) {
  glBindBuffer(GL_ARRAY_BUFFER, instances_);
  glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(n_) * kStride, data);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void BallRenderer::draw(const glm::mat4& view, const glm::mat4& projection, bool orthographic,
                        const BallStyle& style) {
  if (n_ == 0) return;
  shader_.use();
  shader_.set("view", view);
  shader_.set("projection", projection);
  shader_.set("orthographic", orthographic ? 1 : 0);
  shader_.set("colour_mode", static_cast<int>(style.colour_by));
  shader_.set("colour_range", style.range);
  shader_.set("slab", glm::vec3(style.slab ? 1.0f : 0.0f, style.slab_from, style.slab_to));
  glBindVertexArray(vao_);
  glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, n_);
  glBindVertexArray(0);
}

}  // namespace mc::viewer
