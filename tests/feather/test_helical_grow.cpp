// Helical feathers in growing coats and blends (issue #30 item 4): a growing helical feather is the
// helical model at the growth time its schedule maps to (collar growth, then unfurling, then the open
// stage), a mature one is unchanged, and helical and Streit feathers blend in their Streit key-barb form.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/generator.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/helical.hpp"
#include "pteryla/feather/interpolate.hpp"
#include "pteryla/feather/io.hpp"

using namespace pteryla;
using namespace pteryla::feather;

namespace {

const std::string kContour = std::string(PTERYLA_DATA_DIR) + "/feathers/helical-contour.json";
const std::string kStreit = std::string(PTERYLA_DATA_DIR) + "/feathers/contour.json";

HelicalParams paramsOf(const FeatherParams& p) {
  JsonReader r(p.generatorParams, p.sourceFile, "helical");
  return readHelical(r);
}

// Largest |z| (dorsal, barb-local unit chord) over the key barbs of both vanes: 0 for flat vanes, about
// the collar diameter over the chord for barbs rolled on the collar.
double keyBarbDepth(const FeatherParams& p) {
  double z = 0;
  for (int v = 0; v < 2; ++v)
    for (const KeyBarb& k : p.vane(v).keyBarbs)
      for (const auto& c : k.cvs) z = std::max(z, std::abs(c.z));
  return z;
}

double maxSilhouette(const FeatherParams& p) {
  double m = 0;
  for (const auto* prof : {&p.silhouette.left, &p.silhouette.right})
    for (const auto& q : prof->points) m = std::max(m, q.y);
  return m;
}

}  // namespace

// The schedule's stages map to the helical model: collar time = (shaft_length + barb_length) / 2 of
// the end time, unfurl = the parameters' unfurl times opening, the open stage = key_barbs.
TEST(HelicalGrowing, StagesMapToTheHelicalModel) {
  const HelicalParams hp = paramsOf(loadFeather(kContour));
  const GrowthSchedule& s = defaultGrowthSchedule();
  const HelicalGrowthStage a = helicalGrowthStage(growthStateAt(0.15, s), hp);
  EXPECT_DOUBLE_EQ(a.collar, 0.25);  // shaft 0.5, barbs 0
  EXPECT_EQ(a.unfurlLeft, 0.0);
  EXPECT_EQ(a.open, 0.0);
  const HelicalGrowthStage b = helicalGrowthStage(growthStateAt(0.4, s), hp);
  EXPECT_DOUBLE_EQ(b.collar, 0.75);  // shaft 1, barbs 0.5
  const HelicalGrowthStage c = helicalGrowthStage(growthStateAt(0.65, s), hp);
  EXPECT_EQ(c.collar, 1.0);
  EXPECT_DOUBLE_EQ(c.unfurlLeft, 0.5 * hp.unfurlLeft);
  EXPECT_DOUBLE_EQ(c.unfurlRight, 0.5 * hp.unfurlRight);
  EXPECT_EQ(c.curvature, 0.0);
  const HelicalGrowthStage d = helicalGrowthStage(growthStateAt(0.9, s), hp);
  EXPECT_EQ(d.unfurlLeft, hp.unfurlLeft);
  EXPECT_DOUBLE_EQ(d.open, 0.5);
  EXPECT_DOUBLE_EQ(d.curvature, 0.5);
}

