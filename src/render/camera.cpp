// Camera framing and the screen-size hook for continuous level of detail (Streit 2003, 7.1.3).
#include "pteryla/render/camera.hpp"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

namespace pteryla::render {

glm::vec3 Camera::forward() const {
  const glm::vec3 f = target - eye;
  const float len = glm::length(f);
  return len > 0.0f ? f / len : glm::vec3(0.0f, 0.0f, -1.0f);
}

glm::mat4 Camera::view() const {
  glm::vec3 u = up;
  if (glm::length(glm::cross(forward(), u)) < 1e-6f)
    u = std::abs(forward().y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  return glm::lookAt(eye, eye + forward(), u);
}

glm::mat4 Camera::projection(float aspect) const {
  return glm::perspective(glm::radians(fovYDegrees), std::max(aspect, 1e-6f), zNear, zFar);
}

void Camera::frameBounds(const glm::vec3& lo, const glm::vec3& hi, float aspect, float margin) {
  const glm::vec3 centre = 0.5f * (lo + hi);
  float radius = 0.5f * glm::length(hi - lo);
  if (!(radius > 0.0f)) radius = 1.0f;
  const glm::vec3 dir = forward();
  const float halfY = glm::radians(fovYDegrees) * 0.5f;
  const float halfX = std::atan(std::tan(halfY) * std::max(aspect, 1e-6f));
  const float half = std::min(halfX, halfY);
  const float dist = margin * radius / std::sin(half);
  target = centre;
  eye = centre - dir * dist;
  zNear = std::max(1e-4f * dist, dist - radius * 1.5f);
  zFar = dist + radius * 1.5f;
}

float screenSizeOf(const glm::vec3& lo, const glm::vec3& hi, const Camera& camera, const glm::ivec2& viewport) {
  return screenSizeOfSphere(0.5f * (lo + hi), 0.5f * glm::length(hi - lo), camera, viewport);
}

float screenSizeOfSphere(const glm::vec3& centre, float radius, const Camera& camera, const glm::ivec2& viewport) {
  const float dist = glm::length(centre - camera.eye);
  const float h = static_cast<float>(std::max(viewport.y, 1));
  if (dist <= radius) return h;
  // Angular diameter of the sphere against the vertical field of view.
  const float angular = 2.0f * std::asin(radius / dist);
  const float fov = glm::radians(camera.fovYDegrees);
  return h * std::tan(0.5f * angular) / std::tan(0.5f * fov);
}

float lodFraction(float screenPixels, float fullDetailPixels, float minFraction) {
  if (!(fullDetailPixels > 0.0f)) return 1.0f;
  const float f = screenPixels / fullDetailPixels;
  return std::clamp(f, std::clamp(minFraction, 0.0f, 1.0f), 1.0f);
}

}  // namespace pteryla::render
