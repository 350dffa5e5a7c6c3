// Gizmos (gizmo.hpp): a control's offset is written as the constant until it is keyed, then as a key at
// the time asked; Key keys every behaviour and the offset; the axis drag's line parameter is exact; a
// joint's ring turn about its parent's frame turns the joint's children about the ring's world axis,
// and keys round-trip through [axis, degrees]. No display.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/geometric.hpp>

#include "actions.hpp"
#include "document.hpp"
#include "fixtures.hpp"
#include "gizmo.hpp"
#include "pteryla/core/error.hpp"

using namespace pteryla;
using namespace pteryla::viewer;
using viewer_test::smallPatch;

namespace {

glm::dvec3 vec(const Json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

// A three-joint chain over the patch (no weights: every vertex follows the root), the middle joint keyed.
pipeline::Scene chainScene() {
  pipeline::Scene s = smallPatch();
  s.skeleton = Json::parse(R"({
    "joints": [{"name": "root", "parent": -1, "position": [0, 0, 0]},
               {"name": "mid", "parent": 0, "position": [0.5, 0, 0]},
               {"name": "tip", "parent": 1, "position": [1.0, 0, 0]}],
    "weights": [],
    "keys": [{"joint": 0, "t": 0, "rotation": [0, 1, 0, 30]},
             {"joint": 1, "t": 1, "rotation": [0, 0, 1, 20]}]})");
  return s;
}

}  // namespace

TEST(Gizmo, ControlOffsetIsAConstantUntilKeyedThenKeysAtTheTime) {
  Document d;
  d.reset(smallPatch(), "");
  actions::addControl(d, {0.2, 0.05, 0.1}, 0.3);
  actions::setControlValue(d, 0, "direction", 0.7, 0.0);
  setControlOffset(d, 0, {0.1, 0, 0}, 0.5);
  const Json& c = d.scene().controls[0];
  ASSERT_TRUE(c.contains("offset"));
  EXPECT_EQ(vec(c["offset"]), glm::dvec3(0.1, 0, 0));
  EXPECT_FALSE(c.contains("keys"));
  ASSERT_TRUE(controlOffsetAt(d.scene(), 0, 3.0));
  EXPECT_EQ(controlOffsetAt(d.scene(), 0, 3.0)->offset, glm::dvec3(0.1, 0, 0));
  EXPECT_FALSE(controlOffsetAt(d.scene(), 0, 3.0)->keyed);

  // Key: every behaviour and the offset at t = 1, the constants gone.
  keyControlAll(d, 0, 1.0);
  {
    const Json& k = d.scene().controls[0];
    EXPECT_FALSE(k.contains("offset"));
    EXPECT_FALSE(k.contains("direction"));
    ASSERT_EQ(k["keys"].size(), 1u);
    EXPECT_EQ(k["keys"][0]["t"], 1.0);
    EXPECT_EQ(vec(k["keys"][0]["offset"]), glm::dvec3(0.1, 0, 0));
    EXPECT_DOUBLE_EQ(k["keys"][0]["direction"].get<double>(), 0.7);
    for (const char* b : actions::kControlBehaviours) EXPECT_TRUE(k["keys"][0].contains(b)) << b;
  }
  // Keyed now: a new offset at t = 2 is a second key, and between the keys it interpolates (linear).
  setControlOffset(d, 0, {0.1, 0.2, 0}, 2.0);
  ASSERT_EQ(d.scene().controls[0]["keys"].size(), 2u);
  const auto mid = controlOffsetAt(d.scene(), 0, 1.5);
  ASSERT_TRUE(mid);
  EXPECT_TRUE(mid->keyed);
  EXPECT_NEAR(mid->offset.y, 0.1, 1e-12);
  EXPECT_EQ(mid->at, glm::dvec3(0.2, 0.05, 0.1));
  // Setting it again at t = 2 updates that key (no third key); each call is one undo step once the
  // gesture ends (the app ends it when the mouse is released: edits of one drag merge).
  d.endGesture();
  setControlOffset(d, 0, {0.1, 0.3, 0}, 2.0);
  EXPECT_EQ(d.scene().controls[0]["keys"].size(), 2u);
  ASSERT_TRUE(d.undo());
  EXPECT_NEAR(controlOffsetAt(d.scene(), 0, 2.0)->offset.y, 0.2, 1e-12);
  ASSERT_TRUE(d.undo());
  EXPECT_EQ(d.scene().controls[0]["keys"].size(), 1u);
  // A missing control is an error that changes nothing.
  const Json before = d.scene().controls;
  EXPECT_THROW(setControlOffset(d, 5, {0, 0, 0}, 0), Error);
  EXPECT_THROW(keyControlAll(d, 5, 0), Error);
  EXPECT_THROW(setControlOffset(d, 0, {std::nan(""), 0, 0}, 0), Error);
  EXPECT_EQ(d.scene().controls, before);
}

