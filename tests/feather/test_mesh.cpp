// Feather surface generation (Streit 2003, 5.3, 7.1.1, 7.1.2): topology, attributes, placement, batch
// meshing, ranges.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/lod.hpp"
#include "pteryla/feather/mesh.hpp"
#include "test_mesh_fixtures.hpp"

using namespace pteryla;
using namespace pteryla::feather;

namespace {

TriMesh meshOf(const FeatherCurves& c, double lod = 1.0, FeatherMeshRanges* r = nullptr, const MeshOptions& o = {}) {
  FeatherMeshInput in;
  in.curves = &c;
  in.lod = lod;
  TriMesh m;
  appendFeatherMesh(in, o, m, r);
  return m;
}

void expectConsistent(const TriMesh& m) {
  const size_t n = m.positions.size();
  ASSERT_GT(n, 0u);
  EXPECT_EQ(m.normals.size(), n);
  EXPECT_EQ(m.tangents.size(), n);
  EXPECT_EQ(m.uvGlobal.size(), n);
  EXPECT_EQ(m.uvBarb.size(), n);
  EXPECT_EQ(m.uvGrowth.size(), n);
  EXPECT_EQ(m.alpha.size(), n);
  EXPECT_EQ(m.sheath.size(), n);
  EXPECT_EQ(m.barbCount.size(), n);
  EXPECT_EQ(m.featherId.size(), n);
  ASSERT_EQ(m.indices.size() % 3, 0u);
  for (uint32_t i : m.indices) ASSERT_LT(i, n);
  for (size_t i = 0; i < n; ++i) {
    ASSERT_NEAR(glm::length(m.normals[i].get()), 1.0f, 1e-4f) << i;
    ASSERT_NEAR(glm::length(m.tangents[i].get()), 1.0f, 1e-4f) << i;
    for (const auto* uv : {&m.uvGlobal[i], &m.uvBarb[i], &m.uvGrowth[i]}) {
      ASSERT_GE(uv->x, 0.0f);
      ASSERT_LE(uv->x, 1.0f);
      ASSERT_GE(uv->y, 0.0f);
      ASSERT_LE(uv->y, 1.0f);
    }
    ASSERT_GE(m.alpha[i], 0.0f);
    ASSERT_LE(m.alpha[i], 1.0f);
  }
}

glm::vec3 faceNormal(const TriMesh& m, size_t t) {
  const glm::vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]],
                  c = m.positions[m.indices[3 * t + 2]];
  return glm::cross(b - a, c - a);
}

// Vertex index of each position (exact float match).
std::map<std::tuple<float, float, float>, uint32_t> vertexIndex(const TriMesh& m) {
  std::map<std::tuple<float, float, float>, uint32_t> idx;
  for (uint32_t i = 0; i < m.positions.size(); ++i)
    idx.emplace(std::make_tuple(m.positions[i].x, m.positions[i].y, m.positions[i].z), i);
  return idx;
}

}  // namespace

TEST(FeatherMesh, AttributesAreCompleteAndInRange) {
  for (bool flat : {true, false})
    for (double lod : {1.0, 0.4, 0.05}) {
      const FeatherCurves c = generateBarbs(geomtest::contour(flat));
      expectConsistent(meshOf(c, lod));
    }
}

TEST(FeatherMesh, VaneNormalsAreDorsalAndAgreeWithWinding) {
  // Pennaceous barbs everywhere (the default plumulaceous base barbs legitimately cross each other).
  FeatherParams p = geomtest::contour(true);
  for (int v = 0; v < 2; ++v)
    p.vane(v).keyBarbs.insert(p.vane(v).keyBarbs.begin(), geomtest::key(0.0, {{0, 0, 0}, {1, 0, 0}}));
  const FeatherCurves c = generateBarbs(p);
  FeatherMeshRanges r;
  const TriMesh m = meshOf(c, 1.0, &r);
  size_t checked = 0;
  for (uint32_t i = r.leftFirst; i < r.rightFirst + r.rightCount; i += 3) {
    const glm::vec3 fn = faceNormal(m, i / 3);
    if (glm::length(fn) < 1e-9f) continue;
    EXPECT_GT(fn.z, 0.0f) << "triangle " << i / 3;
    for (int k = 0; k < 3; ++k) EXPECT_GT(glm::dot(glm::normalize(fn), m.normals[m.indices[i + k]].get()), 0.5f);
    ++checked;
  }
  EXPECT_GT(checked, 2000u);
  // Shaft faces point away from the centre line.
  for (uint32_t i = r.shaftFirst; i < r.shaftFirst + r.shaftCount; i += 3) {
    const glm::vec3 fn = faceNormal(m, i / 3);
    if (glm::length(fn) < 1e-12f) continue;
    const glm::vec3 centroid =
        (m.positions[m.indices[i]] + m.positions[m.indices[i + 1]] + m.positions[m.indices[i + 2]]) / 3.0f;
    const glm::vec3 radial(0, centroid.y, centroid.z);
    if (glm::length(radial) > 1e-6f) {
      EXPECT_GT(glm::dot(fn, radial), 0.0f);
    }
  }
}

