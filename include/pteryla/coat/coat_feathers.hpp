#pragma once
// CoatFeathers: the hand-off between coat generation (thesis 6.2: one interpolated feather per
// follicle, 6.3.1: its frame, 9.2.1: layer order) and packing (6.3.2-6.3.3). Struct of arrays with
// one entry per feather; feather i grows from follicle `follicle[i]`.
// Frames follow docs/architecture.md: N normal, T direction, B = N x T; the feather-local frame
// (+x shaft, +y left vane, +z dorsal) maps to (T', B, N') after rotation by the elevation angle.
#include <glm/vec3.hpp>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "pteryla/feather/params.hpp"

namespace pteryla::coat {

struct FeatherFrame {
  glm::dvec3 origin{0};  // follicle position on the skin
  glm::dvec3 normal{0, 0, 1};
  glm::dvec3 tangent{1, 0, 0};
  glm::dvec3 binormal{0, 1, 0};  // normal x tangent
};

// Which key feathers a feather was interpolated from (key_feathers.hpp) and their weights: the
// normalised weights its geometry was blended with (feather::blendFeathers). A copy of a key feather
// has one entry of weight 1. The renderer blends the key feathers' materials by them (issue #30 item 2).
struct KeyBlend {
  std::array<uint32_t, 3> key{0, 0, 0};   // indices into CoatFeathers::keyNames
  std::array<double, 3> weight{1, 0, 0};  // > 0 for the first `count` entries, summing to 1
  uint8_t count = 1;
};

struct CoatFeathers {
  std::vector<uint32_t> follicle;              // follicle index per feather
  std::vector<uint32_t> tract;                 // tract index per feather
  std::vector<feather::FeatherParams> params;  // interpolated (and scaled) definition per feather
  std::vector<FeatherFrame> frames;
  std::vector<double> age;           // [0,1] growth age (1 = mature); set by moult
  std::vector<uint8_t> present;      // 0 = moulted out (a gap)
  std::vector<uint32_t> layerOrder;  // feather indices, bottom layer first (packing order)
  // Per feather, the key feathers it was blended from (empty for a coat not made by
  // interpolateCoatFeathers); keyNames are the feather definitions they name.
  std::vector<KeyBlend> keyBlend;
  std::vector<std::string> keyNames;
  size_t size() const { return follicle.size(); }
};

}  // namespace pteryla::coat
