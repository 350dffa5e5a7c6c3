// Document: undo/redo, gestures, save policy (never overwrite without asking), background evaluation
// with cancellation, errors from stages, and bare meshes saving to scenes that reload to the same coat.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <glm/geometric.hpp>

#include "actions.hpp"
#include "document.hpp"
#include "fixtures.hpp"
#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "scene_edit.hpp"

using namespace pteryla;
using namespace pteryla::viewer;
using viewer_test::scratchDir;
using viewer_test::smallPatch;

namespace {

Json js(const pipeline::Scene& s) { return sceneJson(s); }

std::vector<glm::vec3> coatPositions(Document& d) {
  EXPECT_TRUE(d.waitIdle());
  return d.idlePipeline()->coatMesh().mesh.positions;
}

}  // namespace

TEST(Document, UndoRedoRestoresExactScenes) {
  Document d;
  d.reset(smallPatch(), "");
  const Json original = js(d.scene());
  actions::setTractCount(d, 0, 30);
  actions::setRelaxIterations(d, 0, 7);
  actions::addStylingVector(d, {0, 0, 0.5}, {0, 0, 1});
  const Json edited = js(d.scene());
  EXPECT_TRUE(d.modified());
  EXPECT_EQ(d.scene().tracts[0]["count"], 30);
  ASSERT_TRUE(d.undo());
  ASSERT_TRUE(d.undo());
  ASSERT_TRUE(d.undo());
  EXPECT_FALSE(d.canUndo());
  EXPECT_EQ(js(d.scene()), original);
  ASSERT_TRUE(d.redo());
  ASSERT_TRUE(d.redo());
  ASSERT_TRUE(d.redo());
  EXPECT_FALSE(d.canRedo());
  EXPECT_EQ(js(d.scene()), edited);
  // A new edit after an undo drops the redo branch.
  d.undo();
  actions::setTractCount(d, 0, 40);
  EXPECT_FALSE(d.canRedo());
}

TEST(Document, EditsInOneGestureShareOneUndoStep) {
  Document d;
  d.reset(smallPatch(), "");
  const Json original = js(d.scene());
  // A slider drag: many edits with the same label before the mouse is released.
  for (int i = 1; i <= 5; ++i) actions::setBrdf(d, 1.0 + 0.1 * i, 0.0);
  d.endGesture();
  actions::setBrdf(d, 3.0, 0.2);  // a new gesture
  ASSERT_TRUE(d.undo());
  EXPECT_DOUBLE_EQ(d.scene().render.brdfD, 1.5);
  ASSERT_TRUE(d.undo());
  EXPECT_EQ(js(d.scene()), original);
  EXPECT_FALSE(d.canUndo());
}

TEST(Document, ThrowingEditChangesNothing) {
  Document d;
  d.reset(smallPatch(), "");
  const Json before = js(d.scene());
  EXPECT_THROW(actions::setControlValue(d, 3, "lift", 0.5, 0.0), Error);  // no control 3
  EXPECT_THROW(actions::addKeyFeather(d, 0, "no_such_feather", 1), Error);
  EXPECT_EQ(js(d.scene()), before);
  EXPECT_FALSE(d.canUndo());
  EXPECT_FALSE(d.modified());
}

TEST(Document, SaveAsNeverOverwritesWithoutBeingAsked) {
  const std::string dir = scratchDir("save_policy");
  const std::string path = dir + "/taken.json";
  { std::ofstream(path) << "{\"precious\": true}\n"; }
  Document d;
  d.reset(smallPatch(), "");
  actions::setTractCount(d, 0, 31);
  EXPECT_FALSE(d.saveAs(path, false));
  EXPECT_EQ(readJsonFile(path), Json({{"precious", true}}));
  EXPECT_TRUE(d.modified());
  EXPECT_TRUE(d.saveAs(path, true));
  EXPECT_FALSE(d.modified());
  EXPECT_EQ(d.path(), std::filesystem::absolute(path).lexically_normal().string());
  // Saving again to the document's own file is a plain Save.
  actions::setTractCount(d, 0, 32);
  EXPECT_TRUE(d.saveAs(path, false));
  d.save();
  EXPECT_THROW(d.saveAs(dir + "/scene.txt", true), Error);
  EXPECT_THROW(d.saveAs(dir + "/missing_dir/scene.json", true), Error);
}

