// Packing (Streit 2003, 6.3.2-6.3.4, 8.3), styling and the independent coat checker.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <limits>

#include "pack_fixtures.hpp"
#include "pteryla/coat/check.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/primitives.hpp"
#include "pteryla/coat/style.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/bezier.hpp"
#include "../../src/coat/spatial.hpp"

using namespace pteryla;
using namespace pteryla::coat;
using glm::dvec3;

namespace {

struct SphereScene {
  SkinMesh skin = makeIcosphere(3);
  CoatFeathers coat;
  explicit SphereScene(size_t count = 400, double scale = 1.0) { coat = packtest::sphereCoat(skin, count, scale); }
};

const SphereScene& scene() {
  static const SphereScene s;
  return s;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

void expectIdentical(const PackResult& a, const PackResult& b) {
  ASSERT_EQ(a.elevation.size(), b.elevation.size());
  for (size_t i = 0; i < a.elevation.size(); ++i) {
    ASSERT_TRUE(sameBits(a.elevation[i], b.elevation[i]))
        << "feather " << i << ": " << a.elevation[i] << " vs " << b.elevation[i];
  }
  // The packed key barbs, bit for bit.
  const PackedKeyBarbs &ka = a.packedKeys, &kb = b.packedKeys;
  ASSERT_EQ(ka.keyOffset, kb.keyOffset);
  ASSERT_EQ(ka.leftKeys, kb.leftKeys);
  ASSERT_EQ(ka.replaced, kb.replaced);
  ASSERT_EQ(ka.cvOffset, kb.cvOffset);
  ASSERT_EQ(ka.rp.size(), kb.rp.size());
  ASSERT_EQ(ka.cvs.size(), kb.cvs.size());
  EXPECT_EQ(0, std::memcmp(ka.rp.data(), kb.rp.data(), ka.rp.size() * sizeof(double)));
  EXPECT_EQ(0, std::memcmp(ka.cvs.data(), kb.cvs.data(), ka.cvs.size() * sizeof(glm::dvec3)));
  ASSERT_EQ(a.pointOffset, b.pointOffset);
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_EQ(0, std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(glm::vec4)));
}

// Inside the convex icosphere: behind every face plane.
bool insideConvex(const SkinMesh& s, const dvec3& p, double tol) {
  for (size_t f = 0; f < s.faces.size(); ++f)
    if (glm::dot(p - s.positions[s.faces[f][0]], s.faceNormals[f]) > -tol) return false;
  return true;
}

}  // namespace

// ---------------------------------------------------------------- geometry helpers

TEST(PackSpatial, TriangleTriangleCases) {
  using detail::trianglesIntersect;
  const dvec3 a0(0, 0, 0), a1(1, 0, 0), a2(0, 1, 0);
  // Piercing.
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, {0.2, 0.2, -1}, {0.3, 0.2, 1}, {0.2, 0.3, 1}));
  // Above the plane.
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, {0.2, 0.2, 0.1}, {0.3, 0.2, 1}, {0.2, 0.3, 1}));
  // Crossing the plane outside the triangle.
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, {2, 2, -1}, {3, 2, 1}, {2, 3, 1}));
  // Coplanar overlap and coplanar disjoint.
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, {0.1, 0.1, 0}, {2, 0.1, 0}, {0.1, 2, 0}));
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, {1, 1, 0}, {2, 1, 0}, {1, 2, 0}));
  // Coplanar containment.
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, {0.1, 0.1, 0}, {0.2, 0.1, 0}, {0.1, 0.2, 0}));
  // Edge through the interior of the other (two triangles crossing like an X).
  EXPECT_TRUE(trianglesIntersect(a0, a1, a2, {0.25, -0.5, -0.5}, {0.25, 0.5, 0.5}, {0.25, -0.5, 0.5}));
  // Degenerate never intersects.
  EXPECT_FALSE(trianglesIntersect(a0, a1, a2, {0.2, 0.2, -1}, {0.2, 0.2, 0}, {0.2, 0.2, 1}));
}

TEST(PackSpatial, BvhNearestMatchesBruteForce) {
  const SkinMesh s = makeIcosphere(2);
  std::vector<uint32_t> flat;
  for (const auto& f : s.faces) flat.insert(flat.end(), f.begin(), f.end());
  detail::TriangleBvh bvh;
  bvh.build(s.positions.data(), flat.data(), s.faces.size());
  Rng rng(3);
  for (int k = 0; k < 200; ++k) {
    const dvec3 p(rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5));
    dvec3 bary;
    double d2 = 0;
    const int64_t f = bvh.nearest(p, std::numeric_limits<double>::infinity(), bary, d2);
    ASSERT_GE(f, 0);
    double best = std::numeric_limits<double>::infinity();
    for (const auto& t : s.faces) {
      const dvec3 q = closestPointOnTriangle(p, s.positions[t[0]], s.positions[t[1]], s.positions[t[2]]);
      best = std::min(best, glm::dot(q - p, q - p));
    }
    EXPECT_NEAR(d2, best, 1e-12);
  }
}

