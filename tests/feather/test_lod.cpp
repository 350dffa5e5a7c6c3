// Level of detail (Streit 2003, 5.3, Fig. 5.8): collapse order, monotone triangle counts, key barbs
// kept at every level, silhouette preserved.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <tuple>

#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/lod.hpp"
#include "pteryla/feather/mesh.hpp"
#include "test_mesh_fixtures.hpp"

using namespace pteryla;
using namespace pteryla::feather;

namespace {

size_t shaftTriangles(const FeatherCurves& c, const MeshOptions& o, double lod) {
  TriMesh m;
  FeatherMeshRanges r;
  FeatherMeshInput in;
  in.curves = &c;
  in.lod = lod;
  appendFeatherMesh(in, o, m, &r);
  return r.shaftCount / 3;
}

TriMesh meshAt(const FeatherCurves& c, const LodOrder& order, double lod, const MeshOptions& o = {}) {
  FeatherMeshInput in;
  in.curves = &c;
  in.order = &order;
  in.lod = lod;
  TriMesh m;
  appendFeatherMesh(in, o, m);
  return m;
}

}  // namespace

TEST(FeatherLod, OrderIsPermutationWithPinnedBarbsFirst) {
  FeatherParams p = geomtest::contour();
  p.splits.count = 3;
  const FeatherCurves c = generateBarbs(p);
  const LodOrder o = computeLodOrder(c);
  ASSERT_EQ(o.rank.size(), c.barbs.size());
  std::vector<uint32_t> sorted = o.rank;
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  size_t keys = 0, splitEdges = 0;
  for (size_t i = 0; i < c.barbs.size(); ++i) {
    const BarbCurve& b = c.barbs[i];
    const bool first = i == 0 || c.barbs[i - 1].vane != b.vane || c.barbs[i - 1].part != b.part;
    const bool last = i + 1 == c.barbs.size() || c.barbs[i + 1].vane != b.vane || c.barbs[i + 1].part != b.part;
    keys += b.isKey;
    splitEdges += b.isSplitEdge;
    if (b.isSplitEdge || first || last) {
      EXPECT_LT(o.rank[i], o.pinned) << "barb " << i;
    }
  }
  // Key barbs come right after the pinned ones: kept at every level that keeps more than the pinned.
  for (size_t i = 0; i < c.barbs.size(); ++i)
    if (c.barbs[i].isKey && o.rank[i] >= o.pinned) {
      EXPECT_LT(o.rank[i], o.pinned + keys) << "barb " << i;
    }
  EXPECT_EQ(keys, 3u);
  EXPECT_GE(splitEdges, 4u);
  EXPECT_LT(o.pinned, c.barbs.size() / 4);
}

TEST(FeatherLod, DividesAndConquersBetweenPinnedBarbs) {
  // No key barbs, no splits: each vane's ends and its widest barb are pinned (the widest keeps the
  // vane's width at the lowest levels); the barbs added next split the two halves of each vane, and
  // they are dispersed, never adjacent to each other.
  FeatherParams p = geomtest::contour();
  p.left.keyBarbs.clear();
  p.right.keyBarbs.clear();
  const FeatherCurves c = generateBarbs(p);
  const LodOrder o = computeLodOrder(c);
  const uint32_t left = c.barbBegin[0];
  uint32_t leftEnd = left;
  while (leftEnd < c.barbs.size() && c.barbs[leftEnd].vane == 0) ++leftEnd;
  const uint32_t n = leftEnd - left;
  ASSERT_EQ(o.pinned, 6u);  // both ends and the widest barb of both vanes
  uint32_t widest = left;
  for (uint32_t i = left; i < leftEnd; ++i)
    if (c.barbs[i].length > c.barbs[widest].length) widest = i;
  EXPECT_LT(o.rank[widest], o.pinned);
  EXPECT_GT(widest, left + n / 8);  // a contour feather is widest inside its vane, not at an end
  EXPECT_LT(widest, leftEnd - 1 - n / 8);
  std::vector<uint32_t> byRank(c.barbs.size());
  for (size_t i = 0; i < c.barbs.size(); ++i) byRank[o.rank[i]] = static_cast<uint32_t>(i);
  std::vector<uint32_t> next(byRank.begin() + 6, byRank.begin() + 10);
  std::sort(next.begin(), next.end());
  for (size_t i = 1; i < next.size(); ++i) EXPECT_GT(next[i] - next[i - 1], 5u);
}

