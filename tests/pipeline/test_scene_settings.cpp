// SceneSettings (src/pipeline/scene_settings.hpp): the scene's module sections, typed. An edit gives
// exactly the edited section a new revision (the caches keyed by it are made again, no other); a read
// between edits returns what was parsed, without parsing again; a bad section is an Error with the file
// and key path at every read until an edit fixes it. And through the Pipeline: a packing edit packs the
// coat afresh, while an edit of another section keeps the remembered pack as a seed.
#include <gtest/gtest.h>

#include <functional>
#include <set>
#include <string>
#include <vector>

#include "../moult/wing_scene.hpp"
#include "frames.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "scene_settings.hpp"

using namespace pteryla;
using pipeline::InputKey;
using pipeline::Scene;
using pipeline::SceneSettings;
using pipeline::Section;

namespace {

const std::string kSceneFile = std::string(PTERYLA_DATA_DIR) + "/scenes/scene_settings_test_in_memory.json";

// The wing with every typed section: two tracts, a moult, a skeleton, a control, growth, directions,
// ordering and packing.
Scene wingScene() {
  Json j = moult_test::wingScene();  // two tracts, directions, height-field packing
  j.update(Json::parse(R"({
    "time": 5,
    "growth": {"ramps": [{"parameter": "shaft_length", "start": 0, "end": 0.6}]},
    "ordering": {"method": "tracts", "tracts": ["remiges", "coverts"]},
    "moult": {"start": 0, "duration": 10, "window": 0.25, "sequence": "centre_out", "gap": 0.1, "seed": 3},
    "skeleton": {"file": "../meshes/wing.skeleton.json", "keys": [
      {"joint": "elbow", "t": 0, "rotation": [0, 0, 1, 0]}, {"joint": "elbow", "t": 10, "rotation": [0, 0, 1, 30]}]},
    "controls": [{"name": "raise", "tracts": ["coverts"], "at": [0.9, 0.1, 0.0], "radius": 0.35,
                  "keys": [{"t": 0, "lift": 0}, {"t": 8, "lift": 1}]}],
    "render": {"lod": 0.2}
  })"));
  return pipeline::sceneFromJson(j, kSceneFile);
}

constexpr size_t kSections = size_t(Section::Packing) + 1;

std::vector<uint64_t> revisions(const SceneSettings& s) {
  std::vector<uint64_t> r;
  for (size_t i = 0; i < kSections; ++i) r.push_back(s.revision(Section(i)));
  return r;
}

std::set<Section> changed(const std::vector<uint64_t>& a, const std::vector<uint64_t>& b) {
  std::set<Section> out;
  for (size_t i = 0; i < kSections; ++i)
    if (a[i] != b[i]) out.insert(Section(i));
  return out;
}

template <class Fn>
std::string errorElement(Fn&& fn) {
  try {
    fn();
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), kSceneFile) << e.what();
    return e.element();
  }
  return "(no error)";
}

}  // namespace

TEST(SceneSettings, InputKeysAreEqualOnlyForTheSameRevisions) {
  EXPECT_EQ((InputKey{1, 2}), (InputKey{1, 2}));
  EXPECT_NE((InputKey{1, 2}), (InputKey{1, 3}));
  EXPECT_NE((InputKey{1, 2}), (InputKey{1, 2, 0}));  // a revision of 0 still counts
  EXPECT_NE(InputKey{}, (InputKey{0}));              // "not made" equals no made key
  EXPECT_TRUE(InputKey{}.empty());
  InputKey k{1};
  k.add(InputKey{2, 3}).add({4});
  EXPECT_EQ(k, (InputKey{1, 2, 3, 4}));
}