// ---------------------------------------------------------------- packing

TEST(Pack, DeterministicAcrossThreadCounts) {
  const SphereScene& s = scene();
  PackOptions o;
  o.threads = 1;
  const PackResult a = pack(s.skin, s.coat, o);
  o.threads = 2;
  const PackResult b = pack(s.skin, s.coat, o);
  o.threads = 0;
  const PackResult c = pack(s.skin, s.coat, o);
  expectIdentical(a, b);
  expectIdentical(a, c);
  EXPECT_EQ(a.stats.packed, s.coat.size());
  EXPECT_GT(a.stats.dependencies, 0u);
}

TEST(Pack, KeyBarbsNeverBelowTheirHeightField) {
  const SphereScene& s = scene();
  PackOptions o;
  o.captureFields = true;
  const PackResult r = pack(s.skin, s.coat, o);
  ASSERT_FALSE(r.barbFields.empty());
  EXPECT_GT(r.stats.barbsElevated, 0u) << "the scene should need some barb elevation";
  EXPECT_EQ(r.stats.barbsUnresolved, 0u);
  size_t checked = 0, nonEmpty = 0;
  for (const BarbField& f : r.barbFields) {
    // The key barb as packed, rebuilt from the packed parameters (not from the packer's internals).
    const std::vector<PlacedKeyBarb> placed = placedKeyBarbs(s.coat, r, f.feather);
    const PlacedKeyBarb* kb = nullptr;
    int k = 0;
    for (const auto& p : placed) {
      if (p.vane != f.vane) continue;
      if (k == f.key) {
        kb = &p;
        break;
      }
      ++k;
    }
    ASSERT_NE(kb, nullptr);
    ASSERT_LT(glm::length(kb->root - f.root), 1e-9);
    bool any = false;
    for (float h : f.field.h) any = any || std::isfinite(h);
    nonEmpty += any;
    for (int u = 0; u <= 400; ++u) {
      const dvec3 p = feather::bezierPoint(kb->cvs.data(), kb->cvs.size(), u / 400.0);
      const double sAlong = glm::dot(p - f.root, f.along), h = glm::dot(p - f.root, f.up);
      if (sAlong < 0.05 * f.length || sAlong > f.length) continue;
      const double field = f.field.at(sAlong);
      if (!std::isfinite(field)) continue;
      EXPECT_GE(h, field - 1e-7) << "feather " << f.feather << " vane " << int(f.vane) << " key " << f.key << " s "
                                 << sAlong;
      ++checked;
    }
  }
  EXPECT_GT(nonEmpty, 100u);
  EXPECT_GT(checked, 500u);
}

TEST(Pack, NoShaftBelowTheSkinOnASphere) {
  const SphereScene& s = scene();
  PackOptions o;
  const PackResult r = pack(s.skin, s.coat, o);
  size_t tested = 0;
  for (uint32_t i = 0; i < s.coat.size(); ++i) {
    const feather::FeatherParams p = packedParams(s.coat, r, i);
    for (int k = 0; k <= 32; ++k) {
      const feather::RachisFrame f = feather::rachisFrame(p, k / 32.0);
      const dvec3 w = placePoint(s.coat.frames[i], r.elevation[i], f.point);
      ASSERT_FALSE(insideConvex(s.skin, w, 0.0)) << "feather " << i << " rp " << k / 32.0;
      ++tested;
    }
    // Placed key barbs stay outside too.
    for (const auto& kb : placedKeyBarbs(s.coat, r, i))
      for (int u = 1; u <= 16; ++u)
        ASSERT_FALSE(insideConvex(s.skin, feather::bezierPoint(kb.cvs.data(), kb.cvs.size(), u / 16.0), 0.0))
            << "feather " << i;
  }
  EXPECT_GT(tested, 1000u);
}

TEST(Pack, ReducesIntersectingPairsAndSkinPenetrations) {
  const SphereScene& s = scene();
  PackOptions o;
  const PackResult r = pack(s.skin, s.coat, o);
  ProxyMeshOptions mo;
  mo.barbStride = 2;
  const TriMesh packed = proxyCoatMesh(s.coat, r.elevation, allPackedParams(s.coat, r), mo);
  const TriMesh unpacked = proxyCoatMesh(s.coat, std::vector<double>(s.coat.size(), 0.0), s.coat.params, mo);
  CheckOptions co;
  setFeatherBases(co, s.coat, o.baseAllowance);
  co.coverageSamples = 4000;
  std::vector<uint32_t> band;
  for (uint32_t f = 0; f < s.skin.faceCount(); ++f) {
    const auto& t = s.skin.faces[f];
    const dvec3 c = (s.skin.positions[t[0]] + s.skin.positions[t[1]] + s.skin.positions[t[2]]) / 3.0;
    if (std::abs(c.z) < 0.6) band.push_back(f);
  }
  const CheckResult before = check(s.skin, band, unpacked, co);
  const CheckResult after = check(s.skin, band, packed, co);
  std::printf("unpacked: pairs %zu penetrations %zu coverage %.4f | packed: pairs %zu penetrations %zu coverage %.4f\n",
              before.intersectingPairs, before.skinPenetrations, before.coverage, after.intersectingPairs,
              after.skinPenetrations, after.coverage);
  ASSERT_GT(before.intersectingPairs, 1000u);
  EXPECT_LE(after.intersectingPairs * 20, before.intersectingPairs)
      << "packing must remove >= 95% of the intersecting pairs";
  EXPECT_GT(before.skinPenetrations, 0u);
  EXPECT_EQ(after.skinPenetrations, 0u);
  EXPECT_GE(after.coverage, 0.97);
}

