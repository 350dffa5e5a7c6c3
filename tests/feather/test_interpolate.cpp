#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include "feather_fixtures.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/generator.hpp"
#include "pteryla/feather/interpolate.hpp"

using namespace pteryla;
using namespace pteryla::feather;
using pteryla::feather::testing::contourParams;
using pteryla::feather::testing::straightKey;

namespace {

FeatherParams downParams() {
  FeatherParams p;
  p.name = "down";
  p.calamusLength = 0.05;
  p.rachisLength = 0.3;
  p.rachisWidth = 0.01;
  p.barbLength = 0.8;
  p.spacingBase = p.spacingTip = 0.02;
  p.left.baseAngle = p.right.baseAngle = 0.4;
  p.left.tipAngle = p.right.tipAngle = 0.3;
  p.seed = 9;
  return p;
}

double maxCurveDifference(const FeatherCurves& a, const FeatherCurves& b) {
  EXPECT_EQ(a.barbs.size(), b.barbs.size());
  EXPECT_EQ(a.cvs.size(), b.cvs.size());
  if (a.cvs.size() != b.cvs.size()) return 1e9;
  double m = 0;
  for (size_t i = 0; i < a.cvs.size(); ++i) m = std::max(m, double(glm::length(a.cvs[i] - b.cvs[i])));
  return m;
}

}  // namespace

TEST(Interpolate, EndpointsReproduceKeyFeathers) {
  const FeatherParams a = contourParams(), b = downParams();
  EXPECT_EQ(interpolateFeathers(a, b, 0.0), a);
  EXPECT_EQ(interpolateFeathers(a, b, 1.0), b);
  // The general construction (not the endpoint shortcut) also converges to the key feathers.
  const FeatherCurves ca = generateBarbs(a), cb = generateBarbs(b);
  const FeatherParams nearA = interpolateFeathers(a, b, 1e-12);
  const FeatherParams nearB = interpolateFeathers(a, b, 1.0 - 1e-12);
  EXPECT_GE(nearA.left.keyBarbs.size(), a.left.keyBarbs.size() + 2);  // defaults made explicit + inflation
  EXPECT_LT(maxCurveDifference(generateBarbs(nearA), ca), 1e-6);
  EXPECT_LT(maxCurveDifference(generateBarbs(nearB), cb), 1e-6);
}

TEST(Interpolate, InflationKeepsKeyBarbCountsEqualAndShapeUnchanged) {
  const FeatherParams a = contourParams();
  std::vector<KeyBarb> keys = effectiveKeyBarbs(a, 0);
  const std::vector<KeyBarb> orig = keys;
  inflateKeyBarbs(keys, orig.size() + 4);
  ASSERT_EQ(keys.size(), orig.size() + 4);
  for (size_t i = 1; i < keys.size(); ++i) EXPECT_LE(keys[i - 1].rp, keys[i].rp);
  // The added key barbs copy the local shape: every barb is unchanged.
  std::vector<glm::dvec3> s0, s1;
  for (int i = 0; i <= 200; ++i) {
    barbShapeAt(orig, i / 200.0, s0);
    barbShapeAt(keys, i / 200.0, s1);
    ASSERT_EQ(s0.size(), s1.size());
    for (size_t k = 0; k < s0.size(); ++k) EXPECT_LT(glm::length(s0[k] - s1[k]), 1e-12);
  }
  // Interpolating feathers with 2 and 5 key barbs per vane yields equal counts on both sides.
  FeatherParams few = contourParams(), many = contourParams();
  few.left.keyBarbs = {straightKey(0.0), straightKey(0.3)};
  many.left.keyBarbs = {straightKey(0.0), straightKey(0.2), straightKey(0.4), straightKey(0.6), straightKey(1.0)};
  const FeatherParams mid = interpolateFeathers(few, many, 0.5);
  EXPECT_EQ(mid.left.keyBarbs.size(), effectiveKeyBarbs(many, 0).size());
}

TEST(Interpolate, MidpointBlendsScalarsAndKeyBarbs) {
  FeatherParams a = contourParams(), b = contourParams();
  b.rachisLength = 4.0;
  b.left.baseAngle = 0.6;
  b.spacingTip = 0.04;
  b.left.keyBarbs = {straightKey(0.0), straightKey(0.2), straightKey(0.6), straightKey(1.0)};
  a.left.keyBarbs = {straightKey(0.0), straightKey(0.4), straightKey(0.8), straightKey(1.0, 0.5)};
  const FeatherParams m = interpolateFeathers(a, b, 0.25);
  EXPECT_DOUBLE_EQ(m.rachisLength, 0.75 * 2.0 + 0.25 * 4.0);
  EXPECT_DOUBLE_EQ(m.left.baseAngle, 0.75 * 1.0 + 0.25 * 0.6);
  EXPECT_DOUBLE_EQ(m.spacingTip, 0.75 * 0.02 + 0.25 * 0.04);
  ASSERT_EQ(m.left.keyBarbs.size(), 4u);
  // Matched base to tip: rp blends; cvs blend the shapes both feathers have at the new rp.
  EXPECT_DOUBLE_EQ(m.left.keyBarbs[1].rp, 0.75 * 0.4 + 0.25 * 0.2);
  EXPECT_DOUBLE_EQ(m.left.keyBarbs[3].rp, 1.0);
  // Tip key: chord 0.5 on a, 1 on b -> 0.625.
  EXPECT_NEAR(glm::length(m.left.keyBarbs[3].cvs.back()), 0.625, 1e-12);
}