TEST(FeatherMesh, VanesAreConnectedAndSplitsLeaveBoundaries) {
  FeatherParams p = geomtest::contour(false);
  {
    FeatherMeshRanges r;
    const TriMesh m = meshOf(generateBarbs(p), 1.0, &r);
    EXPECT_EQ(geomtest::components(m, r.leftFirst, r.leftCount), 1u);
    EXPECT_EQ(geomtest::components(m, r.rightFirst, r.rightCount), 1u);
    EXPECT_EQ(geomtest::components(m, r.shaftFirst, r.shaftCount), 1u);  // calamus and rachis: no seam
  }
  p.splits.count = 3;
  const FeatherCurves c = generateBarbs(p);
  size_t splitsLeft = 0, splitsRight = 0;
  for (const BarbCurve& b : c.barbs)
    if (b.splitAfter) (b.vane == 0 ? splitsLeft : splitsRight)++;
  ASSERT_GT(splitsLeft, 0u);
  for (double lod : {1.0, 0.3, 0.05}) {
    FeatherMeshRanges r;
    const TriMesh m = meshOf(c, lod, &r);
    EXPECT_EQ(geomtest::components(m, r.leftFirst, r.leftCount), splitsLeft + 1) << lod;
    EXPECT_EQ(geomtest::components(m, r.rightFirst, r.rightCount), splitsRight + 1) << lod;
  }
}

TEST(FeatherMesh, ShaftTapersWithoutSeamToAPoint) {
  const FeatherParams p = geomtest::contour(true);
  const FeatherCurves c = generateBarbs(p);
  FeatherMeshRanges r;
  const TriMesh m = meshOf(c, 1.0, &r);
  // Radius of the shaft vertices as a function of x: calamus base = ratio * width / 2, umbilicus =
  // width / 2 (continuous), tip = 0.
  float rBase = 0, rUmb = 0, rTip = 1;
  float xTip = 0;
  std::set<uint32_t> shaftVerts(m.indices.begin() + r.shaftFirst, m.indices.begin() + r.shaftFirst + r.shaftCount);
  for (uint32_t v : shaftVerts) xTip = std::max(xTip, m.positions[v].x);
  for (uint32_t v : shaftVerts) {
    const glm::vec3 q = m.positions[v];
    const float rad = std::hypot(q.y, q.z);
    if (std::abs(q.x) < 1e-6f) rBase = std::max(rBase, rad);
    if (std::abs(q.x - static_cast<float>(p.calamusLength)) < 1e-6f) rUmb = std::max(rUmb, rad);
    if (std::abs(q.x - xTip) < 1e-6f) rTip = std::min(rTip, rad);
  }
  EXPECT_NEAR(rBase, 0.5 * p.calamusWidthRatio * p.rachisWidth, 1e-6);
  EXPECT_NEAR(rUmb, 0.5 * p.rachisWidth, 1e-6);
  EXPECT_NEAR(xTip, p.totalLength(), 1e-5);
  EXPECT_EQ(rTip, 0.0f);
}