TEST(Pack, FixedAngleFeathersKeepTheirAngleAndOthersPackAgainstThem) {
  const SphereScene& s = scene();
  PackOptions o;
  const PackResult free = pack(s.skin, s.coat, o);
  // Comb: a row of feathers around the equator lifted to 50 degrees.
  StyleSelection comb;
  comb.kind = StyleKind::Sphere;
  comb.center = {1, 0, 0};
  comb.radius = 0.35;
  comb.elevation = 50.0 * feather::kPi / 180.0;
  PackConstraints combed;
  combed.fixedElevation = resolveStyling(s.coat, {comb});
  const PackResult styled = pack(s.skin, s.coat, o, combed);
  size_t fixedCount = 0, othersChanged = 0;
  for (uint32_t i = 0; i < s.coat.size(); ++i) {
    if (!std::isnan(combed.fixedElevation[i])) {
      ++fixedCount;
      EXPECT_TRUE(sameBits(styled.elevation[i], *comb.elevation)) << "feather " << i;
    } else if (!sameBits(styled.elevation[i], free.elevation[i])) {
      ++othersChanged;
    }
  }
  EXPECT_GT(fixedCount, 3u);
  EXPECT_GT(othersChanged, 0u) << "feathers above the lifted ones must repack against them";
  EXPECT_EQ(styled.stats.fixed, fixedCount);
}

TEST(Pack, IncrementalRepackEqualsFullPack) {
  const SphereScene& s = scene();
  PackOptions o;
  o.threads = 2;
  const PackResult before = pack(s.skin, s.coat, o);
  CoatFeathers edited = s.coat;
  // Edit the surface direction of a few feathers (8.3 styling vectors) and fix one angle.
  StyleSelection dir;
  dir.kind = StyleKind::Ids;
  dir.ids = {edited.layerOrder[40], edited.layerOrder[41], edited.layerOrder[120]};
  dir.direction = dvec3(0.3, 0.2, -1.0);
  StyleSelection fix;
  fix.kind = StyleKind::Ids;
  fix.ids = {edited.layerOrder[200]};
  fix.elevation = 0.6;
  const StyleApplied ap = applyStyling(edited, {dir, fix});
  ASSERT_EQ(ap.changed.size(), 4u);
  PackOptions o2 = o;
  PackConstraints fixed;
  fixed.fixedElevation = ap.fixedElevation;
  const PackResult full = pack(s.skin, edited, o2, fixed);
  const PackResult inc = repack(s.skin, edited, before, ap.changed, o2, fixed);
  expectIdentical(full, inc);
  EXPECT_LT(inc.stats.recomputed, edited.size());
  EXPECT_GE(inc.stats.recomputed, ap.changed.size());
  // changedFeathers finds the same set.
  EXPECT_EQ(changedFeathers(s.coat, edited, {}, ap.fixedElevation), ap.changed);
  // Sequential incremental repack gives the same bits.
  o2.threads = 1;
  expectIdentical(full, repack(s.skin, edited, before, ap.changed, o2, fixed));
  // Nothing changed: nothing recomputed, same result.
  const PackResult same = repack(s.skin, edited, full, {}, o2, fixed);
  EXPECT_EQ(same.stats.recomputed, 0u);
  expectIdentical(full, same);
}