// Collar growth: the feather is the helical model at that time: a rachis v_grow t long (at the mature
// feather's scale) with only the barbs fused by then, rolled on the collar; unfurling flattens them.
TEST(HelicalGrowing, GrowsOnTheCollarThenUnfurls) {
  const FeatherParams def = loadFeather(kContour);
  const HelicalParams hp = paramsOf(def);
  const HelicalGrowth g(hp);
  const double tEnd = g.endTime();

  const FeatherParams young = featherAtAge(def, 0.4);  // collar 0.75
  EXPECT_EQ(young.generator, "streit");
  EXPECT_NEAR(young.rachisLength, 0.75 * def.rachisLength, 1e-12 * def.rachisLength);
  EXPECT_EQ(young.rachisLateralCurvature, 0.0);
  EXPECT_EQ(young.rachisVentralDorsalCurvature, 0.0);  // straight while it grows (8.3)
  validateFeather(young);
  // Its barbs are the helical barbs fused with the rachis by t = 0.75 t_end, no more.
  size_t fused = 0;
  for (const HelicalBarb& b : g.barbs()) fused += b.completionTime <= 0.75 * tEnd ? 1 : 0;
  const HelicalConversion direct =
      convertHelicalScaled(g, helicalFeatherAt(g, 0.75 * tEnd, 0.0, 0.0), def.rachisLength / (hp.growthSpeed * tEnd));
  EXPECT_EQ(static_cast<size_t>(direct.barbs[0] + direct.barbs[1]), fused);
  EXPECT_LT(fused, g.completedCount());
  EXPECT_GT(fused, 10u);
  EXPECT_EQ(young.left.keyBarbs, direct.feather.left.keyBarbs);
  EXPECT_EQ(young.silhouette.right.points, direct.feather.silhouette.right.points);
  // Rolled on the collar (w = 0): the barbs reach around the follicle, far out of the vane plane.
  EXPECT_GT(keyBarbDepth(young), 0.4);
  // Fewer barbs than the mature feather: the helical feather adds barbs at its base as it grows.
  EXPECT_LT(generateBarbs(young).barbs.size(), generateBarbs(def).barbs.size());

  // Unfurling: half way through the opening window the barbs are partly flattened, at its end flat.
  const FeatherParams half = featherAtAge(def, 0.65), open = featherAtAge(def, 0.8);
  EXPECT_GT(keyBarbDepth(half), 2 * keyBarbDepth(open));
  EXPECT_LT(keyBarbDepth(half), 0.9 * keyBarbDepth(featherAtAge(def, 0.5)));
  EXPECT_LT(keyBarbDepth(open), 0.1);
  EXPECT_NEAR(open.rachisLength, def.rachisLength, 1e-12 * def.rachisLength);
  EXPECT_NEAR(maxSilhouette(open), maxSilhouette(def), 1e-9 * maxSilhouette(def));
  // Young feathers are short and narrow; the vane widens as the barbs grow on the collar.
  EXPECT_LT(maxSilhouette(featherAtAge(def, 0.2)), maxSilhouette(young));
  // Age 0: a valid, vanishing feather.
  const FeatherParams zero = featherAtAge(def, 0.0);
  validateFeather(zero);
  EXPECT_LT(zero.rachisLength, 1e-5 * def.rachisLength);
}

// The open stage turns the unfurled barbs into the feather's own and curves the rachis; the feather is
// continuous up to the mature one, and mature and worn helical feathers are exactly as before.
TEST(HelicalGrowing, OpenStageReachesTheMatureFeatherAndMatureIsUnchanged) {
  const FeatherParams def = loadFeather(kContour);
  const FeatherParams late = featherAtAge(def, 0.999999);
  EXPECT_NEAR(late.rachisVentralDorsalCurvature, def.rachisVentralDorsalCurvature, 1e-5);
  EXPECT_NEAR(late.rachisLength, def.rachisLength, 1e-9);
  ASSERT_EQ(late.left.keyBarbs.size(), def.left.keyBarbs.size());
  for (size_t k = 0; k < def.left.keyBarbs.size(); ++k)
    for (size_t c = 0; c < def.left.keyBarbs[k].cvs.size(); ++c)
      EXPECT_LT(glm::length(late.left.keyBarbs[k].cvs[c] - def.left.keyBarbs[k].cvs[c]), 1e-5);
  // Mature: the definition itself. Worn: the Streit wear of the derived fields, as for any feather.
  EXPECT_TRUE(featherAtAge(def, 1.0) == def);
  FeatherParams asStreit = def;
  asStreit.generator = "streit";
  for (double age : {1.3, 2.0}) {
    FeatherParams worn = featherAtAge(def, age), expect = featherAtAge(asStreit, age);
    EXPECT_EQ(worn.generator, "helical");
    expect.generator = "helical";
    EXPECT_TRUE(worn == expect) << age;
  }
}

