#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/feather/generator.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/pipeline/pipeline.hpp"

using namespace pteryla;
using namespace pteryla::pipeline;

namespace {
Scene smallScene() {
  Json j = Json::parse(R"({"pteryla": 1, "seed": 5, "mesh": "meshes/sphere_250.obj",
    "feathers": {"contour": "feathers/contour.json"},
    "tracts": [{"name": "all", "count": 120, "feather_scale": "auto", "relax": {"iterations": 10},
                "parameterization": {"method": "projection", "view_direction": [0, -1, 0]}}],
    "directions": {"axis": [[0, 1.5, 0], [0, -1.5, 0]]},
    "ordering": {"method": "axis", "axis": [[0, 1.5, 0], [0, -1.5, 0]]},
    "packing": {"method": "height_field"},
    "render": {"lod": 0.3}})");
  return sceneFromJson(j, std::string(PTERYLA_DATA_DIR) + "/scene_test.json");
}
}  // namespace

TEST(PipelineEval, SameSceneAndSeedGiveTheSameCoatBitForBit) {
  Pipeline a(smallScene()), b(smallScene());
  const TriMesh& ma = a.coatMesh().mesh;
  const TriMesh& mb = b.coatMesh().mesh;
  ASSERT_FALSE(ma.empty());
  EXPECT_EQ(ma.positions, mb.positions);
  EXPECT_EQ(ma.indices, mb.indices);
  EXPECT_EQ(a.elevations(), b.elevations());
  Scene other = smallScene();
  other.seed = 6;
  Pipeline c(std::move(other));
  EXPECT_NE(c.coatMesh().mesh.positions, ma.positions);
}

TEST(PipelineEval, TimeAndLodEditsDirtyOnlyDownstreamStages) {
  // A moult makes the coat depend on time (without one a new time recomputes nothing:
  // IncrementalFrames.TimeWithoutTimeDependentSectionsRecomputesNothing); it starts after t = 3.
  Scene scene = smallScene();
  scene.moult = Json::parse(R"({"start": 10, "duration": 1})");
  Pipeline p(std::move(scene));
  p.coatMesh();
  const Pipeline& g = p;
  const auto skin = Stage::Skin, dist = Stage::Distribute, pack = Stage::Pack, mesh = Stage::Mesh;
  EXPECT_EQ(g.evaluations(skin), 1u);
  p.setTime(3.0);
  p.coatMesh();
  EXPECT_EQ(g.evaluations(skin), 1u);  // a timeline scrub does not reload the mesh
  EXPECT_EQ(g.evaluations(dist), 1u);  // nor re-relax follicles
  EXPECT_EQ(g.evaluations(pack), 2u);
  p.setLod(0.9);
  p.coatMesh();
  EXPECT_EQ(g.evaluations(pack), 2u);  // a LOD change re-meshes without repacking
  EXPECT_EQ(g.evaluations(mesh), 3u);
  p.invalidate(Stage::Pack);
  p.coatMesh();
  EXPECT_EQ(g.evaluations(dist), 1u);  // repacking does not re-relax
  EXPECT_EQ(g.evaluations(pack), 3u);
  // Packing and direction settings are read by their own stages: editing them never re-relaxes.
  p.editScene(Stage::Controls, [](Scene& s) { s.packing["clearance"] = 0.002; });
  p.coatMesh();
  EXPECT_EQ(g.evaluations(dist), 1u);
  EXPECT_EQ(g.evaluations(pack), 4u);
  p.editScene(Stage::Directions, [](Scene& s) { s.directions["axis"] = Json::array({{1.5, 0, 0}, {-1.5, 0, 0}}); });
  p.coatMesh();
  EXPECT_EQ(g.evaluations(dist), 1u);
  EXPECT_EQ(g.evaluations(pack), 5u);
}

TEST(PipelineEval, LodReducesTrianglesAndEveryFeatherHasARange) {
  Pipeline p(smallScene());
  p.setLod(1.0);
  const size_t full = p.coatMesh().mesh.triangleCount();
  const size_t feathers = p.coatMesh().ranges.size();
  EXPECT_EQ(feathers, p.follicles().size());
  p.setLod(0.2);
  EXPECT_LT(p.coatMesh().mesh.triangleCount(), full / 2);
}

TEST(PipelineEval, SceneJsonRoundTrips) {
  const Scene s = smallScene();
  const Json j = sceneToJson(s, s.file);
  const Scene back = sceneFromJson(j, s.file);
  EXPECT_EQ(sceneToJson(back, s.file), j);
}

TEST(PipelineEval, BadTractKeyNamesItsPath) {
  Scene s = smallScene();
  s.tracts[0]["densty"] = 3;
  Pipeline p(std::move(s));
  try {
    p.follicles();
    FAIL() << "unknown tract key accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "tracts[0].densty") << e.what();
  }
}

TEST(PipelineEval, DuplicateTractNameIsAnError) {
  Scene s = smallScene();
  s.tracts.push_back(s.tracts[0]);
  Pipeline p(std::move(s));
  try {
    p.tracts();
    FAIL() << "two tracts named 'all' accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "tracts[1].name") << e.what();
  }
}