TEST(Pack, PackOverPacksOnlyTheChangedFeathers) {
  const SphereScene& s = scene();
  PackOptions o;
  o.threads = 2;
  const PackResult base = pack(s.skin, s.coat, o);
  // Listing every feather repacks each against the others' new results in layer order: a full pack.
  std::vector<uint32_t> all(s.coat.size());
  std::iota(all.begin(), all.end(), 0u);
  expectIdentical(base, packOver(s.skin, s.coat, base, all, o));
  // One unchanged feather listed: packed against the same neighbours, the same bits as in the full pack.
  const PackResult one = packOver(s.skin, s.coat, base, {s.coat.layerOrder[150]}, o);
  expectIdentical(base, one);
  EXPECT_EQ(one.stats.recomputed, 1u);

  // A moult: every 7th feather lost, every 5th shorter (growing).
  CoatFeathers moulted = s.coat;
  std::vector<uint32_t> changed;
  for (uint32_t i = 0; i < moulted.size(); ++i) {
    if (i % 7 == 3) {
      moulted.present[i] = 0;
      changed.push_back(i);
    } else if (i % 5 == 1) {
      moulted.params[i] = packtest::contourFeather(0.6);
      changed.push_back(i);
    }
  }
  const PackResult over = packOver(s.skin, moulted, base, changed, o);
  o.threads = 1;
  expectIdentical(over, packOver(s.skin, moulted, base, changed, o));
  size_t growing = 0, repacked = 0;
  for (uint32_t i = 0; i < moulted.size(); ++i) {
    const uint32_t cnt = over.pointOffset[i + 1] - over.pointOffset[i];
    if (!moulted.present[i]) {
      EXPECT_EQ(cnt, 0u) << "a lost feather leaves no points to pack against";
      EXPECT_EQ(over.recomputed[i], 0);
      continue;
    }
    if (i % 5 == 1) {
      ++growing;
      EXPECT_EQ(over.recomputed[i], 1);
      repacked += sameBits(over.elevation[i], base.elevation[i]) ? 0 : 1;
      // Packed, so its shaft stays out of the sphere beyond the calamus zone.
      for (uint32_t q = over.pointOffset[i] + 2; q < over.pointOffset[i] + o.shaftSamples + 1; ++q)
        EXPECT_FALSE(insideConvex(s.skin, dvec3(over.points[q]), 1e-4)) << "feather " << i;
      continue;
    }
    // Everything else keeps its pose from the base pack exactly.
    EXPECT_EQ(over.recomputed[i], 0);
    ASSERT_TRUE(sameBits(over.elevation[i], base.elevation[i])) << i;
    ASSERT_TRUE(packedParams(moulted, over, i) == packedParams(s.coat, base, i)) << i;
    ASSERT_EQ(cnt, base.pointOffset[i + 1] - base.pointOffset[i]);
    EXPECT_EQ(0, std::memcmp(over.points.data() + over.pointOffset[i], base.points.data() + base.pointOffset[i],
                             cnt * sizeof(glm::vec4)));
  }
  EXPECT_EQ(over.stats.recomputed, growing);
  // The growing feathers were packed with their own shape (a shorter shaft needs another angle).
  EXPECT_GT(repacked, growing / 2);

  // Bad bases are rejected: wrong size, another skin, a present feather the base did not pack.
  EXPECT_THROW(packOver(s.skin, moulted, pack(s.skin, SphereScene(120).coat), changed), Error);
  SkinMesh moved = s.skin;
  moved.positions[0].x += 1e-3;
  EXPECT_THROW(packOver(moved, moulted, base, changed), Error);
  const PackResult gap = packOver(s.skin, moulted, base, changed);
  EXPECT_THROW(packOver(s.skin, s.coat, gap, {}), Error);
}

TEST(Pack, ThinFeathersFindTheSkinBetweenSamples) {
  // Inside a sphere (faces turned inward, so the skin is concave): a feather lying along its tangent
  // plane leaves through the skin. Pin feathers (barbs closed) have footprints narrower than a skin
  // patch; they must still find the skin under them.
  const SkinMesh outer = makeIcosphere(3);
  std::vector<std::array<uint32_t, 3>> faces = outer.faces;
  for (auto& f : faces) std::swap(f[1], f[2]);
  const SkinMesh inner = makeSkinMesh(outer.positions, faces);
  CoatFeathers c = packtest::sphereCoat(inner, 120, 0.6);
  for (auto& p : c.params) {
    p.barbLength = 1e-4;
    p.left.keyBarbs.clear();
    p.right.keyBarbs.clear();
  }
  PackOptions o;
  o.threads = 1;
  const PackResult r = pack(inner, c, o);
  size_t checked = 0;
  for (uint32_t i = 0; i < c.size(); ++i) {
    // Shaft points beyond the calamus zone stay inside the sphere (on the feather side of the skin).
    for (uint32_t q = r.pointOffset[i] + 3; q < r.pointOffset[i] + o.shaftSamples + 1; ++q) {
      EXPECT_LT(glm::length(dvec3(r.points[q])), 1.0 + 1e-4) << "feather " << i << " point " << q - r.pointOffset[i];
      ++checked;
    }
  }
  EXPECT_GT(checked, 500u);
}

TEST(Pack, UnopenedFeathersPackAsStraightShafts) {
  SphereScene s(160);
  for (size_t i = 0; i < s.coat.size(); i += 3) s.coat.age[i] = 0.5;
  PackOptions o;
  const PackResult r = pack(s.skin, s.coat, o);
  size_t unopened = 0;
  for (size_t i = 0; i < s.coat.size(); ++i) {
    if (s.coat.age[i] >= o.openingAge) continue;
    ++unopened;
    EXPECT_EQ(r.packedKeys.replaced[i], 0);
    EXPECT_TRUE(packedParams(s.coat, r, i) == s.coat.params[i]);
    EXPECT_EQ(r.barbsChanged[i], 0);
    EXPECT_EQ(r.pointOffset[i + 1] - r.pointOffset[i], static_cast<uint32_t>(o.shaftSamples + 1));
    // Straight: all shaft points on one line through the follicle.
    const FeatherFrame& F = s.coat.frames[i];
    const dvec3 dir = placeDirection(F, r.elevation[i], {1, 0, 0});
    for (uint32_t q = r.pointOffset[i]; q < r.pointOffset[i + 1]; ++q) {
      const dvec3 v = dvec3(r.points[q]) - F.origin;
      EXPECT_LT(glm::length(v - glm::dot(v, dir) * dir), 1e-5);
    }
  }
  EXPECT_EQ(r.stats.unopened, unopened);
  EXPECT_GT(unopened, 10u);
}

