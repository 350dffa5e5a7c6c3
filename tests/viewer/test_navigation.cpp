// Navigation coat: the long feathers whole and every other feather as a card within the triangle budget
// (every k-th card only when even the smallest do not fit); layer order kept.
#include <gtest/gtest.h>

#include <algorithm>

#include "navigation.hpp"

using namespace pteryla;
using namespace pteryla::viewer;

namespace {
// A coat of `n` feathers, each a zigzag strip of `tris` triangles along y, 0.6 wide, over its own
// vertices; feathers whose index is a multiple of 10 are 10 times longer.
pipeline::CoatMesh stripCoat(size_t n, size_t tris) {
  pipeline::CoatMesh c;
  for (size_t f = 0; f < n; ++f) {
    pipeline::CoatDrawRange r;
    r.firstIndex = static_cast<uint32_t>(c.mesh.indices.size());
    r.origin = {float(f), 0.0f, 0.0f};
    const float step = f % 10 == 0 ? 10.0f : 1.0f;
    const uint32_t base = static_cast<uint32_t>(c.mesh.positions.size());
    r.axisX = {0.0f, 1.0f, 0.0f};  // the shaft along y, the vane across x
    r.axisY = {1.0f, 0.0f, 0.0f};
    for (size_t v = 0; v < tris + 2; ++v) {
      c.mesh.positions.push_back({float(f) + (v % 2 ? 0.3f : -0.3f), step * float(v), 0.0f});
      c.mesh.uvBarb.push_back({float(v), float(f)});
      c.mesh.featherId.push_back(uint32_t(f));
    }
    for (uint32_t t = 0; t < tris; ++t) {
      c.mesh.indices.push_back(base + t);
      c.mesh.indices.push_back(base + t + 1);
      c.mesh.indices.push_back(base + t + 2);
    }
    r.indexCount = static_cast<uint32_t>(3 * tris);
    r.material = uint32_t(f % 3);
    r.partCount[0] = r.indexCount;
    c.ranges.push_back(r);
  }
  return c;
}
}  // namespace

TEST(Navigation, LongFeathersWholeAndEveryOtherFeatherAsACard) {
  const pipeline::CoatMesh coat = stripCoat(100, 10);        // 1000 triangles; feathers 0, 10, ..., 90 long
  EXPECT_TRUE(makeNavigationCoat(coat, 1000).mesh.empty());  // fits: nothing to do
  const NavigationCoat nav = makeNavigationCoat(coat, 300);
  EXPECT_LE(nav.mesh.triangleCount(), 300u);
  EXPECT_EQ(nav.longKept, 10u);  // the ten long feathers: 100 triangles <= half the budget
  EXPECT_EQ(nav.cards, 90u);     // every other feather is there, as a card (#28: the body stays covered)
  EXPECT_EQ(nav.stride, 1u);
  EXPECT_EQ(nav.cardBins, 2);  // 200 triangles of room for 90 cards: 2 triangles each
  std::vector<uint32_t> kept;
  for (const auto& r : nav.ranges) kept.push_back(nav.mesh.featherId[nav.mesh.indices[r.firstIndex]]);
  ASSERT_EQ(kept.size(), 100u);
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));  // layer order
  for (size_t k = 0; k < nav.ranges.size(); ++k) {
    const auto& r = nav.ranges[k];
    const auto& src = coat.ranges[kept[k]];
    EXPECT_EQ(r.material, src.material);
    // Extent along the shaft (y) of the source feather and of what the navigation coat draws for it.
    float lo = 1e9f, hi = -1e9f, nlo = 1e9f, nhi = -1e9f;
    for (uint32_t i = 0; i < src.indexCount; ++i) {
      const float y = coat.mesh.positions[coat.mesh.indices[src.firstIndex + i]].y;
      lo = std::min(lo, y), hi = std::max(hi, y);
    }
    for (uint32_t i = 0; i < r.indexCount; ++i) {
      const uint32_t v = nav.mesh.indices[r.firstIndex + i];
      EXPECT_EQ(nav.mesh.featherId[v], kept[k]);  // a card is made of its own feather's vertices
      nlo = std::min(nlo, nav.mesh.positions[v].y), nhi = std::max(nhi, nav.mesh.positions[v].y);
    }
    if (kept[k] % 10 == 0) {  // long: whole, geometry copied exactly
      EXPECT_EQ(r.indexCount, src.indexCount);
      for (uint32_t i = 0; i < r.indexCount; ++i) {
        const uint32_t a = nav.mesh.indices[r.firstIndex + i], b = coat.mesh.indices[src.firstIndex + i];
        EXPECT_EQ(nav.mesh.positions[a], coat.mesh.positions[b]);
        EXPECT_EQ(nav.mesh.uvBarb[a], coat.mesh.uvBarb[b]);
      }
    } else {  // a card of two triangles spanning most of the feather
      EXPECT_EQ(r.indexCount, 6u);
      EXPECT_GE(nhi - nlo, 0.5f * (hi - lo)) << kept[k];
      EXPECT_LE(nhi - nlo, hi - lo);
    }
  }
  EXPECT_TRUE(nav.mesh.normals.empty());  // absent attributes stay absent

  // A larger budget gives rounder cards; a tiny one keeps every k-th card.
  EXPECT_EQ(makeNavigationCoat(coat, 900).cardBins, 5);  // 800 triangles of room: 8 (5 rows) each
  const NavigationCoat tight = makeNavigationCoat(coat, 120);
  EXPECT_LE(tight.mesh.triangleCount(), 120u);
  EXPECT_GT(tight.stride, 1u);
  EXPECT_GT(tight.cards, 0u);
}

TEST(AdaptiveNavigation, FullCoatWhileItIsFastEnough) {
  // Not measured yet (after an upload or resize): try the full coat first.
  EXPECT_FALSE(useNavigationCoat(false, true, -1.0, 85.0));
  // Fast enough: keep every feather while moving; too slow: the navigation coat.
  EXPECT_FALSE(useNavigationCoat(false, true, 60.0, 85.0));
  EXPECT_FALSE(useNavigationCoat(false, true, 85.0, 85.0));
  EXPECT_TRUE(useNavigationCoat(false, true, 90.0, 85.0));
  // Forced (show navigation on) or adaptive off: always the navigation coat.
  EXPECT_TRUE(useNavigationCoat(true, true, 10.0, 85.0));
  EXPECT_TRUE(useNavigationCoat(false, false, 10.0, 85.0));
  // Smoothing: the first sample as it is, then a running blend that follows a slowdown.
  EXPECT_DOUBLE_EQ(smoothFrameMs(-1.0, 70.0), 70.0);
  double ms = 70.0;
  for (int i = 0; i < 10; ++i) ms = smoothFrameMs(ms, 120.0);
  EXPECT_GT(ms, 115.0);
  EXPECT_LT(ms, 120.0);
  EXPECT_TRUE(useNavigationCoat(false, true, ms, 85.0));
}
