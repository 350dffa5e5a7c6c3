// Frame-to-frame reuse in the pipeline (incremental repacking from the last frame's or the natural
// pack, barb curves and mesh slices kept for unchanged feathers) never changes a result: every frame of a
// scrub equals a fresh evaluation at that time, bit for bit (elevations, packed key barbs, every mesh
// attribute, draw ranges). The tests also check that the reuse paths really ran.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "frames.hpp"
#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/feather/lod.hpp"
#include "pteryla/feather/mesh.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

using namespace pteryla;
using pipeline::Pipeline;
using pipeline_test::expectIdentical;
using pipeline_test::Frame;
using pipeline_test::grab;
using pipeline_test::sameBytes;

namespace {

const std::string kSceneFile = std::string(PTERYLA_DATA_DIR) + "/scenes/incremental_test_in_memory.json";

// A gently curved open patch (normals +Y), feathers pointing +X. Explicit clearances keep every
// feather's packing independent of which other feathers are present.
Json patchScene() {
  return Json::parse(R"({
    "pteryla": 1,
    "seed": 9,
    "mesh": "../meshes/patch.obj",
    "feathers": {"contour": "../feathers/contour.json"},
    "tracts": [{"name": "patch", "groups": ["patch"], "count": 220, "feather_scale": "auto",
                "feather_spacings": 1.5, "relax": {"iterations": 10}}],
    "directions": {"vectors": [{"at": [0, 0, 0], "direction": [1, 0, 0]}]},
    "packing": {"method": "height_field", "clearance": 0.0004, "skin_sample_spacing": 0.01}
  })");
}

Frame fresh(const pipeline::Scene& scene, double t, double lod) {
  Pipeline p(scene);
  p.setLod(lod);
  p.setTime(t);
  return grab(p);
}

}  // namespace

// A moult without gaps: the mature coat's pack is the same in every frame and reused; only the growing
// feathers are packed over it, and most feathers' triangles are copied; growing feathers get new curves
// every frame. Forward, backward and repeated times all equal fresh evaluations.
TEST(IncrementalFrames, MoultScrubEqualsFreshEvaluation) {
  Json j = patchScene();
  j["moult"] = Json::parse(R"({"start": 0, "duration": 10, "window": 0.3, "sequence": "centre_out", "gap": 0,
                               "seed": 3})");
  const pipeline::Scene scene = pipeline::sceneFromJson(j, kSceneFile);
  Pipeline scrub(scene);
  scrub.setLod(0.2);
  const double times[] = {4.0, 4.1, 4.2, 4.25, 4.2, 2.0, 2.0 + 1.0 / 24.0};
  size_t incremental = 0, partial = 0, reused = 0, keptCurves = 0;
  for (double t : times) {
    scrub.setTime(t);
    const Frame f = grab(scrub);
    const pipeline::FrameReuse r = scrub.frameReuse();
    const size_t n = scrub.feathers().size();
    EXPECT_TRUE(r.moult) << t;
    EXPECT_LE(r.moultRecomputed, r.moultChanged) << t;
    incremental += r.packIncremental ? 1 : 0;
    partial += r.packIncremental && r.packRecomputed < n && r.moultRecomputed < n ? 1 : 0;
    reused += r.meshReused;
    keptCurves += r.meshRegenerated < n ? 1 : 0;
    expectIdentical(f, fresh(scene, t, 0.2), t);
  }
  EXPECT_GE(incremental, 4u);
  EXPECT_GE(partial, 2u);  // frames that packed only part of the coat
  EXPECT_GT(reused, 0u);   // mesh slices copied from the last frame
  EXPECT_GE(keptCurves, 4u);
}

// A scene with no skeleton, moult or controls is the same coat at every time: changing the time
// re-evaluates nothing (a host's frame change is free), yet the time is kept, so a moult added later
// evaluates at it.
TEST(IncrementalFrames, TimeWithoutTimeDependentSectionsRecomputesNothing) {
  const pipeline::Scene scene = pipeline::sceneFromJson(patchScene(), kSceneFile);
  Pipeline p(scene);
  p.setLod(0.3);
  const Frame at0 = grab(p);
  auto evaluations = [&](pipeline::Stage s) { return p.evaluations(s); };
  const uint64_t pose = evaluations(pipeline::Stage::Pose), pack = evaluations(pipeline::Stage::Pack),
                 mesh = evaluations(pipeline::Stage::Mesh);
  p.setTime(4.0);
  EXPECT_EQ(p.time(), 4.0);
  const Frame at4 = grab(p);
  EXPECT_EQ(evaluations(pipeline::Stage::Pose), pose);
  EXPECT_EQ(evaluations(pipeline::Stage::Pack), pack);
  EXPECT_EQ(evaluations(pipeline::Stage::Mesh), mesh);
  expectIdentical(at4, fresh(scene, 4.0, 0.3), 4.0);
  expectIdentical(at4, at0, 4.0);

  p.editScene(pipeline::Stage::Ages, [](pipeline::Scene& s) {
    s.moult = Json::parse(R"({"start": 0, "duration": 10, "window": 0.3, "gap": 0.5})");
  });
  const Frame moulting = grab(p);
  pipeline::Scene withMoult = scene;
  withMoult.moult = Json::parse(R"({"start": 0, "duration": 10, "window": 0.3, "gap": 0.5})");
  expectIdentical(moulting, fresh(withMoult, 4.0, 0.3), 4.0);
  size_t absent = 0;
  for (uint8_t x : moulting.present) absent += x ? 0 : 1;
  EXPECT_GT(absent, 0u);
  // Now time matters: a new time is a new frame.
  p.setTime(4.5);
  expectIdentical(grab(p), fresh(withMoult, 4.5, 0.3), 4.5);
}

