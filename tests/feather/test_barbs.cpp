#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>

#include "feather_fixtures.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/bezier.hpp"
#include "pteryla/feather/io.hpp"

using namespace pteryla;
using namespace pteryla::feather;
using pteryla::feather::testing::contourParams;
using pteryla::feather::testing::straightKey;

namespace {
std::vector<const BarbCurve*> vaneBarbs(const FeatherCurves& c, int vane, int part = 0) {
  std::vector<const BarbCurve*> out;
  for (uint32_t i = c.barbBegin[part]; i < c.barbEnd[part]; ++i)
    if (c.barbs[i].vane == vane) out.push_back(&c.barbs[i]);
  return out;
}
glm::vec3 barbTip(const FeatherCurves& c, const BarbCurve& b) { return c.cvs[b.cvOffset + b.cvCount - 1]; }
}  // namespace

TEST(Barbs, CountFollowsFromConstantSpacing) {
  FeatherParams p = contourParams();
  p.rachisLength = 1.0;
  p.spacingBase = p.spacingTip = 0.01;
  EXPECT_EQ(barbCount(p), 101u);
  p.rachisLength = 0.375;
  p.spacingBase = p.spacingTip = 0.05;  // 7.5 gaps -> barbs at 0, 0.05, ..., 0.35
  EXPECT_EQ(barbCount(p), 8u);
  const FeatherCurves c = generateBarbs(p);
  EXPECT_EQ(c.barbs.size(), 16u);  // both vanes
  const auto left = vaneBarbs(c, 0);
  ASSERT_EQ(left.size(), 8u);
  for (size_t k = 0; k < left.size(); ++k) EXPECT_NEAR(left[k]->rp * p.rachisLength, 0.05 * k, 1e-6);
}

TEST(Barbs, CountFollowsFromLinearSpacing) {
  FeatherParams p = contourParams();
  p.rachisLength = 2.0;
  p.spacingBase = 0.04;
  p.spacingTip = 0.01;
  // ds/dk = sp(s) integrates to k(L) = L ln(b/a) / (b - a).
  const double k = p.rachisLength * std::log(p.spacingTip / p.spacingBase) / (p.spacingTip - p.spacingBase);
  EXPECT_EQ(barbCount(p), static_cast<size_t>(std::floor(k)) + 1);
  std::vector<double> rps;
  barbPositions(p, rps);
  for (size_t i = 1; i < rps.size(); ++i) {
    const double s0 = rps[i - 1] * p.rachisLength, s1 = rps[i] * p.rachisLength;
    const double sp0 = p.spacingBase + (p.spacingTip - p.spacingBase) * s0 / p.rachisLength;
    const double sp1 = p.spacingBase + (p.spacingTip - p.spacingBase) * s1 / p.rachisLength;
    EXPECT_LE(s1 - s0, sp0 + 1e-12);  // gap lies between the spacings at its ends
    EXPECT_GE(s1 - s0, sp1 - 1e-12);
  }
}

TEST(Barbs, StraightBarbGeometryFollowsFrames) {
  FeatherParams p;
  p.calamusLength = 0.1;
  p.rachisLength = 1.0;
  p.rachisWidth = 0.0;
  p.barbLength = 0.5;
  p.spacingBase = p.spacingTip = 0.25;
  p.left.baseAngle = p.left.tipAngle = 0.7;
  p.right.baseAngle = p.right.tipAngle = 1.1;
  p.left.keyBarbs = {straightKey(0), straightKey(1)};
  p.right.keyBarbs = p.left.keyBarbs;
  const FeatherCurves c = generateBarbs(p);
  for (const BarbCurve& b : c.barbs) {
    const double a = b.vane == 0 ? 0.7 : 1.1;
    const double side = b.vane == 0 ? 1 : -1;
    const glm::dvec3 expectRoot(0.1 + b.rp * 1.0, 0, 0);
    EXPECT_LT(glm::length(glm::dvec3(b.root) - expectRoot), 1e-6);
    const glm::dvec3 tip = glm::dvec3(barbTip(c, b));
    const glm::dvec3 expectTip = expectRoot + 0.5 * glm::dvec3(std::cos(a), side * std::sin(a), 0);
    EXPECT_LT(glm::length(tip - expectTip), 1e-6);
    EXPECT_GT(tip.y * (b.vane == 0 ? 1 : -1), 0);
  }
}

