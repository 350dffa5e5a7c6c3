// The section-to-stage table (pipeline/scene_stages.hpp) against what the stages really read. For every
// row, an edit of that section of a scene that reads the time (moult, skeleton, controls, growth):
//  - earliestChangedStage names the row's stage;
//  - re-running from it re-runs exactly that stage and every later one, once, and gives the frame a
//    fresh pipeline gives for the edited scene, bit for bit (the stage is late enough);
//  - re-running from the next stage instead leaves a stale frame (the stage is not too early).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include "frames.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/pipeline/scene_stages.hpp"

using namespace pteryla;
using pipeline::Pipeline;
using pipeline::Scene;
using pipeline::Stage;
using pipeline_test::Frame;
using pipeline_test::grab;

namespace {

const std::string kSceneFile = std::string(PTERYLA_DATA_DIR) + "/scenes/scene_stages_test_in_memory.json";

// The wing at t = 5 with every time-dependent section: mid-moult (growing feathers), posed by its
// skeleton, a control raising coverts.
Scene baseScene() {
  return pipeline::sceneFromJson(Json::parse(R"({
    "pteryla": 1,
    "seed": 5,
    "time": 5,
    "mesh": "../meshes/wing.obj",
    "feathers": {"contour": "../feathers/contour.json"},
    "tracts": [
      {"name": "coverts", "groups": ["coverts"], "count": 90, "feather_scale": "auto",
       "feather_spacings": 1.5, "relax": {"iterations": 5}},
      {"name": "remiges", "groups": ["remiges_base"], "count": 40, "feather_scale": "auto",
       "feather_spacings": 1.5, "relax": {"iterations": 5}}
    ],
    "directions": {"axis": [[0, 0, -0.2], [2, 0, 0.4]]},
    "packing": {"method": "height_field"},
    "moult": {"start": 0, "duration": 10, "window": 0.25, "sequence": "centre_out", "gap": 0.1, "seed": 3},
    "skeleton": {"file": "../meshes/wing.skeleton.json", "keys": [
      {"joint": "elbow", "t": 0, "rotation": [0, 0, 1, 0]}, {"joint": "elbow", "t": 10, "rotation": [0, 0, 1, 30]}]},
    "controls": [{"name": "raise", "at": [0.9, 0.1, 0.0], "radius": 0.35, "keys": [{"t": 0, "lift": 0}, {"t": 8, "lift": 1}]}],
    "render": {"lod": 0.2}
  })"),
                                 kSceneFile);
}

// The wing's mesh scaled by 2%: same vertices, faces and groups (the skeleton's weights still fit).
std::string scaledWing() {
  const std::string path = testing::TempDir() + "/scene_stages_wing_scaled.obj";
  std::ifstream in(std::string(PTERYLA_DATA_DIR) + "/meshes/wing.obj");
  std::ofstream out(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) {
      std::istringstream s(line.substr(2));
      double x, y, z;
      s >> x >> y >> z;
      out << "v " << x * 1.02 << ' ' << y * 1.02 << ' ' << z * 1.02 << '\n';
    } else {
      out << line << '\n';
    }
  }
  return path;
}

struct Edit {
  std::string key, subKey;
  std::function<void(Scene&)> apply;
  bool staleObservable = true;  // the edit changes the coat, so a stale frame shows
};

std::vector<Edit> edits() {
  return {
      {"name", "", [](Scene& s) { s.name = "renamed"; }},
      {"time", "", [](Scene& s) { s.time = 2; }},
      {"mesh", "", [](Scene& s) { s.meshPath = scaledWing(); }},
      // The wing needs no repair: the stale frame (no re-load) is the same coat.
      {"mesh_repair", "", [](Scene& s) { s.meshRepair = true; }, false},
      {"feathers", "",
       [](Scene& s) { s.feathers["contour"] = std::string(PTERYLA_DATA_DIR) + "/feathers/covert.json"; }},
      {"tracts", "", [](Scene& s) { s.tracts[0]["count"] = 80; }},
      {"tracts", "moult", [](Scene& s) { s.tracts[1]["moult"] = false; }},
      {"growth", "",
       [](Scene& s) {
         s.growth = Json::parse(R"({"ramps": [{"parameter": "shaft_length", "start": 0, "end": 0.6}]})");
       }},
      {"seed", "", [](Scene& s) { s.seed = 6; }},
      {"density_map", "",
       [](Scene& s) {
         // Painted: half the wing's vertices at three times the density (the mesh has 1,000-odd vertices).
         auto f = std::make_shared<std::vector<float>>(Pipeline(s).restSkin().positions.size(), 1.0f);
         for (size_t v = 0; v < f->size(); v += 2) (*f)[v] = 3.0f;
         s.densityFactor = f;
       }},
      {"directions", "", [](Scene& s) { s.directions["axis"] = Json::parse("[[0, 0, -0.2], [2, 0, 0.1]]"); }},
      {"ordering", "",
       [](Scene& s) {
         s.ordering = {{"method", "tracts"}, {"tracts", {"remiges", "coverts"}}};
       }},
      {"skeleton", "", [](Scene& s) { s.skeleton["keys"][1]["rotation"] = Json::parse("[0, 0, 1, 10]"); }},
      {"moult", "", [](Scene& s) { s.moult["window"] = 0.35; }},
      {"controls", "", [](Scene& s) { s.controls[0]["radius"] = 0.5; }},
      {"packing", "", [](Scene& s) { s.packing["clearance"] = 0.002; }},
      {"camera", "", [](Scene& s) { s.camera.fovDeg = 20; }},
      {"lights", "", [](Scene& s) { s.lights.pop_back(); }},
      {"render", "", [](Scene& s) { s.render.lod = 0.5; }},
      {"render", "instance_tolerance", [](Scene& s) { s.render.instanceTolerance = 0.05; }},
  };
}

