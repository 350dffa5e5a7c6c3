// Growth schedules from files and wear past age 1 (issue #30 item 1, Streit 2003 5.2.5): a feather file,
// a scene and a tract can each give the growth object; old plumage wears (moult.old_age) and a renewed
// feather wears over moult.wear_time; a worn feather's barbs are shorter than the fresh one's.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <string>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/moult/schedule.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

using namespace pteryla;
using pipeline::Pipeline;

namespace {

const std::string kSceneFile = std::string(PTERYLA_DATA_DIR) + "/scenes/wear_test_in_memory.json";
const std::string kContour = std::string(PTERYLA_DATA_DIR) + "/feathers/contour.json";

Json patchScene() {
  return Json::parse(R"({
    "pteryla": 1,
    "seed": 9,
    "mesh": "../meshes/patch.obj",
    "feathers": {"contour": "../feathers/contour.json"},
    "tracts": [{"name": "a", "groups": ["patch"], "count": 60, "feather_scale": "auto",
                "feather_spacings": 1.5, "relax": {"iterations": 3}}],
    "directions": {"vectors": [{"at": [0, 0, 0], "direction": [1, 0, 0]}]},
    "packing": {"method": "height_field"}
  })");
}

// Barbs lose `shortening` of their length over ages 1 to 1.5; no extra splits.
Json growth(double shortening) {
  return Json{{"ramps", Json::array({Json{{"parameter", "wear_length"}, {"start", 1.0}, {"end", 1.5}}})},
              {"wear_max_shortening", shortening},
              {"wear_max_splits", 0}};
}

// Sum over the coat mesh's triangles of their area: shorter barbs, less area.
double coatArea(Pipeline& p) {
  const TriMesh& m = p.coatMesh().mesh;
  double a = 0;
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    const glm::dvec3 p0(m.positions[m.indices[3 * t]]), p1(m.positions[m.indices[3 * t + 1]]),
        p2(m.positions[m.indices[3 * t + 2]]);
    a += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
  }
  return a;
}

}  // namespace

TEST(Wear, FeatherFileGrowthRoundTripsAndIsComparedByValue) {
  Json in = readJsonFile(kContour);
  in["growth"] = Json::parse(R"({"ramps": [{"parameter": "wear_length", "start": 1, "end": 1.25, "easing": "smooth"}],
                                 "wear_max_shortening": 0.5})");
  JsonReader r(in, "f.json");
  const feather::FeatherParams p = feather::readFeather(r);
  ASSERT_TRUE(p.growth);
  EXPECT_EQ(p.growth->wearMaxShortening, 0.5);
  const feather::GrowthSchedule& s = feather::growthScheduleOf(p);
  const auto it = std::find_if(s.ramps.begin(), s.ramps.end(), [](const feather::GrowthRamp& g) {
    return g.parameter == feather::GrowthParam::WearLength;
  });
  ASSERT_NE(it, s.ramps.end());
  EXPECT_EQ(it->end, 1.25);
  // Ramps not given keep the default schedule's.
  EXPECT_EQ(s.ramps.size(), feather::defaultGrowthSchedule().ramps.size());

  const Json j = feather::featherToJson(p);
  ASSERT_TRUE(j.contains("growth"));
  JsonReader back(j, "back.json");
  const feather::FeatherParams q = feather::readFeather(back);
  EXPECT_TRUE(q == p);
  feather::FeatherParams other = q;
  feather::GrowthSchedule changed = *q.growth;
  changed.wearMaxShortening = 0.4;
  other.growth = std::make_shared<const feather::GrowthSchedule>(changed);
  EXPECT_FALSE(other == p);
  // No growth object: none written, the default used.
  feather::FeatherParams plain = p;
  plain.growth.reset();
  EXPECT_FALSE(feather::featherToJson(plain).contains("growth"));
  EXPECT_EQ(&feather::growthScheduleOf(plain), &feather::defaultGrowthSchedule());
}

TEST(Wear, BadGrowthInAFeatherFileNamesItsKeyPath) {
  Json in = readJsonFile(kContour);
  in["growth"] = Json::parse(R"({"ramps": [{"parameter": "wear_length", "start": 0.5, "end": 1.5}]})");
  JsonReader r(in, "bad.json");
  try {
    (void)feather::readFeather(r);
    FAIL() << "a wear ramp before age 1 was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "bad.json");
    EXPECT_NE(e.element().find("growth.ramps[0]"), std::string::npos) << e.element();
  }
}

