#pragma once
// TriMesh: the render-ready triangle mesh every producer hands to consumers (feather meshing -> coat
// assembly -> renderer / OBJ-PLY export). Struct of arrays; an attribute array is either empty or has
// one entry per vertex. Pure data: no GL, no OpenMesh. Attributes are kept in the smallest types exact
// enough for rendering and export (core/packed.hpp): unit vectors as 16-bit signed normalized integers,
// alpha, sheath and barb count as half floats; positions and texture coordinates stay float (16-bit texture
// coordinates flip nearest-texel look-ups at texel borders). 58 bytes per vertex, from 76
// (docs/limits.md).
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <cstdint>
#include <vector>

#include "pteryla/core/packed.hpp"

namespace pteryla {

struct TriMesh {
  std::vector<glm::vec3> positions;
  std::vector<PackedDir> normals;   // unit, per vertex
  std::vector<PackedDir> tangents;  // barb (or shaft) direction, for the anisotropic BRDF
  std::vector<glm::vec2> uvGlobal;  // feather-global texture coordinates (7.1.1)
  std::vector<glm::vec2> uvBarb;    // barb-local texture coordinates
  std::vector<glm::vec2> uvGrowth;  // growth mapping: u around the pin cone, v along the shaft
  std::vector<Half> alpha;          // per-vertex alpha (7.1.2)
  std::vector<Half> sheath;         // pin-feather sheath weight in [0,1] (8.1)
  std::vector<Half> barbCount;      // barbs represented by the polygon (alpha texture repeat; halves)
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