TEST(Barbs, RachisCurvatureDirections) {
  FeatherParams p = contourParams();
  p.rachisLateralCurvature = 0.4;
  p.rachisVentralDorsalCurvature = 0.6;
  const RachisFrame tip = rachisFrame(p, 1.0);
  EXPECT_GT(tip.point.y, 0);  // lateral > 0 bends toward the left vane
  EXPECT_LT(tip.point.z, 0);  // ventral-dorsal > 0 bends toward the body
  // Frames stay orthonormal and right-handed; the arc has the rachis length.
  double arc = 0;
  glm::dvec3 prev = rachisFrame(p, 0).point;
  for (int i = 0; i <= 1000; ++i) {
    const RachisFrame f = rachisFrame(p, i / 1000.0);
    EXPECT_NEAR(glm::dot(f.tangent, f.left), 0, 1e-12);
    EXPECT_NEAR(glm::dot(f.tangent, f.dorsal), 0, 1e-12);
    EXPECT_LT(glm::length(glm::cross(f.tangent, f.left) - f.dorsal), 1e-12);
    arc += glm::length(f.point - prev);
    prev = f.point;
  }
  EXPECT_NEAR(arc, p.rachisLength, 1e-5);
  // Bezier form agrees with the arc to a fraction of a percent.
  const auto bz = rachisBezier(p);
  for (int i = 0; i <= 10; ++i) {
    const glm::dvec3 q = bezierPoint(bz, i / 10.0);
    double best = 1e9;
    for (int k = 0; k <= 2000; ++k) best = std::min(best, glm::length(rachisFrame(p, k / 2000.0).point - q));
    EXPECT_LT(best, 2e-3 * p.rachisLength);
  }
}

TEST(Barbs, MirroredParametersGiveMirrorSymmetricVanes) {
  for (bool defaults : {false, true}) {
    FeatherParams p = contourParams();
    if (defaults) p.left.keyBarbs.clear();
    p.right = p.left;
    p.splits.count = 0;
    const FeatherCurves c = generateBarbs(p);
    const auto l = vaneBarbs(c, 0), r = vaneBarbs(c, 1);
    ASSERT_EQ(l.size(), r.size());
    ASSERT_GT(l.size(), 50u);
    double maxErr = 0;
    for (size_t i = 0; i < l.size(); ++i) {
      ASSERT_EQ(l[i]->cvCount, r[i]->cvCount);
      for (uint16_t k = 0; k < l[i]->cvCount; ++k) {
        glm::vec3 a = c.cvs[l[i]->cvOffset + k], b = c.cvs[r[i]->cvOffset + k];
        b.y = -b.y;
        maxErr = std::max(maxErr, double(glm::length(a - b)));
      }
    }
    EXPECT_LT(maxErr, 1e-6) << (defaults ? "default key barbs" : "explicit key barbs");
    // And the vanes are not degenerate: left barbs really point to +y.
    EXPECT_GT(barbTip(c, *l[l.size() / 2]).y, 0.1f);
  }
}

TEST(Barbs, BarbAtKeyPositionReproducesKeyBarb) {
  FeatherParams p = contourParams();
  p.rachisVentralDorsalCurvature = 0;
  p.rachisWidth = 0;
  p.spacingBase = p.spacingTip = 0.02;  // 0.5 * 2.0 / 0.02 = barb 50 sits on rp 0.5
  p.left.baseAngle = p.left.tipAngle = 0.8;
  const FeatherCurves c = generateBarbs(p);
  const auto l = vaneBarbs(c, 0);
  const BarbCurve& b = *l[50];
  ASSERT_NEAR(b.rp, 0.5, 1e-9);
  EXPECT_TRUE(b.isKey);
  const glm::dvec3 u(std::cos(0.8), std::sin(0.8), 0), w(std::sin(0.8), -std::cos(0.8), 0), d(0, 0, 1);
  const auto& key = p.left.keyBarbs[1].cvs;
  const double chord = glm::length(key.back());
  for (size_t k = 0; k < key.size(); ++k) {
    const glm::dvec3 q = key[k] / std::max(1.0, chord);
    const glm::dvec3 expect = glm::dvec3(b.root) + p.barbLength * (q.x * u + q.y * w + q.z * d);
    EXPECT_LT(glm::length(glm::dvec3(c.cvs[b.cvOffset + k]) - expect), 1e-5);
  }
}

