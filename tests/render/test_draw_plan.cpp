// The coat's draw plan without a GL context (draw_plan.hpp): the octant order of 7.1.2, layer order,
// frustum, occlusion and sub-pixel culling, material runs, the shadow pass's runs, empty input.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/trigonometric.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/render/draw_plan.hpp"

using namespace pteryla;
using namespace pteryla::render;

namespace {

constexpr int kSize = 64;  // viewport, pixels

// A coat built triangle by triangle; every triangle has its own three vertices, so an index names the
// triangle it belongs to (index / 3).
struct Coat {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  std::vector<FeatherDrawRange> ranges;

  // A triangle about `c`, `size` across, in the plane z = c.z. Returns its number.
  uint32_t triangle(glm::vec3 c, float size = 0.2f) {
    const uint32_t first = static_cast<uint32_t>(positions.size());
    positions.push_back(c + glm::vec3(-size, -size, 0) * 0.5f);
    positions.push_back(c + glm::vec3(size, -size, 0) * 0.5f);
    positions.push_back(c + glm::vec3(0, size, 0) * 0.5f);
    indices.insert(indices.end(), {first, first + 1, first + 2});
    return first / 3;
  }
  // A feather of `count` triangles along +x from c (one part: the fallback block).
  FeatherDrawRange& feather(glm::vec3 c, int count, uint32_t material = 0) {
    FeatherDrawRange f;
    f.firstIndex = static_cast<uint32_t>(indices.size());
    for (int k = 0; k < count; ++k) triangle(c + glm::vec3(0.1f * k, 0, 0));
    f.indexCount = static_cast<uint32_t>(indices.size()) - f.firstIndex;
    f.material = material;
    f.origin = c;
    ranges.push_back(f);
    return ranges.back();
  }
  DrawPlan plan() const {
    DrawPlan p;
    p.setCoat(positions, indices, ranges);
    return p;
  }
};

Camera cameraAt(glm::vec3 eye, glm::vec3 target = glm::vec3(0.0f)) {
  Camera c;
  c.eye = eye;
  c.target = target;
  c.zNear = 0.1f;
  c.zFar = 100.0f;
  return c;
}

// Looking at the origin from the side of +x: a feather at the origin along +x is drawn forward.
Camera front() { return cameraAt({2, 1, 5}); }

// The triangles of the plan's index list, by number, in draw order (each must be whole).
std::vector<uint32_t> drawnTriangles(const DrawPlan& p) {
  const std::vector<uint32_t>& idx = p.indices();
  std::vector<uint32_t> t;
  for (size_t k = 0; k + 2 < idx.size(); k += 3) {
    EXPECT_EQ(idx[k] % 3, 0u);
    EXPECT_EQ(idx[k + 1], idx[k] + 1);
    EXPECT_EQ(idx[k + 2], idx[k] + 2);
    t.push_back(idx[k] / 3);
  }
  EXPECT_EQ(idx.size() % 3, 0u);
  return t;
}

// One feather in the xy plane, shaft along +x and left vane toward +y (dorsal +z), with four parts of
// kPerPart triangles each, in storage order shaft, left vane, right vane, afterfeather. Each part's
// triangles run from the base (x = 0) toward the tip; the vanes lie at y = +-0.5, the afterfeather just
// below the vane plane and the shaft just above it.
constexpr uint32_t kPerPart = 3;
Coat fourPartFeather() {
  Coat coat;
  const glm::vec3 part[4] = {{0, 0, 0.02f}, {0, 0.5f, 0}, {0, -0.5f, 0}, {0, 0, -0.05f}};
  FeatherDrawRange f;
  for (int k = 0; k < 4; ++k) {
    for (uint32_t t = 0; t < kPerPart; ++t) coat.triangle(part[k] + glm::vec3(0.3f * t, 0, 0));
    f.partCount[k] = 3 * kPerPart;
  }
  f.indexCount = static_cast<uint32_t>(coat.indices.size());
  coat.ranges.push_back(f);
  return coat;
}

}  // namespace