// Every edit of a scene changes the revisions of exactly the typed sections it touches; handing the same
// scene again changes none.
TEST(SceneSettings, AnEditChangesTheRevisionOfItsSectionOnly) {
  struct Edit {
    std::string what;
    std::function<void(Scene&)> apply;
    std::set<Section> sections;
  };
  const std::vector<Edit> edits = {
      {"tract count", [](Scene& s) { s.tracts[0]["count"] = 80; }, {Section::Tracts}},
      {"tract moult", [](Scene& s) { s.tracts[1]["moult"] = false; }, {Section::TractMoult}},
      {"tract added",
       [](Scene& s) {
         s.tracts.push_back({{"name", "more"}, {"groups", {"coverts"}}});
       },
       {Section::Tracts, Section::TractMoult}},
      {"growth", [](Scene& s) { s.growth["ramps"][0]["end"] = 0.5; }, {Section::Growth}},
      {"directions", [](Scene& s) { s.directions["axis"][1][2] = 0.1; }, {Section::Directions}},
      {"ordering",
       [](Scene& s) {
         s.ordering["tracts"] = {"coverts", "remiges"};
       },
       {Section::Ordering}},
      {"skeleton", [](Scene& s) { s.skeleton["keys"][1]["rotation"][3] = 10; }, {Section::Skeleton}},
      {"moult", [](Scene& s) { s.moult["window"] = 0.35; }, {Section::Moult}},
      {"controls", [](Scene& s) { s.controls[0]["radius"] = 0.5; }, {Section::Controls}},
      {"packing", [](Scene& s) { s.packing["clearance"] = 0.002; }, {Section::Packing}},
      // Sections no typed setting reads.
      {"seed", [](Scene& s) { s.seed = 6; }, {}},
      {"feathers", [](Scene& s) { s.feathers["other"] = s.feathers["contour"]; }, {}},
      {"camera", [](Scene& s) { s.camera.fovDeg = 20; }, {}},
      {"render", [](Scene& s) { s.render.lod = 0.5; }, {}},
  };
  const Scene base = wingScene();
  for (const Edit& e : edits) {
    SCOPED_TRACE(e.what);
    SceneSettings s;
    s.update(base);
    const std::vector<uint64_t> before = revisions(s);
    for (uint64_t r : before) EXPECT_GT(r, 0u);
    Scene after = base;
    e.apply(after);
    s.update(after);
    const std::vector<uint64_t> edited = revisions(s);
    EXPECT_EQ(changed(before, edited), e.sections);
    s.update(after);
    EXPECT_EQ(revisions(s), edited) << "the same scene again changes nothing";
    s.update(base);
    EXPECT_EQ(changed(edited, revisions(s)), e.sections) << "undoing the edit is an edit";
  }
}

// A read returns the settings parsed at the last change of the section: editing the JSON without
// update() shows nothing (nothing is parsed again), update() shows the edit.
TEST(SceneSettings, ReadsParseOncePerChange) {
  Scene scene = wingScene();
  SceneSettings s;
  s.update(scene);
  const double clearance = s.packing(scene).options.clearance;
  const double window = s.moult(scene)[0]->window;
  const double radius = s.controls(scene).controls[0].radius;
  const coat::SkinMesh rest = pipeline::Pipeline(scene).restSkin();
  const size_t vertices = rest.vertexCount();
  ASSERT_EQ(s.tracts(scene, rest, 1).size(), 2u);
  const size_t count = s.tracts(scene, rest, 1)[0].count;
  const moult::SkinRig* rig = s.skeleton(scene, vertices);
  ASSERT_NE(rig, nullptr);
  const moult::SkeletonAnimation animation = rig->animation;
  const coat::DirectionOptions* directions = s.directions(scene);
  ASSERT_NE(directions, nullptr);
  const glm::dvec3 axisEnd = directions->field.axis.at(1);
  ASSERT_NE(s.growth(scene), nullptr);
  const auto growth = s.growth(scene);

  scene.packing["clearance"] = clearance * 2 + 0.001;
  scene.moult["window"] = window + 0.1;
  scene.controls[0]["radius"] = radius + 0.1;
  scene.directions["axis"][1][2] = axisEnd.z + 1;
  scene.growth["ramps"][0]["end"] = 0.5;
  scene.skeleton["keys"][1]["rotation"][3] = 10;
  scene.tracts[0]["count"] = count + 10;
  EXPECT_EQ(s.tracts(scene, rest, 1)[0].count, count);
  EXPECT_EQ(s.skeleton(scene, vertices), rig);
  EXPECT_EQ(rig->animation.times, animation.times);
  EXPECT_EQ(rig->animation.rotations, animation.rotations);
  EXPECT_EQ(s.packing(scene).options.clearance, clearance);
  EXPECT_EQ(s.moult(scene)[0]->window, window);
  EXPECT_EQ(s.controls(scene).controls[0].radius, radius);
  EXPECT_EQ(s.directions(scene)->field.axis.at(1), axisEnd);
  EXPECT_EQ(s.growth(scene), growth) << "the same schedule object, not a new parse";

  s.update(scene);
  EXPECT_EQ(s.packing(scene).options.clearance, clearance * 2 + 0.001);
  EXPECT_EQ(s.moult(scene)[0]->window, window + 0.1);
  EXPECT_EQ(s.controls(scene).controls[0].radius, radius + 0.1);
  EXPECT_EQ(s.directions(scene)->field.axis.at(1).z, axisEnd.z + 1);
  EXPECT_NE(s.growth(scene), growth);
  EXPECT_NE(s.skeleton(scene, vertices)->animation.rotations, animation.rotations);
  EXPECT_EQ(s.tracts(scene, rest, 1)[0].count, count + 10);
}

