#pragma once
// Feather surface generation (Streit 2003, 5.3, 7.1.1, 7.1.2): barb curves -> render-ready TriMesh at any
// level of detail (lod.hpp) and any age (growth.hpp).
//
// Vane surface. Each kept barb is a polyline of `segments` segments (the tessellation parameter) and
// the centre row of a ribbon made of two triangle strips, one on each side. The side rows are shared
// with the neighbouring kept barb (the midpoint of the two barbs at equal curve parameter), so a vane
// is one connected surface between splits. At a split (BarbCurve::splitAfter) and at the vane ends
// the side row is not shared: it mirrors the barb's other half-gap to its original neighbour, leaving
// a boundary edge along the split (no triangle bridges a split). Triangles per kept barb:
// 2 strips x 2 x segments; at full detail a vane of n barbs has 4 n segments triangles.
//
// Shaft. Calamus and rachis form one tapered generalized cylinder of `shaftSides` sides over the
// shaft polyline (no seam between them: the calamus width comes from the width ratio) that closes to a
// point at the rachis tip. The follicle end is open (it sits in the skin).
//
// Attributes (TriMesh):
//  normals    vane normal (dorsal side for a regular vane; winding agrees), radial on the shaft
//  tangents   barb direction on the vane, shaft direction on the shaft
//  uvGlobal   feather-global map (7.1.1), shaft curvature ignored: u = 0.5 - across / (2 maxAcross)
//             (0 left-vane edge, 0.5 rachis, 1 right-vane edge), v = along-shaft distance from the
//             follicle normalized to the feather's extent (0 base, 1 tip)
//  uvBarb     barb-glued map: u along the barb from the rachis edge (at t = 0) to the barb tip's
//             global u (left vane u < 0.5, right u > 0.5), v = the barb's rp (rachis rp on the shaft)
//  uvGrowth   growth map: u around the pin-feather cone (0.5 dorsal at the rachis, barb tips at the
//             ventral seam: left vane 0.5 -> 0, right 0.5 -> 1), v = distance from the follicle in the
//             closed pin pose (attachment arc length + t * barb length) over the largest such distance
//  alpha      1, falling quadratically to MeshOptions::alphaTip at the barb tip over the last segment
//             of a full-detail barb on the centre row and over the last two on the side rows (7.1.2)
//  sheath     pin-feather sheath weight from FeatherMeshInput::sheathShed (0 when mature)
//  barbCount  original barbs the ribbon at this vertex stands for (1 at full detail; at lower detail an
//             alpha texture repeats this many times across the ribbon)
//  featherId  FeatherMeshInput::featherId
// All texture coordinates lie in [0, 1] and come from the reference (mature, open) feather when one is
// given, so pigment travels with the barbs while a feather grows (8.1).
//
// Ranges: per feather, index ranges (offsets into TriMesh::indices, counts in indices) of the main
// shaft, left vane and right vane, and of the whole afterfeather. Vane triangles are in barb order base
// to tip, each ribbon from the rachis to the barb tip, so a renderer can draw the vanes in view
// dependent order (7.1.2) by choosing the vane order and walking a range forward or backward.
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "pteryla/core/trimesh.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/lod.hpp"
#include "pteryla/feather/params.hpp"

