// Feather growth and wear (Streit 2003, 5.2.5, 8.1, Fig. 8.1).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/mesh.hpp"
#include "test_mesh_fixtures.hpp"

using namespace pteryla;
using namespace pteryla::feather;

namespace {

FeatherParams curvedFeather() {
  FeatherParams p = geomtest::contour(false);
  p.splits.count = 2;
  auto after = std::make_shared<FeatherParams>(geomtest::contour(true));
  after->rachisLength = 0.4;
  after->barbLength = 0.1;
  after->silhouette = {};
  p.afterfeather = after;
  return p;
}

// Angle between a barb's chord and the rachis tangent at its root.
double barbAngle(const FeatherParams& p, const FeatherCurves& c, const BarbCurve& b) {
  const glm::dvec3 root(c.cvs[b.cvOffset]), tip(c.cvs[b.cvOffset + b.cvCount - 1]);
  const glm::dvec3 t = rachisFrame(p, b.rp).tangent;
  const glm::dvec3 d = tip - root;
  if (glm::length(d) < 1e-12) return 0;
  return std::acos(std::clamp(glm::dot(glm::normalize(d), t), -1.0, 1.0));
}

}  // namespace

TEST(FeatherGrowth, MatureAtAgeOneExactly) {
  const FeatherParams p = curvedFeather();
  EXPECT_EQ(featherAtAge(p, 1.0), p);
  const TriMesh grown = buildFeatherMesh(p, 1.0, 1.0);
  // Same as meshing the static feather directly.
  const FeatherCurves c = generateBarbs(p);
  TriMesh direct;
  appendFeatherMesh(c, MeshOptions{}, FeatherPlacement{}, 0, direct);
  EXPECT_EQ(grown.positions, direct.positions);
  EXPECT_EQ(grown.uvGlobal, direct.uvGlobal);
  EXPECT_EQ(grown.indices, direct.indices);
  for (float s : grown.sheath) EXPECT_EQ(s, 0.0f);
}

TEST(FeatherGrowth, AgeZeroIsDegenerate) {
  const FeatherParams p = curvedFeather();
  const FeatherParams g = featherAtAge(p, 0.0);
  EXPECT_LE(g.totalLength(), 1e-5 * p.totalLength());
  EXPECT_EQ(g.barbLength, 0.0);
  EXPECT_EQ(g.rachisWidth, 0.0);
  EXPECT_EQ(barbCount(g), barbCount(p));  // attachments already final
  const TriMesh m = buildFeatherMesh(p, 0.0, 1.0);
  glm::vec3 lo, hi;
  ASSERT_TRUE(m.bounds(lo, hi));
  EXPECT_LT(glm::length(hi - lo), 1e-5f * static_cast<float>(p.totalLength()));
  for (float s : m.sheath) EXPECT_EQ(s, 1.0f);
}

TEST(FeatherGrowth, ShaftStraightUntilEightyPercent) {
  const FeatherParams p = curvedFeather();
  for (int i = 0; i < 80; ++i) {
    const double age = i / 100.0;
    const FeatherParams g = featherAtAge(p, age);
    EXPECT_EQ(g.rachisLateralCurvature, 0.0) << age;
    EXPECT_EQ(g.rachisVentralDorsalCurvature, 0.0) << age;
    const FeatherCurves c = generateBarbs(g);
    for (const auto& q : c.shafts[0].points) {
      EXPECT_EQ(q.y, 0.0f) << age;
      EXPECT_EQ(q.z, 0.0f) << age;
    }
  }
  EXPECT_GT(featherAtAge(p, 0.9).rachisVentralDorsalCurvature, 0.0);
}

TEST(FeatherGrowth, LengthsGrowMonotonicallyThenWearShortens) {
  const FeatherParams p = curvedFeather();
  double prevTotal = -1, prevBarb = -1, prevShaftLen = -1, prevWidth = -1;
  for (int i = 0; i <= 100; ++i) {
    const double age = i / 100.0;
    const FeatherParams g = featherAtAge(p, age);
    EXPECT_GE(g.totalLength(), prevTotal) << age;
    EXPECT_GE(g.silhouette.left.at(0.5), prevBarb) << age;
    EXPECT_GE(g.rachisWidth, prevWidth) << age;
    const FeatherCurves c = generateBarbs(g);
    double arc = 0;  // shaft arc length (straight until 0.8, then curving)
    for (size_t k = 1; k < c.shafts[0].points.size(); ++k)
      arc += glm::length(c.shafts[0].points[k] - c.shafts[0].points[k - 1]);
    EXPECT_GE(arc, prevShaftLen - 1e-4 * p.totalLength()) << age;  // polyline chords shorten as it curves
    prevShaftLen = arc;
    prevTotal = g.totalLength();
    prevBarb = g.silhouette.left.at(0.5);
    prevWidth = g.rachisWidth;
  }
  // Shaft first (30%), barbs next (to 50%).
  EXPECT_NEAR(featherAtAge(p, 0.3).totalLength(), p.totalLength(), 1e-12);
  EXPECT_EQ(featherAtAge(p, 0.3).silhouette.left.at(0.5), 0.0);
  EXPECT_NEAR(featherAtAge(p, 0.4).silhouette.left.at(0.5), 0.5 * p.silhouette.left.at(0.5), 1e-12);
  // Wear: shorter barbs, more splits, monotone past maturity.
  const FeatherParams w1 = featherAtAge(p, 1.5), w2 = featherAtAge(p, 2.0);
  EXPECT_LT(w1.silhouette.left.at(0.5), p.silhouette.left.at(0.5));
  EXPECT_LT(w2.silhouette.left.at(0.5), w1.silhouette.left.at(0.5));
  EXPECT_NEAR(w2.silhouette.left.at(0.5), 0.7 * p.silhouette.left.at(0.5), 1e-12);
  EXPECT_GT(w1.splits.count, p.splits.count);
  EXPECT_GE(w2.splits.count, w1.splits.count);
  EXPECT_EQ(w2.splits.count, p.splits.count + 6);
  EXPECT_EQ(featherAtAge(p, 3.0), w2);  // wear saturates
}