TEST(Pack, PackedParamsComeFromTheFlatKeyBarbs) {
  SphereScene s(120);
  for (size_t i = 0; i < s.coat.size(); i += 5) s.coat.age[i] = 0.5;  // unopened: input key barbs kept
  const PackResult r = pack(s.skin, s.coat, PackOptions{});
  const PackedKeyBarbs& K = r.packedKeys;
  size_t raised = 0;
  feather::FeatherParams reused = packtest::contourFeather(2.0);  // storage of another feather, reused
  for (uint32_t i = 0; i < s.coat.size(); ++i) {
    const feather::FeatherParams p = packedParams(s.coat, r, i);
    packedParamsInto(s.coat, r, i, reused);
    ASSERT_TRUE(reused == p) << i;
    ASSERT_TRUE(packedParamsEqual(p, s.coat, r, i)) << i;
    EXPECT_TRUE(p.equalExceptKeyBarbs(s.coat.params[i])) << i;
    if (!K.replaced[i]) {
      EXPECT_TRUE(p == s.coat.params[i]) << i;
      continue;
    }
    // The left vane's key barbs first, then the right's, each as stored.
    ASSERT_EQ(p.left.keyBarbs.size(), K.leftKeys[i]);
    ASSERT_EQ(p.left.keyBarbs.size() + p.right.keyBarbs.size(), K.keyOffset[i + 1] - K.keyOffset[i]);
    const feather::KeyBarb& last = p.right.keyBarbs.back();
    const uint32_t k = K.keyOffset[i + 1] - 1;
    EXPECT_EQ(last.rp, K.rp[k]);
    ASSERT_EQ(last.cvs.size(), K.cvOffset[k + 1] - K.cvOffset[k]);
    EXPECT_TRUE(last.cvs.back() == K.cvs[K.cvOffset[k + 1] - 1]);
    raised += r.barbsChanged[i];
    // Any difference is seen: a control vertex, a key barb's position, another field.
    feather::FeatherParams q = p;
    q.left.keyBarbs.front().cvs.back().z += 1e-9;
    EXPECT_FALSE(packedParamsEqual(q, s.coat, r, i));
    q = p;
    q.right.keyBarbs.back().rp -= 1e-9;
    EXPECT_FALSE(packedParamsEqual(q, s.coat, r, i));
    q = p;
    q.right.tipAngle += 0.01;
    EXPECT_FALSE(packedParamsEqual(q, s.coat, r, i));
  }
  EXPECT_GT(raised, 0u);  // some stored key barbs are elevated ones
  EXPECT_EQ(allPackedParams(s.coat, r).size(), s.coat.size());
}

TEST(Pack, MissingFeathersAreSkippedAndBadInputThrows) {
  SphereScene s(120);
  s.coat.present[5] = 0;
  const PackResult r = pack(s.skin, s.coat);
  EXPECT_EQ(r.stats.packed, s.coat.size() - 1);
  EXPECT_EQ(r.pointOffset[6] - r.pointOffset[5], 0u);
  CoatFeathers bad = s.coat;
  bad.layerOrder[3] = 100000;
  EXPECT_THROW(pack(s.skin, bad), Error);
  bad = s.coat;
  bad.frames.pop_back();
  EXPECT_THROW(pack(s.skin, bad), Error);
  bad = s.coat;
  bad.layerOrder[1] = bad.layerOrder[0];
  EXPECT_THROW(pack(s.skin, bad), Error);
  PackConstraints wrongLength;
  wrongLength.fixedElevation = {0.1};
  EXPECT_THROW(pack(s.skin, s.coat, {}, wrongLength), Error);
  wrongLength = PackConstraints{};
  wrongLength.minElevation = {0.1, 0.2};
  EXPECT_THROW(pack(s.skin, s.coat, {}, wrongLength), Error);
  wrongLength = PackConstraints{};
  wrongLength.shaftBand = {0.5};
  EXPECT_THROW(pack(s.skin, s.coat, {}, wrongLength), Error);
}