TEST(Barbs, ChordClampAndLengthScaling) {
  FeatherParams p = contourParams();
  p.rachisVentralDorsalCurvature = 0;
  p.left.keyBarbs = {straightKey(0, 2.0), straightKey(1, 2.0)};   // clamped to chord 1
  p.right.keyBarbs = {straightKey(0, 0.5), straightKey(1, 0.5)};  // shorter than the barb length
  p.silhouette.left.points = {{0, 0.2}, {1, 0.8}};
  const FeatherCurves c = generateBarbs(p);
  for (const BarbCurve& b : c.barbs) {
    const double chord = glm::length(glm::dvec3(barbTip(c, b)) - glm::dvec3(b.root));
    const double want = b.vane == 0 ? 0.2 + 0.6 * b.rp : 0.5 * p.barbLength;
    EXPECT_NEAR(chord, want, 1e-5);
  }
}

TEST(Barbs, DifferentControlVertexCountsAreElevated) {
  FeatherParams p = contourParams();
  p.left.keyBarbs = {{0.0, {{0, 0, 0}, {1, 0, 0}}},
                     {1.0, {{0, 0, 0}, {0.2, 0.3, 0.1}, {0.4, -0.2, 0.2}, {0.6, 0.1, 0}, {0.9, 0, 0.1}}}};
  const FeatherCurves c = generateBarbs(p);
  for (const auto* b : vaneBarbs(c, 0)) EXPECT_EQ(b->cvCount, 5);
  // The base barb (rp 0) is the straight key barb, elevated: still a straight segment of barb length.
  const auto* b0 = vaneBarbs(c, 0).front();
  ASSERT_EQ(b0->rp, 0.0f);
  const glm::vec3* cv = &c.cvs[b0->cvOffset];
  const glm::vec3 dir = glm::normalize(cv[4] - cv[0]);
  for (int i = 0; i < 100; ++i) {
    const glm::vec3 q = bezierPoint(cv, 5, i / 99.0) - cv[0];
    EXPECT_LT(glm::length(q - glm::dot(q, dir) * dir), 1e-6);
  }
}

TEST(Barbs, DefaultKeyBarbs) {
  FeatherParams p = contourParams();
  p.left.keyBarbs.clear();
  const auto keys = effectiveKeyBarbs(p, 0);  // down: B_df1 everywhere
  ASSERT_EQ(keys.size(), 2u);
  EXPECT_EQ(keys[0].cvs, keys[1].cvs);
  EXPECT_EQ(keys[0].cvs, defaultPlumulaceousBarb(p.seed));
  EXPECT_NE(defaultPlumulaceousBarb(1), defaultPlumulaceousBarb(2));
  // Displacement from the line grows toward the tip on average.
  double near = 0, far = 0;
  for (uint64_t s = 0; s < 200; ++s) {
    const auto b = defaultPlumulaceousBarb(s);
    near += std::hypot(b[1].y, b[1].z);
    far += std::hypot(b[3].y, b[3].z);
    EXPECT_LE(glm::length(b[3]), 1.0 + 1e-12);
  }
  EXPECT_GT(far, 2 * near);
  // One key barb in the middle: B_df1 below it at rp 0, B_df2 above it at rp 1.
  p.left.keyBarbs = {straightKey(0.5)};
  const auto k2 = effectiveKeyBarbs(p, 0);
  ASSERT_EQ(k2.size(), 3u);
  EXPECT_EQ(k2.front().rp, 0.0);
  EXPECT_EQ(k2.front().cvs, defaultPlumulaceousBarb(p.seed));
  EXPECT_EQ(k2.back().rp, 1.0);
  EXPECT_EQ(k2.back().cvs, defaultPennaceousBarb());
}

