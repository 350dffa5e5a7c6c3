#include "picking.hpp"

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

namespace pteryla::viewer {

std::optional<SurfaceHit> raycast(const TriMesh& mesh, const Ray& ray) {
  std::optional<SurfaceHit> best;
  float bestT = std::numeric_limits<float>::infinity();
  const size_t n = mesh.triangleCount();
  for (size_t t = 0; t < n; ++t) {
    const glm::vec3& a = mesh.positions[mesh.indices[3 * t]];
    const glm::vec3& b = mesh.positions[mesh.indices[3 * t + 1]];
    const glm::vec3& c = mesh.positions[mesh.indices[3 * t + 2]];
    const glm::vec3 e1 = b - a, e2 = c - a;
    const glm::vec3 pv = glm::cross(ray.direction, e2);
    const float det = glm::dot(e1, pv);
    if (std::abs(det) < 1e-12f) continue;
    const float inv = 1.0f / det;
    const glm::vec3 tv = ray.origin - a;
    const float u = glm::dot(tv, pv) * inv;
    if (u < 0.0f || u > 1.0f) continue;
    const glm::vec3 qv = glm::cross(tv, e1);
    const float v = glm::dot(ray.direction, qv) * inv;
    if (v < 0.0f || u + v > 1.0f) continue;
    const float d = glm::dot(e2, qv) * inv;
    if (d <= 0.0f || d >= bestT) continue;
    bestT = d;
    SurfaceHit h;
    h.point = ray.origin + d * ray.direction;
    glm::vec3 nrm = glm::cross(e1, e2);
    const float len = glm::length(nrm);
    nrm = len > 0 ? nrm / len : glm::vec3(0, 0, 1);
    if (glm::dot(nrm, ray.direction) > 0) nrm = -nrm;
    h.normal = nrm;
    h.triangle = static_cast<uint32_t>(t);
    h.distance = d;
    best = h;
  }
  return best;
}

int pickPoint(const std::vector<glm::vec3>& points, const std::vector<glm::vec3>& normals, const render::Camera& camera,
              const glm::ivec2& viewport, const glm::vec2& pixel, float maxPixels) {
  int best = -1;
  float bestD2 = maxPixels * maxPixels;
  for (size_t i = 0; i < points.size(); ++i) {
    if (i < normals.size() && glm::dot(normals[i], camera.eye - points[i]) < 0.0f) continue;
    glm::vec2 q;
    if (!projectToPixel(camera, points[i], viewport, q)) continue;
    const glm::vec2 d = q - pixel;
    const float d2 = glm::dot(d, d);
    if (d2 <= bestD2) {
      bestD2 = d2;
      best = static_cast<int>(i);
    }
  }
  return best;
}

int pickFeather(const TriMesh& coat, const TriMesh& skin, const Ray& ray) {
  if (coat.featherId.size() != coat.positions.size()) return -1;
  const auto hit = raycast(coat, ray);
  if (!hit) return -1;
  const auto body = raycast(skin, ray);
  if (body && body->distance < hit->distance) return -1;
  return static_cast<int>(coat.featherId[coat.indices[3 * size_t(hit->triangle)]]);
}

}  // namespace pteryla::viewer