TEST(Pack, FlatPatchFeathersRestJustAboveTheSkin) {
  // With no neighbours a feather rotates down to lie on the skin, less the allowance for its ventral
  // curvature (6.3.2): the elevation is about the rachis turning angle, never 0, never upright.
  SkinMesh patch = makeGridPatch(20, 20, 2.0, 2.0);
  CoatFeathers c;
  FeatherFrame f;
  f.origin = {0.5, 1.0, 0};
  c.frames.push_back(f);
  c.params.push_back(packtest::contourFeather(1.0));
  c.follicle = {0};
  c.layerOrder = {0};
  const PackResult r = pack(patch, c);
  EXPECT_GT(r.elevation[0], 0.3 * c.params[0].rachisVentralDorsalCurvature);
  EXPECT_LT(r.elevation[0], 2.0 * c.params[0].rachisVentralDorsalCurvature);
  for (int k = 0; k <= 20; ++k) {
    const dvec3 w = placePoint(f, r.elevation[0], feather::rachisFrame(c.params[0], k / 20.0).point);
    EXPECT_GE(w.z, 0.0);
  }
}

// ---------------------------------------------------------------- options and styling

TEST(PackOptionsJson, ParsesAndRejects) {
  const Json j = Json::parse(R"({
    "clearance": 0.002, "max_elevation_deg": 80, "key_barbs_per_vane": 7, "threads": 2, "moult_pack": "full",
    "posed_drape": "full",
    "styling": [
      {"select": "ids", "ids": [1, 2, 3], "elevation_deg": 40},
      {"select": "sphere", "center": [1, 0, 0], "radius": 0.3, "elevation_deg": 30},
      {"select": "comb", "from": [0, 0, 0], "to": [1, 0, 0], "radius": 0.1, "direction": [0, 0, -1]}
    ]})");
  JsonReader r(j, "scene.json", "packing");
  const PackingSettings settings = parsePackingSettings(r);
  const PackOptions& o = settings.options;
  EXPECT_DOUBLE_EQ(o.clearance, 0.002);
  EXPECT_NEAR(o.maxElevation, 80 * feather::kPi / 180, 1e-12);
  EXPECT_EQ(o.keyBarbsPerVane, 7);
  EXPECT_FALSE(settings.moultOver);
  EXPECT_FALSE(settings.carryPosedDrape);
  EXPECT_TRUE(PackingSettings().carryPosedDrape);  // carried unless asked
  ASSERT_EQ(settings.styling.size(), 3u);
  EXPECT_EQ(settings.styling[0].ids, (std::vector<uint32_t>{1, 2, 3}));
  EXPECT_EQ(settings.styling[1].kind, StyleKind::Sphere);
  EXPECT_TRUE(settings.styling[2].direction.has_value());
  EXPECT_FALSE(settings.styling[2].elevation.has_value());
  // Round trip.
  const Json back = packingSettingsToJson(settings);
  JsonReader r2(back, "x", "packing");
  EXPECT_EQ(packingSettingsToJson(parsePackingSettings(r2)), back);

  auto fails = [](const char* text, const char* where) {
    const Json jj = Json::parse(text);
    JsonReader rr(jj, "scene.json", "packing");
    try {
      parsePackingSettings(rr);
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "no error for " << text;
  };
  fails(R"({"clearence": 1})", "clearence");
  fails(R"({"key_barbs_per_vane": 1})", "key_barbs_per_vane");
  fails(R"({"moult_pack": "partial"})", "moult_pack");
  fails(R"({"posed_drape": "rigid"})", "posed_drape");
  fails(R"({"styling": [{"select": "ids", "ids": [1.5], "elevation_deg": 3}]})", "ids");
  fails(R"({"styling": [{"select": "blob", "elevation_deg": 3}]})", "select");
  fails(R"({"styling": [{"select": "sphere", "center": [0,0,0], "radius": 1}]})", "elevation_deg");
}

TEST(Style, SelectionsPickTheRightFeathers) {
  const SphereScene& s = scene();
  StyleSelection sphere;
  sphere.kind = StyleKind::Sphere;
  sphere.center = {0, 1, 0};
  sphere.radius = 0.3;
  for (uint32_t i : selectFeathers(s.coat, sphere))
    EXPECT_LE(glm::length(s.coat.frames[i].origin - sphere.center), 0.3);
  StyleSelection comb;
  comb.kind = StyleKind::Comb;
  comb.from = {1, 0, 0.2};
  comb.to = {0, 1, 0.2};
  comb.radius = 0.15;
  const auto sel = selectFeathers(s.coat, comb);
  EXPECT_FALSE(sel.empty());
  StyleSelection ids;
  ids.ids = {static_cast<uint32_t>(s.coat.size())};
  EXPECT_THROW(selectFeathers(s.coat, ids, "styling[0]"), Error);
}

// ---------------------------------------------------------------- checker