TEST(Wear, OldPlumageAndRenewedFeathersAgePastOne) {
  moult::MoultOptions o;
  o.start = 0;
  o.duration = 10;
  o.window = 0.2;
  o.gap = 0.1;
  o.oldAge = 1.7;
  o.wearTime = 4;
  const std::vector<glm::dvec2> uv = {{0.1, 0.5}, {0.5, 0.5}, {0.9, 0.5}};
  const moult::MoultPlan plan = moult::planMoult(uv, {1, 1, 1}, {0, 1, 2}, o);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(moult::moultStateAt(plan, i, -1.0).age, 1.7) << "old plumage, before the moult";
    // Renewed at start + duration * (order + window) / sweep; wears linearly over wear_time, then stays at 2.
    const double renewedAt = o.start + o.duration * (plan.order[i] + plan.window[i]) / plan.sweep;
    const moult::MoultState fresh = moult::moultStateAt(plan, i, renewedAt + 1e-6);
    EXPECT_EQ(fresh.phase, moult::MoultPhase::Renewed);
    EXPECT_NEAR(fresh.age, 1.0, 1e-6);
    EXPECT_NEAR(moult::moultStateAt(plan, i, renewedAt + 1.0).age, 1.25, 1e-9);
    EXPECT_EQ(moult::moultStateAt(plan, i, renewedAt + 100.0).age, 2.0);
  }
  // Defaults: no wear, every mature feather at age 1 (the behaviour of scenes without these keys).
  moult::MoultOptions d;
  const moult::MoultPlan dp = moult::planMoult(uv, {1, 1, 1}, {0, 1, 2}, d);
  EXPECT_EQ(moult::moultStateAt(dp, 0, -1.0).age, 1.0);
  EXPECT_EQ(moult::moultStateAt(dp, 0, 100.0).age, 1.0);
}

TEST(Wear, SceneAndTractGrowthReachTheirFeathersTractFirst) {
  Json j = patchScene();
  j["tracts"].push_back(Json::parse(R"({"name": "b", "groups": ["patch"], "count": 30, "feather_scale": "auto",
                                        "feather_spacings": 1.5, "relax": {"iterations": 3}})"));
  j["growth"] = growth(0.2);
  j["tracts"][1]["growth"] = growth(0.6);
  Pipeline p(pipeline::sceneFromJson(j, kSceneFile));
  const coat::CoatFeathers& c = p.feathers();
  size_t seen[2] = {0, 0};
  for (size_t i = 0; i < c.size(); ++i) {
    ASSERT_TRUE(c.params[i].growth) << "feather " << i;
    EXPECT_EQ(c.params[i].growth->wearMaxShortening, c.tract[i] == 1 ? 0.6 : 0.2) << "feather " << i;
    ++seen[c.tract[i] == 1];
  }
  EXPECT_GT(seen[0], 0u);
  EXPECT_GT(seen[1], 0u);
  // Written back with the scene.
  const Json back = pipeline::sceneToJson(p.scene(), "");
  EXPECT_EQ(back["growth"], j["growth"]);
  EXPECT_EQ(back["tracts"][1]["growth"], j["tracts"][1]["growth"]);
  // A bad tract growth names its tract.
  j["tracts"][1]["growth"]["wear_max_shortening"] = 3;
  try {
    Pipeline bad(pipeline::sceneFromJson(j, kSceneFile));
    (void)bad.feathers();
    FAIL() << "wear_max_shortening 3 was accepted";
  } catch (const Error& e) {
    EXPECT_NE(e.element().find("tracts[1].growth.wear_max_shortening"), std::string::npos) << e.element();
  }
}

TEST(Wear, WornOldPlumageMeshesShorterBarbsThanFreshAndFollowsTheSchedule) {
  auto areaWith = [](double oldAge, double shortening) {
    Json j = patchScene();
    j["moult"] = Json::parse(R"({"start": 100, "duration": 10})");  // not begun by t = 0: all old plumage
    j["moult"]["old_age"] = oldAge;
    j["growth"] = growth(shortening);
    Pipeline p(pipeline::sceneFromJson(j, kSceneFile));
    p.setLod(0.3);
    p.setTime(0);
    for (double a : p.feathers().age) EXPECT_EQ(a, oldAge);
    return coatArea(p);
  };
  const double fresh = areaWith(1.0, 0.5);
  const double worn = areaWith(1.5, 0.5);   // full wear: barbs 50% shorter
  const double half = areaWith(1.25, 0.5);  // half way up the ramp
  const double none = areaWith(1.5, 0.0);   // a schedule that does not wear
  EXPECT_LT(worn, 0.8 * fresh);
  EXPECT_GT(half, worn);
  EXPECT_LT(half, fresh);
  EXPECT_DOUBLE_EQ(none, fresh);
}