TEST(Document, SavedSceneReloadsIdentically) {
  const std::string dir = scratchDir("round_trip");
  Document d;
  d.reset(smallPatch(), "");
  actions::addControl(d, {0, 0.05, 0}, 0.5);
  actions::setControlValue(d, 0, "lift", 0.6, 0.0);
  actions::addControlKeyframe(d, 0, 1.0);
  actions::addBrush(d, {0.3, 0.05, 0}, 0.2, 40);
  d.setTime(0.5);
  const std::string path = dir + "/out.json";
  ASSERT_TRUE(d.saveAs(path));
  const pipeline::Scene back = pipeline::loadScene(path);
  EXPECT_EQ(pipeline::sceneToJson(back, path), readJsonFile(path));
  EXPECT_EQ(js(back), js(d.scene()));
  EXPECT_DOUBLE_EQ(back.time, 0.5);
}

TEST(Document, BareMeshSavesToASceneWithTheSameCoat) {
  // The implicit bare-mesh defaults are written explicitly, so the saved file evaluates to the coat
  // the viewer showed (and that a bare-mesh evaluation gives).
  const std::string dir = scratchDir("bare_mesh");
  pipeline::Scene bare = pipeline::loadScene(viewer_test::dataPath("meshes/sphere_250.obj"));
  ASSERT_TRUE(bare.fromBareMesh);
  bare.tracts[0]["count"] = 40;
  bare.tracts[0]["relax"] = {{"iterations", 2}};
  bare.render.lod = 0.1;
  pipeline::Pipeline reference(bare);
  const std::vector<glm::vec3> expected = reference.coatMesh().mesh.positions;
  ASSERT_FALSE(expected.empty());

  Document d;
  pipeline::Scene explicitScene = bare;
  makeBareMeshExplicit(explicitScene);
  EXPECT_FALSE(explicitScene.fromBareMesh);
  d.reset(explicitScene, "");
  EXPECT_EQ(coatPositions(d), expected);
  const std::string path = dir + "/sphere.json";
  ASSERT_TRUE(d.saveAs(path));
  Document reloaded;
  reloaded.open(path);
  EXPECT_EQ(coatPositions(reloaded), expected);
}

TEST(Document, OpenBareMeshAsksForAFileOnSave) {
  Document d;
  d.open(viewer_test::dataPath("meshes/sphere_250.obj"));
  EXPECT_TRUE(d.path().empty());
  EXPECT_FALSE(d.scene().fromBareMesh);
  EXPECT_TRUE(d.scene().directions.contains("axis"));
  EXPECT_THROW(d.save(), Error);
}

TEST(Document, EvaluatesInTheBackgroundAndEditsCancel) {
  Document d;
  d.reset(smallPatch(), "");
  d.update();
  EXPECT_TRUE(d.busy());
  // Edits while the worker runs: the running job is cancelled and the final result is that of the
  // final scene, equal to a fresh evaluation of it.
  actions::setTractCount(d, 0, 26);
  actions::setRelaxIterations(d, 0, 2);
  ASSERT_TRUE(d.waitIdle());
  EXPECT_TRUE(d.upToDate());
  const auto got = d.idlePipeline()->coatMesh().mesh.positions;
  pipeline::Pipeline fresh(d.scene());
  fresh.setLod(d.lod());
  EXPECT_EQ(got, fresh.coatMesh().mesh.positions);
  const Snapshot& s = d.snapshot();
  EXPECT_EQ(s.follicle.size(), 26u + 0u);
  EXPECT_EQ(s.coatFeathers, fresh.coatMesh().ranges.size());
  EXPECT_FALSE(s.skin.empty());
  EXPECT_EQ(s.tractNames, std::vector<std::string>{"patch"});
}

