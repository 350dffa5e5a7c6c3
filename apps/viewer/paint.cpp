#include "paint.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

#include <glm/geometric.hpp>

namespace pteryla::viewer {

namespace {
glm::vec3 vertexAt(const coat::SkinMesh& rest, const std::vector<glm::vec3>& posed, uint32_t v) {
  return posed.size() == rest.positions.size() ? posed[v] : glm::vec3(rest.positions[v]);
}
}  // namespace

std::vector<uint32_t> facesInBrush(const coat::SkinMesh& rest, const std::vector<glm::vec3>& posed,
                                   const glm::vec3& center, float radius) {
  std::vector<uint32_t> out;
  if (!(radius > 0)) return out;
  const float r2 = radius * radius;
  for (size_t t = 0; t < rest.faces.size(); ++t) {
    const auto& f = rest.faces[t];
    const glm::vec3 c =
        (vertexAt(rest, posed, f[0]) + vertexAt(rest, posed, f[1]) + vertexAt(rest, posed, f[2])) / 3.0f;
    const glm::vec3 d = c - center;
    if (glm::dot(d, d) <= r2) out.push_back(t < rest.sourceFace.size() ? rest.sourceFace[t] : uint32_t(t));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<uint32_t> faceUnion(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  std::vector<uint32_t> out;
  std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

std::vector<uint32_t> faceDifference(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
  std::vector<uint32_t> out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

void densityDab(std::vector<float>& factor, const coat::SkinMesh& rest, const std::vector<glm::vec3>& posed,
                const glm::vec3& center, float radius, float value, float strength) {
  factor.resize(rest.positions.size(), 1.0f);
  if (!(radius > 0)) return;
  strength = std::clamp(strength, 0.0f, 1.0f);
  for (uint32_t v = 0; v < factor.size(); ++v) {
    const float d = glm::length(vertexAt(rest, posed, v) - center) / radius;
    if (d >= 1.0f) continue;
    const float w = strength * (1.0f - d * d) * (1.0f - d * d);
    factor[v] += (value - factor[v]) * w;
  }
}

void quantizeDensity(std::vector<float>& factor) {
  for (float& f : factor) f = std::clamp(std::round(f * 1000.0f) / 1000.0f, 0.0f, 100.0f);
}

}  // namespace pteryla::viewer
