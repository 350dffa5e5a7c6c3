#pragma once
// SkinMesh: the body surface follicles live on (Streit 2003, 6: "the model to be feathered is a polygonal
// mesh ... sufficiently subdivided so that feather tracts can be formed from subgroups of polygons").
//
// Contract: a SkinMesh is always triangulated, finite, free of degenerate faces, edge-manifold (every edge
// has one or two faces) and consistently oriented. Closed meshes of any genus and meshes with boundaries
// are fine; vertices where several fans meet (bow-ties) are allowed. loadSkinMesh / makeSkinMesh enforce
// this: a violation is a pteryla::Error naming the element ("face 17 (line 42)", "vertex 5") unless
// MeshLoadOptions::repair is set, in which case the documented repair is applied and logged in `repairs`.
//
// Indices: `faces` are triangles. `sourceFace[t]` is the polygon index in the file (0-based, file order)
// triangle t came from; per-face label files and JSON face lists refer to these source indices. Vertex
// indices are never renumbered (repair leaves welded/unused vertices in place, unreferenced), so per-vertex
// arrays aligned with the file's vertices stay valid.
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "pteryla/core/trimesh.hpp"

namespace pteryla::coat {

// Skin meshes are refused (pteryla::Error naming the vertex) when a coordinate exceeds kMaxMeshCoordinate,
// or when the farthest coordinate is more than kMaxMeshRange typical (median) edge lengths from the origin:
// feathers are meshed and rendered in 32-bit float, which cannot resolve them there (docs/limits.md).
constexpr double kMaxMeshCoordinate = 1e6;
constexpr double kMaxMeshRange = 1e4;

struct MeshLoadOptions {
  // Repair instead of rejecting: drop faces touching non-finite vertices, drop polygons with < 3 vertices,
  // weld vertices closer than weldTolerance, drop degenerate faces, drop faces that make an edge
  // non-manifold (the first two faces of an edge in file order are kept), re-orient faces consistently per
  // connected component (closed components outward). Out-of-range indices and non-orientable meshes stay
  // errors. Without repair, face orientation is kept exactly as in the file (it must be consistent).
  bool repair = false;
  double weldTolerance = 1e-9;         // relative to the bounding-box diagonal (repair only)
  double degenerateTolerance = 1e-14;  // face is degenerate when area < tol * diagonal^2
};

struct MeshRepairLog {
  size_t droppedNonFinite = 0;      // faces dropped because a vertex was NaN/inf
  size_t droppedShortPolygons = 0;  // polygons with fewer than 3 vertices
  size_t weldedVertices = 0;        // vertices merged into an earlier one
  size_t droppedDegenerate = 0;
  size_t droppedNonManifold = 0;
  size_t flippedFaces = 0;
  bool any() const {
    return droppedNonFinite + droppedShortPolygons + weldedVertices + droppedDegenerate + droppedNonManifold +
               flippedFaces >
           0;
  }
};

struct SkinMesh {
  std::vector<glm::dvec3> positions;
  std::vector<std::array<uint32_t, 3>> faces;      // counter-clockwise seen from the normal side
  std::vector<glm::dvec3> vertexNormals;           // unit; zero for vertices no face uses
  std::vector<glm::dvec3> faceNormals;             // unit
  std::vector<double> faceAreas;                   // scene units^2
  std::vector<std::string> groupNames;             // OBJ g (else o, else usemtl) names
  std::vector<int32_t> faceGroup;                  // per triangle: index into groupNames, -1 = none
  std::vector<uint32_t> sourceFace;                // per triangle: polygon index in the source file
  std::vector<std::array<glm::dvec2, 3>> faceUVs;  // per-corner texture coordinates; empty if the file has none
  // Adjacency, built once (connectivity never changes under deformation):
  std::vector<std::array<int32_t, 3>> faceNeighbors;  // face across edge (corner c -> c+1 mod 3), -1 = boundary
  std::vector<uint32_t> vertexFaceOffsets;            // CSR: faces around v are
  std::vector<uint32_t> vertexFaces;                  //   vertexFaces[vertexFaceOffsets[v] .. [v+1])
  size_t sourceFaceCount = 0;   // number of polygons in the source (label files must have this many lines)
  bool hasFileNormals = false;  // vertexNormals came from the file (recomputeGeometry replaces them)
  std::string file;             // source path, "" for in-memory meshes
  MeshRepairLog repairs;

  size_t vertexCount() const { return positions.size(); }
  size_t faceCount() const { return faces.size(); }
  double totalArea() const;
  // Group index by name, -1 if absent. A group whose OBJ `g` line listed several names ("g wing left")
  // is found by any one of them.
  int32_t findGroup(const std::string& name) const;
  bool groupMatches(int32_t group, const std::string& name) const;
};

// A point on the skin, stored so it rides along when the skin deforms.
struct SurfacePoint {
  uint32_t face = 0;
  glm::dvec3 bary{1.0 / 3.0};  // weights of faces[face][0..2], sum 1
};

// Loads OBJ (own reader: keeps g/o/usemtl groups, vt, vn), PLY, OFF, STL (OpenMesh readers).
// Polygons are triangulated (quads along the shorter diagonal, larger polygons as fans).
SkinMesh loadSkinMesh(const std::string& path, const MeshLoadOptions& options = {});

// Builds and validates an in-memory triangle mesh (generated meshes, tests). faceGroup is empty or one
// entry per face; groupNames may be empty when faceGroup is. Same checks and repairs as loadSkinMesh.
SkinMesh makeSkinMesh(std::vector<glm::dvec3> positions, std::vector<std::array<uint32_t, 3>> faces,
                      std::vector<std::string> groupNames = {}, std::vector<int32_t> faceGroup = {},
                      const MeshLoadOptions& options = {}, const std::string& file = {});

// Recomputes face normals, areas and area-weighted vertex normals from the current positions (call after
// deforming `positions`; connectivity is unchanged). Parallel, deterministic.
void recomputeGeometry(SkinMesh& mesh);

// Render mesh: positions, vertex normals, uvGlobal from faceUVs when present (corners are split then).
TriMesh toTriMesh(const SkinMesh& mesh);

glm::dvec3 pointAt(const SkinMesh& mesh, uint32_t face, const glm::dvec3& bary);
// Interpolated vertex normal, normalised (falls back to the face normal where it vanishes).
glm::dvec3 normalAt(const SkinMesh& mesh, uint32_t face, const glm::dvec3& bary);
// Interpolated texture coordinate; requires !faceUVs.empty().
glm::dvec2 uvAt(const SkinMesh& mesh, uint32_t face, const glm::dvec3& bary);
inline glm::dvec3 pointAt(const SkinMesh& mesh, const SurfacePoint& p) { return pointAt(mesh, p.face, p.bary); }

// Closest point on triangle (a,b,c) to p; writes its barycentric coordinates when bary != nullptr.
glm::dvec3 closestPointOnTriangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                                  glm::dvec3* bary = nullptr);
// Closest point on the given faces (all faces when `faces` is null). Linear scan: for occasional queries
// such as placing pinned follicles, not for inner loops.
SurfacePoint closestSurfacePoint(const SkinMesh& mesh, const glm::dvec3& p,
                                 const std::vector<uint32_t>* faces = nullptr);

}  // namespace pteryla::coat