TEST(Document, OnlyDownstreamStagesRerun) {
  Document d;
  d.reset(smallPatch(), "");
  ASSERT_TRUE(d.waitIdle());
  auto evals = [&](pipeline::Stage s) { return d.idlePipeline()->evaluations(s); };
  const auto distribute = evals(pipeline::Stage::Distribute), mesh = evals(pipeline::Stage::Mesh);
  d.setLod(0.3);
  ASSERT_TRUE(d.waitIdle());
  EXPECT_EQ(evals(pipeline::Stage::Distribute), distribute);
  EXPECT_EQ(evals(pipeline::Stage::Mesh), mesh + 1);
  // Instancing re-meshes only; an out-of-range value is refused and changes nothing.
  actions::setInstanceTolerance(d, 0.01);
  ASSERT_TRUE(d.waitIdle());
  EXPECT_EQ(d.scene().render.instanceTolerance, 0.01);
  EXPECT_EQ(evals(pipeline::Stage::Distribute), distribute);
  EXPECT_EQ(evals(pipeline::Stage::Mesh), mesh + 2);
  EXPECT_THROW(actions::setInstanceTolerance(d, 0.5), Error);
  EXPECT_EQ(d.scene().render.instanceTolerance, 0.01);
  actions::setInstanceTolerance(d, 0.0);
  ASSERT_TRUE(d.waitIdle());
  EXPECT_EQ(evals(pipeline::Stage::Mesh), mesh + 3);
  // View-only edits re-run nothing.
  actions::setBrdf(d, 2.0, 0.1);
  d.update();
  EXPECT_FALSE(d.busy());
  EXPECT_EQ(evals(pipeline::Stage::Mesh), mesh + 3);
  // patch.json reads no time (no skeleton, moult or controls): a new time re-runs nothing ...
  const auto pose = evals(pipeline::Stage::Pose);
  d.setTime(0.25);
  ASSERT_TRUE(d.waitIdle());
  EXPECT_EQ(evals(pipeline::Stage::Pose), pose);
  // ... and with a moult it re-runs the time stages, never the follicles.
  d.edit("moult", [](pipeline::Scene& s) { s.moult = Json::parse(R"({"start": 0, "duration": 2})"); });
  ASSERT_TRUE(d.waitIdle());
  const auto poseMoult = evals(pipeline::Stage::Pose);
  d.setTime(0.5);
  ASSERT_TRUE(d.waitIdle());
  EXPECT_EQ(evals(pipeline::Stage::Distribute), distribute);
  EXPECT_EQ(evals(pipeline::Stage::Pose), poseMoult + 1);
}

// The preview meshes by screen size (render.lod_by_screen_size, on by default) once the viewer gives it
// its view: every feather at the preview lod until then, far fewer triangles seen from afar (the mesh
// stage alone re-runs), nothing re-run for the same view, and the preview lod everywhere again with the
// key off.
TEST(Document, PreviewLevelsFollowTheViewByScreenSize) {
  Document d;
  pipeline::Scene s = smallPatch();
  s.render.lod = 1.0;
  d.reset(s, "");
  ASSERT_TRUE(d.waitIdle());
  auto evals = [&](pipeline::Stage st) { return d.idlePipeline()->evaluations(st); };
  auto triangles = [&] { return d.snapshot().coatTriangles; };
  const size_t uniform = triangles();
  EXPECT_TRUE(d.idlePipeline()->featherLods().empty());
  const auto distribute = evals(pipeline::Stage::Pack), mesh = evals(pipeline::Stage::Mesh);
  const glm::vec3 lo = d.snapshot().skinLo, hi = d.snapshot().skinHi;
  render::Camera cam;
  cam.eye = glm::vec3(0, 0, 1);
  cam.frameBounds(lo, hi, 4.0f / 3.0f, 1.0f);
  d.setPreviewView(cam, 320, 240);
  EXPECT_FALSE(d.upToDate());
  ASSERT_TRUE(d.waitIdle());
  const size_t nearTri = triangles();
  EXPECT_EQ(evals(pipeline::Stage::Mesh), mesh + 1);
  EXPECT_EQ(evals(pipeline::Stage::Pack), distribute);
  EXPECT_EQ(d.idlePipeline()->featherLods().size(), d.idlePipeline()->feathers().size());
  render::Camera far = cam;
  far.eye = cam.target + 20.0f * (cam.eye - cam.target);
  d.setPreviewView(far, 320, 240);
  ASSERT_TRUE(d.waitIdle());
  const size_t farTri = triangles();
  EXPECT_LE(nearTri, uniform);
  EXPECT_LT(farTri, nearTri / 2) << "near " << nearTri << ", far " << farTri;
  d.setPreviewView(far, 320, 240);
  ASSERT_TRUE(d.waitIdle());
  EXPECT_EQ(evals(pipeline::Stage::Mesh), mesh + 2);
  d.edit("levels by screen size", [](pipeline::Scene& sc) { sc.render.lodByScreenSize = false; });
  ASSERT_TRUE(d.waitIdle());
  EXPECT_EQ(triangles(), uniform);
  EXPECT_TRUE(d.idlePipeline()->featherLods().empty());
}