// A moult with gaps (feathers leave and return) and a level-of-detail change.
TEST(IncrementalFrames, GapsAndLodChangesEqualFreshEvaluation) {
  Json j = patchScene();
  j["moult"] = Json::parse(R"({"start": 0, "duration": 10, "window": 0.3, "sequence": "radial", "gap": 0.3,
                               "random": 0.2, "seed": 5})");
  const pipeline::Scene scene = pipeline::sceneFromJson(j, kSceneFile);
  Pipeline scrub(scene);
  scrub.setLod(0.5);
  scrub.setTime(5.0);
  grab(scrub);
  scrub.setTime(5.1);
  expectIdentical(grab(scrub), fresh(scene, 5.1, 0.5), 5.1);
  scrub.setLod(0.2);
  expectIdentical(grab(scrub), fresh(scene, 5.1, 0.2), 5.1);
  scrub.setTime(6.0);
  const Frame at6 = grab(scrub);
  expectIdentical(at6, fresh(scene, 6.0, 0.2), 6.0);
  size_t absent = 0;
  for (uint8_t p : at6.present) absent += p ? 0 : 1;
  EXPECT_GT(absent, 0u);
}

// A moult frame packs the lost and growing feathers over the mature coat: every mature feather keeps
// the pose it has without the moult, bit for bit (a lost feather leaves a gap), growing ones are packed
// with their own shape.
TEST(IncrementalFrames, MoultFramesKeepTheMatureCoat) {
  Json j = patchScene();
  const pipeline::Scene still = pipeline::sceneFromJson(j, kSceneFile);
  j["moult"] = Json::parse(R"({"start": 0, "duration": 10, "window": 0.3, "sequence": "radial", "gap": 0.3,
                               "random": 0.2, "seed": 5})");
  const pipeline::Scene moulting = pipeline::sceneFromJson(j, kSceneFile);
  Pipeline a(still), b(moulting);
  a.setTime(5.0);
  b.setTime(5.0);
  const std::vector<double> ea = a.elevations(), eb = b.elevations();
  const coat::CoatFeathers& c = b.feathers();
  ASSERT_EQ(ea.size(), eb.size());
  size_t mature = 0, absent = 0, growing = 0, growingMoved = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    if (!c.present[i]) {
      ++absent;
    } else if (c.age[i] >= 1.0) {
      ++mature;
      EXPECT_EQ(0, std::memcmp(&ea[i], &eb[i], sizeof(double))) << "feather " << i;
    } else {
      ++growing;
      growingMoved += std::memcmp(&ea[i], &eb[i], sizeof(double)) != 0 ? 1 : 0;
    }
  }
  EXPECT_GT(mature, 50u);
  EXPECT_GT(absent, 0u);
  EXPECT_GT(growing, 10u);
  EXPECT_GT(growingMoved, 0u);
  const pipeline::FrameReuse r = b.frameReuse();
  EXPECT_TRUE(r.moult);
  EXPECT_GE(r.moultChanged, absent);
  EXPECT_LE(r.moultRecomputed, r.moultChanged - absent);
  EXPECT_FALSE(a.frameReuse().moult);

  // "moult_pack": "full" repacks every feather: mature feathers settle into the gaps.
  j["packing"]["moult_pack"] = "full";
  Pipeline full(pipeline::sceneFromJson(j, kSceneFile));
  full.setTime(5.0);
  const std::vector<double> ef = full.elevations();
  EXPECT_FALSE(full.frameReuse().moult);
  size_t matureMoved = 0;
  for (size_t i = 0; i < c.size(); ++i)
    if (c.present[i] && c.age[i] >= 1.0) matureMoved += std::memcmp(&ea[i], &ef[i], sizeof(double)) != 0 ? 1 : 0;
  EXPECT_GT(matureMoved, 0u);
}