TEST(Check, CountsPenetrationsAndCoverageIndependently) {
  const SkinMesh skin = makeIcosphere(2);
  TriMesh m;
  // A shell at radius 1.2 covering the +z hemisphere, and one triangle inside the sphere.
  const SkinMesh shell = makeIcosphere(2, 1.2);
  for (const auto& p : shell.positions) m.positions.emplace_back(p);
  for (const auto& f : shell.faces) {
    const dvec3 c = (shell.positions[f[0]] + shell.positions[f[1]] + shell.positions[f[2]]) / 3.0;
    if (c.z > 0) m.indices.insert(m.indices.end(), {f[0], f[1], f[2]});
  }
  m.featherId.assign(m.positions.size(), 0);
  const uint32_t base = static_cast<uint32_t>(m.positions.size());
  m.positions.insert(m.positions.end(), {{0.1f, 0.1f, 0.1f}, {0.3f, 0.1f, 0.1f}, {0.1f, 0.3f, 0.1f}});
  m.featherId.insert(m.featherId.end(), {1, 1, 1});
  m.indices.insert(m.indices.end(), {base, base + 1, base + 2});
  std::vector<uint32_t> top, bottom;
  for (uint32_t f = 0; f < skin.faceCount(); ++f) {
    const auto& t = skin.faces[f];
    const double cz = (skin.positions[t[0]].z + skin.positions[t[1]].z + skin.positions[t[2]].z) / 3.0;
    (cz > 0.3 ? top : bottom).push_back(f);
  }
  CheckOptions o;
  o.coverageSamples = 3000;
  const CheckResult rt = check(skin, top, m, o);
  EXPECT_EQ(rt.skinPenetrations, 3u);
  EXPECT_EQ(rt.penetratingFeathers, std::vector<uint32_t>{1});
  EXPECT_EQ(rt.intersectingPairs, 0u);
  EXPECT_GT(rt.coverage, 0.99);
  const CheckResult rb = check(skin, bottom, m, o);
  EXPECT_LT(rb.coverage, 0.6);
  // A triangle of feather 2 through the shell intersects it.
  const uint32_t b2 = static_cast<uint32_t>(m.positions.size());
  m.positions.insert(m.positions.end(), {{0.0f, 0.05f, 0.9f}, {0.05f, 0.0f, 1.5f}, {-0.05f, 0.0f, 1.5f}});
  m.featherId.insert(m.featherId.end(), {2, 2, 2});
  m.indices.insert(m.indices.end(), {b2, b2 + 1, b2 + 2});
  EXPECT_GE(countIntersectingPairs(m), 1u);
  EXPECT_EQ(countIntersectingPairs(m, 1), countIntersectingPairs(m, 2));
}

TEST(Check, OpenPatchBelowAndBeyondTheBoundary) {
  const SkinMesh patch = makeGridPatch(4, 4, 1.0, 1.0);
  TriMesh m;
  m.positions = {{0.5f, 0.5f, -0.1f}, {0.6f, 0.5f, 0.1f}, {1.5f, 0.5f, -0.2f}};
  m.featherId = {0, 0, 0};
  m.indices = {0, 1, 2};
  CheckOptions o;
  o.coverage = false;
  const CheckResult r = check(patch, {}, m, o);
  EXPECT_EQ(r.skinPenetrations, 1u);  // below the patch; the point past the boundary is not
}

TEST(PackGeometry, PlacedKeyBarbsMatchTheBarbGenerator) {
  // The packer places key barbs itself (no full barb generation per feather); it must agree with
  // feather::generateBarbs on the barb that sits exactly at a key barb's rp.
  CoatFeathers c;
  FeatherFrame f;
  f.origin = {0.3, -0.2, 0.5};
  f.normal = glm::normalize(dvec3(0.2, 0.1, 1));
  f.tangent = glm::normalize(glm::cross(dvec3(0, 1, 0), f.normal));
  f.binormal = glm::cross(f.normal, f.tangent);
  c.frames.push_back(f);
  feather::FeatherParams p = packtest::contourFeather(1.0);
  p.rachisLateralCurvature = 0.2;
  c.params.push_back(p);
  c.follicle = {0};
  PackResult r;
  r.elevation = {0.4};
  r.packedKeys.keyOffset = {0, 0};  // the feather keeps its input key barbs
  r.packedKeys.leftKeys = {0};
  r.packedKeys.replaced = {0};
  r.packedKeys.cvOffset = {0};
  const feather::FeatherCurves curves = feather::generateBarbs(p);
  size_t matched = 0;
  for (const PlacedKeyBarb& kb : placedKeyBarbs(c, r, 0)) {
    for (uint32_t b = curves.barbBegin[0]; b < curves.barbEnd[0]; ++b) {
      const feather::BarbCurve& bc = curves.barbs[b];
      if (bc.vane != kb.vane || std::abs(bc.rp - kb.rp) > 1e-6) continue;
      ASSERT_EQ(bc.cvCount, kb.cvs.size());
      for (size_t k = 0; k < kb.cvs.size(); ++k) {
        const dvec3 g = placePoint(f, 0.4, dvec3(curves.cvs[bc.cvOffset + k]));
        EXPECT_LT(glm::length(g - kb.cvs[k]), 1e-5) << "vane " << int(kb.vane) << " rp " << kb.rp << " cv " << k;
      }
      ++matched;
    }
  }
  EXPECT_GE(matched, 4u);  // rp 0, 0.5 and 1 exist as barbs on both vanes
}