TEST(Document, StageErrorsAreReportedAndUndoRecovers) {
  Document d;
  d.reset(smallPatch(), "");
  ASSERT_TRUE(d.waitIdle());
  // A value only the tracts stage rejects (the scene reader keeps tract objects as JSON).
  d.edit("bad", [](pipeline::Scene& s) { s.tracts[0]["relax"]["over_relaxation"] = 7.0; });
  EXPECT_FALSE(d.waitIdle());
  EXPECT_TRUE(d.failed());
  const auto e = d.takeError();
  ASSERT_TRUE(e.has_value());
  EXPECT_NE(e->find("over_relaxation"), std::string::npos) << *e;
  EXPECT_FALSE(d.takeError().has_value());
  ASSERT_TRUE(d.undo());
  EXPECT_TRUE(d.waitIdle());
  EXPECT_FALSE(d.failed());
}

TEST(Document, CancelHoldsEvaluationUntilResumed) {
  Document d;
  d.reset(smallPatch(), "");
  d.update();
  d.cancel();
  EXPECT_FALSE(d.waitIdle());
  EXPECT_TRUE(d.halted());
  EXPECT_FALSE(d.upToDate());
  d.resume();
  EXPECT_TRUE(d.waitIdle());
}

TEST(Document, CheckRunsTheCheckerAndKeepsTheViewLod) {
  Document d;
  d.reset(smallPatch(), "");
  d.requestCheck();
  ASSERT_TRUE(d.waitIdle());
  ASSERT_TRUE(d.metrics().has_value());
  EXPECT_EQ(d.metrics()->follicles.value_or(0), 24u);
  // View > Problems marks the offending feathers: Pipeline::check's, indices into the snapshot's feathers.
  const pipeline::QualityMetrics ref = pipeline::Pipeline(smallPatch()).check();
  ASSERT_GT(ref.intersectingPairs.value_or(0), 0u);  // the small patch's coat crosses
  EXPECT_EQ(d.metrics()->intersectingFeathers, ref.intersectingFeathers);
  EXPECT_FALSE(d.metrics()->intersectingFeathers.empty());
  for (uint32_t i : d.metrics()->intersectingFeathers) EXPECT_LT(i, d.snapshot().featherOrigin.size());
  EXPECT_FALSE(d.idlePipeline()->dirty(pipeline::Stage::Mesh));
  EXPECT_DOUBLE_EQ(d.idlePipeline()->lod(), d.lod());
}