// Animated lift without a moult: the natural pack (the frame without its raises) does not change between
// frames and is reused as is; the frame's pack is repacked from the last frame's (or the natural) pack.
TEST(IncrementalFrames, LiftControlsReuseTheNaturalPack) {
  Json j = patchScene();
  j["controls"] = Json::parse(R"([{"name": "crest", "at": [0.1, 0.2, 0.0], "radius": 0.3, "falloff": 0.4,
                                   "keys": [{"t": 0, "lift": 0}, {"t": 4, "lift": 1}]}])");
  const pipeline::Scene scene = pipeline::sceneFromJson(j, kSceneFile);
  Pipeline scrub(scene);
  scrub.setLod(0.2);
  scrub.setTime(1.0);
  grab(scrub);
  ASSERT_TRUE(scrub.frameReuse().naturalPacked);
  for (double t : {1.1, 1.2, 0.5}) {
    scrub.setTime(t);
    const Frame f = grab(scrub);
    const pipeline::FrameReuse r = scrub.frameReuse();
    EXPECT_TRUE(r.naturalPacked);
    EXPECT_TRUE(r.naturalIncremental);
    EXPECT_EQ(r.naturalRecomputed, 0u) << t;  // same natural inputs: the pack is reused
    EXPECT_TRUE(r.packIncremental);
    EXPECT_GT(r.packChanged, 0u);  // the raised feathers
    EXPECT_LT(r.packRecomputed, scrub.feathers().size());
    expectIdentical(f, fresh(scene, t, 0.2), t);
  }
}

// Editing the packing section re-packs from scratch (the remembered packs belong to other options)
// and still equals a fresh pipeline with the edited scene.
TEST(IncrementalFrames, PackingEditsDoNotReuseStalePacks) {
  Json j = patchScene();
  j["moult"] = Json::parse(R"({"start": 0, "duration": 10, "window": 0.3, "gap": 0, "seed": 3})");
  Pipeline p(pipeline::sceneFromJson(j, kSceneFile));
  p.setLod(0.2);
  p.setTime(4.0);
  grab(p);
  p.editScene(pipeline::Stage::Controls, [](pipeline::Scene& s) { s.packing["clearance"] = 0.002; });
  const Frame edited = grab(p);
  EXPECT_FALSE(p.frameReuse().packIncremental);
  j["packing"]["clearance"] = 0.002;
  expectIdentical(edited, fresh(pipeline::sceneFromJson(j, kSceneFile), 4.0, 0.2), 4.0);
}

// The moult plan is kept across frames; editing the moult section (or anything upstream) re-plans.
TEST(IncrementalFrames, MoultEditsReplan) {
  Json j = patchScene();
  j["moult"] = Json::parse(R"({"start": 0, "duration": 10, "window": 0.3, "gap": 0.2, "seed": 3})");
  Pipeline p(pipeline::sceneFromJson(j, kSceneFile));
  p.setLod(0.2);
  p.setTime(4.0);
  const Frame before = grab(p);
  p.editScene(pipeline::Stage::Ages, [](pipeline::Scene& s) { s.moult["sequence"] = "increasing_u"; });
  const Frame edited = grab(p);
  j["moult"]["sequence"] = "increasing_u";
  expectIdentical(edited, fresh(pipeline::sceneFromJson(j, kSceneFile), 4.0, 0.2), 4.0);
  EXPECT_NE(before.age, edited.age);
}

