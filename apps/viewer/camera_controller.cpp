#include "camera_controller.hpp"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

namespace pteryla::viewer {
namespace {
glm::vec3 rotateAbout(const glm::vec3& v, float angle, const glm::vec3& axis) {
  return glm::vec3(glm::rotate(glm::mat4(1.0f), angle, axis) * glm::vec4(v, 0.0f));
}
}  // namespace

void CameraController::set(const render::Camera& c) {
  camera_ = c;
  if (!(glm::length(camera_.up) > 0)) camera_.up = {0, 1, 0};
  camera_.up = glm::normalize(camera_.up);
  radius_ = std::max(0.5f * (camera_.zFar - camera_.zNear) / 1.5f, 1e-3f);
  updateClip();
}

float CameraController::distance() const { return glm::length(camera_.eye - camera_.target); }

void CameraController::updateClip() {
  const float d = std::max(distance(), 1e-6f);
  camera_.zNear = std::max(1e-4f * d, d - radius_ * 1.5f);
  if (camera_.zNear <= 0) camera_.zNear = 1e-4f * d;
  camera_.zFar = d + radius_ * 1.5f;
}

void CameraController::orbit(float yaw, float pitch) {
  const glm::vec3 up = camera_.up;
  glm::vec3 offset = camera_.eye - camera_.target;
  const float dist = glm::length(offset);
  if (!(dist > 0)) return;
  offset = rotateAbout(offset, yaw, up);
  // Pitch: angle between the offset and up stays inside (1 deg, 179 deg).
  const float current = std::acos(std::clamp(glm::dot(offset / dist, up), -1.0f, 1.0f));
  const float lo = glm::radians(1.0f), hi = glm::radians(179.0f);
  const float target = std::clamp(current - pitch, lo, hi);
  glm::vec3 right = glm::cross(up, offset);
  if (glm::length(right) > 1e-9f) {
    right = glm::normalize(right);
    offset = rotateAbout(offset, target - current, right);
  }
  camera_.eye = camera_.target + offset;
  updateClip();
}

void CameraController::orbitPixels(const glm::vec2& pixels, float height) {
  const float h = std::max(height, 1.0f);
  orbit(-pixels.x / h * 3.14159265f, pixels.y / h * 3.14159265f);
}

void CameraController::panPixels(const glm::vec2& pixels, float height) {
  const float h = std::max(height, 1.0f);
  const glm::vec3 f = camera_.forward();
  glm::vec3 right = glm::cross(f, camera_.up);
  if (glm::length(right) < 1e-9f) return;
  right = glm::normalize(right);
  const glm::vec3 upv = glm::normalize(glm::cross(right, f));
  const float visible = 2.0f * distance() * std::tan(glm::radians(camera_.fovYDegrees) * 0.5f);
  const glm::vec3 move = (-pixels.x * right + pixels.y * upv) * (visible / h);
  camera_.eye += move;
  camera_.target += move;
}

void CameraController::zoom(float factor) {
  if (!(factor > 0) || !std::isfinite(factor)) return;
  const glm::vec3 offset = camera_.eye - camera_.target;
  const float d = glm::length(offset);
  const float nd = std::clamp(d * factor, 1e-4f * radius_, 1e3f * radius_);
  camera_.eye = camera_.target + offset * (nd / std::max(d, 1e-12f));
  updateClip();
}

void CameraController::frame(const glm::vec3& lo, const glm::vec3& hi, float aspect) {
  camera_.frameBounds(lo, hi, aspect, 1.05f);
  radius_ = std::max(0.5f * glm::length(hi - lo), 1e-3f);
  updateClip();
}

Ray pixelRay(const render::Camera& c, const glm::vec2& pixel, const glm::ivec2& viewport) {
  const float w = float(std::max(viewport.x, 1)), h = float(std::max(viewport.y, 1));
  const glm::mat4 inv = glm::inverse(c.projection(w / h) * c.view());
  const float x = 2.0f * pixel.x / w - 1.0f, y = 1.0f - 2.0f * pixel.y / h;
  glm::vec4 a = inv * glm::vec4(x, y, -1.0f, 1.0f), b = inv * glm::vec4(x, y, 1.0f, 1.0f);
  a /= a.w;
  b /= b.w;
  Ray r;
  r.origin = glm::vec3(a);
  r.direction = glm::normalize(glm::vec3(b - a));
  return r;
}

bool projectToPixel(const render::Camera& c, const glm::vec3& p, const glm::ivec2& viewport, glm::vec2& pixel) {
  const float w = float(std::max(viewport.x, 1)), h = float(std::max(viewport.y, 1));
  const glm::vec4 q = c.projection(w / h) * c.view() * glm::vec4(p, 1.0f);
  if (q.w <= 1e-9f) return false;
  pixel = {(q.x / q.w * 0.5f + 0.5f) * w, (0.5f - q.y / q.w * 0.5f) * h};
  return true;
}

}  // namespace pteryla::viewer
