#pragma once
// Internal: polygon soup as read from a file, before validation/triangulation (skin.cpp).
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "pteryla/coat/skin.hpp"

namespace pteryla::coat::detail {

struct RawMesh {
  std::vector<glm::dvec3> positions;
  std::vector<uint32_t> polyIndices;     // vertex indices of all polygons, concatenated
  std::vector<uint32_t> polyOffsets{0};  // polygon p = polyIndices[polyOffsets[p] .. polyOffsets[p+1])
  std::vector<int32_t> polyGroup;        // per polygon, -1 none (may be empty)
  std::vector<std::string> groupNames;
  std::vector<glm::dvec2> cornerUVs;      // parallel to polyIndices, or empty
  std::vector<glm::dvec3> vertexNormals;  // per vertex, or empty (zero entries = missing)
  std::vector<uint32_t> polyLine;         // OBJ line of each polygon (for messages), or empty
  size_t polygonCount() const { return polyOffsets.size() - 1; }
};

// OBJ reader (own: OpenMesh's does not report g/o/usemtl groups).
RawMesh readObj(const std::string& path);
// PLY / OFF / STL through OpenMesh's readers with a capturing importer (no connectivity fix-ups).
RawMesh readWithOpenMesh(const std::string& path);
// PLY / OFF / STL: checks the header, declared counts (against the file size and the memory ceiling)
// and list lengths before OpenMesh reads the file; throws pteryla::Error naming the file and element.
void checkMeshFileStructure(const std::string& path);
// Validates / repairs and builds the SkinMesh.
SkinMesh buildSkinMesh(RawMesh raw, const MeshLoadOptions& options, const std::string& file);

}  // namespace pteryla::coat::detail
