#pragma once
// Key-feather interpolation (Streit 2003, 6.2): the user places a few designed key feathers at follicles
// of a tract; a 2D Delaunay triangulation of the key follicles in the tract's (u,v) parameterization
// (parameterize.hpp) gives every follicle a triangle, and its feather is the barycentric blend of the
// triangle's three key feathers (feather::blendFeathers). Follicles outside the convex hull of the keys
// blend the two key feathers of the nearest hull edge (clamped to its ends); a tract with one key feather
// is constant, one whose keys are collinear blends along the chain of keys.
//
// A follicle that carries a key feather gets exactly that feather (no blending, no jitter), and so does a
// follicle whose weight for one key is 1 (within 1e-12). Every other feather may be scaled by a per-
// follicle factor in [1 - scaleJitter, 1 + scaleJitter] drawn from hashUniform(seed, follicle id, ...); the
// factor multiplies every length of the feather (calamus, rachis length and width, barb length,
// silhouette lengths, barb spacing, and the afterfeather's), so a jittered feather is a similar copy.
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/parameterize.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/feather/params.hpp"

namespace pteryla::coat {

// Feather definitions by name (the scene's "feathers" section).
using FeatherLibrary = std::map<std::string, feather::FeatherParams>;

// A key feather as written in a scene: at a follicle (its stable Follicles::id) or at the follicle of the
// tract nearest to a point in space.
struct KeyFeatherSpec {
  std::string feather;  // name in the FeatherLibrary
  bool byFollicle = false;
  uint64_t follicleId = 0;  // byFollicle: Follicles::id
  glm::dvec3 at{0.0};       // !byFollicle: scene units
  std::string element;      // JSON path for errors, e.g. "tracts[2].key_feathers[1]"
};

// A key feather resolved to a follicle of its tract.
struct KeyFeather {
  uint32_t follicle = 0;  // index into Follicles
  std::string feather;    // name in the FeatherLibrary
};

// Per-tract settings read from a tract object (see parseTractFeatherOptions).
struct TractFeatherOptions {
  ParameterizeOptions parameterization;
  std::vector<KeyFeatherSpec> keys;
  std::string feather;       // the tract's feather when it has no key feathers ("" = the library's only one)
  double scaleJitter = 0.0;  // relative, in [0, 1)
};

// Resolves key feathers of a tract: ids must be follicles of this tract, points pick the nearest
// follicle of the tract (ties: lowest index); feather names must be in the library; two keys on one
// follicle, or on follicles with the same (u,v), are rejected. With no keys, `defaultFeather` (or the
// library's only feather) is placed on the tract's first follicle. Errors name spec.element and `file`.
std::vector<KeyFeather> resolveKeyFeathers(const Follicles& follicles, const TractParameterization& param,
                                           const std::vector<KeyFeatherSpec>& specs, const FeatherLibrary& library,
                                           const std::string& tractName, const std::string& defaultFeather = {},
                                           const std::string& file = {});

// Delaunay triangulation of key positions in (u,v) (CGAL, exact predicates). Positions must be distinct.
struct KeyTriangulation {
  std::vector<glm::dvec2> keys;
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise; empty when the keys are collinear
  std::vector<std::array<uint32_t, 2>> hullEdges;  // convex hull edges, or the chain of collinear keys
};
KeyTriangulation triangulateKeys(const std::vector<glm::dvec2>& keys);

// Up to three keys and their weights: non-negative, sum 1, unused slots have weight 0 and key = key[0].
struct BlendWeights {
  std::array<uint32_t, 3> key{0, 0, 0};
  std::array<double, 3> weight{1, 0, 0};
  uint8_t count = 1;   // 1 (a single key), 2 (hull edge / collinear chain) or 3 (triangle)
  bool inside = true;  // false when the point lies outside the keys' convex hull
};
BlendWeights locateInKeys(const KeyTriangulation& tri, const glm::dvec2& p);

struct InterpolateOptions {
  uint64_t seed = 1;  // scale jitter
};

struct InterpolateStats {
  size_t feathers = 0;
  size_t copied = 0;       // exact copies of a key feather
  size_t blended = 0;      // blends of 2 or 3 key feathers
  size_t outsideHull = 0;  // follicles outside their tract's key hull
};

// Inputs of one tract for interpolateCoatFeathers.
struct TractKeys {
  const TractParameterization* param = nullptr;  // required
  std::vector<KeyFeather> keys;                  // resolved, non-empty
  double scaleJitter = 0.0;
};

// One feather per follicle that appears in a tract's parameterization, in ascending follicle order.
// Fills coat.follicle, .tract, .params, .age (1), .present (1), .frames (origin and normal from the
// follicle caches, an arbitrary tangent until evaluateFrames() in directions.hpp) and clears .layerOrder
// (see ordering.hpp).
// Blends run in parallel; the result does not depend on the thread count.
InterpolateStats interpolateCoatFeathers(const Follicles& follicles, const std::vector<TractKeys>& tracts,
                                         const FeatherLibrary& library, const InterpolateOptions& options,
                                         CoatFeathers& coat);

// Weights of every follicle of a tract (param.follicles order): a key follicle gets exactly its key.
std::vector<BlendWeights> tractBlendWeights(const TractParameterization& param, const std::vector<KeyFeather>& keys);

// Multiplies every length of p (and its afterfeather's) by s > 0.
void scaleFeather(feather::FeatherParams& p, double s);

// JSON (docs/coat.md). One key feather object: {"feather": name, "follicle": id} or
// {"feather": name, "at": [x,y,z]}; calls r.finish().
KeyFeatherSpec parseKeyFeather(JsonReader& r);
// The optional "key_feathers" array of a tract object (does not finish the tract reader).
std::vector<KeyFeatherSpec> parseKeyFeathers(JsonReader& tract);
// The optional per-tract keys "parameterization" (object), "key_feathers", "feather", "scale_jitter" of
// a tract object. Does not call tract.finish(): the scene parser reads the tract's other keys too.
TractFeatherOptions parseTractFeatherOptions(JsonReader& tract);

}  // namespace pteryla::coat
