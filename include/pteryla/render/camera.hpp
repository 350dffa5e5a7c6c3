#pragma once
// Camera, lights and the level-of-detail hook (thesis 7.1.3: callers choose how much feather
// geometry to generate from how large a feather appears on screen). Pure math: no GL.
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace pteryla::render {

struct Camera {
  glm::vec3 eye{0.0f, 0.0f, 5.0f};
  glm::vec3 target{0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float fovYDegrees = 40.0f;  // vertical field of view, degrees
  float zNear = 0.01f;        // scene units
  float zFar = 100.0f;        // scene units

  glm::mat4 view() const;                    // right-handed look-at
  glm::mat4 projection(float aspect) const;  // OpenGL clip space, aspect = width / height
  glm::vec3 forward() const;                 // unit, eye -> target

  // Aims at the centre of the box [lo, hi] and moves the eye back along the current viewing
  // direction until the box's bounding sphere fits the view (both fields of view), times `margin`.
  // Sets zNear / zFar to bracket the sphere. A degenerate box is treated as a unit sphere.
  void frameBounds(const glm::vec3& lo, const glm::vec3& hi, float aspect = 1.0f, float margin = 1.05f);
};

// A directional light. `direction` points from the surface toward the light (need not be unit).
// `color` is the radiance scale: a white Lambertian surface facing the light reflects `color`.
struct Light {
  glm::vec3 direction{0.3f, 0.5f, 1.0f};
  glm::vec3 color{1.0f};
};

// Projected diameter in pixels of the bounding sphere of the box [lo, hi], seen by `camera` in a
// viewport of `viewport` pixels (perspective, vertical field of view). Returns the viewport height
// when the eye is inside the sphere.
float screenSizeOf(const glm::vec3& lo, const glm::vec3& hi, const Camera& camera, const glm::ivec2& viewport);
// The same for the sphere of `radius` about `centre`.
float screenSizeOfSphere(const glm::vec3& centre, float radius, const Camera& camera, const glm::ivec2& viewport);

// Continuous level of detail from screen size: 1 at or above `fullDetailPixels`, falling linearly
// with the projected size down to `minFraction`. The thesis shows 60% geometry plus the alpha and
// BRDF textures keeping the look of a feather (Fig. 7.4).
float lodFraction(float screenPixels, float fullDetailPixels = 400.0f, float minFraction = 0.1f);

}  // namespace pteryla::render