TEST(FeatherGrowth, PinFeatherBarbsLieAlongTheShaftThenOpenTipToBase) {
  const FeatherParams p = geomtest::contour(true);
  {  // barbs lengthening, closed: parallel to the shaft pointing to the tip
    const FeatherParams g = featherAtAge(p, 0.45);
    const FeatherCurves c = generateBarbs(g);
    for (const BarbCurve& b : c.barbs) EXPECT_LT(barbAngle(g, c, b), 0.03) << b.rp;
  }
  {  // opening front (the migrating key barb) at rp 0.5: open above, closed below
    const FeatherParams g = featherAtAge(p, 0.65);
    const FeatherCurves c = generateBarbs(g);
    for (const BarbCurve& b : c.barbs) {
      const VaneParams& v = p.vane(b.vane);
      const double finalAngle = v.baseAngle * (1 - b.rp) + v.tipAngle * b.rp;
      const double a = barbAngle(g, c, b);
      if (b.rp > 0.55) {
        EXPECT_GT(a, 0.4 * finalAngle) << b.rp;
      }
      if (b.rp < 0.2) {
        EXPECT_LT(a, 0.05) << b.rp;
      }
    }
  }
  {  // open at 80%: final angles, straight barbs
    const FeatherParams g = featherAtAge(p, 0.8);
    const FeatherCurves c = generateBarbs(g);
    for (const BarbCurve& b : c.barbs) {
      const VaneParams& v = p.vane(b.vane);
      const double finalAngle = v.baseAngle * (1 - b.rp) + v.tipAngle * b.rp;
      EXPECT_NEAR(barbAngle(g, c, b), finalAngle, 0.02) << b.rp;
    }
  }
}

TEST(FeatherGrowth, TexturesTravelWithTheBarbs) {
  // UVs come from the mature, open feather: a growing feather has the same texture coordinates per
  // vertex as the mature one (same barbs, same tessellation), although its geometry differs.
  const FeatherParams p = curvedFeather();
  const TriMesh mature = buildFeatherMesh(p, 1.0, 0.5);
  for (double age : {0.35, 0.6, 0.9}) {
    const TriMesh g = buildFeatherMesh(p, age, 0.5);
    ASSERT_EQ(g.vertexCount(), mature.vertexCount());
    EXPECT_NE(g.positions, mature.positions);
    for (size_t i = 0; i < g.vertexCount(); ++i) {
      ASSERT_NEAR(g.uvBarb[i].x, mature.uvBarb[i].x, 1e-5f) << age;
      ASSERT_NEAR(g.uvBarb[i].y, mature.uvBarb[i].y, 1e-5f) << age;
      ASSERT_NEAR(g.uvGrowth[i].x, mature.uvGrowth[i].x, 1e-5f) << age;
      ASSERT_NEAR(g.uvGrowth[i].y, mature.uvGrowth[i].y, 1e-5f) << age;
      ASSERT_NEAR(g.uvGlobal[i].x, mature.uvGlobal[i].x, 1e-4f) << age;
      ASSERT_NEAR(g.uvGlobal[i].y, mature.uvGlobal[i].y, 1e-4f) << age;
    }
  }
}

