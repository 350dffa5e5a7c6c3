#pragma once
// Picking in the 3D view: a ray against the skin's triangles (placing key feathers, styling vectors,
// brushes and controls on the body) and the nearest projected point (selecting follicles).
// Pure CPU math over TriMesh; brute force is fast enough for skins of ~10k triangles.
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "camera_controller.hpp"
#include "pteryla/core/trimesh.hpp"

namespace pteryla::viewer {

struct SurfaceHit {
  glm::vec3 point{0};
  glm::vec3 normal{0, 0, 1};  // geometric normal of the hit triangle, facing the ray origin
  uint32_t triangle = 0;
  float distance = 0;
};
// Nearest intersection of the ray with the mesh's triangles (Moller-Trumbore, both sides).
std::optional<SurfaceHit> raycast(const TriMesh& mesh, const Ray& ray);

// The feather a ray meets first: the coat triangle it hits (its featherId), unless the skin is hit
// nearer (the feather is behind the body). -1 when it hits no feather or the coat has no feather ids.
int pickFeather(const TriMesh& coat, const TriMesh& skin, const Ray& ray);

// Index of the point whose projection is nearest `pixel`, within `maxPixels`; points facing away from
// the eye (dot(normal, eye - p) < 0, when normals are given) are skipped. -1 when none.
int pickPoint(const std::vector<glm::vec3>& points, const std::vector<glm::vec3>& normals, const render::Camera& camera,
              const glm::ivec2& viewport, const glm::vec2& pixel, float maxPixels);

}  // namespace pteryla::viewer