TEST(Actions, ControlsFollowTheMoultModuleSchema) {
  Document d;
  d.reset(smallPatch(), "");
  const size_t c = actions::addControl(d, {0, 0.05, 0}, 0.5);
  actions::setControlValue(d, c, "lift", 0.8, 0.0);
  EXPECT_DOUBLE_EQ(actions::controlAt(d.scene(), c, 3.0).value[0], 0.8);
  EXPECT_FALSE(actions::controlAt(d.scene(), c, 3.0).keyed[0]);
  // Keying turns constants into keys; later slider edits at another time add keys there.
  actions::addControlKeyframe(d, c, 0.0);
  EXPECT_FALSE(d.scene().controls[c].contains("lift"));
  actions::setControlValue(d, c, "lift", 0.2, 2.0);
  const auto mid = actions::controlAt(d.scene(), c, 1.0);
  EXPECT_TRUE(mid.keyed[0]);
  EXPECT_NEAR(mid.value[0], 0.5, 1e-12);  // linear between (0, 0.8) and (2, 0.2)
  EXPECT_THROW(actions::setControlValue(d, c, "dynamic_blend", 0.5, 0.0), Error);
  EXPECT_THROW(actions::setControlValue(d, c, "aim", 1.5, 0.0), Error);
  ASSERT_TRUE(d.waitIdle()) << d.takeError().value_or("");  // the pipeline accepts what the panel wrote
}

TEST(Actions, DesignedFeatherIsWrittenInlineAndChangesTheCoat) {
  const std::string dir = scratchDir("designer");
  Document d;
  d.reset(smallPatch(), "");
  const auto before = coatPositions(d);
  feather::FeatherParams p = feather::loadFeather(viewer_test::dataPath("feathers/contour.json"));
  p.rachisLength *= 0.5;
  p.rachisLateralCurvature = 0.3;
  actions::setFeatherInline(d, "contour", p);
  ASSERT_TRUE(d.scene().feathers["contour"].is_object());
  const auto after = coatPositions(d);
  EXPECT_NE(after, before);
  // Saved inline, reloaded, evaluated: the same coat.
  ASSERT_TRUE(d.saveAs(dir + "/designed.json"));
  Document back;
  back.open(dir + "/designed.json");
  back.setLod(d.lod());
  EXPECT_EQ(coatPositions(back), after);
  // An invalid design is refused before it reaches the scene.
  p.spacingBase = -1;
  EXPECT_THROW(actions::setFeatherInline(d, "contour", p), Error);
}

TEST(Document, FailedOpenKeepsTheCurrentScene) {
  const std::string dir = scratchDir("bad_open");
  { std::ofstream(dir + "/broken.json") << "{\"pteryla\": 1, \"mesh\": \"nope.obj\", \"tractz\": []}\n"; }
  Document d;
  d.reset(smallPatch(), "");
  actions::setTractCount(d, 0, 25);
  const Json before = js(d.scene());
  EXPECT_THROW(d.open(dir + "/missing.json"), Error);
  try {
    d.open(dir + "/broken.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.json"), std::string::npos) << e.what();
  }
  EXPECT_EQ(js(d.scene()), before);
  EXPECT_TRUE(d.modified());
  EXPECT_TRUE(d.canUndo());
}

