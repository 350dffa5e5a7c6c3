#pragma once
// TriMesh: the render-ready triangle mesh every producer hands to consumers (feather meshing -> coat
// assembly -> renderer / OBJ-PLY export). Struct of arrays; an attribute array is either empty or has
// one entry per vertex. Pure data: no GL, no OpenMesh.
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <cstdint>
#include <vector>

namespace pteryla {

struct TriMesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;   // unit, per vertex
  std::vector<glm::vec3> tangents;  // barb (or shaft) direction, for the anisotropic BRDF
  std::vector<glm::vec2> uvGlobal;  // feather-global texture coordinates (7.1.1)
  std::vector<glm::vec2> uvBarb;    // barb-local texture coordinates
  std::vector<glm::vec2> uvGrowth;  // growth mapping: u around the pin cone, v along the shaft
  std::vector<float> alpha;         // per-vertex alpha (7.1.2)
  std::vector<float> sheath;        // pin-feather sheath weight in [0,1] (8.1)
  std::vector<float> barbCount;     // barbs represented by the polygon (alpha texture repeat)
  std::vector<uint32_t> featherId;  // which feather of the coat a vertex belongs to
  std::vector<uint32_t> indices;    // 3 per triangle

  size_t vertexCount() const { return positions.size(); }
  size_t triangleCount() const { return indices.size() / 3; }
  bool empty() const { return indices.empty(); }
  void clear() { *this = TriMesh(); }
  // Appends `other`, offsetting its indices. Attribute arrays present in only one side are padded
  // with defaults (alpha 1, sheath 0, barbCount 1, zeros otherwise) so the result stays consistent.
  void append(const TriMesh& other);
  // Axis-aligned bounds; returns false for an empty mesh.
  bool bounds(glm::vec3& lo, glm::vec3& hi) const;
};

}  // namespace pteryla
