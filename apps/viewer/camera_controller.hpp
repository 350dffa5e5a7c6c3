#pragma once
// Orbit / pan / zoom camera for the viewer: the eye moves on a sphere around a target, with the scene's
// up vector kept vertical (turntable), so orbiting never rolls the view. Produces a render::Camera.
// Pure math (no GL, no windowing): the app feeds it mouse deltas in pixels.
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "pteryla/render/camera.hpp"

namespace pteryla::viewer {

class CameraController {
 public:
  // Starts from a camera (e.g. render::sceneCamera of the scene): keeps its eye, target, up and fov.
  void set(const render::Camera& c);
  const render::Camera& camera() const { return camera_; }

  // Turntable rotation: yaw about `up` through the target, pitch about the view's right axis (clamped
  // 1 degree short of the poles). Radians.
  void orbit(float yaw, float pitch);
  // Mouse-drag versions: `pixels` moved in a viewport `height` pixels tall (a full-height drag turns
  // by pi for orbit, moves the target by the visible height for pan).
  void orbitPixels(const glm::vec2& pixels, float height);
  void panPixels(const glm::vec2& pixels, float height);
  // Moves the eye toward (factor < 1) or away from (factor > 1) the target.
  void zoom(float factor);
  // Frame all: aims at the box and backs off until it fits (render::Camera::frameBounds).
  void frame(const glm::vec3& lo, const glm::vec3& hi, float aspect);

  float distance() const;

 private:
  void updateClip();
  render::Camera camera_;
  float radius_ = 1.0f;  // scene radius from the last frame(), for clip planes
};

// A world-space ray through a pixel (pixel (0,0) = top-left, as window coordinates).
struct Ray {
  glm::vec3 origin{0}, direction{0, 0, -1};
};
Ray pixelRay(const render::Camera& c, const glm::vec2& pixel, const glm::ivec2& viewport);
// Window pixel of a world point; returns false when it is behind the eye.
bool projectToPixel(const render::Camera& c, const glm::vec3& p, const glm::ivec2& viewport, glm::vec2& pixel);

}  // namespace pteryla::viewer