// #28: adding a styling vector used to delete directions.axis, so one stroke re-combed the whole bird.
// Over an axis a vector now combs locally (coat/directions.hpp): the axis is kept, feathers near the
// stroke turn to it, and feathers a few radii away keep their direction.
TEST(Document, AStylingVectorCombsTheAxisInsteadOfReplacingIt) {
  Document d;
  d.reset(smallPatch(), "");
  actions::setBodyAxis(d, {{-1.5, 0, 0}, {1.5, 0, 0}});  // replaces patch.json's vectors-only field
  EXPECT_FALSE(d.scene().directions.contains("vectors"));
  ASSERT_TRUE(d.waitIdle());
  const std::vector<coat::FeatherFrame> before = d.idlePipeline()->feathers().frames;
  const Json axis = d.scene().directions["axis"];

  // The stroke starts at the follicle nearest the patch's centre.
  glm::dvec3 at = before.at(0).origin;
  for (const auto& f : before)
    if (glm::length(f.origin) < glm::length(at)) at = f.origin;
  actions::addStylingVector(d, at, {0, 0, 1});
  const Json& dirs = d.scene().directions;
  EXPECT_EQ(dirs["axis"], axis) << "the axis was dropped";
  ASSERT_EQ(dirs["vectors"].size(), 1u);
  EXPECT_DOUBLE_EQ(dirs["vectors"][0]["radius"].get<double>(), actions::combRadius(d.scene()));
  EXPECT_NEAR(actions::combRadius(d.scene()), 0.3, 1e-12);  // by default a tenth of the axis
  // A narrower stroke, as the panel's comb radius gives, in place of the default one.
  ASSERT_TRUE(d.undo());
  const double radius = 0.15;
  actions::addStylingVector(d, at, {0, 0, 1}, radius);
  EXPECT_EQ(d.scene().directions["vectors"][0]["radius"].get<double>(), radius);
  ASSERT_TRUE(d.waitIdle());
  const std::vector<coat::FeatherFrame> after = d.idlePipeline()->feathers().frames;
  ASSERT_EQ(after.size(), before.size());
  size_t near = 0, far = 0;
  for (size_t i = 0; i < after.size(); ++i) {
    const double dist = glm::length(after[i].origin - at);
    if (dist < 1e-9) {
      EXPECT_GT(after[i].tangent.z, 0.9) << "feather " << i << " at the stroke did not turn";
      ++near;
    } else if (dist > 5 * radius) {
      EXPECT_NEAR(glm::length(after[i].tangent - before[i].tangent), 0.0, 1e-4) << "feather " << i << " moved";
      ++far;
    }
  }
  EXPECT_EQ(near, 1u);
  EXPECT_GT(far, 0u);

  // A new axis keeps the comb strokes; undo gives back the uncombed axis.
  actions::setBodyAxis(d, {{-1.5, 0, 0.1}, {1.5, 0, 0.1}});
  EXPECT_EQ(d.scene().directions["vectors"].size(), 1u);
  ASSERT_TRUE(d.undo());
  ASSERT_TRUE(d.undo());
  EXPECT_FALSE(d.scene().directions.contains("vectors"));
  EXPECT_EQ(d.scene().directions["axis"], axis);
}

// #28: the lift brush gives the feathers under it a lower bound on their elevation (min_elevation_deg),
// the fixed brush an exact angle (elevation_deg); each saves to the scene's packing.styling.
TEST(Document, LiftAndFixedBrushesReachTheCoat) {
  Document d;
  d.reset(smallPatch(), "");
  ASSERT_TRUE(d.waitIdle());
  const double deg = 3.14159265358979323846 / 180.0;
  const glm::dvec3 at(0, 0.05, 0);
  const double radius = 0.6;
  auto under = [&](const pipeline::Pipeline& p, size_t i) {
    (void)p;
    return glm::length(d.idlePipeline()->feathers().frames[i].origin - at) < 0.5 * radius;
  };
  actions::addBrush(d, at, radius, 40.0, true);
  const Json& lift = d.scene().packing["styling"].back();
  EXPECT_EQ(lift["min_elevation_deg"], 40.0);
  EXPECT_FALSE(lift.contains("elevation_deg"));
  ASSERT_TRUE(d.waitIdle());
  size_t lifted = 0;
  {
    pipeline::Pipeline& p = *d.idlePipeline();
    const std::vector<double> e = p.elevations();
    for (size_t i = 0; i < e.size(); ++i)
      if (under(p, i) && p.feathers().present[i]) {
        EXPECT_GE(e[i], 40.0 * deg - 1e-9) << "feather " << i;
        ++lifted;
      }
  }
  EXPECT_GT(lifted, 0u);
  ASSERT_TRUE(d.undo());
  actions::addBrush(d, at, radius, 12.0, false);
  EXPECT_EQ(d.scene().packing["styling"].back()["elevation_deg"], 12.0);
  ASSERT_TRUE(d.waitIdle());
  pipeline::Pipeline& p = *d.idlePipeline();
  const std::vector<double> e = p.elevations();
  for (size_t i = 0; i < e.size(); ++i) {
    if (under(p, i) && p.feathers().present[i]) {
      EXPECT_NEAR(e[i], 12.0 * deg, 1e-9) << "feather " << i;
    }
  }
}