// Per tract moult options: the scene's, overridden by the tract's; false turns a tract's moult off.
TEST(SceneSettings, TractMoultOverridesTheScenesMoult) {
  Scene scene = wingScene();
  scene.tracts[0]["moult"] = {{"window", 0.5}};
  scene.tracts[1]["moult"] = false;
  SceneSettings s;
  s.update(scene);
  const auto& m = s.moult(scene);
  ASSERT_EQ(m.size(), 2u);
  ASSERT_TRUE(m[0].has_value());
  EXPECT_EQ(m[0]->window, 0.5);
  EXPECT_EQ(m[0]->duration, 10.0);  // from the scene's moult
  EXPECT_FALSE(m[1].has_value());
  EXPECT_TRUE(s.readsTime());
  Scene still = wingScene();
  still.moult = Json::object();
  still.skeleton = Json::object();
  still.controls = Json::array();
  s.update(still);
  EXPECT_FALSE(s.readsTime());
  EXPECT_FALSE(s.moult(still)[0].has_value());
}

// A bad section is an Error naming the scene file and the key at every read (nothing is kept from the
// failed parse) until an edit fixes it. The controls name tracts, so renaming a tract can fix them.
TEST(SceneSettings, BadSectionIsAnErrorAtEveryReadUntilAnEditFixesIt) {
  Scene scene = wingScene();
  scene.packing["clerance"] = 0.01;
  scene.tracts[1]["moult"] = {{"sequence", "sideways"}};
  scene.controls[0]["tracts"] = {"tail"};
  SceneSettings s;
  s.update(scene);
  for (int read = 0; read < 2; ++read) {
    EXPECT_EQ(errorElement([&] { s.packing(scene); }), "packing.clerance");
    EXPECT_EQ(errorElement([&] { s.moult(scene); }), "tracts[1].moult.sequence");
    EXPECT_EQ(errorElement([&] { s.controls(scene); }), "controls[0].tracts[0]");
  }
  scene.packing.erase("clerance");
  scene.tracts[1]["moult"] = {{"sequence", "increasing_u"}};
  scene.tracts[1]["name"] = "tail";
  s.update(scene);
  EXPECT_NO_THROW(s.packing(scene));
  EXPECT_NO_THROW(s.moult(scene));
  ASSERT_EQ(s.controls(scene).tracts.size(), 1u);
  EXPECT_EQ(s.controls(scene).tracts[0], std::vector<uint32_t>{1});
}

// Through the pipeline: the frame's remembered pack is keyed by the rest state and the packing section.
// A moult edit keeps it (the frame repacks incrementally from it); a packing edit does not (a full pack);
// both give the frame of a fresh pipeline bit for bit.
TEST(SceneSettings, PackingEditPacksAfreshOtherEditsKeepThePack) {
  Scene base = wingScene();
  base.controls = Json::array();  // no natural pack: the frame's pack seeds from the last frame's only
  base.skeleton = Json::object();
  pipeline::Pipeline p(base);
  p.coatMesh();

  Scene moultEdit = base;
  moultEdit.moult["window"] = 0.3;
  p.editScene(pipeline::Stage::Ages, [&](Scene& s) { s = moultEdit; });
  const pipeline_test::Frame a = pipeline_test::grab(p);
  EXPECT_TRUE(p.frameReuse().packIncremental) << "a moult edit dropped the remembered pack";
  pipeline::Pipeline freshA(moultEdit);
  pipeline_test::expectIdentical(a, pipeline_test::grab(freshA), base.time);

  Scene packingEdit = moultEdit;
  packingEdit.packing["clearance"] = 0.002;
  p.editScene(pipeline::Stage::Controls, [&](Scene& s) { s = packingEdit; });
  const pipeline_test::Frame b = pipeline_test::grab(p);
  EXPECT_FALSE(p.frameReuse().packIncremental) << "a packing edit kept a pack made with other options";
  pipeline::Pipeline freshB(packingEdit);
  pipeline_test::expectIdentical(b, pipeline_test::grab(freshB), base.time);
}