TEST(FeatherGrowth, SheathShedsFromTipToBase) {
  const FeatherParams p = geomtest::contour(true);
  auto sheathed = [&](double age) {
    const TriMesh m = buildFeatherMesh(p, age, 1.0);
    double s = 0;
    for (float x : m.sheath) s += x;
    return s / static_cast<double>(m.vertexCount());
  };
  EXPECT_EQ(sheathed(0.4), 1.0);
  const double mid = sheathed(0.65);
  EXPECT_GT(mid, 0.1);
  EXPECT_LT(mid, 0.9);
  EXPECT_EQ(sheathed(0.85), 0.0);
  // At mid shedding the sheathed vertices are the ones near the base.
  const TriMesh m = buildFeatherMesh(p, 0.65, 1.0);
  for (size_t i = 0; i < m.vertexCount(); ++i) {
    if (m.uvGrowth[i].y < 0.3f) {
      EXPECT_EQ(m.sheath[i], 1.0f);
    }
    if (m.uvGrowth[i].y > 0.7f) {
      EXPECT_EQ(m.sheath[i], 0.0f);
    }
  }
  EXPECT_EQ(sheathWeight(0.0, 0.0, 0.05), 1.0);
  EXPECT_EQ(sheathWeight(1.0, 0.0, 0.05), 1.0);
  EXPECT_EQ(sheathWeight(0.0, 1.0, 0.05), 0.0);
}

TEST(FeatherGrowth, ScheduleIsDataAndLoadsFromJson) {
  const FeatherParams p = geomtest::contour(true);
  GrowthSchedule slow = defaultGrowthSchedule();
  for (auto& r : slow.ramps)
    if (r.parameter == GrowthParam::ShaftLength) r = {GrowthParam::ShaftLength, 0.0, 0.6, Easing::Linear};
  EXPECT_NEAR(featherAtAge(p, 0.3, slow).rachisLength, 0.5 * p.rachisLength, 1e-12);
  EXPECT_NEAR(featherAtAge(p, 0.3).rachisLength, p.rachisLength, 1e-12);

  const std::string path = std::string(PTERYLA_BUILD_DIR) + "/test_growth_schedule.json";
  {
    std::ofstream f(path);
    f << R"({"growth": {"ramps": [{"parameter": "shaft_length", "start": 0, "end": 0.6, "easing": "smooth"},
                                  {"parameter": "wear_length", "start": 1, "end": 3}],
                        "wear_max_splits": 2}})";
  }
  const GrowthSchedule s = loadGrowthSchedule(path);
  EXPECT_EQ(s.wearMaxSplits, 2);
  EXPECT_EQ(s.ramps.size(), defaultGrowthSchedule().ramps.size());  // others keep their defaults
  const GrowthState st = growthStateAt(0.3, s);
  EXPECT_NEAR(st[GrowthParam::ShaftLength], 0.5, 1e-12);  // smoothstep at the midpoint
  EXPECT_NEAR(growthStateAt(0.15, s)[GrowthParam::ShaftLength], 0.15625, 1e-12);
  EXPECT_NEAR(growthStateAt(2.0, s)[GrowthParam::WearLength], 0.5, 1e-12);
  // Round trip.
  const Json j = growthScheduleToJson(s);
  JsonReader r(j, "roundtrip");
  const GrowthSchedule s2 = readGrowthSchedule(r);
  ASSERT_EQ(s2.ramps.size(), s.ramps.size());
  for (size_t i = 0; i < s.ramps.size(); ++i) {
    EXPECT_EQ(s2.ramps[i].parameter, s.ramps[i].parameter);
    EXPECT_EQ(s2.ramps[i].start, s.ramps[i].start);
    EXPECT_EQ(s2.ramps[i].end, s.ramps[i].end);
    EXPECT_EQ(s2.ramps[i].easing, s.ramps[i].easing);
  }
}

TEST(FeatherGrowth, BadSchedulesAreRejectedWithTheirPath) {
  auto load = [](const std::string& text) {
    const Json j = Json::parse(text);
    JsonReader r(j, "g.json", "growth");
    return readGrowthSchedule(r);
  };
  auto element = [&](const std::string& text) {
    try {
      load(text);
    } catch (const Error& e) {
      return e.element();
    }
    return std::string("no error");
  };
  EXPECT_EQ(element(R"({"ramps": [{"parameter": "shaft_lenght", "start": 0, "end": 0.3}]})"),
            "growth.ramps[0].parameter");
  EXPECT_EQ(element(R"({"ramps": [{"parameter": "barb_length", "start": 0.5, "end": 1.2}]})"), "growth.ramps[0].end");
  EXPECT_EQ(element(R"({"ramps": [{"parameter": "barb_length", "start": 0.5, "end": 0.4}]})"), "growth.ramps[0].end");
  EXPECT_EQ(element(R"({"ramps": [{"parameter": "wear_splits", "start": 0.5, "end": 1.5}]})"), "growth.ramps[0].start");
  EXPECT_EQ(element(R"({"ramps": [{"parameter": "sheath", "start": 0, "end": 1},
                                  {"parameter": "sheath", "start": 0, "end": 1}]})"),
            "growth.ramps[1].parameter");
  EXPECT_EQ(element(R"({"ramps": [{"parameter": "sheath", "start": 0, "end": 1, "easing": "bouncy"}]})"),
            "growth.ramps[0].easing");
  EXPECT_EQ(element(R"({"ramps": [], "speed": 2})"), "growth.speed");
  EXPECT_THROW(featherAtAge(geomtest::contour(), std::nan("")), Error);
}