TEST(FeatherLod, LowestLevelKeepsTheVaneWidth) {
  // At the lowest level a contour feather keeps its widest barbs, so its vane does not collapse into a
  // sliver between the short barbs at its ends (the coat of a bird seen from afar stays closed).
  FeatherParams p = geomtest::contour();
  const FeatherCurves c = generateBarbs(p);
  const LodOrder o = computeLodOrder(c);
  float widestAll = 0, widestKept = 0;
  for (size_t i = 0; i < c.barbs.size(); ++i) {
    widestAll = std::max(widestAll, c.barbs[i].length);
    if (o.rank[i] < keptBarbCount(o, 0.01)) widestKept = std::max(widestKept, c.barbs[i].length);
  }
  EXPECT_EQ(widestKept, widestAll);
}

TEST(FeatherLod, WidestGapFirstThenNearestKeyBarb) {
  // Synthetic vanes of 21 barbs: the left one has a key barb in the middle, the right one none.
  FeatherCurves c;
  for (int v = 0; v < 2; ++v)
    for (int i = 0; i <= 20; ++i) {
      BarbCurve b;
      b.vane = static_cast<uint8_t>(v);
      b.rp = static_cast<float>(i / 20.0);
      b.isKey = v == 0 && i == 10;
      c.barbs.push_back(b);
    }
  c.barbBegin = {0};
  c.barbEnd = {42};
  const LodOrder o = computeLodOrder(c);
  ASSERT_EQ(o.pinned, 4u);  // L0, L20, R0, R20; then the key barb L10
  std::vector<uint32_t> byRank(c.barbs.size());
  for (size_t i = 0; i < c.barbs.size(); ++i) byRank[o.rank[i]] = static_cast<uint32_t>(i);
  EXPECT_EQ(byRank[4], 10u);
  EXPECT_EQ(byRank[5], 21u + 10u);  // widest interval: the whole right vane
  // Now four intervals of 10: the left ones (middles 5 from the key barb) before the right ones.
  EXPECT_EQ(byRank[6], 5u);
  EXPECT_EQ(byRank[7], 15u);
  EXPECT_EQ(byRank[8], 21u + 5u);
  EXPECT_EQ(byRank[9], 21u + 15u);
}

TEST(FeatherLod, ManyKeyBarbsStillReachLowLevelsDispersed) {
  // A vane of 31 barbs whose every barb but the ends is a key barb (the packer refines key barbs, so
  // packed feathers can have nearly as many key barbs as barbs): level f keeps about f x barbs, and the
  // key barbs kept at a low level are spread over the vane, not bunched at its base.
  FeatherCurves c;
  for (int i = 0; i <= 30; ++i) {
    BarbCurve b;
    b.rp = static_cast<float>(i / 30.0);
    b.isKey = true;
    c.barbs.push_back(b);
  }
  c.barbBegin = {0};
  c.barbEnd = {31};
  const LodOrder o = computeLodOrder(c);
  EXPECT_EQ(o.pinned, 2u);
  EXPECT_EQ(keptBarbCount(o, 0.2), 6u);
  EXPECT_EQ(keptBarbCount(o, 0.6), 19u);
  std::vector<uint32_t> kept;
  for (size_t i = 0; i < c.barbs.size(); ++i)
    if (o.rank[i] < keptBarbCount(o, 0.2)) kept.push_back(static_cast<uint32_t>(i));
  ASSERT_EQ(kept.size(), 6u);
  for (size_t i = 1; i < kept.size(); ++i) EXPECT_GE(kept[i] - kept[i - 1], 3u) << "kept barbs bunched";
}

