#pragma once
// Synthetic feathers and coats: fixtures for the renderer's tests, goldens and benchmarks (and a
// viewer demo) until the feather and coat modules produce real meshes. Geometry follows the shared
// frames of docs/architecture.md (feather-local +x shaft, +y left vane, +z dorsal) and the TriMesh
// attribute conventions of renderer.hpp. Pure CPU code, deterministic.
#include <cstdint>
#include <vector>

#include "pteryla/core/trimesh.hpp"
#include "pteryla/render/renderer.hpp"

namespace pteryla::render {

// Unit-normal UV sphere (rings >= 2, segments >= 3).
TriMesh makeUvSphere(float radius, int rings, int segments);
// Same, scaled per axis into an ellipsoid (normals corrected).
TriMesh makeEllipsoid(const glm::vec3& radii, int rings, int segments);

struct SyntheticFeatherParams {
  float length = 1.0f;       // shaft length, scene units
  float width = 0.25f;       // longest barb
  int barbsPerVane = 22;     // at full detail
  int segmentsPerBarb = 4;   // each segment is 4 triangles (barb centre line + two fringe edges)
  float barbAngle = 0.85f;   // radians between shaft and barbs
  float cupping = 0.08f;     // vane edge drop toward -z, fraction of width
  float lodFraction = 1.0f;  // in (0,1]: keeps round(f * barbsPerVane) wider barbs per vane,
                             // each standing for 1/f barbs (barbCount)
  uint32_t featherId = 0;
};

struct SyntheticFeather {
  TriMesh mesh;                          // feather-local frame
  uint32_t partCount[4] = {0, 0, 0, 0};  // shaft, left vane, right vane, afterfeather (none)
};

SyntheticFeather makeSyntheticFeather(const SyntheticFeatherParams& params);

struct SyntheticCoatParams {
  int featherCount = 3150;
  glm::vec3 bodyRadii{1.0f, 0.55f, 0.6f};  // ellipsoid, head toward +x
  float featherLength = 0.32f;
  float featherWidth = 0.09f;
  float elevation = 0.12f;         // radians above the skin
  SyntheticFeatherParams feather;  // length/width overridden per feather; lodFraction used
  int materialCount = 1;           // materials assigned by hashing follicle index
  uint64_t seed = 7;
};

struct SyntheticCoat {
  TriMesh skin;
  TriMesh coat;
  std::vector<FeatherDrawRange> ranges;  // layer order: tail-most (bottom) feathers first
};

SyntheticCoat makeSyntheticCoat(const SyntheticCoatParams& params);

// Transforms a feather-local mesh into the world with frame (origin, X, Y, Z = X x Y).
void placeFeather(TriMesh& mesh, const glm::vec3& origin, const glm::vec3& axisX, const glm::vec3& axisY);

}  // namespace pteryla::render