// Mixed generators blend in the Streit key-barb form; one generator keeps its own blend.
TEST(HelicalBlend, HelicalAndStreitBlendThroughTheConvertedKeyBarbs) {
  const FeatherParams h = loadFeather(kContour), s = loadFeather(kStreit);
  const FeatherParams hs = streitForm(h);
  EXPECT_EQ(hs.generator, "streit");
  EXPECT_TRUE(hs.generatorParams.is_null());
  EXPECT_EQ(hs.rachisLength, h.rachisLength);
  EXPECT_EQ(hs.left.keyBarbs, h.left.keyBarbs);
  EXPECT_EQ(hs.silhouette.right.points, h.silhouette.right.points);
  // Weights 1/0 and 0/1 give exactly each key's converted form.
  EXPECT_TRUE(blendFeathers({&h, &s}, {1.0, 0.0}) == hs);
  EXPECT_TRUE(blendFeathers({&h, &s}, {0.0, 1.0}) == s);
  EXPECT_TRUE(interpolateFeathers(s, h, 1.0) == hs);
  // Half way: the blend of the converted forms, and analytically between the two.
  const FeatherParams mid = interpolateFeathers(h, s, 0.5);
  EXPECT_TRUE(mid == interpolateFeathers(hs, s, 0.5));
  EXPECT_EQ(mid.generator, "streit");
  EXPECT_DOUBLE_EQ(mid.rachisLength, 0.5 * h.rachisLength + 0.5 * s.rachisLength);
  // Key barbs: against a Streit feather with the helical key barbs bent dorsally (interior control
  // vertices raised by 0.2, chords unchanged) and a twice as long rachis, every key barb of the blend is
  // the helical one raised by 0.1 (same rp, so the bilinear construction reduces to the weighted sum).
  FeatherParams bent = hs;
  bent.rachisLength *= 2;
  for (int v = 0; v < 2; ++v)
    for (KeyBarb& k : bent.vane(v).keyBarbs)
      for (size_t c = 1; c + 1 < k.cvs.size(); ++c) k.cvs[c].z += 0.2;
  const FeatherParams m2 = interpolateFeathers(h, bent, 0.5);
  EXPECT_DOUBLE_EQ(m2.rachisLength, 1.5 * h.rachisLength);
  for (int v = 0; v < 2; ++v) {
    const auto& a = h.vane(v).keyBarbs;
    const auto& b = m2.vane(v).keyBarbs;
    ASSERT_EQ(a.size(), b.size());
    for (size_t k = 0; k < a.size(); ++k) {
      EXPECT_DOUBLE_EQ(b[k].rp, a[k].rp);
      const size_t n = a[k].cvs.size();
      for (size_t c = 0; c < n; ++c) {
        const glm::dvec3 expect = a[k].cvs[c] - a[k].cvs[0] + glm::dvec3(0, 0, c > 0 && c + 1 < n ? 0.1 : 0.0);
        EXPECT_LT(glm::length(b[k].cvs[c] - expect), 1e-12) << v << " " << k << " " << c;
      }
    }
  }
  // Helical with helical: today's behaviour (the heaviest feather's helical object, blended fields).
  FeatherParams h2 = h;
  h2.rachisLength *= 1.2;
  const FeatherParams hh = interpolateFeathers(h, h2, 0.3);
  EXPECT_EQ(hh.generator, "helical");
  EXPECT_EQ(hh.generatorParams, h.generatorParams);
  EXPECT_DOUBLE_EQ(hh.rachisLength, 0.7 * h.rachisLength + 0.3 * h2.rachisLength);
}