TEST(FeatherMesh, TextureCoordinatesContinuousAlongBarbs) {
  const FeatherCurves c = generateBarbs(geomtest::contour(true));
  const TriMesh m = meshOf(c);
  const auto idx = vertexIndex(m);
  // Lipschitz bound of the global map on a flat feather: |d uv| <= |d p| (1 / (2 maxAcross) + 1 / alongRange).
  float maxAcross = 0, xMin = 0, xMax = 0;
  for (const auto& q : m.positions) {
    maxAcross = std::max(maxAcross, std::abs(q.y));
    xMin = std::min(xMin, q.x);
    xMax = std::max(xMax, q.x);
  }
  const float lip = 1.0f / (2 * maxAcross) + 1.0f / (xMax - xMin);
  std::vector<glm::vec3> line;
  size_t checked = 0;
  for (const BarbCurve& b : c.barbs) {
    barbPolyline(c, b, 4, line);
    std::vector<uint32_t> vs;
    for (const auto& q : line) {
      auto it = idx.find({q.x, q.y, q.z});
      ASSERT_NE(it, idx.end());
      vs.push_back(it->second);
    }
    const float side = b.vane == 0 ? 1.0f : -1.0f;
    for (size_t k = 1; k < vs.size(); ++k) {
      const glm::vec2 dG = m.uvGlobal[vs[k]] - m.uvGlobal[vs[k - 1]];
      EXPECT_LE(glm::length(dG), 1.02f * lip * glm::length(line[k] - line[k - 1]) + 1e-6f);
      // Barb map: u moves away from the rachis linearly in t; v is the barb's rp.
      const float du = m.uvBarb[vs[k]].x - m.uvBarb[vs[k - 1]].x;
      EXPECT_LE(side * du, 0.0f);
      EXPECT_NEAR(du, m.uvBarb[vs[1]].x - m.uvBarb[vs[0]].x, 1e-5f);
      EXPECT_NEAR(m.uvBarb[vs[k]].y, b.rp, 1e-6f);
      // Growth map: around the cone from the rachis (0.5) toward the ventral seam, up the shaft.
      EXPECT_NEAR(m.uvGrowth[vs[k]].x, 0.5f - side * 0.5f * k / 4.0f, 1e-5f);
      EXPECT_GT(m.uvGrowth[vs[k]].y, m.uvGrowth[vs[k - 1]].y);
    }
    EXPECT_NEAR(m.uvGrowth[vs[0]].x, 0.5f, 1e-6f);
    ++checked;
  }
  EXPECT_EQ(checked, c.barbs.size());
  // Global map orientation: left vane u < 0.5, right vane u > 0.5; v grows toward the tip.
  float vMin = 1, vMax = 0;
  for (size_t i = 0; i < m.positions.size(); ++i) {
    if (m.positions[i].y > 0.05f) {
      EXPECT_LT(m.uvGlobal[i].x, 0.5f);
    }
    if (m.positions[i].y < -0.05f) {
      EXPECT_GT(m.uvGlobal[i].x, 0.5f);
    }
    vMin = std::min(vMin, m.uvGlobal[i].y);
    vMax = std::max(vMax, m.uvGlobal[i].y);
  }
  EXPECT_LT(vMin, 0.01f);
  EXPECT_GT(vMax, 0.95f);
}

TEST(FeatherMesh, AlphaFallsOffQuadraticallyEarlierOnTheEdges) {
  const FeatherCurves c = generateBarbs(geomtest::contour(true));
  MeshOptions opt;
  opt.alphaTip = 0.1;
  const TriMesh m = meshOf(c, 1.0, nullptr, opt);
  const auto idx = vertexIndex(m);
  std::vector<glm::vec3> line;
  const BarbCurve& b = c.barbs[20];
  barbPolyline(c, b, 4, line);
  std::vector<float> a;
  for (const auto& q : line) a.push_back(m.alpha[idx.at({q.x, q.y, q.z})]);
  EXPECT_EQ(a[0], 1.0f);
  EXPECT_EQ(a[3], 1.0f);                 // centre row: fall-off over the last segment only
  EXPECT_NEAR(a[4], 0.1f, 0.1f / 2048);  // alpha is a half float (11 significant bits)
  // Side rows: midpoint between barbs 20 and 21, fall-off over the last two segments, quadratic.
  std::vector<glm::vec3> next;
  barbPolyline(c, c.barbs[21], 4, next);
  std::vector<float> e;
  for (size_t k = 0; k < line.size(); ++k) {
    const glm::vec3 q = 0.5f * line[k] + 0.5f * next[k];
    const glm::vec3 mid(q.x, q.y, q.z);
    // Nearest vertex (the mesher uses the same midpoint).
    float best = 1e9f;
    uint32_t bi = 0;
    for (uint32_t i = 0; i < m.positions.size(); ++i) {
      const float d = glm::length(m.positions[i] - mid);
      if (d < best) {
        best = d;
        bi = i;
      }
    }
    ASSERT_LT(best, 1e-5f);
    e.push_back(m.alpha[bi]);
  }
  EXPECT_EQ(e[2], 1.0f);
  EXPECT_NEAR(e[3], 1.0f - 0.9f * 0.25f, 0.775f / 2048);
  EXPECT_NEAR(e[4], 0.1f, 0.1f / 2048);
}