TEST(Barbs, SplitsAreReproducibleFromTheSeed) {
  FeatherParams p = contourParams();
  p.splits.count = 3;
  p.splits.reach = 2;
  const FeatherCurves a = generateBarbs(p), b = generateBarbs(p);
  ASSERT_EQ(a.cvs.size(), b.cvs.size());
  EXPECT_EQ(0, std::memcmp(a.cvs.data(), b.cvs.data(), a.cvs.size() * sizeof(glm::vec3)));
  int edges = 0, after = 0;
  for (const BarbCurve& x : a.barbs) {
    edges += x.isSplitEdge;
    after += x.splitAfter;
  }
  EXPECT_GE(after, 2);  // at least some splits land between distinct barbs
  EXPECT_GE(edges, after);
  // The barbs beside a split open away from each other.
  const auto l = vaneBarbs(a, 0);
  for (size_t i = 0; i + 1 < l.size(); ++i)
    if (l[i]->splitAfter) {
      EXPECT_GT(l[i]->angle - l[i + 1]->angle, 0.02);
    }
  const auto s1 = vaneSplits(p, 0);
  p.seed = 43;
  const auto s2 = vaneSplits(p, 0);
  ASSERT_EQ(s1.size(), 3u);
  EXPECT_NE(s1[0].rp, s2[0].rp);
  for (const auto& s : s1) {
    EXPECT_GE(s.rp, p.splits.rpMin);
    EXPECT_LE(s.rp, p.splits.rpMax);
  }
}

TEST(Barbs, AfterfeatherAttachesAtUmbilicus) {
  FeatherParams p = contourParams();
  FeatherParams a = contourParams();
  a.calamusLength = 0;
  a.rachisLength = 0.5;
  a.rachisVentralDorsalCurvature = 0;
  a.barbLength = 0.2;
  a.left.keyBarbs.clear();
  a.right.keyBarbs.clear();
  p.afterfeather = std::make_shared<const FeatherParams>(a);
  const FeatherCurves c = generateBarbs(p);
  ASSERT_EQ(c.partCount(), 2u);
  ASSERT_GT(c.barbEnd[1], c.barbBegin[1]);
  EXPECT_EQ(c.barbBegin[1], c.barbEnd[0]);
  const BarbCurve& first = c.barbs[c.barbBegin[1]];
  EXPECT_EQ(first.part, 1);
  EXPECT_NEAR(first.root.x, p.calamusLength, 1e-5);
  EXPECT_NEAR(c.shafts[1].points.back().x, p.calamusLength + 0.5, 1e-5);
  GenerateOptions noAfter;
  noAfter.afterfeather = false;
  EXPECT_EQ(generateBarbs(p, noAfter).partCount(), 1u);
}

TEST(Barbs, ReusedOutputDoesNotReallocate) {
  const FeatherParams p = contourParams();
  FeatherCurves c;
  generateBarbs(p, c);
  const auto* cvData = c.cvs.data();
  const auto* barbData = c.barbs.data();
  const size_t n = c.barbs.size();
  generateBarbs(p, c);
  EXPECT_EQ(c.barbs.size(), n);
  EXPECT_EQ(c.cvs.data(), cvData);
  EXPECT_EQ(c.barbs.data(), barbData);
}

TEST(Barbs, InvalidParametersNameTheField) {
  FeatherParams p = contourParams();
  p.spacingBase = 0;
  try {
    generateBarbs(p);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "barbs.spacing_base");
  }
  p = contourParams();
  p.left.keyBarbs[1].rp = 1.5;
  try {
    generateBarbs(p);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "left_vane.key_barbs[1].rp");
  }
  p = contourParams();
  p.right.keyBarbs[0].cvs.resize(1);
  EXPECT_THROW(generateBarbs(p), Error);
}