// A skin held in memory (the host API's door) evaluates like the same mesh read from its file, and a
// pose given as positions moves the coat without re-distributing or re-interpolating it.
TEST(PipelineEval, SkinInMemoryAndCallerPose) {
  Pipeline fromFile(smallScene());
  const coat::SkinMesh& rest = fromFile.restSkin();
  Pipeline p(smallScene(), coat::makeSkinMesh(rest.positions, rest.faces, rest.groupNames, rest.faceGroup));
  EXPECT_EQ(p.coatMesh().mesh.positions, fromFile.coatMesh().mesh.positions);
  for (size_t k = 0; k < p.coatMesh().ranges.size(); ++k)
    EXPECT_EQ(p.coatMesh().ranges[k].feather, p.feathers().layerOrder[k]);  // every feather present

  const Pipeline& g = p;
  const auto dist = Stage::Distribute, interp = Stage::Interpolate, pose = Stage::Pose;
  std::vector<glm::dvec3> moved = rest.positions;
  for (auto& v : moved) v.x *= 1.25;
  p.setSkinPose(moved);
  const std::vector<glm::vec3> posedCoat = p.coatMesh().mesh.positions;
  EXPECT_EQ(g.evaluations(dist), 1u);
  EXPECT_EQ(g.evaluations(interp), 1u);
  EXPECT_EQ(g.evaluations(pose), 2u);
  EXPECT_EQ(p.posedSkin().positions, moved);
  EXPECT_NE(posedCoat, fromFile.coatMesh().mesh.positions);
  // Follicles ride the skin: same (face, barycentric), posed position.
  const coat::Follicles& f = p.follicles();
  const coat::CoatFeathers& c = p.feathers();
  for (size_t i = 0; i < c.size(); ++i) {
    const glm::dvec3 expect = coat::pointAt(p.posedSkin(), f.face[c.follicle[i]], f.bary[c.follicle[i]]);
    EXPECT_EQ(c.frames[i].origin, expect);
  }
  p.setSkinPose(moved);  // unchanged: nothing to redo
  p.coatMesh();
  EXPECT_EQ(g.evaluations(pose), 2u);
  p.setSkinPose({});  // back to the rest skin, the rest coat bit for bit
  EXPECT_EQ(p.coatMesh().mesh.positions, fromFile.coatMesh().mesh.positions);

  std::vector<glm::dvec3> bad = rest.positions;
  bad.pop_back();
  EXPECT_THROW(p.setSkinPose(bad), Error);
  bad = rest.positions;
  bad[3].y = std::nan("");
  try {
    p.setSkinPose(bad);
    FAIL() << "NaN pose accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "vertex 3") << e.what();
  }
  EXPECT_TRUE(p.skinPose().empty());  // a refused pose changes nothing
}

// A helical (Zhang & Kanai) feather is an ordinary feather to the coat: it distributes, packs and meshes.
TEST(PipelineEval, CoatOfHelicalFeathers) {
  Scene s = smallScene();
  s.feathers = Json::object();
  s.feathers["contour"] = std::string(PTERYLA_DATA_DIR) + "/feathers/helical-contour.json";
  Pipeline p(std::move(s));
  const CoatMesh& m = p.coatMesh();
  EXPECT_EQ(m.ranges.size(), p.follicles().size());
  EXPECT_GT(m.mesh.triangleCount(), 100u * m.ranges.size());
  for (double e : p.elevations()) EXPECT_TRUE(std::isfinite(e));
}

// In a moult, growing helical feathers grow by the helical model (issue #30 item 4): while on the collar
// they have only the barbs fused with the rachis so far, so they mesh with fewer triangles than the same
// feathers grown as Streit feathers (whose barb count never changes); mature ones mesh identically.
TEST(PipelineEval, MoultingHelicalFeathersGrowHelically) {
  const std::string helical = std::string(PTERYLA_DATA_DIR) + "/feathers/helical-contour.json";
  auto scene = [&](const Json& feather) {
    Scene s = smallScene();
    s.feathers = Json::object();
    s.feathers["contour"] = feather;
    s.moult = Json::parse(R"({"start": 0, "duration": 10, "window": 0.4, "gap": 0.3, "seed": 3})");
    s.time = 5;
    return s;
  };
  Pipeline h(scene(helical));
  Pipeline st(scene(feather::featherToJson(feather::streitForm(feather::loadFeather(helical)), false)));
  auto triangles = [](Pipeline& p) {
    std::map<uint32_t, uint32_t> t;
    for (const auto& r : p.coatMesh().ranges) t[r.feather] = r.indexCount / 3;
    return t;
  };
  const auto th = triangles(h), ts = triangles(st);
  const coat::CoatFeathers& coat = h.feathers();
  ASSERT_EQ(coat.age, st.feathers().age);
  size_t collar = 0, mature = 0;
  for (const auto& [i, n] : th) {
    ASSERT_TRUE(ts.count(i)) << i;
    if (coat.age[i] > 0.1 && coat.age[i] < 0.45) {
      EXPECT_LT(n, ts.at(i)) << "feather " << i << " at age " << coat.age[i];
      ++collar;
    } else if (coat.age[i] >= 1.0) {
      EXPECT_EQ(n, ts.at(i)) << "feather " << i;
      ++mature;
    }
  }
  EXPECT_GE(collar, 3u);
  EXPECT_GE(mature, 10u);
  for (const auto& q : h.coatMesh().mesh.positions) ASSERT_TRUE(std::isfinite(q.x) && std::isfinite(q.y));
}