TEST(FeatherMesh, BarbCountIsOneAtFullDetailAndGrowsAtLowDetail) {
  const FeatherCurves c = generateBarbs(geomtest::contour(true));
  FeatherMeshRanges r;
  const TriMesh full = meshOf(c, 1.0, &r);
  for (uint32_t i = r.leftFirst; i < r.rightFirst + r.rightCount; ++i) EXPECT_EQ(full.barbCount[full.indices[i]], 1.0f);
  const TriMesh low = meshOf(c, 0.1, &r);
  float maxCount = 0;
  for (uint32_t i = r.leftFirst; i < r.rightFirst + r.rightCount; ++i)
    maxCount = std::max(maxCount, static_cast<float>(low.barbCount[low.indices[i]]));
  EXPECT_GT(maxCount, 4.0f);
  // Summed over kept barbs' centre rows (t = 0 vertices) the counts cover every barb once.
  double sum = 0;
  const LodOrder order = computeLodOrder(c);
  const uint32_t keep = keptBarbCount(order, 0.1);
  const auto idx = vertexIndex(low);
  std::vector<glm::vec3> line;
  const int segs = lodSegments(4, 2, 0.5, 0.1);
  for (size_t i = 0; i < c.barbs.size(); ++i) {
    if (order.rank[i] >= keep) continue;
    barbPolyline(c, c.barbs[i], segs, line);
    sum += low.barbCount[idx.at({line[0].x, line[0].y, line[0].z})];
  }
  EXPECT_NEAR(sum, static_cast<double>(c.barbs.size()), 2.0);  // ends count half a gap beyond
}

TEST(FeatherMesh, PlacementTransformsPositionsNormalsTangents) {
  const FeatherCurves c = generateBarbs(geomtest::contour(false));
  const TriMesh local = meshOf(c, 0.5);
  const glm::dvec3 T = glm::normalize(glm::dvec3(1, 1, 0)), N(0, 0, 1);
  const FeatherPlacement pl = FeatherPlacement::fromFollicle({3, -2, 5}, T, N, 0.3, 2.0);
  TriMesh world;
  world.positions.push_back({9, 9, 9});  // existing content without attributes is padded
  world.indices = {0, 0, 0};
  FeatherMeshInput in;
  in.curves = &c;
  in.lod = 0.5;
  in.placement = pl;
  in.featherId = 17;
  appendFeatherMesh(in, MeshOptions{}, world);
  ASSERT_EQ(world.vertexCount(), local.vertexCount() + 1);
  EXPECT_EQ(world.normals.size(), world.vertexCount());
  EXPECT_EQ(world.featherId[0], 0u);
  for (size_t i = 0; i < local.vertexCount(); ++i) {
    const glm::dvec3 p(local.positions[i]);
    const glm::dvec3 expect = pl.origin + p.x * pl.x + p.y * pl.y + p.z * pl.z;
    ASSERT_NEAR(glm::length(glm::dvec3(world.positions[i + 1]) - expect), 0.0, 1e-5);
    const glm::dvec3 n(local.normals[i].get());
    const glm::dvec3 en = glm::normalize(n.x * pl.x + n.y * pl.y + n.z * pl.z);  // rotation + uniform scale
    ASSERT_NEAR(glm::length(glm::dvec3(world.normals[i + 1].get()) - en), 0.0, 1e-4);
    EXPECT_EQ(world.featherId[i + 1], 17u);
    EXPECT_EQ(world.uvGlobal[i + 1], local.uvGlobal[i]);
  }
  for (size_t i = 3; i < world.indices.size(); ++i) EXPECT_EQ(world.indices[i], local.indices[i - 3] + 1);
}

