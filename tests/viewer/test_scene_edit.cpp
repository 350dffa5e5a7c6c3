// Scene edits: which stage an edit re-runs (the pipeline's table, as the viewer uses it), JSON-pointer edits through
// the strict scene reader, tract references.
#include <gtest/gtest.h>

#include "fixtures.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/scene_stages.hpp"
#include "scene_edit.hpp"

using namespace pteryla;
using namespace pteryla::viewer;
using pipeline::Stage;

TEST(SceneEdit, EarliestChangedStage) {
  const pipeline::Scene a = viewer_test::smallPatch();
  auto changed = [&](const std::function<void(pipeline::Scene&)>& f) {
    pipeline::Scene b = a;
    f(b);
    return pipeline::earliestChangedStage(a, b);
  };
  EXPECT_FALSE(changed([](pipeline::Scene&) {}).has_value());
  EXPECT_FALSE(changed([](pipeline::Scene& s) { s.render.brdfD = 3; }).has_value());
  EXPECT_FALSE(changed([](pipeline::Scene& s) { s.lights.clear(); }).has_value());
  EXPECT_FALSE(changed([](pipeline::Scene& s) { s.camera.fovDeg = 20; }).has_value());
  EXPECT_EQ(changed([](pipeline::Scene& s) { s.feathers["x"] = s.feathers["contour"]; }), Stage::Skin);
  EXPECT_EQ(changed([](pipeline::Scene& s) { s.meshPath += "x"; }), Stage::Skin);
  EXPECT_EQ(changed([](pipeline::Scene& s) { s.tracts[0]["count"] = 5; }), Stage::Tracts);
  EXPECT_EQ(changed([](pipeline::Scene& s) { s.packing["clearance"] = 0.1; }), Stage::Controls);
  EXPECT_EQ(changed([](pipeline::Scene& s) { s.directions["falloff"] = 0.2; }), Stage::Directions);
  EXPECT_EQ(changed([](pipeline::Scene& s) { s.seed = 77; }), Stage::Distribute);
  EXPECT_EQ(changed([](pipeline::Scene& s) { s.skeleton["x"] = 1; }), Stage::Pose);
  EXPECT_EQ(changed([](pipeline::Scene& s) { s.moult["start"] = 1; }), Stage::Ages);
  EXPECT_EQ(changed([](pipeline::Scene& s) { s.controls.push_back(Json::object()); }), Stage::Controls);
  // The earliest stage wins when several sections change.
  EXPECT_EQ(changed([](pipeline::Scene& s) {
              s.controls.push_back(Json::object());
              s.seed = 3;
            }),
            Stage::Distribute);
}

TEST(SceneEdit, SetPointerGoesThroughTheStrictReader) {
  pipeline::Scene s = viewer_test::smallPatch();
  setScenePointer(s, "/tracts/0/relax/iterations", 9);
  EXPECT_EQ(s.tracts[0]["relax"]["iterations"], 9);
  setScenePointer(s, "/render/brdf/d", 2.5);
  EXPECT_DOUBLE_EQ(s.render.brdfD, 2.5);
  setScenePointer(s, "/directions/vectors/-", Json{{"at", {0, 0, 0}}, {"direction", {0, 0, 1}}});
  EXPECT_EQ(s.directions["vectors"].size(), 2u);
  const Json before = sceneJson(s);
  // Out-of-range value rejected by the scene reader, naming the key; the scene is unchanged.
  try {
    setScenePointer(s, "/render/brdf/h", 5.0);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("brdf.h"), std::string::npos) << e.what();
  }
  EXPECT_THROW(setScenePointer(s, "/render/no_such_key", 1), Error);  // unknown key
  EXPECT_THROW(setScenePointer(s, "/nosection/x", 1), Error);         // unknown section
  setScenePointer(s, "/moult/duration", 4);                           // omitted when empty: created
  EXPECT_EQ(s.moult["duration"], 4);
  setScenePointer(s, "/moult", Json::object());
  EXPECT_THROW(setScenePointer(s, "/tracts/7/count", 1), Error);  // index out of range
  EXPECT_THROW(setScenePointer(s, "no-slash", 1), Error);         // not a pointer
  EXPECT_THROW(setScenePointer(s, "", 1), Error);
  EXPECT_EQ(sceneJson(s), before);
}

TEST(SceneEdit, LooseValues) {
  EXPECT_EQ(parseLooseValue("3"), Json(3));
  EXPECT_EQ(parseLooseValue("[1, 2]"), Json::array({1, 2}));
  EXPECT_EQ(parseLooseValue("true"), Json(true));
  EXPECT_EQ(parseLooseValue("centre_out"), Json("centre_out"));
}

TEST(SceneEdit, ResolveTracts) {
  pipeline::Scene s = viewer_test::smallPatch();
  s.tracts.push_back({{"name", "second"}, {"all", true}});
  EXPECT_EQ(resolveTracts(s, "1", "x"), std::vector<size_t>{1});
  EXPECT_EQ(resolveTracts(s, "patch", "x"), std::vector<size_t>{0});
  EXPECT_EQ(resolveTracts(s, "*", "x"), (std::vector<size_t>{0, 1}));
  EXPECT_THROW(resolveTracts(s, "2", "x"), Error);
  EXPECT_THROW(resolveTracts(s, "nope", "x"), Error);
}

TEST(SceneEdit, BareMeshDefaultsBecomeExplicit) {
  pipeline::Scene s = pipeline::loadScene(viewer_test::dataPath("meshes/sphere_250.obj"));
  makeBareMeshExplicit(s, {-1, -2, -0.5}, {1, 2, 0.5});
  EXPECT_FALSE(s.fromBareMesh);
  // Longest axis is y: the body axis runs along it through the box centre.
  EXPECT_EQ(s.directions["axis"], Json::parse("[[0.0, -2.0, 0.0], [0.0, 2.0, 0.0]]"));
  EXPECT_EQ(s.ordering["method"], "axis");
  EXPECT_EQ(s.tracts[0]["feather_scale"], "auto");
  // Explicit scenes are left alone.
  const Json before = sceneJson(s);
  makeBareMeshExplicit(s, {0, 0, 0}, {5, 5, 5});
  EXPECT_EQ(sceneJson(s), before);
}

TEST(SceneEdit, TimeSpanFromKeysAndMoultWindows) {
  pipeline::Scene s = viewer_test::smallPatch();
  EXPECT_FALSE(sceneTimeSpan(s).has_value());
  s.moult = {{"start", 2.0}, {"duration", 3.0}};
  EXPECT_EQ(sceneTimeSpan(s), std::make_pair(2.0, 5.0));
  s.controls =
      Json::parse(R"([{"at": [0, 0, 0], "radius": 1, "keys": [{"t": -1, "lift": 0}, {"t": 7.5, "lift": 1}]}])");
  EXPECT_EQ(sceneTimeSpan(s), std::make_pair(-1.0, 7.5));
  s.tracts[0]["moult"] = {{"start", 9.0}};
  EXPECT_EQ(sceneTimeSpan(s), std::make_pair(-1.0, 10.0));
}