namespace pteryla::feather {

struct MeshOptions {
  int barbSegments = 4;          // polyline segments per barb at full detail, 1..64
  int minBarbSegments = 2;       // segments per barb at the lowest detail
  double segmentLodStart = 0.5;  // below this level barbs lose segments (lodSegments)
  int shaftSides = 4;            // sides of the shaft cylinder, 3..64
  int minShaftSegments = 4;      // rachis segments at the lowest detail (ceil(lod * segments) above)
  bool shaft = true;             // mesh the calamus and rachis
  bool afterfeather = true;      // mesh the afterfeather when the curves have one
  double alphaTip = 0.0;         // alpha at the barb tips, [0, 1]
};
// Throws pteryla::Error (element "mesh.<option>") for out-of-range options.
void validateMeshOptions(const MeshOptions& opt);

// Feather-local -> world: world(p) = origin + p.x * x + p.y * y + p.z * z. For a follicle frame with
// elevation (docs/architecture.md) x = T', y = B, z = N'. Axes may be scaled; normals use the inverse
// transpose.
struct FeatherPlacement {
  glm::dvec3 origin{0.0};
  glm::dvec3 x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
  // Follicle frame (T, N unit, orthogonal) raised by `elevation` radians about B = N x T.
  static FeatherPlacement fromFollicle(const glm::dvec3& origin, const glm::dvec3& T, const glm::dvec3& N,
                                       double elevation = 0, double scale = 1);
};

struct FeatherMeshRanges {
  uint32_t shaftFirst = 0, shaftCount = 0;
  uint32_t leftFirst = 0, leftCount = 0;
  uint32_t rightFirst = 0, rightCount = 0;
  uint32_t afterFirst = 0, afterCount = 0;  // whole afterfeather (shaft, left, right in that order)
};

struct FeatherMeshInput {
  const FeatherCurves* curves = nullptr;     // required: the feather to mesh (any age)
  const FeatherCurves* reference = nullptr;  // mature, open feather for texture coordinates; null = curves
  const LodOrder* order = nullptr;           // computeLodOrder(*curves) (or of the mature feather while
                                             // growing: same barbs, stable LOD); null = computed per call
  FeatherPlacement placement;
  uint32_t featherId = 0;
  double lod = 1;            // fraction of geometry, (0, 1]
  double sheathShed = 1;     // GrowthState[GrowthParam::Sheath]; 1 = no sheath
  double sheathBand = 0.05;  // GrowthSchedule::sheathBand
  // Write positions, normals and tangents before placement (`placement` is ignored): placeFeatherVertices
  // places them later exactly as meshing with a placement would, so a coat can move a feather without
  // meshing it again. Every other attribute and the indices do not depend on the placement.
  bool unplaced = false;
};

struct FeatherMeshSize {
  size_t vertices = 0, indices = 0;
};

// What a level of detail decides of a feather's mesh: the barbs kept, the barb segments and the shaft
// points of each part. Meshing depends on FeatherMeshInput::lod through these alone, so two inputs with
// the same curves, LOD order, reference, sheath and level mesh to the same vertices and indices (but
// for featherId, and positions where placed differently).
struct FeatherMeshLevel {
  uint32_t keep = 0;
  int segs = 0;
  std::vector<int> shaft;  // the shaft points kept, part after part, each part's list ended by -1
  bool operator==(const FeatherMeshLevel& o) const { return keep == o.keep && segs == o.segs && shaft == o.shaft; }
};
FeatherMeshLevel featherMeshLevel(const FeatherMeshInput& in, const MeshOptions& opt);
// Exact size appendFeatherMesh will add.
FeatherMeshSize featherMeshSize(const FeatherMeshInput& in, const MeshOptions& opt);

// Appends one feather to `out` (all attribute arrays of `out` end up with one entry per vertex).
void appendFeatherMesh(const FeatherMeshInput& in, const MeshOptions& opt, TriMesh& out,
                       FeatherMeshRanges* ranges = nullptr);
void appendFeatherMesh(const FeatherCurves& curves, const MeshOptions& opt, const FeatherPlacement& placement,
                       uint32_t featherId, TriMesh& out, FeatherMeshRanges* ranges = nullptr);
// Many feathers at once, in parallel (TBB): sizes, one resize of `out`, then every feather written
// into its own slice. Same result as appending them one by one. `ranges` (optional) gets `count` entries.
void appendFeatherMeshes(const FeatherMeshInput* inputs, size_t count, const MeshOptions& opt, TriMesh& out,
                         std::vector<FeatherMeshRanges>* ranges = nullptr);

// Places vertices written with FeatherMeshInput::unplaced: out = what meshing with `placement` writes,
// bit for bit. Input and output arrays must not overlap.
void placeFeatherVertices(const FeatherPlacement& placement, const glm::vec3* positions, const PackedDir* normals,
                          const PackedDir* tangents, size_t count, glm::vec3* outPositions, PackedDir* outNormals,
                          PackedDir* outTangents);

// Single-feather convenience (CLI `pteryla feather`): the feather at `age` (growth.hpp) at level `lod`
// in (0, 1], texture coordinates from the mature feather, in feather-local coordinates.
TriMesh buildFeatherMesh(const FeatherParams& p, double age, double lod, const MeshOptions& opt = {},
                         const GrowthSchedule& schedule = defaultGrowthSchedule(), FeatherMeshRanges* ranges = nullptr);

}  // namespace pteryla::feather
