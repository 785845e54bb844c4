#include "viewer/camera.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace mc::viewer {

void Camera::end_view(float aspect) {
  target_ = {0, 0, 0.5f * length_};
  yaw_ = pitch_ = 0;
  ortho_ = true;
  // The shell, the toe/shoulder marks (to 1.22 R) and their labels fit the
  // shorter side.
  const float half = 1.32f * radius_ * std::max(1.0f, 1.0f / aspect);
  distance_ = half / std::tan(0.5f * fov_y_);
}

void Camera::isometric(float aspect) {
  target_ = {0, -0.15f * radius_, 0.5f * length_};
  yaw_ = 0.6f;
  pitch_ = 0.45f;
  ortho_ = false;
  const float reach = std::sqrt(radius_ * radius_ + 0.25f * length_ * length_);
  distance_ = 1.35f * reach * std::max(1.0f, 1.0f / aspect) / std::tan(0.5f * fov_y_);
}

glm::vec3 Camera::eye() const {
  const glm::vec3 dir{std::cos(pitch_) * std::sin(yaw_), std::sin(pitch_), std::cos(pitch_) * std::cos(yaw_)};
  return target_ + distance_ * dir;
}

glm::mat4 Camera::view() const { return glm::lookAt(eye(), target_, glm::vec3(0, 1, 0)); }

float Camera::half_height() const { return distance_ * std::tan(0.5f * fov_y_); }

glm::mat4 Camera::projection(float aspect) const {
  const float reach = 2.0f * (radius_ + length_) + distance_;
  if (ortho_) {
    const float h = half_height();
    return glm::ortho(-h * aspect, h * aspect, -h, h, 0.01f * distance_, distance_ + reach);
  }
  return glm::perspective(fov_y_, aspect, std::max(1e-3f, 0.02f * distance_), distance_ + reach);
}

void Camera::orbit(float dx_px, float dy_px) {
  yaw_ -= 0.005f * dx_px;
  pitch_ = std::clamp(pitch_ + 0.005f * dy_px, -1.55f, 1.55f);
}

void Camera::pan(float dx_px, float dy_px, float viewport_h_px) {
  const glm::mat4 v = view();
  const glm::vec3 right{v[0][0], v[1][0], v[2][0]}, up{v[0][1], v[1][1], v[2][1]};
  const float m_per_px = 2 * half_height() / std::max(1.0f, viewport_h_px);
  target_ += m_per_px * (-dx_px * right + dy_px * up);
}

void Camera::zoom(float wheel_steps) {
  distance_ = std::clamp(distance_ * std::pow(0.88f, wheel_steps), 0.05f * radius_, 40.0f * radius_);
}

}  // namespace mc::viewer