TEST(Interpolate, BarycentricBlend) {
  FeatherParams a = contourParams(), b = contourParams(), c = downParams();
  b.rachisLength = 3.0;
  b.silhouette.left.points = {{0, 0.1}, {0.5, 0.9}, {1, 0.0}};
  const std::vector<const FeatherParams*> fs{&a, &b, &c};
  EXPECT_EQ(blendFeathers(fs, {0, 2, 0}), b);
  const FeatherParams m = blendFeathers(fs, {1, 1, 2});  // normalized to 1/4, 1/4, 1/2
  EXPECT_DOUBLE_EQ(m.rachisLength, 0.25 * 2.0 + 0.25 * 3.0 + 0.5 * 0.3);
  // Silhouette: feathers without one contribute their constant barb length.
  const double at = 0.25 * a.barbLength + 0.25 * 0.5 + 0.5 * c.barbLength;  // b at rp 0.25 is 0.5
  EXPECT_NEAR(m.barbLengthAt(0, 0.25), at, 1e-12);
  EXPECT_NEAR(m.barbLengthAt(1, 0.25), 0.25 * a.barbLength + 0.25 * b.barbLength + 0.5 * c.barbLength, 1e-12);
  // Blending identical feathers changes nothing visible.
  const FeatherParams same = blendFeathers({&a, &a}, {0.3, 0.7});
  EXPECT_LT(maxCurveDifference(generateBarbs(same), generateBarbs(a)), 1e-5);
  EXPECT_THROW(blendFeathers(fs, {1, -1, 1}), Error);
  EXPECT_THROW(blendFeathers(fs, {0, 0, 0}), Error);
  EXPECT_THROW(blendFeathers(fs, {1, 1}), Error);
}

TEST(Interpolate, AfterfeatherFadesWithWeight) {
  FeatherParams a = contourParams(), b = contourParams();
  FeatherParams after = downParams();
  a.afterfeather = std::make_shared<const FeatherParams>(after);
  const FeatherParams m = interpolateFeathers(a, b, 0.5);
  ASSERT_TRUE(m.afterfeather);
  EXPECT_NEAR(m.afterfeather->rachisLength, 0.5 * after.rachisLength, 1e-12);
  EXPECT_NEAR(m.afterfeather->barbLength, 0.5 * after.barbLength, 1e-12);
  EXPECT_FALSE(interpolateFeathers(a, b, 1.0).afterfeather);
}

TEST(Interpolate, SilhouetteJumpsSurviveBlending) {
  FeatherParams a = contourParams(), b = contourParams();
  a.silhouette.left.points = {{0, 0.3}, {0.2, 0.3}, {0.2, 0.0}, {1, 0.0}};  // bristle-like discontinuity
  const FeatherParams m = interpolateFeathers(a, b, 0.5);
  EXPECT_NEAR(m.barbLengthAt(0, 0.1999999), 0.5 * 0.3 + 0.5 * b.barbLength, 1e-5);
  EXPECT_NEAR(m.barbLengthAt(0, 0.2000001), 0.5 * b.barbLength, 1e-5);
}

TEST(Interpolate, DifferentGeneratorsBlendInTheirStreitForm) {
  // Each feather enters as its derived Streit fields (tests/feather/test_helical_grow.cpp for helical).
  FeatherParams a = contourParams(), b = contourParams();
  b.generator = "something_else";
  b.generatorParams = {{"x", 1}};
  b.rachisLength *= 2;
  const FeatherParams m = interpolateFeathers(a, b, 0.5);
  EXPECT_EQ(m.generator, "streit");
  EXPECT_TRUE(m.generatorParams.is_null());
  EXPECT_TRUE(m == interpolateFeathers(a, streitForm(b), 0.5));
  EXPECT_DOUBLE_EQ(m.rachisLength, 1.5 * a.rachisLength);
  EXPECT_TRUE(interpolateFeathers(a, b, 1.0) == streitForm(b));
}

TEST(Interpolate, MaterialColourAndBrdfBlendWhenEveryFeatherSetsThem) {
  FeatherParams a = feather::testing::contourParams(), b = a;
  a.material.baseColor = glm::dvec3(1.0, 0.0, 0.5);
  b.material.baseColor = glm::dvec3(0.0, 1.0, 0.5);
  a.material.brdfD = 1.0;
  b.material.brdfD = 3.0;
  a.material.brdfH = 0.2;  // b leaves h to the scene: not blended
  const FeatherParams m = interpolateFeathers(a, b, 0.25);
  EXPECT_DOUBLE_EQ(m.material.baseColor->x, 0.75);
  EXPECT_DOUBLE_EQ(m.material.baseColor->y, 0.25);
  EXPECT_DOUBLE_EQ(*m.material.brdfD, 1.5);
  EXPECT_EQ(m.material.brdfH, a.material.brdfH);  // the heaviest's
  EXPECT_EQ(interpolateFeathers(a, b, 0.0).material, a.material);
  EXPECT_EQ(interpolateFeathers(a, b, 1.0).material, b.material);
}
