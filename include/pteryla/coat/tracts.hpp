#pragma once
// Tracts (pterylae): named sets of skin faces that carry feathers (Streit 2003, 6.1: "groups of polygons
// that belong to each feather tract. A polygon can belong to more than one tract, and thus the tracts can
// overlap ... set operators on both individual and groups of polygons"). The JSON form is documented in
// docs/tracts.md. Follicles are distributed and relaxed tract by tract.
#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "pteryla/coat/skin.hpp"
#include "pteryla/core/json.hpp"

namespace pteryla::coat {

struct Tract {
  std::string name;
  std::vector<uint32_t> faces;  // sorted, unique indices into SkinMesh::faces (triangles)

  size_t size() const { return faces.size(); }
  bool contains(uint32_t face) const;  // binary search
};

// The default tract: every face of the mesh.
Tract wholeMeshTract(const SkinMesh& mesh, const std::string& name = "all");
// Faces of the named OBJ groups (union). Unknown names throw, listing the mesh's groups.
Tract tractFromGroups(const SkinMesh& mesh, const std::string& name, const std::vector<std::string>& groups);
// Faces that came from the given source polygons (indices as in the file, see SkinMesh::sourceFace).
Tract tractFromSourceFaces(const SkinMesh& mesh, const std::string& name, const std::vector<int64_t>& sourceFaces);
// Faces whose source polygon's label is one of `wanted` (labels: one per source polygon).
Tract tractFromLabels(const SkinMesh& mesh, const std::string& name, const std::vector<int64_t>& labels,
                      const std::vector<int64_t>& wanted);

// Per-face label file: one integer per source polygon in file order, separated by any whitespace (one
// per line is conventional); '#' starts a comment to the end of the line; negative = unlabelled.
// Throws Error(file, "line N") for a token that is not an integer and for a count != expectedCount.
std::vector<int64_t> readFaceLabels(const std::string& path, size_t expectedCount);

Tract tractUnion(const Tract& a, const Tract& b, const std::string& name = {});
Tract tractIntersection(const Tract& a, const Tract& b, const std::string& name = {});
Tract tractDifference(const Tract& a, const Tract& b, const std::string& name = {});  // a minus b

// Builds one tract from the selection keys of a JSON object (docs/tracts.md): name, all, groups, faces,
// labels_file, label, union, intersect, subtract. Names in union/intersect/subtract refer to tracts in
// `earlier` first, then to mesh groups. Reads only these keys and does NOT call finish(), so the caller
// (the scene parser) can read its own per-tract keys (density, bias, ...) from the same object.
// labels_file is resolved relative to r.file().
Tract readTract(JsonReader& r, const SkinMesh& mesh, const std::vector<Tract>& earlier);
// A list of tract objects in order; later ones may refer to earlier ones. Rejects duplicate names.
// Does not call finish() on the items.
std::vector<Tract> readTracts(std::vector<JsonReader>& items, const SkinMesh& mesh);
// A stand-alone tract file {"tracts": [ ... ]}; unknown keys are rejected. An empty list gives the
// whole-mesh tract.
std::vector<Tract> loadTractFile(const std::string& path, const SkinMesh& mesh);

// Geometry helpers used by scattering, relaxation and metrics.
double tractArea(const SkinMesh& mesh, const Tract& tract);
std::vector<uint8_t> tractFaceMask(const SkinMesh& mesh, const Tract& tract);  // 1 per face in the tract
// Edges of tract faces whose other side is a mesh boundary or a face outside the tract, as segments.
std::vector<std::array<glm::dvec3, 2>> tractBoundarySegments(const SkinMesh& mesh, const Tract& tract);
// Bit c of entry k is set when edge c (corner c -> c+1) of tract.faces[k] is a tract boundary edge.
std::vector<uint8_t> tractBoundaryEdgeBits(const SkinMesh& mesh, const Tract& tract);

}  // namespace pteryla::coat