std::optional<Stage> tableStage(const std::string& key, const std::string& subKey) {
  for (const auto& row : pipeline::sectionStages())
    if (row.key == key && row.subKey == subKey) return row.stage;
  ADD_FAILURE() << "no row for " << key << "." << subKey;
  return std::nullopt;
}

std::vector<uint64_t> evaluations(const Pipeline& p) {
  std::vector<uint64_t> e;
  for (size_t s = 0; s < pipeline::kStageCount; ++s) e.push_back(p.evaluations(Stage(s)));
  return e;
}

}  // namespace

// Every row of the table has an edit below ("pteryla" has one valid value only).
TEST(SceneStages, EveryRowIsTested) {
  const std::vector<Edit> list = edits();
  for (const auto& row : pipeline::sectionStages()) {
    if (std::string(row.key) == "pteryla") continue;
    bool found = false;
    for (const Edit& e : list) found = found || (e.key == row.key && e.subKey == row.subKey);
    EXPECT_TRUE(found) << row.key << "." << row.subKey;
  }
}

class SceneStagesEdit : public testing::TestWithParam<size_t> {};

TEST_P(SceneStagesEdit, RerunsExactlyFromTheTableStage) {
  const Edit edit = edits()[GetParam()];
  SCOPED_TRACE(edit.key + (edit.subKey.empty() ? "" : "." + edit.subKey));
  const Scene before = baseScene();
  Scene after = before;
  edit.apply(after);
  const std::optional<Stage> stage = tableStage(edit.key, edit.subKey);
  ASSERT_EQ(pipeline::earliestChangedStage(before, after), stage);

  Pipeline p(before);
  const Frame old = grab(p);
  const std::vector<uint64_t> e0 = evaluations(p);
  if (!stage) {
    // Read by no stage: nothing is dirtied, nothing changes.
    for (size_t s = 0; s < pipeline::kStageCount; ++s) EXPECT_FALSE(p.dirty(Stage(s))) << s;
    return;
  }
  p.editScene(*stage, [&](Scene& s) { s = after; });
  const Frame edited = grab(p);
  const std::vector<uint64_t> e1 = evaluations(p);
  for (size_t s = 0; s < pipeline::kStageCount; ++s)
    EXPECT_EQ(e1[s], e0[s] + (s >= size_t(*stage) ? 1 : 0)) << pipeline::stageName(Stage(s));

  Pipeline fresh(after);
  const Frame expected = grab(fresh);
  pipeline_test::expectIdentical(edited, expected, after.time);
  if (!edit.staleObservable) return;
  EXPECT_FALSE(pipeline_test::sameMesh(old.mesh, expected.mesh)) << "the edit changes nothing";

  if (*stage != Stage::Mesh) {
    Pipeline late(before);
    late.coatMesh();
    late.editScene(Stage(int(*stage) + 1), [&](Scene& s) { s = after; });
    const Frame stale = grab(late);
    EXPECT_FALSE(pipeline_test::sameMesh(stale.mesh, expected.mesh)) << "a later stage would do";
  }
}

INSTANTIATE_TEST_SUITE_P(Sections, SceneStagesEdit, testing::Range<size_t>(0, edits().size()),
                         [](const testing::TestParamInfo<size_t>& info) {
                           const Edit e = edits()[info.param];
                           return e.key + (e.subKey.empty() ? "" : "_" + e.subKey);
                         });

// A scene without tracts (one default tract, "all") edited the way the viewer edits: its own copy of the
// scene, still without tracts, handed back, re-running from a time stage. The moult and a control naming
// tract "all" must still apply, as in a fresh pipeline. (Before the default tract was filled in where a
// scene enters the pipeline, only the tracts stage added it, so this edit lost the moult and the control
// failed with an unknown tract.)
TEST(SceneStages, SceneWithoutTractsKeepsItsDefaultTractThroughEdits) {
  Scene before = baseScene();
  before.tracts = Json::array();
  before.controls = Json::parse(
      R"([{"name": "raise", "tracts": ["all"], "at": [0.9, 0.1, 0.0], "radius": 0.35, "keys": [{"t": 0, "lift": 0}, {"t": 8, "lift": 1}]}])");
  Pipeline p(before);
  const Frame first = grab(p);
  size_t growing = 0;
  for (double a : first.age) growing += a < 1 ? 1 : 0;
  ASSERT_GT(growing, 0u) << "the moult should be under way at t = 5";

  Scene after = before;  // the viewer's copy: still no tracts
  after.moult["window"] = 0.3;
  p.editScene(Stage::Ages, [&](Scene& s) { s = after; });
  const Frame edited = grab(p);
  Pipeline fresh(after);
  pipeline_test::expectIdentical(edited, grab(fresh), after.time);
  size_t growingAfter = 0;
  for (double a : edited.age) growingAfter += a < 1 ? 1 : 0;
  EXPECT_GT(growingAfter, 0u) << "the moult was lost with the default tract";
}