TEST(FeatherMesh, BatchEqualsSequentialAppends) {
  FeatherParams a = geomtest::contour(false);
  FeatherParams b = geomtest::contour(true);
  b.splits.count = 2;
  auto after = std::make_shared<FeatherParams>(geomtest::contour(true));
  after->rachisLength = 0.4;
  after->barbLength = 0.1;
  after->silhouette = {};
  b.afterfeather = after;
  const FeatherCurves ca = generateBarbs(a), cb = generateBarbs(b);
  const LodOrder oa = computeLodOrder(ca);
  std::vector<FeatherMeshInput> ins;
  for (int i = 0; i < 40; ++i) {
    FeatherMeshInput in;
    in.curves = i % 2 ? &cb : &ca;
    in.order = i % 2 ? nullptr : &oa;
    in.lod = 0.05 + 0.95 * (i % 7) / 6.0;
    in.featherId = static_cast<uint32_t>(i);
    in.placement.origin = {i * 0.1, 0, 0};
    ins.push_back(in);
  }
  TriMesh seq, par;
  std::vector<FeatherMeshRanges> rs(ins.size()), rp;
  for (size_t i = 0; i < ins.size(); ++i) appendFeatherMesh(ins[i], MeshOptions{}, seq, &rs[i]);
  appendFeatherMeshes(ins.data(), ins.size(), MeshOptions{}, par, &rp);
  EXPECT_EQ(seq.positions, par.positions);
  EXPECT_EQ(seq.normals, par.normals);
  EXPECT_EQ(seq.uvGlobal, par.uvGlobal);
  EXPECT_EQ(seq.uvGrowth, par.uvGrowth);
  EXPECT_EQ(seq.alpha, par.alpha);
  EXPECT_EQ(seq.barbCount, par.barbCount);
  EXPECT_EQ(seq.featherId, par.featherId);
  EXPECT_EQ(seq.indices, par.indices);
  ASSERT_EQ(rp.size(), rs.size());
  for (size_t i = 0; i < rs.size(); ++i) {
    EXPECT_EQ(rs[i].leftFirst, rp[i].leftFirst);
    EXPECT_EQ(rs[i].afterCount, rp[i].afterCount);
    if (i % 2) {
      EXPECT_GT(rs[i].afterCount, 0u);
    } else
      EXPECT_EQ(rs[i].afterCount, 0u);
  }
}

TEST(FeatherMesh, RangesPartitionIndicesInBarbOrder) {
  FeatherParams p = geomtest::contour(true);
  auto after = std::make_shared<FeatherParams>(geomtest::contour(true));
  after->rachisLength = 0.4;
  after->silhouette = {};
  after->barbLength = 0.1;
  p.afterfeather = after;
  const FeatherCurves c = generateBarbs(p);
  FeatherMeshRanges r;
  const TriMesh m = meshOf(c, 0.6, &r);
  EXPECT_EQ(r.shaftFirst, 0u);
  EXPECT_EQ(r.leftFirst, r.shaftFirst + r.shaftCount);
  EXPECT_EQ(r.rightFirst, r.leftFirst + r.leftCount);
  EXPECT_EQ(r.afterFirst, r.rightFirst + r.rightCount);
  EXPECT_EQ(r.afterFirst + r.afterCount, m.indices.size());
  for (uint32_t i = r.leftFirst; i < r.leftFirst + r.leftCount; ++i) EXPECT_GE(m.positions[m.indices[i]].y, -1e-6f);
  for (uint32_t i = r.rightFirst; i < r.rightFirst + r.rightCount; ++i) EXPECT_LE(m.positions[m.indices[i]].y, 1e-6f);
  // Barb order base to tip: ribbon root vertices (t = 0, the first vertex of each ribbon's first
  // triangle) move up the shaft.
  const int segs = lodSegments(4, 2, 0.5, 0.6);
  const uint32_t perRibbon = 2 * 2 * 3 * static_cast<uint32_t>(segs);
  float prevX = -1;
  for (uint32_t i = r.leftFirst; i < r.leftFirst + r.leftCount; i += perRibbon) {
    const float x = m.positions[m.indices[i]].x;
    EXPECT_GT(x, prevX);
    prevX = x;
  }
}

TEST(FeatherMesh, RejectsBadInput) {
  const FeatherParams p = geomtest::contour();
  MeshOptions bad;
  bad.barbSegments = 0;
  EXPECT_THROW(buildFeatherMesh(p, 1.0, 1.0, bad), Error);
  bad = {};
  bad.shaftSides = 2;
  EXPECT_THROW(buildFeatherMesh(p, 1.0, 1.0, bad), Error);
  EXPECT_THROW(buildFeatherMesh(p, 1.0, 0.0), Error);
  EXPECT_THROW(buildFeatherMesh(p, 1.0, 1.5), Error);
  EXPECT_THROW(buildFeatherMesh(p, std::nan(""), 1.0), Error);
  FeatherParams q = p;
  q.spacingBase = -1;
  EXPECT_THROW(buildFeatherMesh(q, 1.0, 1.0), Error);
}

TEST(FeatherMesh, DownFeatherAndSingleBarbVanes) {
  FeatherParams down;
  down.rachisLength = 0.05;
  down.spacingBase = down.spacingTip = 0.01;
  down.barbLength = 0.2;
  expectConsistent(buildFeatherMesh(down, 1.0, 1.0));
  FeatherParams one = down;
  one.spacingBase = one.spacingTip = 1.0;  // one barb per vane
  const TriMesh m = buildFeatherMesh(one, 1.0, 1.0);
  expectConsistent(m);
  EXPECT_EQ(generateBarbs(one).barbs.size(), 2u);
}
