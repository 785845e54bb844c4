// An orbit camera about a target point: yaw and pitch of the eye around it,
// distance (zoom) and a pan of the target in the view plane; perspective or
// orthographic. Presets look along the mill axis (end view: x to the right,
// y up, as the angles of DESIGN.md are drawn) or from an isometric corner.
#pragma once

#include <glm/glm.hpp>

namespace mc::viewer {

class Camera {
 public:
  // The mill: axis along z from 0 to length, shell radius `radius`.
  void frame_mill(double radius, double length) {
    radius_ = static_cast<float>(radius);
    length_ = static_cast<float>(length);
  }
  // Looking along −z at the whole cross-section, orthographic.
  void end_view(float aspect);
  // From above the rising side and in front, perspective.
  void isometric(float aspect);

  void orbit(float dx_px, float dy_px);      // mouse drag, pixels
  void pan(float dx_px, float dy_px, float viewport_h_px);
  void zoom(float wheel_steps);

  glm::mat4 view() const;
  glm::mat4 projection(float aspect) const;
  glm::vec3 eye() const;
  bool orthographic() const { return ortho_; }
  void set_orthographic(bool o) { ortho_ = o; }

 private:
  float half_height() const;  // of the view at the target, m
  float radius_ = 0.5f, length_ = 0.2f;
  glm::vec3 target_{0, 0, 0};
  float yaw_ = 0, pitch_ = 0;  // rad; 0, 0: the eye on +z
  float distance_ = 2;
  float fov_y_ = 0.6f;         // rad
  bool ortho_ = true;
};

}  // namespace mc::viewer
