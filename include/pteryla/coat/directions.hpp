#pragma once
// Surface directions and follicle frames (Streit 2003, 6.3.1): each follicle gets a surface direction T
// (where its feather points), from either
//  - a body axis: a polyline from head to tail (the "medial axis of the body segment"); T is the
//    direction of the polyline segment closest to the follicle, projected onto the tangent plane; or
//  - styling vectors: a few object-space vectors placed on the body, blended with weights that fall off
//    with the Euclidean distance d from the follicle (Gaussian exp(-(d^2 - d_min^2) / (2 falloff^2)) when
//    falloff > 0, else inverse-distance-squared 1 / (d^2 + eps^2), eps = 1e-3 times the extent of the
//    vectors' positions) and the blend projected onto the tangent plane (thesis: "projecting an
//    interpolated object-space direction vector onto the surface"); or
//  - both, a combed axis: the axis everywhere, and near each styling vector its direction, with a local
//    Gaussian weight g_i = exp(-d_i^2 / (2 r_i^2)) (r_i = the vector's radius, else falloff). The vectors'
//    coverage W = 1 - prod(1 - g_i) blends A (the unit axis direction) with V (the unit g-weighted sum of
//    the vectors): (1 - W) A + W V. At a vector's position W = 1 (its direction exactly); far from every
//    vector W -> 0 (the axis). This is what the viewer's comb paints.
// Where that projection vanishes (the axis or the blend is parallel to the normal) the fallback vector
// is projected instead, and where that vanishes too, the follicle face's first edge.
//
// The frame is N (interpolated vertex normal), T, B = N x T (docs/architecture.md). To survive skin
// deformation the direction is stored per follicle in the follicle face's edge basis: at rest,
// T = a (p1 - p0) + b (p2 - p0) + c N; on a deformed face, T' = a (p1' - p0') + b (p2' - p0') projected
// onto the deformed tangent plane and normalised. At rest this gives back T exactly.
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/json.hpp"

namespace pteryla::coat {

struct StylingVector {
  glm::dvec3 at{0.0};         // scene units
  glm::dvec3 direction{0.0};  // object space, non-zero (its length is ignored)
  double radius = 0;          // scene units; over an axis, this vector's Gaussian reach (0 = the spec's falloff)
};

// One direction field: an axis, styling vectors, both (a combed axis: then every vector needs a radius or
// the spec a falloff), or neither (then the fallback everywhere).
struct DirectionSpec {
  std::vector<glm::dvec3> axis;  // body-axis polyline, head to tail, >= 2 distinct points
  std::vector<StylingVector> vectors;
  double falloff = 0.0;                 // scene units; 0 = inverse-distance-squared weights
  glm::dvec3 fallback{0.0, -1.0, 0.0};  // object-space direction where the field is undefined
};

struct DirectionOptions {
  DirectionSpec field;                                        // every tract not listed below
  std::vector<std::pair<std::string, DirectionSpec>> tracts;  // per-tract fields by tract name
};

// Rest directions of every follicle, in its face's edge basis.
struct SurfaceDirections {
  std::vector<glm::dvec2> faceCoords;  // (a, b) per follicle
  std::vector<uint8_t> usedFallback;   // 1 where the field was undefined (fallback or face edge)
  size_t fallbacks = 0;
};

// Object-space direction of a field at a point (before projection to the tangent plane). Zero when
// undefined (no axis and no vectors).
glm::dvec3 fieldDirection(const DirectionSpec& spec, const glm::dvec3& p);

// Evaluates the field of each follicle's tract (follicles.tract indexes `tracts`; names in
// options.tracts must exist) on the rest skin. Throws Error for bad specs (element "directions...").
SurfaceDirections computeSurfaceDirections(const SkinMesh& restSkin, const std::vector<Tract>& tracts,
                                           const Follicles& follicles, const DirectionOptions& options);

// Edge-basis coordinates of a tangent direction t at (face, bary) (the inverse of directionAt).
glm::dvec2 directionToFaceCoords(const SkinMesh& skin, uint32_t face, const glm::dvec3& bary, const glm::dvec3& t);
// Unit tangent at (face, bary) of the (possibly deformed) skin from edge-basis coordinates; orthogonal
// to normalAt(skin, face, bary). Falls back to the face's first edge when the coordinates vanish.
glm::dvec3 directionAt(const SkinMesh& skin, uint32_t face, const glm::dvec3& bary, const glm::dvec2& coords);
// Orthonormal right-handed frame (origin, N, T, B = N x T) at (face, bary) of the (possibly deformed) skin.
FeatherFrame follicleFrame(const SkinMesh& skin, uint32_t face, const glm::dvec3& bary, const glm::dvec2& coords);

// Re-evaluates coat.frames (one per feather, from its follicle) on `skin`, the rest or a deformed copy
// with the same connectivity (call recomputeGeometry after deforming). Parallel, deterministic.
void evaluateFrames(const SkinMesh& skin, const Follicles& follicles, const SurfaceDirections& directions,
                    CoatFeathers& coat);

// JSON (docs/coat.md): {"axis": [[x,y,z], ...]} and/or {"vectors": [{"at": [x,y,z], "direction": [x,y,z],
// "radius": r}, ...]} (radius optional), optional "falloff", "fallback", and "tracts": {"<tract name>": {same keys
// except "tracts"}}. Calls r.finish().
DirectionOptions parseDirections(JsonReader& r);
DirectionSpec parseDirectionSpec(JsonReader& r);  // one field, no "tracts"; calls r.finish()

}  // namespace pteryla::coat
