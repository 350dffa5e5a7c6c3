// Follicle scattering: determinism, stable prefixes, area and density weighting, pinned placement.
#include <gtest/gtest.h>

#include <cstring>

#include <glm/geometric.hpp>

#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/primitives.hpp"
#include "pteryla/core/error.hpp"

using namespace pteryla;
using namespace pteryla::coat;

namespace {

bool sameBits(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b, size_t n) {
  return a.size() >= n && b.size() >= n && std::memcmp(a.data(), b.data(), n * sizeof(glm::dvec3)) == 0;
}

}  // namespace

TEST(Scatter, SameSeedBitIdenticalOtherSeedDifferent) {
  const SkinMesh m = makeIcosphere(3);
  const Tract t = wholeMeshTract(m);
  ScatterOptions o;
  o.count = 3000;
  o.seed = 17;
  const Follicles a = scatterFollicles(m, t, o), b = scatterFollicles(m, t, o);
  ASSERT_EQ(a.size(), 3000u);
  EXPECT_TRUE(sameBits(a.position, b.position, a.size()));
  EXPECT_TRUE(sameBits(a.bary, b.bary, a.size()));
  EXPECT_EQ(a.face, b.face);
  o.seed = 18;
  const Follicles c = scatterFollicles(m, t, o);
  EXPECT_FALSE(sameBits(a.position, c.position, a.size()));
}

TEST(Scatter, MoreFolliclesKeepTheFirstOnes) {
  const SkinMesh m = makeGridPatch(10, 10);
  const Tract t = wholeMeshTract(m);
  ScatterOptions o;
  o.seed = 5;
  o.density.uniform = 1000;
  const Follicles a = scatterFollicles(m, t, o);
  EXPECT_EQ(a.size(), 1000u);
  o.density.uniform = 1100;  // 10% more
  const Follicles b = scatterFollicles(m, t, o);
  ASSERT_EQ(b.size(), 1100u);
  EXPECT_TRUE(sameBits(a.position, b.position, a.size()));
  EXPECT_TRUE(std::equal(a.face.begin(), a.face.end(), b.face.begin()));
  EXPECT_TRUE(std::equal(a.id.begin(), a.id.end(), b.id.begin()));
}

TEST(Scatter, FolliclesLieInsideTractFacesWithUnitNormals) {
  const SkinMesh m = makeGridPatch(6, 6);
  Tract t;
  for (uint32_t f = 0; f < m.faceCount(); f += 3) t.faces.push_back(f);
  ScatterOptions o;
  o.count = 2000;
  o.tractIndex = 3;
  const Follicles f = scatterFollicles(m, t, o);
  for (size_t i = 0; i < f.size(); ++i) {
    ASSERT_TRUE(t.contains(f.face[i]));
    EXPECT_GT(f.bary[i].x, 0);
    EXPECT_GT(f.bary[i].y, 0);
    EXPECT_GT(f.bary[i].z, 0);
    EXPECT_NEAR(f.bary[i].x + f.bary[i].y + f.bary[i].z, 1.0, 1e-12);
    EXPECT_NEAR(glm::length(f.normal[i]), 1.0, 1e-12);
    EXPECT_EQ(f.position[i], pointAt(m, f.face[i], f.bary[i]));
    EXPECT_EQ(f.tract[i], 3u);
    EXPECT_EQ(f.id[i], (uint64_t(3) << 40) + i);
    EXPECT_EQ(f.pinned[i], 0);
  }
}

TEST(Scatter, AreaWeightedFaceChoice) {
  // One small and one large triangle: follicles split by area (9:1).
  const SkinMesh m =
      makeSkinMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-3, 0, 0}, {0, -3, 0}}, {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}});
  Tract t;
  t.faces = {0, 2};  // areas 0.5 and 4.5
  ScatterOptions o;
  o.count = 20000;
  const Follicles f = scatterFollicles(m, t, o);
  size_t big = 0;
  for (uint32_t face : f.face) big += face == 2;
  EXPECT_NEAR(double(big) / f.size(), 0.9, 0.01);
}

TEST(Scatter, PerVertexDensityIsLinearAcrossFaces) {
  // Density proportional to x on [0,1]^2: count = integral = 0.5 * 4000, mean x = 2/3.
  const SkinMesh m = makeGridPatch(8, 8);
  const Tract t = wholeMeshTract(m);
  ScatterOptions o;
  for (const auto& p : m.positions) o.density.perVertex.push_back(4000.0 * p.x);
  EXPECT_EQ(expectedFollicleCount(m, t, o.density), 2000u);
  const Follicles f = scatterFollicles(m, t, o);
  ASSERT_EQ(f.size(), 2000u);
  double mean = 0;
  for (const auto& p : f.position) mean += p.x;
  mean /= f.size();
  EXPECT_NEAR(mean, 2.0 / 3.0, 0.015);
  o.density.perVertex.pop_back();
  EXPECT_THROW(scatterFollicles(m, t, o), Error);
}

TEST(Scatter, DensityMultiplierPicksFaces) {
  const SkinMesh m = makeGridPatch(8, 8);
  const Tract t = wholeMeshTract(m);
  ScatterOptions o;
  o.count = 4000;
  o.density.multiplier = [&](uint32_t face, const glm::dvec3& b) { return pointAt(m, face, b).y < 0.5 ? 0.0 : 1.0; };
  const Follicles f = scatterFollicles(m, t, o);
  for (const auto& p : f.position) ASSERT_GE(p.y, 0.5);
}

TEST(Scatter, RejectsBadDensity) {
  const SkinMesh m = makeGridPatch(2, 2);
  const Tract t = wholeMeshTract(m);
  ScatterOptions o;
  EXPECT_THROW(scatterFollicles(m, t, o), Error);  // neither density nor count
  o.density.uniform = -1;
  EXPECT_THROW(scatterFollicles(m, t, o), Error);
  o.density.uniform = 1e12;
  EXPECT_THROW(scatterFollicles(m, t, o), Error);  // runaway count
}

TEST(Follicles, PinnedPlacementAndDeformation) {
  SkinMesh m = makeGridPatch(4, 4);
  Tract right;
  for (uint32_t f = 0; f < m.faceCount(); ++f)
    if (pointAt(m, f, glm::dvec3(1.0 / 3)).x > 0.5) right.faces.push_back(f);
  Follicles f;
  const size_t a = addPinnedFollicleNear(f, m, right, {0.1, 0.3, 1.0}, 0, 99);  // left of the tract: snaps to x = 0.5
  EXPECT_NEAR(f.position[a].x, 0.5, 1e-12);
  EXPECT_NEAR(f.position[a].y, 0.3, 1e-12);
  EXPECT_EQ(f.pinned[a], 1);
  EXPECT_EQ(f.id[a], 99u);
  const size_t b = addPinnedFollicle(f, m, {7, {0.2, 0.3, 0.5}}, 0, 100);
  EXPECT_THROW(addPinnedFollicle(f, m, {7, {0.2, 0.3, 0.6}}, 0, 101), Error);
  EXPECT_THROW(addPinnedFollicle(f, m, {700, {0.2, 0.3, 0.5}}, 0, 101), Error);
  // Follicles ride the skin: lift it and they follow.
  for (auto& p : m.positions) p.z += p.x;
  recomputeGeometry(m);
  updateFollicleGeometry(m, f);
  EXPECT_NEAR(f.position[b].z, f.position[b].x, 1e-12);
  EXPECT_NEAR(f.normal[b].x, -std::sqrt(0.5), 1e-9);
}