TEST(DrawPlan, EachOctantDrawsThePartsAndBarbsFarthestFirst) {
  const Coat coat = fourPartFeather();
  DrawPlan plan = coat.plan();
  // Octant of the eye (signs along the feather's x, y, z) -> parts in draw order (7.1.2): seen from
  // above (+z) the afterfeather under the vanes comes first and the shaft on top of them last, from
  // below the reverse; of the two vanes the one on the far side of the shaft (-y seen from +y) first.
  struct Case {
    int sx, sy, sz;
    std::array<uint32_t, 4> parts;
  };
  const Case cases[] = {
      {+1, +1, +1, {3, 2, 1, 0}}, {+1, -1, +1, {3, 1, 2, 0}}, {+1, +1, -1, {0, 2, 1, 3}}, {+1, -1, -1, {0, 1, 2, 3}},
      {-1, +1, +1, {3, 2, 1, 0}}, {-1, -1, +1, {3, 1, 2, 0}}, {-1, +1, -1, {0, 2, 1, 3}}, {-1, -1, -1, {0, 1, 2, 3}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(testing::Message() << "eye octant " << c.sx << " " << c.sy << " " << c.sz);
    // The tip is at x = 0.6: an eye beyond it (x = 3) sees the tip nearer, one before the base does not.
    const glm::vec3 eye(c.sx > 0 ? 3.0f : -3.0f, 3.0f * c.sy, 5.0f * c.sz);
    const Camera cam = cameraAt(eye, {0.3f, 0, 0});
    plan.build(cam, kSize, kSize, DrawOptions());
    // Barbs back to front: base to tip when the tip is nearer (sx > 0), tip to base otherwise.
    std::vector<uint32_t> expected;
    for (uint32_t part : c.parts)
      for (uint32_t n = 0; n < kPerPart; ++n) expected.push_back(part * kPerPart + (c.sx > 0 ? n : kPerPart - 1 - n));
    EXPECT_EQ(drawnTriangles(plan), expected);
    EXPECT_EQ(plan.counts().backwardParts, c.sx > 0 ? 0u : 4u);
    // Geometrically: the first vane drawn is the farther one, and within each vane the distance to the
    // eye never grows from one triangle to the next.
    const std::vector<uint32_t> drawn = drawnTriangles(plan);
    auto distance = [&](uint32_t t) {
      const glm::vec3 centre = (coat.positions[3 * t] + coat.positions[3 * t + 1] + coat.positions[3 * t + 2]) / 3.0f;
      return glm::length(eye - centre);
    };
    const size_t firstVane = kPerPart, secondVane = 2 * kPerPart;  // positions of the vanes in draw order
    EXPECT_GT(distance(drawn[firstVane]), distance(drawn[secondVane]));
    for (size_t v : {firstVane, secondVane})
      for (size_t n = v + 1; n < v + kPerPart; ++n) EXPECT_LE(distance(drawn[n]), distance(drawn[n - 1]));
  }
}

TEST(DrawPlan, WithoutViewDependentOrderEveryPartIsDrawnForwardInStoredOrder) {
  const Coat coat = fourPartFeather();
  DrawPlan plan = coat.plan();
  DrawOptions o;
  o.viewDependentOrder = false;
  std::vector<uint32_t> stored(4 * kPerPart);
  for (uint32_t t = 0; t < stored.size(); ++t) stored[t] = t;
  for (const glm::vec3 eye : {glm::vec3(-3, -3, -5), glm::vec3(3, 3, 5)}) {
    plan.build(cameraAt(eye), kSize, kSize, o);
    EXPECT_EQ(drawnTriangles(plan), stored);
    EXPECT_EQ(plan.counts().backwardParts, 0u);
  }
}

TEST(DrawPlan, BackwardReversesWholeTrianglesAcrossChunks) {
  // 70 triangles: three chunks (32, 32, 6) of one block.
  Coat coat;
  FeatherDrawRange& f = coat.feather({0, 0, 0}, 70);
  f.axisX = {1, 0, 0};
  f.origin = {1000, 0, 0};  // the tip side (+x) faces away from any eye near the origin
  DrawPlan plan = coat.plan();
  plan.build(cameraAt({0, 0, 8}, {3.5f, 0, 0}), kSize, kSize, DrawOptions());
  std::vector<uint32_t> reversed(70);
  for (uint32_t t = 0; t < 70; ++t) reversed[t] = 69 - t;
  EXPECT_EQ(drawnTriangles(plan), reversed);
  EXPECT_EQ(plan.counts().backwardParts, 1u);
  EXPECT_EQ(plan.counts().triangles, 70u);
}

TEST(DrawPlan, FeathersFollowTheRangesOrderWhateverTheirPlaceInTheIndexList) {
  Coat coat;
  coat.feather({0, 0, 0}, 2);
  coat.feather({0, 0.5f, 0}, 2);
  coat.feather({0, -0.5f, 0}, 2);
  std::swap(coat.ranges[0], coat.ranges[2]);  // layer order: triangles 4-5, 2-3, 0-1
  DrawPlan plan = coat.plan();
  for (const glm::vec3 eye : {glm::vec3(3, 3, 5), glm::vec3(3, -3, -5)}) {
    plan.build(cameraAt(eye), kSize, kSize, DrawOptions());
    EXPECT_EQ(drawnTriangles(plan), (std::vector<uint32_t>{4, 5, 2, 3, 0, 1}));
  }
}

TEST(DrawPlan, FeathersOutsideTheFrustumAreDropped) {
  Coat coat;
  coat.feather({0, 0, 0}, 2);     // in view
  coat.feather({50, 0, 0}, 2);    // far to the side
  coat.feather({0, 0, 9}, 2);     // behind the eye
  coat.feather({0, 0, -200}, 2);  // beyond the far plane
  coat.feather({0.4f, 0.2f, 0}, 2);
  DrawPlan plan = coat.plan();
  plan.build(front(), kSize, kSize, DrawOptions());
  EXPECT_EQ(drawnTriangles(plan), (std::vector<uint32_t>{0, 1, 8, 9}));
  EXPECT_EQ(plan.counts().culledFeathers, 3u);
  EXPECT_EQ(plan.counts().triangles, 4u);
  // The same feathers, looked at from the side they lie on.
  plan.build(cameraAt({52, 1, 5}, {50, 0, 0}), kSize, kSize, DrawOptions());
  EXPECT_EQ(drawnTriangles(plan), (std::vector<uint32_t>{2, 3}));
}

TEST(DrawPlan, WhatLiesBehindTheOccludersIsDropped) {
  // A wall filling the view at z = 0, seen from z = 5: its window depth everywhere.
  const Camera cam = cameraAt({0, 0, 5});
  const glm::mat4 viewProj = cam.projection(1.0f) * cam.view();
  const glm::vec4 q = viewProj * glm::vec4(0, 0, 0, 1);
  std::vector<float> depth(kSize * kSize, q.z / q.w * 0.5f + 0.5f);
  DepthTiles wall;
  wall.build(depth.data(), kSize, kSize);

  Coat coat;
  coat.feather({0, 0, -1}, 3);  // behind the wall
  coat.feather({0, 0, 1}, 3);   // in front of it
  // Through the wall: one chunk, its triangles tested one by one.
  FeatherDrawRange f;
  f.firstIndex = static_cast<uint32_t>(coat.indices.size());
  for (float z : {1.0f, -1.0f, 1.0f, -1.0f}) coat.triangle({0.2f, 0.2f, z});
  f.indexCount = static_cast<uint32_t>(coat.indices.size()) - f.firstIndex;
  coat.ranges.push_back(f);
  for (FeatherDrawRange& r : coat.ranges) r.origin = {-10, 0, 0};  // tips toward the eye: forward
  DrawPlan plan = coat.plan();

  plan.build(cam, kSize, kSize, DrawOptions(), &wall);
  EXPECT_EQ(drawnTriangles(plan), (std::vector<uint32_t>{3, 4, 5, 6, 8}));
  EXPECT_EQ(plan.counts().occludedFeathers, 1u);
  EXPECT_EQ(plan.counts().occludedTriangles, 2u);
  EXPECT_EQ(plan.counts().culledFeathers, 0u);
  // Without occluders everything in view is drawn.
  plan.build(cam, kSize, kSize, DrawOptions());
  EXPECT_EQ(plan.counts().triangles, 10u);
  EXPECT_EQ(plan.counts().occludedFeathers, 0u);
}

TEST(DrawPlan, SubpixelCullingDropsTrianglesBetweenPixelCentres) {
  Coat coat;
  coat.triangle({0, 0, 0}, 1e-4f);  // far smaller than a pixel, inside one pixel away from its centre
  coat.triangle({0, 0, 0}, 1.0f);   // many pixels
  coat.ranges.push_back({0, 6});
  DrawPlan plan = coat.plan();
  // Shift the view by a quarter pixel so the origin falls between pixel centres.
  const float pixel = 2.0f * 5.0f * std::tan(glm::radians(20.0f)) / kSize;
  const Camera cam = cameraAt({0.25f * pixel, 0.25f * pixel, 5}, {0.25f * pixel, 0.25f * pixel, 0});
  DrawOptions o;
  o.subpixelCulling = true;
  plan.build(cam, kSize, kSize, o);
  EXPECT_EQ(drawnTriangles(plan), (std::vector<uint32_t>{1}));
  EXPECT_EQ(plan.counts().subpixelTriangles, 1u);
  o.subpixelCulling = false;
  plan.build(cam, kSize, kSize, o);
  EXPECT_EQ(drawnTriangles(plan), (std::vector<uint32_t>{0, 1}));
}

// With multisampling, coverage is sampled at the pixel's sample positions instead of its centre: a
// triangle between the centres that holds a sample position is kept, one that holds none is dropped.
TEST(DrawPlan, SubpixelCullingTestsTheSamplePositionsWhenMultisampling) {
  const float pixel = 2.0f * 5.0f * std::tan(glm::radians(20.0f)) / kSize;
  // The origin falls a quarter pixel up and right of a pixel corner (0.25, 0.25 within its pixel): no
  // centre near it, but a sample position there.
  const Camera cam = cameraAt({-0.25f * pixel, -0.25f * pixel, 5}, {-0.25f * pixel, -0.25f * pixel, 0});
  Coat coat;
  coat.triangle({0, 0, 0}, 0.1f * pixel);  // around (0.25, 0.25) of its pixel
  coat.ranges.push_back({0, 3});
  DrawPlan plan = coat.plan();
  DrawOptions o;
  o.subpixelCulling = true;
  plan.build(cam, kSize, kSize, o);
  EXPECT_EQ(plan.counts().triangles, 0u);  // no pixel centre: dropped
  EXPECT_EQ(plan.counts().subpixelTriangles, 1u);
  o.samplePositions = {{0.25f, 0.25f}, {0.75f, 0.75f}};
  plan.build(cam, kSize, kSize, o);
  EXPECT_EQ(plan.counts().triangles, 1u);  // holds a sample position: kept
  EXPECT_EQ(plan.counts().subpixelTriangles, 0u);
  o.samplePositions = {{0.75f, 0.25f}, {0.25f, 0.75f}};
  plan.build(cam, kSize, kSize, o);
  EXPECT_EQ(plan.counts().triangles, 0u);  // holds neither: dropped
}

TEST(DrawPlan, MaterialRunsAreMaximal) {
  Coat coat;
  const uint32_t materials[] = {0, 0, 1, 1, 1, 0, 2, 2};
  for (int i = 0; i < 8; ++i) coat.feather({0.05f * i, 0, 0}, 2, materials[i]);
  DrawPlan plan = coat.plan();
  plan.build(front(), kSize, kSize, DrawOptions());
  const std::vector<DrawRun>& runs = plan.runs();
  ASSERT_EQ(runs.size(), 4u);
  const uint32_t runMaterial[] = {0, 1, 0, 2};
  const size_t runFeathers[] = {2, 3, 1, 2};
  size_t at = 0;
  for (size_t k = 0; k < runs.size(); ++k) {
    EXPECT_EQ(runs[k].material, runMaterial[k]);
    EXPECT_EQ(runs[k].first, at);
    EXPECT_EQ(runs[k].count, runFeathers[k] * 6);
    at += runs[k].count;
  }
  EXPECT_EQ(at, plan.indices().size());
}

TEST(DrawPlan, AFeatherNotDrawnDoesNotSplitARun) {
  Coat coat;
  coat.feather({0, 0, 0}, 2, 0);
  coat.feather({50, 0, 0}, 2, 1);  // out of view
  coat.feather({0.2f, 0, 0}, 2, 0);
  DrawPlan plan = coat.plan();
  plan.build(front(), kSize, kSize, DrawOptions());
  ASSERT_EQ(plan.runs().size(), 1u);
  EXPECT_EQ(plan.runs()[0].material, 0u);
  EXPECT_EQ(plan.runs()[0].count, 12u);
}

TEST(DrawPlan, AFeatherWhoseTrianglesAreAllCulledDoesNotSplitARun) {
  // The middle feather is in the frustum, but its one triangle falls between pixel centres.
  const float pixel = 2.0f * 5.0f * std::tan(glm::radians(20.0f)) / kSize;
  const glm::vec3 centre(0.25f * pixel, 0.25f * pixel, 0);
  Coat coat;
  coat.feather({0, 0.5f, 0}, 2, 0);
  FeatherDrawRange tiny;
  tiny.firstIndex = static_cast<uint32_t>(coat.indices.size());
  tiny.indexCount = 3;
  tiny.material = 1;
  coat.triangle({0, 0, 0}, 1e-4f);
  coat.ranges.push_back(tiny);
  coat.feather({0, -0.5f, 0}, 2, 0);
  DrawPlan plan = coat.plan();
  DrawOptions o;
  o.subpixelCulling = true;
  plan.build(cameraAt(centre + glm::vec3(0, 0, 5), centre), kSize, kSize, o);
  EXPECT_EQ(plan.counts().subpixelTriangles, 1u);
  EXPECT_EQ(plan.counts().culledFeathers, 0u);
  ASSERT_EQ(plan.runs().size(), 1u);
  EXPECT_EQ(plan.runs()[0].material, 0u);
  EXPECT_EQ(plan.runs()[0].count, 12u);
  // Every run draws something, and neighbouring runs differ in material.
  o.subpixelCulling = false;
  plan.build(cameraAt(centre + glm::vec3(0, 0, 5), centre), kSize, kSize, o);
  ASSERT_EQ(plan.runs().size(), 3u);
  for (size_t k = 0; k < plan.runs().size(); ++k) {
    EXPECT_GT(plan.runs()[k].count, 0u);
    if (k > 0) {
      EXPECT_NE(plan.runs()[k].material, plan.runs()[k - 1].material);
    }
  }
}

TEST(DrawPlan, EmptyInputGivesAnEmptyPlan) {
  DrawPlan fresh;
  fresh.build(front(), kSize, kSize, DrawOptions());
  EXPECT_TRUE(fresh.indices().empty());
  EXPECT_TRUE(fresh.runs().empty());
  EXPECT_TRUE(fresh.shadowRuns().empty());

  Coat coat;
  DrawPlan plan = coat.plan();
  plan.build(front(), kSize, kSize, DrawOptions());
  EXPECT_TRUE(plan.ranges().empty());
  EXPECT_TRUE(plan.indices().empty());
  EXPECT_TRUE(plan.runs().empty());
  EXPECT_TRUE(plan.shadowRuns().empty());
  EXPECT_EQ(plan.counts().triangles, 0u);

  // Ranges without triangles: nothing to draw either, and nothing counted as culled.
  coat.triangle({0, 0, 0});
  coat.ranges = {FeatherDrawRange{0, 0}, FeatherDrawRange{3, 0, 1}};
  plan = coat.plan();
  plan.build(front(), kSize, kSize, DrawOptions());
  EXPECT_TRUE(plan.indices().empty());
  EXPECT_TRUE(plan.runs().empty());
  EXPECT_TRUE(plan.shadowRuns().empty());
  EXPECT_EQ(plan.counts().culledFeathers, 0u);
}

TEST(DrawPlan, NoRangesMakeTheWholeMeshOneFeatherOfMaterialZero) {
  Coat coat;
  coat.triangle({0, 0, 0});
  coat.triangle({0.3f, 0, 0});
  DrawPlan plan = coat.plan();
  ASSERT_EQ(plan.ranges().size(), 1u);
  plan.build(front(), kSize, kSize, DrawOptions());
  EXPECT_EQ(drawnTriangles(plan), (std::vector<uint32_t>{0, 1}));
  ASSERT_EQ(plan.runs().size(), 1u);
  EXPECT_EQ(plan.runs()[0].material, 0u);
}

TEST(DrawPlan, ShadowRunsMergeNeighboursOfOneMaterialInTheIndexList) {
  Coat coat;
  for (uint32_t m : {0, 0, 1, 0, 0}) coat.feather({0, 0, 0}, 2, m);
  std::swap(coat.ranges[3], coat.ranges[4]);  // same material, but drawn out of index order
  DrawPlan plan = coat.plan();
  const std::vector<DrawRun>& runs = plan.shadowRuns();
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(runs[0].material, 0u);
  EXPECT_EQ(runs[0].first, 0u);
  EXPECT_EQ(runs[0].count, 12u);
  EXPECT_EQ(runs[1].material, 1u);
  EXPECT_EQ(runs[1].first, 12u);
  EXPECT_EQ(runs[1].count, 6u);
  EXPECT_EQ(runs[2].first, 24u);  // ranges[3] is the fifth feather
  EXPECT_EQ(runs[3].first, 18u);
}

TEST(DrawPlan, DepthTilesKeepEachTilesNearestAndFarthestDepth) {
  // 10 x 9 pixels: 2 x 2 tiles of 8 pixels (the last row and column partial).
  std::vector<float> depth(10 * 9, 0.5f);
  depth[0] = 0.1f;           // tile (0, 0)
  depth[9] = 0.9f;           // pixel (9, 0): tile (1, 0)
  depth[8 * 10 + 3] = 0.2f;  // pixel (3, 8): tile (0, 1)
  DepthTiles t;
  t.build(depth.data(), 10, 9);
  ASSERT_EQ(t.tilesX, 2);
  ASSERT_EQ(t.tilesY, 2);
  EXPECT_EQ(t.nearest, (std::vector<float>{0.1f, 0.5f, 0.2f, 0.5f}));
  EXPECT_EQ(t.farthest, (std::vector<float>{0.5f, 0.9f, 0.5f, 0.5f}));
}

TEST(DrawPlan, RangesThatOverlapOrDoNotFitAreRefused) {
  FeatherDrawRange a{0, 6}, b{3, 6}, c{0, 4};
  EXPECT_NO_THROW(DrawPlan::validateRanges({a}, 6));
  EXPECT_THROW(DrawPlan::validateRanges({a, b}, 12), Error);
  EXPECT_THROW(DrawPlan::validateRanges({a}, 3), Error);
  EXPECT_THROW(DrawPlan::validateRanges({c}, 6), Error);
  a.partCount[1] = 3;
  EXPECT_THROW(DrawPlan::validateRanges({a}, 6), Error);
}

// A plan made by reference (the renderer's CoatStorage::Reference, SceneView's default) keeps no copy of
// the coat: it plans exactly what a copying plan plans, from the caller's arrays.
TEST(DrawPlan, AReferencePlanIsTheCopyingOneWithoutTheCopy) {
  Coat coat;
  coat.feather({0, 0, 0}, 40);
  coat.feather({0.4f, 0.2f, 0.1f}, 70, 1);
  coat.feather({50, 0, 0}, 3);
  coat.triangle({0.2f, -0.3f, 0.0f}, 1e-4f);
  coat.ranges.push_back({static_cast<uint32_t>(coat.indices.size() - 3), 3});
  DrawPlan copy = coat.plan(), ref;
  ref.setCoatReference(coat.positions, coat.indices, coat.ranges);
  DrawOptions o;
  o.subpixelCulling = true;
  for (const Camera& cam : {front(), cameraAt({-3, 2, 4}), cameraAt({52, 1, 5}, {50, 0, 0})}) {
    copy.build(cam, kSize, kSize, o);
    ref.build(cam, kSize, kSize, o);
    EXPECT_EQ(ref.indices(), copy.indices());
    EXPECT_EQ(ref.runs().size(), copy.runs().size());
    EXPECT_EQ(ref.counts().triangles, copy.counts().triangles);
    EXPECT_EQ(ref.counts().subpixelTriangles, copy.counts().subpixelTriangles);
  }
  copy.buildShadow(glm::mat4(1.0f), 256);
  ref.buildShadow(glm::mat4(1.0f), 256);
  EXPECT_EQ(ref.indices(), copy.indices());
  EXPECT_EQ(ref.coatIndices(), coat.indices.data());  // no copy of the index list
  EXPECT_EQ(ref.coatIndexCount(), coat.indices.size());
  EXPECT_NE(copy.coatIndices(), coat.indices.data());
}
