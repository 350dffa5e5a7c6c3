// Packed key barbs as feather parameters and placed key barbs (the public accessors of a PackResult).
#include <algorithm>
#include <cmath>

#include "pteryla/core/error.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat {

using feather::kPi;
using glm::dvec3;

namespace {
// Feather i's packed keys: checks that `result` is a pack of `coat`.
const PackedKeyBarbs& packedKeysOf(const CoatFeathers& coat, const PackResult& result, uint32_t i) {
  const PackedKeyBarbs& K = result.packedKeys;
  PTERYLA_CHECK(i < coat.size() && K.replaced.size() == coat.size() && K.keyOffset.size() == coat.size() + 1,
                "packedParams: the result is not a pack of this coat");
  return K;
}

// Keys [first, second) of feather i's vane v (0 left, 1 right) in K.
std::pair<uint32_t, uint32_t> vaneKeys(const PackedKeyBarbs& K, uint32_t i, int v) {
  const uint32_t m = K.keyOffset[i] + K.leftKeys[i];
  return v == 0 ? std::make_pair(K.keyOffset[i], m) : std::make_pair(m, K.keyOffset[i + 1]);
}
}  // namespace

void packedParamsInto(const CoatFeathers& coat, const PackResult& result, uint32_t i, feather::FeatherParams& out) {
  const PackedKeyBarbs& K = packedKeysOf(coat, result, i);
  out = coat.params[i];
  if (!K.replaced[i]) return;
  for (int v = 0; v < 2; ++v) {
    std::vector<feather::KeyBarb>& kb = out.vane(v).keyBarbs;
    const auto [k0, k1] = vaneKeys(K, i, v);
    kb.resize(k1 - k0);
    for (uint32_t k = k0; k < k1; ++k) {
      kb[k - k0].rp = K.rp[k];
      kb[k - k0].cvs.assign(K.cvs.begin() + K.cvOffset[k], K.cvs.begin() + K.cvOffset[k + 1]);
    }
  }
}

feather::FeatherParams packedParams(const CoatFeathers& coat, const PackResult& result, uint32_t i) {
  feather::FeatherParams p;
  packedParamsInto(coat, result, i, p);
  return p;
}

bool packedParamsEqual(const feather::FeatherParams& p, const CoatFeathers& coat, const PackResult& result,
                       uint32_t i) {
  const PackedKeyBarbs& K = packedKeysOf(coat, result, i);
  if (!K.replaced[i]) return p == coat.params[i];
  for (int v = 0; v < 2; ++v) {
    const std::vector<feather::KeyBarb>& kb = p.vane(v).keyBarbs;
    const auto [k0, k1] = vaneKeys(K, i, v);
    if (kb.size() != k1 - k0) return false;
    for (uint32_t k = k0; k < k1; ++k)
      if (!(kb[k - k0].rp == K.rp[k]) || !std::equal(kb[k - k0].cvs.begin(), kb[k - k0].cvs.end(),
                                                     K.cvs.begin() + K.cvOffset[k], K.cvs.begin() + K.cvOffset[k + 1]))
        return false;
  }
  return p.equalExceptKeyBarbs(coat.params[i]);
}

std::vector<feather::FeatherParams> allPackedParams(const CoatFeathers& coat, const PackResult& result) {
  std::vector<feather::FeatherParams> out(coat.size());
  for (uint32_t i = 0; i < coat.size(); ++i) packedParamsInto(coat, result, i, out[i]);
  return out;
}

std::vector<PlacedKeyBarb> placedKeyBarbs(const CoatFeathers& coat, const PackResult& result, uint32_t i) {
  PTERYLA_CHECK(i < coat.size() && i < result.elevation.size(), "feather index out of range");
  const feather::FeatherParams p = packedParams(coat, result, i);
  const FeatherFrame& F = coat.frames[i];
  const double e = result.elevation[i];
  std::vector<PlacedKeyBarb> out;
  for (int v = 0; v < 2; ++v) {
    const double side = v == 0 ? 1.0 : -1.0;
    const feather::VaneParams& vp = p.vane(v);
    for (const feather::KeyBarb& kb : feather::effectiveKeyBarbs(p, v)) {
      const feather::RachisFrame f = feather::rachisFrame(p, kb.rp);
      const double angle = std::clamp(vp.baseAngle * (1 - kb.rp) + vp.tipAngle * kb.rp, 0.01, kPi - 0.01);
      const dvec3 u = std::cos(angle) * f.tangent + (side * std::sin(angle)) * f.left;
      const dvec3 w = std::sin(angle) * f.tangent - (side * std::cos(angle)) * f.left;
      const dvec3 root = f.point + (side * 0.5 * f.width) * f.left;
      const double len = p.barbLengthAt(v, kb.rp);
      PlacedKeyBarb pk;
      pk.vane = static_cast<uint8_t>(v);
      pk.rp = kb.rp;
      pk.length = len;
      pk.root = placePoint(F, e, root);
      pk.along = placeDirection(F, e, u);
      pk.up = placeDirection(F, e, f.dorsal);
      for (const auto& c : kb.cvs)
        pk.cvs.push_back(placePoint(F, e, root + len * (c.x * u + c.y * w + c.z * f.dorsal)));
      out.push_back(std::move(pk));
    }
  }
  return out;
}

}  // namespace pteryla::coat
