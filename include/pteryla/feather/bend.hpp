#pragma once
// A feather bent along its shaft (the dynamic chain of moult/chain.hpp): the placement's shaft axis
// (FeatherPlacement::x, from the follicle) carries joints 0..N at equal spacing over `length`; joint k
// >= 1 is displaced by offset[k - 1] (world). The shaft is the smooth curve through the displaced joints
// (Catmull-Rom over the displacements, zero slope at the root so the root segment leaves along the
// follicle frame), resampled at 4 N points and made inextensible follow-the-leader style (every sample
// keeps its rest distance from the one before). Each vertex is carried by the shaft frame at its
// along-shaft coordinate (local x, clamped to [0, length]; beyond the tip, the tip frame): rotation
// minimizing frames transported from the root, blended linearly between samples. Barbs, vanes and the
// shaft cylinder thus follow the bent shaft as a bend deformer would. With no offsets (or all zero)
// placeBentFeatherVertices gives placeFeatherVertices' bits.
#include <glm/vec3.hpp>

#include <cstddef>
#include <vector>

#include "pteryla/core/packed.hpp"

#include "pteryla/feather/mesh.hpp"

namespace pteryla::feather {

struct ShaftBend {
  double length = 0;               // world length of the chain along the shaft (> 0)
  std::vector<glm::dvec3> offset;  // displacement of joints 1..N (world); empty = rigid
  bool rigid() const;              // no offset, all offsets zero, or no length
};

// Places vertices written with FeatherMeshInput::unplaced through `placement` bent by `bend`.
void placeBentFeatherVertices(const FeatherPlacement& placement, const ShaftBend& bend, const glm::vec3* positions,
                              const PackedDir* normals, const PackedDir* tangents, size_t count,
                              glm::vec3* outPositions, PackedDir* outNormals, PackedDir* outTangents);

// The bent shaft's centre line: samples 0..4N from the follicle to the tip (world).
std::vector<glm::dvec3> bentShaft(const FeatherPlacement& placement, const ShaftBend& bend);

}  // namespace pteryla::feather