TEST(FeatherLod, KeptCountAndSegmentsAreMonotone) {
  LodOrder o;
  o.rank.resize(200);
  o.pinned = 10;
  uint32_t prevK = 0;
  int prevS = 0;
  for (int i = 1; i <= 1000; ++i) {
    const double f = i / 1000.0;
    const uint32_t k = keptBarbCount(o, f);
    const int s = lodSegments(4, 2, 0.5, f);
    EXPECT_GE(k, prevK);
    EXPECT_GE(s, prevS);
    EXPECT_GE(k, 10u);
    EXPECT_GE(s, 2);
    prevK = k;
    prevS = s;
  }
  EXPECT_EQ(keptBarbCount(o, 1.0), 200u);
  EXPECT_EQ(keptBarbCount(o, 0.5), 100u);
  EXPECT_EQ(keptBarbCount(o, 0.001), 10u);
  EXPECT_EQ(lodSegments(4, 2, 0.5, 1.0), 4);
  EXPECT_EQ(lodSegments(4, 2, 0.5, 0.3), 3);
  EXPECT_EQ(lodSegments(4, 2, 0.5, 0.05), 2);
}

TEST(FeatherLod, TriangleCountMonotoneAndFullDetailMatchesStrips) {
  for (bool withSplits : {false, true}) {
    FeatherParams p = geomtest::contour(false);
    if (withSplits) p.splits.count = 4;
    const FeatherCurves c = generateBarbs(p);
    const LodOrder order = computeLodOrder(c);
    const MeshOptions opt;
    size_t prev = 0;
    for (int i = 1; i <= 100; ++i) {
      const double f = i / 100.0;
      const TriMesh m = meshAt(c, order, f, opt);
      EXPECT_GE(m.triangleCount(), prev) << "lod " << f;
      FeatherMeshInput in;
      in.curves = &c;
      in.order = &order;
      in.lod = f;
      EXPECT_EQ(featherMeshSize(in, opt).indices, m.indices.size());
      EXPECT_EQ(featherMeshSize(in, opt).vertices, m.vertexCount());
      prev = m.triangleCount();
    }
    // Full detail: 2 strips x 2 triangles x segments per barb, plus the shaft.
    const TriMesh full = meshAt(c, order, 1.0, opt);
    const size_t shaft = shaftTriangles(c, opt, 1.0);
    EXPECT_EQ(full.triangleCount(), c.barbs.size() * 2 * 2 * opt.barbSegments + shaft);
    // Shaft: (rings - 1) quads of `sides` plus the tip fan; follicle + 16 rachis rings (the straight,
    // linearly tapered calamus needs no ring in between).
    EXPECT_EQ(shaft, (17 - 1) * 4 * 2 + 4u);
    EXPECT_EQ(shaftTriangles(c, opt, 0.2), (5 - 1) * 4 * 2 + 4u);
  }
}

TEST(FeatherLod, ContourFeatherGoesFrom3000To200Triangles) {
  const FeatherCurves c = generateBarbs(geomtest::contour());
  const LodOrder order = computeLodOrder(c);
  const size_t full = meshAt(c, order, 1.0).triangleCount();
  const size_t tenth = meshAt(c, order, 0.1).triangleCount();
  const size_t lowest = meshAt(c, order, 0.01).triangleCount();
  EXPECT_GT(full, 2700u);
  EXPECT_LT(full, 3300u);
  EXPECT_LT(tenth, 260u);
  EXPECT_LT(lowest, 200u);
  EXPECT_GT(lowest, 40u);
}

