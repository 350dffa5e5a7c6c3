// Packing on a posed skin from the rest pose's pack (coat::packDeformed, Streit 2003 8.3): feathers whose
// surroundings moved rigidly with them are carried, the others packed again.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>

#include "pack_fixtures.hpp"
#include "pteryla/coat/check.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/primitives.hpp"
#include "pteryla/core/error.hpp"

using namespace pteryla;
using namespace pteryla::coat;
using glm::dvec3;

namespace {

struct Rest {
  SkinMesh skin = makeIcosphere(3);
  CoatFeathers coat = packtest::sphereCoat(skin, 300, 1.0);
  PackResult pack;
  Rest() {
    PackOptions o;
    o.threads = 2;
    pack = coat::pack(skin, coat, o);
  }
};

const Rest& rest() {
  static const Rest r;
  return r;
}

std::vector<FeatherFrame> framesOf(const CoatFeathers& c) { return c.frames; }

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// The skin pushed out along its normal by `amount` x smoothstep over z in [z0, z0 + 0.3]: the south
// (z < z0) does not move at all, the north bulges.
SkinMesh bulged(const SkinMesh& s, double z0, double amount) {
  SkinMesh out = s;
  for (auto& p : out.positions) {
    const double u = std::clamp((p.z - z0) / 0.3, 0.0, 1.0);
    const double w = u * u * (3 - 2 * u);
    if (w > 0) p += amount * w * glm::normalize(p);
  }
  recomputeGeometry(out);
  return out;
}

// The rest coat's follicles on a posed skin: each follicle keeps its face and barycentric coordinates,
// its frame follows the face (tangent toward the south pole, projected).
CoatFeathers posedCoat(const SkinMesh& restSkin, const SkinMesh& posed, const CoatFeathers& c) {
  CoatFeathers out = c;
  for (size_t i = 0; i < c.size(); ++i) {
    const SurfacePoint sp = closestSurfacePoint(restSkin, c.frames[i].origin);
    FeatherFrame& f = out.frames[i];
    const dvec3 o = pointAt(posed, sp);
    const dvec3 n = normalAt(posed, sp.face, sp.bary);
    if (o == c.frames[i].origin && n == c.frames[i].normal) continue;  // untouched skin: the same frame
    f.origin = o;
    f.normal = n;
    const dvec3 t = dvec3(0, 0, -1) - glm::dot(dvec3(0, 0, -1), n) * n;
    f.tangent = glm::normalize(t);
    f.binormal = glm::normalize(glm::cross(n, f.tangent));
  }
  return out;
}

}  // namespace

// A rigid motion of the whole skin and coat moves nothing relative to anything: every feather is
// carried, with the reference's elevations and key barbs, and its points where the motion puts them.
TEST(PackDeformed, ARigidMotionCarriesEveryFeather) {
  const Rest& r = rest();
  const double a = 0.7;
  const dvec3 shift(0.3, -1.2, 2.0);
  auto move = [&](const dvec3& p) {
    return dvec3(std::cos(a) * p.x - std::sin(a) * p.y, std::sin(a) * p.x + std::cos(a) * p.y, p.z) + shift;
  };
  auto turn = [&](const dvec3& d) { return move(d) - move(dvec3(0)); };
  SkinMesh skin = r.skin;
  for (auto& p : skin.positions) p = move(p);
  recomputeGeometry(skin);
  CoatFeathers coat = r.coat;
  for (auto& f : coat.frames) {
    f.origin = move(f.origin);
    f.normal = turn(f.normal);
    f.tangent = turn(f.tangent);
    f.binormal = turn(f.binormal);
  }
  PackOptions o;
  o.threads = 2;
  DeformedPackStats st;
  const PackResult d = packDeformed(skin, coat, r.skin, framesOf(r.coat), r.pack, 0.25, o, {}, &st);
  EXPECT_EQ(st.moved, 0u);
  EXPECT_EQ(st.repacked, 0u);
  EXPECT_EQ(d.stats.recomputed, 0u);
  ASSERT_EQ(d.elevation.size(), r.pack.elevation.size());
  for (size_t i = 0; i < d.elevation.size(); ++i) ASSERT_TRUE(sameBits(d.elevation[i], r.pack.elevation[i])) << i;
  EXPECT_EQ(d.packedKeys.keyOffset, r.pack.packedKeys.keyOffset);
  ASSERT_EQ(d.points.size(), r.pack.points.size());
  double worst = 0;
  for (size_t q = 0; q < d.points.size(); ++q) {
    const glm::vec4& p = r.pack.points[q];
    worst = std::max(worst, glm::length(move(dvec3(p.x, p.y, p.z)) - dvec3(d.points[q])));
  }
  EXPECT_LT(worst, 1e-5);
  // The same coat: its proxy intersects itself exactly as the reference's does.
  const TriMesh a0 = proxyCoatMesh(r.coat, r.pack.elevation, allPackedParams(r.coat, r.pack));
  const TriMesh a1 = proxyCoatMesh(coat, d.elevation, allPackedParams(coat, d));
  EXPECT_EQ(countIntersectingPairs(a0, 2), countIntersectingPairs(a1, 2));
}