// Meshing unplaced and placing later (how the pipeline moves a feather without meshing it again) writes
// exactly what meshing with the placement writes, for a mature and a growing feather at two LODs.
TEST(IncrementalFrames, UnplacedMeshPlacedLaterEqualsPlacedMesh) {
  const feather::FeatherParams p = feather::loadFeather(std::string(PTERYLA_DATA_DIR) + "/feathers/contour.json");
  const feather::FeatherCurves mature = feather::generateBarbs(p);
  const feather::GrowthState st = feather::growthStateAt(0.7, feather::defaultGrowthSchedule());
  const feather::FeatherCurves grown =
      feather::generateBarbs(feather::featherAtState(p, st, feather::defaultGrowthSchedule()));
  const feather::LodOrder order = feather::computeLodOrder(mature);
  for (int growing = 0; growing < 2; ++growing)
    for (double lod : {1.0, 0.2}) {
      feather::FeatherMeshInput in;
      in.curves = growing ? &grown : &mature;
      in.reference = growing ? &mature : nullptr;
      in.order = &order;
      in.lod = lod;
      in.sheathShed = growing ? st[feather::GrowthParam::Sheath] : 1.0;
      in.featherId = 7;
      in.placement = feather::FeatherPlacement::fromFollicle(
          {0.3, -1.2, 0.05}, glm::normalize(glm::dvec3(1, 0.2, -0.1)), glm::normalize(glm::dvec3(-0.2, 1, 0.05)), 0.37);
      TriMesh placedMesh, unplacedMesh;
      feather::appendFeatherMesh(in, {}, placedMesh);
      in.unplaced = true;
      feather::appendFeatherMesh(in, {}, unplacedMesh);
      const size_t n = unplacedMesh.vertexCount();
      ASSERT_EQ(n, placedMesh.vertexCount());
      ASSERT_GT(n, 0u);
      EXPECT_FALSE(sameBytes(unplacedMesh.positions, placedMesh.positions));  // really unplaced
      std::vector<glm::vec3> pos(n);
      std::vector<PackedDir> nrm(n), tan(n);
      feather::placeFeatherVertices(in.placement, unplacedMesh.positions.data(), unplacedMesh.normals.data(),
                                    unplacedMesh.tangents.data(), n, pos.data(), nrm.data(), tan.data());
      EXPECT_TRUE(sameBytes(pos, placedMesh.positions));
      EXPECT_TRUE(sameBytes(nrm, placedMesh.normals));
      EXPECT_TRUE(sameBytes(tan, placedMesh.tangents));
      EXPECT_TRUE(sameBytes(unplacedMesh.uvGlobal, placedMesh.uvGlobal));
      EXPECT_TRUE(sameBytes(unplacedMesh.uvGrowth, placedMesh.uvGrowth));
      EXPECT_TRUE(sameBytes(unplacedMesh.sheath, placedMesh.sheath));
      EXPECT_TRUE(sameBytes(unplacedMesh.indices, placedMesh.indices));
    }
}

// Posed frames pack from the rest pose's pack (coat::packDeformed): a host's pose that lifts one end of
// the patch carries the coat elsewhere and packs only around the lift. Whatever was evaluated before, a
// frame (pose, time) is the same bits as a fresh evaluation of it, with lift controls and a moult too.
TEST(IncrementalFrames, PosedFramesEqualFreshEvaluationWhateverCameBefore) {
  Json j = patchScene();
  j["controls"] = Json::parse(R"([{"name": "crest", "at": [0.1, 0.2, 0.0], "radius": 0.3, "falloff": 0.4,
                                   "keys": [{"t": 0, "lift": 0}, {"t": 4, "lift": 1}]}])");
  j["moult"] = Json::parse(R"({"start": 0, "duration": 10, "window": 0.3, "sequence": "centre_out", "gap": 0,
                               "seed": 3})");
  const pipeline::Scene scene = pipeline::sceneFromJson(j, kSceneFile);
  Pipeline scrub(scene);
  scrub.setLod(0.2);
  const coat::SkinMesh rest = scrub.restSkin();
  double xMin = 1e30, xMax = -1e30;
  for (const auto& p : rest.positions) {
    xMin = std::min(xMin, p.x);
    xMax = std::max(xMax, p.x);
  }
  // The last fifth of the patch (in x) bends up by `h` x (its span), smoothly.
  auto pose = [&](double h) {
    std::vector<glm::dvec3> out = rest.positions;
    const double x0 = xMax - 0.2 * (xMax - xMin);
    for (auto& p : out)
      if (p.x > x0) {
        const double u = (p.x - x0) / (xMax - x0);
        p.y += h * (xMax - xMin) * u * u;
      }
    return out;
  };
  auto freshPosed = [&](double h, double t) {
    Pipeline p(scene);
    p.setLod(0.2);
    p.setSkinPose(pose(h));
    p.setTime(t);
    return grab(p);
  };
  const std::pair<double, double> frames[] = {{0.05, 4.0}, {0.1, 4.0}, {0.1, 4.1}, {0.05, 4.0}, {0.0, 4.0},
                                              {0.1, 2.0},  {0.1, 1.0}, {0.1, 3.0}, {0.05, 4.0}};
  size_t deformed = 0, partial = 0;
  for (const auto& [h, t] : frames) {
    scrub.setSkinPose(pose(h));
    scrub.setTime(t);
    const Frame f = grab(scrub);
    const pipeline::FrameReuse r = scrub.frameReuse();
    if (h > 0) {
      deformed += r.deformedPacks > 0 ? 1 : 0;
      partial += r.deformedPacks > 0 && r.poseRepacked < scrub.feathers().size() ? 1 : 0;
      if (r.deformedPacks > 0) {
        EXPECT_GT(r.poseMoved, 0u) << h << " " << t;
      }
    } else {
      EXPECT_EQ(r.deformedPacks, 0u);  // the rest pose packs as a frame without a pose does
    }
    expectIdentical(f, freshPosed(h, t), t);
  }
  EXPECT_GE(deformed, 3u);  // (a frame whose pose and mature coat were packed before reuses that pack)
  EXPECT_GE(partial, 3u);
}