TEST(FeatherLod, KeyBarbVerticesPresentAtEveryLevel) {
  FeatherParams p = geomtest::contour(false);
  p.splits.count = 2;
  const FeatherCurves c = generateBarbs(p);
  const LodOrder order = computeLodOrder(c);
  const MeshOptions opt;
  std::vector<glm::vec3> line;
  size_t keys = 0;
  for (const BarbCurve& b : c.barbs) keys += b.isKey && !b.isSplitEdge;
  // Key barbs rank right after the pinned barbs: present at every level that keeps at least that many.
  const double floorLevel = double(order.pinned + keys) / double(c.barbs.size());
  ASSERT_LT(floorLevel, 0.1);
  for (double f : {1.0, 0.7, 0.5, 0.3, 0.2, 0.1, floorLevel}) {
    const TriMesh m = meshAt(c, order, f, opt);
    std::set<std::tuple<float, float, float>> verts;
    for (const auto& v : m.positions) verts.insert({v.x, v.y, v.z});
    const int segs = lodSegments(opt.barbSegments, opt.minBarbSegments, opt.segmentLodStart, f);
    size_t checked = 0;
    for (const BarbCurve& b : c.barbs) {
      if (!b.isKey && !b.isSplitEdge) continue;
      barbPolyline(c, b, segs, line);
      for (const auto& q : line) EXPECT_TRUE(verts.count({q.x, q.y, q.z})) << "lod " << f << " rp " << b.rp;
      ++checked;
    }
    EXPECT_GE(checked, 5u);
  }
}

TEST(FeatherLod, OutlineAtTenthDetailWithinTenPercent) {
  const FeatherCurves c = generateBarbs(geomtest::contour(true));  // vane plane = xy
  const LodOrder order = computeLodOrder(c);
  auto outline = [&](double f) {
    FeatherMeshInput in;
    in.curves = &c;
    in.order = &order;
    in.lod = f;
    TriMesh m;
    FeatherMeshRanges r;
    appendFeatherMesh(in, MeshOptions{}, m, &r);
    std::vector<glm::dvec2> pts;
    for (uint32_t i = r.leftFirst; i < r.rightFirst + r.rightCount; ++i)
      pts.emplace_back(m.positions[m.indices[i]].x, m.positions[m.indices[i]].y);
    return geomtest::hullArea(pts);
  };
  const double full = outline(1.0);
  ASSERT_GT(full, 0.5);
  for (double f : {0.5, 0.2, 0.1}) EXPECT_NEAR(outline(f) / full, 1.0, 0.10) << "lod " << f;
}

// featherMeshLevel is all a level of detail decides: levels that give the same one mesh to the same
// vertices and indices, and any two different ones mesh differently (the mesher makes one mesh per level
// for instanced feathers on this).
TEST(FeatherMeshLevel, EqualLevelsMeshIdenticallyOthersDiffer) {
  const FeatherCurves c = generateBarbs(geomtest::contour(false));
  const LodOrder order = computeLodOrder(c);
  const MeshOptions opt;
  std::vector<FeatherMeshLevel> levels;
  std::vector<TriMesh> meshes;
  size_t sameLevelPairs = 0;
  for (int k = 1; k <= 200; ++k) {
    FeatherMeshInput in;
    in.curves = &c;
    in.order = &order;
    in.lod = k / 200.0;
    const FeatherMeshLevel level = featherMeshLevel(in, opt);
    TriMesh m;
    appendFeatherMesh(in, opt, m);
    for (size_t j = 0; j < levels.size(); ++j) {
      const bool sameMesh =
          m.positions == meshes[j].positions && m.indices == meshes[j].indices && m.uvBarb == meshes[j].uvBarb;
      EXPECT_EQ(level == levels[j], sameMesh) << "lod " << in.lod << " against entry " << j;
      sameLevelPairs += level == levels[j];
    }
    levels.push_back(level);
    meshes.push_back(std::move(m));
  }
  EXPECT_GT(sameLevelPairs, 0u);  // the level is coarser than the lod
}