TEST(Gizmo, ClosestOnLineIsWhereTheRayCrossesTheAxis) {
  const glm::dvec3 o(1, 2, 3), a(0, 0, 1);
  // A ray aimed through o + 4 a from the side meets the line there.
  const glm::dvec3 ro(5, 2, 9), target = o + 4.0 * a;
  const auto s = closestOnLine(o, a, ro, glm::normalize(target - ro));
  ASSERT_TRUE(s);
  EXPECT_NEAR(*s, 4.0, 1e-12);
  // A skew ray: the closest point's parameter.
  const auto skew = closestOnLine(o, a, glm::dvec3(1, 5, -2), glm::dvec3(1, 0, 0));
  ASSERT_TRUE(skew);
  EXPECT_NEAR(*skew, -5.0, 1e-12);
  EXPECT_FALSE(closestOnLine(o, a, ro, a));  // along the line: no single point
}

TEST(Gizmo, AxisAngleRoundTripsAndTheIdentityIsExplicit) {
  EXPECT_EQ(axisAngleJson(glm::dquat(1, 0, 0, 0)), Json::parse("[0, 0, 1, 0]"));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 200; ++i) {
    const glm::dquat q = glm::normalize(glm::dquat(u(rng), u(rng), u(rng), u(rng)));
    const Json j = axisAngleJson(q);
    EXPECT_GE(j[3].get<double>(), 0.0);
    EXPECT_LE(j[3].get<double>(), 180.0 + 1e-9);
    const glm::dquat back = moult::rotationFromAxisAngle(vec(j), j[3].get<double>());
    EXPECT_NEAR(std::abs(glm::dot(back, q)), 1.0, 1e-12) << j.dump();
  }
}

TEST(Gizmo, RingTurnsAboutTheParentFrameAxisAndKeysReachTheScene) {
  Document d;
  d.reset(chainScene(), "");
  RigCache cache;
  const moult::SkinRig* rig = cache.get(d.scene(), 4);
  ASSERT_TRUE(rig) << cache.error();
  ASSERT_EQ(rig->skeleton.jointCount(), 3u);
  const double t = 1.0;
  const PosedJoints before = poseJoints(*rig, t);
  // The root turns 30 degrees about y, so the mid joint's rings are the root's turned axes.
  const glm::dvec3 ringAxis = before.parentFrame[1] * glm::dvec3(1, 0, 0);
  EXPECT_NEAR(ringAxis.z, -0.5, 1e-12);  // x turned 30 degrees about y
  const double degrees = 40;
  keyJointRotation(d, rig->skeleton, 1, t, turnLocal(before.local[1], 0, degrees));
  // The key numbered the joint (index 1 at t = 1): it is replaced, not duplicated.
  const Json& keys = d.scene().skeleton["keys"];
  ASSERT_EQ(keys.size(), 2u);
  EXPECT_EQ(keys[1]["joint"], 1);
  const moult::SkinRig* after = cache.get(d.scene(), 4);
  ASSERT_TRUE(after);
  const PosedJoints now = poseJoints(*after, t);
  // The mid joint stays put; the tip turned about the ring's world axis through the mid pivot.
  EXPECT_NEAR(glm::length(now.pivot[1] - before.pivot[1]), 0.0, 1e-12);
  const glm::dvec3 expected = before.pivot[1] + glm::mat3_cast(glm::angleAxis(glm::radians(degrees), ringAxis)) *
                                                    (before.pivot[2] - before.pivot[1]);
  EXPECT_NEAR(glm::length(now.pivot[2] - expected), 0.0, 1e-9);
  EXPECT_NEAR(glm::degrees(angleAbout(before.pivot[2] - before.pivot[1], now.pivot[2] - now.pivot[1], ringAxis)),
              degrees, 1e-9);
  // A key at a new time names the joint; undo removes it, the earlier edit stays.
  keyJointRotation(d, after->skeleton, 2, 0.5, glm::dquat(1, 0, 0, 0));
  ASSERT_EQ(d.scene().skeleton["keys"].size(), 3u);
  EXPECT_EQ(d.scene().skeleton["keys"][2]["joint"], "tip");
  ASSERT_TRUE(d.undo());
  EXPECT_EQ(d.scene().skeleton["keys"].size(), 2u);
  EXPECT_THROW(keyJointRotation(d, after->skeleton, 3, 0, glm::dquat(1, 0, 0, 0)), Error);
}

TEST(Gizmo, NoSkeletonNoRig) {
  Document d;
  d.reset(smallPatch(), "");
  RigCache cache;
  EXPECT_EQ(cache.get(d.scene(), 100), nullptr);
  EXPECT_TRUE(cache.error().empty());
  moult::Skeleton sk;
  sk.names = {"root"};
  sk.parent = {-1};
  sk.position = {glm::dvec3(0)};
  EXPECT_THROW(keyJointRotation(d, sk, 0, 0, glm::dquat(1, 0, 0, 0)), Error);
  // A broken section is reported, not thrown.
  d.edit("skeleton", [](pipeline::Scene& s) { s.skeleton = Json::parse(R"({"joints": 3})"); });
  EXPECT_EQ(cache.get(d.scene(), 100), nullptr);
  EXPECT_FALSE(cache.error().empty());
}