TEST(Pack, LayerOrderConflictsDoNotStandFeathersUp) {
  // Two follicles closer than a shaft's width: the second cannot clear the first at any angle. It must not
  // be stood upright (which would push everything above it up as well); the conflict is reported.
  SkinMesh patch = makeGridPatch(10, 10, 2.0, 2.0);
  CoatFeathers c;
  for (int k = 0; k < 2; ++k) {
    FeatherFrame f;
    f.origin = {0.5 + 0.002 * k, 1.0, 0};
    c.frames.push_back(f);
    c.params.push_back(packtest::contourFeather(1.0));
    c.follicle.push_back(k);
  }
  c.layerOrder = {0, 1};
  const PackResult r = pack(patch, c);
  EXPECT_LE(r.elevation[1], PackOptions{}.conflictElevation);
  EXPECT_GE(r.stats.conflicts, 1u);
  PackOptions strict;
  strict.conflictElevation = 10.0;  // never a conflict: the height field alone decides
  const PackResult s = pack(patch, c, strict);
  EXPECT_GT(s.elevation[1], r.elevation[1]);
}

TEST(PackOptions, WithDefaultSamplingResetsOnlyTheSampling) {
  PackOptions o;
  o.keyBarbsPerVane = 12;
  o.barbSamples = 16;
  o.shaftSamples = 24;
  o.barbFieldBins = 32;
  o.heightFieldBins = 64;
  o.skinSampleSpacing = 0.004;
  o.clearance = 0.003;
  o.threads = 2;
  const PackOptions d = withDefaultSampling(o), def;
  EXPECT_EQ(d.keyBarbsPerVane, def.keyBarbsPerVane);
  EXPECT_EQ(d.barbSamples, def.barbSamples);
  EXPECT_EQ(d.shaftSamples, def.shaftSamples);
  EXPECT_EQ(d.barbFieldBins, def.barbFieldBins);
  EXPECT_EQ(d.heightFieldBins, def.heightFieldBins);
  EXPECT_EQ(d.skinSampleSpacing, def.skinSampleSpacing);
  EXPECT_EQ(d.clearance, 0.003);
  EXPECT_EQ(d.threads, 2);
}

namespace {
double keyArcLength(const PackedKeyBarbs& K, size_t key) {
  const glm::dvec3* cv = K.cvs.data() + K.cvOffset[key];
  const size_t n = K.cvOffset[key + 1] - K.cvOffset[key];
  double l = 0;
  dvec3 prev = feather::bezierPoint(cv, n, 0.0);
  for (int u = 1; u <= 2000; ++u) {
    const dvec3 p = feather::bezierPoint(cv, n, u / 2000.0);
    l += glm::length(p - prev);
    prev = p;
  }
  return l;
}
}  // namespace

TEST(Pack, FlattenedBarbsKeepTheirArcLengthWhenAsked) {
  // Thesis 6.4: packing bends barbs keeping their arc length. A key barb that flattens straightens out
  // and, flattened alone, gets shorter; with keep_barb_arc_length it is scaled back to the length it had
  // (the packer's key barbs before any fitting: the same pack with elevate_barbs off).
  const SphereScene& s = scene();
  PackOptions plain;
  plain.elevateBarbs = false;
  const PackResult ref = pack(s.skin, s.coat, plain);
  PackOptions flat, kept;
  kept.keepBarbArcLength = true;
  const PackResult rf = pack(s.skin, s.coat, flat), rk = pack(s.skin, s.coat, kept);
  ASSERT_GT(rk.stats.barbsElevated, 50u);
  EXPECT_EQ(rk.stats.barbsUnresolved, 0u);
  for (const PackResult* r : {&rf, &rk}) {
    ASSERT_EQ(r->packedKeys.keyOffset, ref.packedKeys.keyOffset);
    ASSERT_EQ(r->packedKeys.cvOffset, ref.packedKeys.cvOffset);
  }
  size_t shortened = 0, changed = 0;
  const size_t keys = ref.packedKeys.cvOffset.size() - 1;
  for (size_t k = 0; k < keys; ++k) {
    const double l0 = keyArcLength(ref.packedKeys, k);
    const double lf = keyArcLength(rf.packedKeys, k), lk = keyArcLength(rk.packedKeys, k);
    if (lf < l0 * (1 - 1e-3)) ++shortened;
    if (lk != l0) ++changed;
    EXPECT_NEAR(lk, l0, 2e-3 * l0) << "key barb " << k;  // kept (the packer measures on 65 samples)
    EXPECT_GE(lk, lf * (1 - 1e-9)) << "key barb " << k;
  }
  EXPECT_GT(shortened, 20u);  // without the option, flattening shortens barbs
  EXPECT_GT(changed, 20u);
  // Off by default, read and written as packing.keep_barb_arc_length.
  EXPECT_FALSE(PackOptions{}.keepBarbArcLength);
  PackingSettings keptSettings;
  keptSettings.options = kept;
  const Json j = packingSettingsToJson(keptSettings);
  EXPECT_EQ(j.at("keep_barb_arc_length"), true);
  JsonReader r(j, "scene.json", "packing");
  EXPECT_TRUE(parsePackingSettings(r).options.keepBarbArcLength);
}