// Tolerance 0 is a full pack of the posed coat, bit for bit.
TEST(PackDeformed, ToleranceZeroIsAFullPack) {
  const Rest& r = rest();
  const SkinMesh skin = bulged(r.skin, 0.1, 0.08);
  const CoatFeathers coat = posedCoat(r.skin, skin, r.coat);
  PackOptions o;
  o.threads = 2;
  const PackResult full = pack(skin, coat, o);
  const PackResult d = packDeformed(skin, coat, r.skin, framesOf(r.coat), r.pack, 0.0, o);
  for (size_t i = 0; i < full.elevation.size(); ++i) ASSERT_TRUE(sameBits(d.elevation[i], full.elevation[i])) << i;
  EXPECT_EQ(d.stats.recomputed, full.stats.recomputed);
}

// A bulge in the north: the south does not move, and only what lies in or over the bulge (the layer
// order runs south to north, so the bulge's feathers lie over the south's) packs again.
TEST(PackDeformed, ALocalBulgeRepacksOnlyWhatItMoved) {
  const Rest& r = rest();
  const SkinMesh skin = bulged(r.skin, 0.2, 0.08);
  const CoatFeathers coat = posedCoat(r.skin, skin, r.coat);
  PackOptions o;
  o.threads = 2;
  DeformedPackStats st;
  const PackResult d = packDeformed(skin, coat, r.skin, framesOf(r.coat), r.pack, 0.25, o, {}, &st);
  const PackResult full = pack(skin, coat, o);
  size_t south = 0, north = 0;
  for (size_t i = 0; i < coat.size(); ++i) {
    if (r.coat.frames[i].origin.z < -0.3) {
      ++south;
      EXPECT_EQ(d.recomputed[i], 0) << "feather " << i << " far south of the bulge was packed again";
    }
    if (r.coat.frames[i].origin.z > 0.5) {
      ++north;
      EXPECT_EQ(d.recomputed[i], 1) << "feather " << i << " on the bulge was carried";
    }
  }
  ASSERT_GT(south, 50u);
  ASSERT_GT(north, 20u);
  EXPECT_GT(st.moved, 0u);
  EXPECT_LT(st.repacked, coat.size());
  EXPECT_GE(st.repacked, st.moved);
  // Against a full pack of the posed coat: feathers whose surroundings did not move at all are the full
  // pack's bits; the rest (carried within the tolerance, or packed over those) differ a little, and the
  // coat is as clean: its proxy crosses itself no more than 10% more often, and nothing enters the skin.
  size_t differ = 0;
  double worst = 0;
  for (size_t i = 0; i < full.elevation.size(); ++i) {
    if (sameBits(d.elevation[i], full.elevation[i])) continue;
    ++differ;
    worst = std::max(worst, std::abs(d.elevation[i] - full.elevation[i]));
  }
  EXPECT_LT(worst, 0.01);
  const TriMesh pf = proxyCoatMesh(coat, full.elevation, allPackedParams(coat, full));
  const TriMesh pd = proxyCoatMesh(coat, d.elevation, allPackedParams(coat, d));
  const size_t pairsFull = countIntersectingPairs(pf, 2), pairsDeformed = countIntersectingPairs(pd, 2);
  EXPECT_LE(double(pairsDeformed), 1.1 * double(pairsFull) + 2) << pairsFull;
  CheckOptions co;
  co.intersections = false;
  co.coverage = false;
  EXPECT_EQ(check(skin, {}, pd, co).skinPenetrations, check(skin, {}, pf, co).skinPenetrations);
  std::printf(
      "bulge: %zu feathers, %zu moved, %zu packed again, %zu differ from the full pack (worst %.2g rad), "
      "proxy pairs %zu vs %zu\n",
      coat.size(), st.moved, st.repacked, differ, worst, pairsDeformed, pairsFull);
}

TEST(PackDeformed, BadInputIsAnError) {
  const Rest& r = rest();
  PackOptions o;
  EXPECT_THROW(packDeformed(r.skin, r.coat, r.skin, framesOf(r.coat), r.pack, -1.0, o), Error);
  EXPECT_THROW(packDeformed(r.skin, r.coat, r.skin, framesOf(r.coat), r.pack, std::nan(""), o), Error);
  std::vector<FeatherFrame> fewer = framesOf(r.coat);
  fewer.pop_back();
  EXPECT_THROW(packDeformed(r.skin, r.coat, r.skin, fewer, r.pack, 0.25, o), Error);
  SkinMesh other = makeIcosphere(2);
  EXPECT_THROW(packDeformed(r.skin, r.coat, other, framesOf(r.coat), r.pack, 0.25, o), Error);
}
