#pragma once
// Brushes that paint on the skin (docs/viewer.md, "Painting"): tract faces and the follicle density map.
// A brush is a sphere on the posed skin (what the view shows); what it paints is indexed like the rest
// skin (triangles -> source polygons for tracts, mesh vertices for density), which the pose never
// renumbers. Pure math over coat::SkinMesh: no GL, no ImGui (unit-tested in tests/viewer).
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "pteryla/coat/skin.hpp"

namespace pteryla::viewer {

// Source polygons (docs/tracts.md "Face numbering") with a triangle whose centroid lies within `radius`
// of `center`, sorted and unique. `posed`: vertex positions to measure on (the posed skin, one per
// rest vertex); empty or of another size: the rest positions.
std::vector<uint32_t> facesInBrush(const coat::SkinMesh& rest, const std::vector<glm::vec3>& posed,
                                   const glm::vec3& center, float radius);

// Sorted-set helpers for face lists.
std::vector<uint32_t> faceUnion(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b);
std::vector<uint32_t> faceDifference(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b);

// One dab of the density brush: each vertex within `radius` moves toward `value` by
// strength x (1 - (d/r)^2)^2 (full strength at the centre, none at the rim). `factor` is resized to the
// vertex count, new entries 1 (the unpainted density).
void densityDab(std::vector<float>& factor, const coat::SkinMesh& rest, const std::vector<glm::vec3>& posed,
                const glm::vec3& center, float radius, float value, float strength);

// Factors rounded to 1/1000 (what the viewer stores: the side file then reads back the same floats).
void quantizeDensity(std::vector<float>& factor);

}  // namespace pteryla::viewer