// A tract interpolating a helical and a Streit key feather blends them in the Streit key-barb form.
TEST(PipelineEval, TractMixingHelicalAndStreitKeyFeathersEvaluates) {
  Scene s = smallScene();
  s.feathers["helical"] = std::string(PTERYLA_DATA_DIR) + "/feathers/helical-contour.json";
  s.tracts[0]["key_feathers"] =
      Json::parse(R"([{"feather": "helical", "at": [0, 1.5, 0]}, {"feather": "contour", "at": [0, -1.5, 0]}])");
  Pipeline p(std::move(s));
  const CoatMesh& m = p.coatMesh();
  EXPECT_EQ(m.ranges.size(), p.follicles().size());
  const coat::CoatFeathers& coat = p.feathers();
  ASSERT_GT(coat.size(), 10u);
  // Near a key the tract copies it (a helical feather stays helical); between the keys the feathers are
  // blends of the helical key's converted key barbs and the Streit key's.
  const feather::FeatherParams hk =
      feather::loadFeather(std::string(PTERYLA_DATA_DIR) + "/feathers/helical-contour.json");
  const feather::FeatherParams sk = feather::loadFeather(std::string(PTERYLA_DATA_DIR) + "/feathers/contour.json");
  size_t helical = 0, blended = 0;
  for (size_t i = 0; i < coat.size(); ++i) {
    const feather::FeatherParams& f = coat.params[i];
    if (f.generator == "helical") {
      ++helical;
      EXPECT_EQ(f.left.keyBarbs, hk.left.keyBarbs);
    } else if (f.left.keyBarbs != hk.left.keyBarbs && f.left.keyBarbs != sk.left.keyBarbs) {
      EXPECT_EQ(f.generator, "streit");
      EXPECT_TRUE(f.generatorParams.is_null());
      ++blended;
    }
  }
  EXPECT_GT(helical, 0u);
  EXPECT_GT(blended, 0u);
  for (const auto& q : m.mesh.positions) ASSERT_TRUE(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z));
}

TEST(PipelineEval, PerFeatherLodsLowerOnlyTheirFeathers) {
  // Screen-size LOD hands the pipeline one level per feather (multiplying the scene's lod): a feather
  // given a lower level loses triangles, every other feather is meshed exactly as before, and clearing
  // the levels gives back the uniform mesh bit for bit.
  Pipeline p(smallScene());
  p.setLod(1.0);
  const CoatMesh uniform = p.coatMesh();
  const size_t n = p.feathers().size();
  ASSERT_GT(n, 10u);
  auto trianglesOf = [](const CoatMesh& m) {
    std::vector<uint32_t> t;
    for (const auto& r : m.ranges) t.push_back(r.indexCount / 3);
    return t;
  };
  // Ranges are in layer order: find the range of feather `lowered` through the mesh's featherId.
  const uint32_t lowered = p.feathers().layerOrder[n / 2];
  std::vector<double> lods(n, 1.0);
  lods[lowered] = 0.2;
  const Pipeline& g = p;
  const auto pack = Stage::Pack;
  const size_t packs = g.evaluations(pack);
  p.setFeatherLods(lods);
  const CoatMesh mixed = p.coatMesh();
  EXPECT_EQ(g.evaluations(pack), packs);  // only the mesh stage re-evaluates
  const auto a = trianglesOf(uniform), b = trianglesOf(mixed);
  ASSERT_EQ(a.size(), b.size());
  size_t lower = 0;
  for (size_t k = 0; k < a.size(); ++k) {
    const uint32_t id = uniform.mesh.featherId[uniform.mesh.indices[uniform.ranges[k].firstIndex]];
    if (id == lowered) {
      EXPECT_LT(b[k], a[k] * 0.6) << "feather " << id;
      ++lower;
    } else {
      EXPECT_EQ(b[k], a[k]) << "feather " << id;
    }
  }
  EXPECT_EQ(lower, 1u);
  p.setFeatherLods({});
  EXPECT_EQ(p.coatMesh().mesh.positions, uniform.mesh.positions);
  EXPECT_EQ(p.coatMesh().mesh.indices, uniform.mesh.indices);
  lods[0] = 0.0;
  EXPECT_THROW(p.setFeatherLods(lods), Error);
  lods[0] = std::nan("");
  EXPECT_THROW(p.setFeatherLods(lods), Error);
}
