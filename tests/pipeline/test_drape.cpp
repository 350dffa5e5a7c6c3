// Draped packing (coat/drape.hpp) through the pipeline: a draped coat lies down, stays out of the skin
// and out of other feathers on a smooth body, is deterministic, and the check's unpacked baseline does
// not depend on how the coat was packed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/pipeline.hpp"

using namespace pteryla;
using namespace pteryla::pipeline;

namespace {
// The sphere with one direction axis and nothing else but the packing method.
Scene sphereScene(const char* method, double clearance = 0) {
  Json j = Json::parse(R"({"pteryla": 1, "seed": 3, "mesh": "meshes/sphere_1600.obj",
    "feathers": {"contour": "feathers/contour.json"},
    "tracts": [{"name": "all", "count": 400, "feather_scale": "auto", "feather_spacings": 3.0,
                "parameterization": {"method": "projection", "view_direction": [0, -1, 0]}}],
    "directions": {"axis": [[0, 1.5, 0], [0, -1.5, 0]]},
    "ordering": {"method": "axis", "axis": [[0, 1.5, 0], [0, -1.5, 0]]}})");
  j["packing"] = Json{{"method", method}};
  if (clearance > 0) j["packing"]["clearance"] = clearance;
  return sceneFromJson(j, std::string(PTERYLA_DATA_DIR) + "/scene_test.json");
}
}  // namespace

TEST(Drape, SphereCoatLiesDownWithoutPenetrationsOrCrossings) {
  Pipeline p(sphereScene("drape"));
  const QualityMetrics m = p.check();
  ASSERT_TRUE(m.skinPenetrations && m.intersectingPairs && m.intersectingPairsUnpacked && m.elevationP50);
  EXPECT_EQ(*m.skinPenetrations, 0u);
  EXPECT_EQ(*m.intersectingPairs, 0u);
  EXPECT_GT(*m.intersectingPairsUnpacked, 1000u);  // the same feathers at 10 degrees cross everywhere
  EXPECT_LT(*m.elevationP50, 10.0);                // a coat a few feathers deep
  EXPECT_GT(*m.coverage, 0.97);
  ASSERT_TRUE(m.hiddenFeathers);
  EXPECT_LT(*m.hiddenFeathers, 4u);
}

TEST(Drape, FeathersFollowTheSkinInsteadOfStandingOff) {
  // Every vertex of a draped feather lies close over the skin (the sphere's radius is 1; its polygons lie
  // up to a few percent inside it), where a rigid feather's tip floats off a convex body.
  Pipeline p(sphereScene("drape"));
  const TriMesh& m = p.coatMesh().mesh;
  ASSERT_FALSE(m.empty());
  double worst = 0;
  for (const auto& v : m.positions) worst = std::max(worst, std::abs(double(glm::length(v)) - 1.0));
  Pipeline rigid(sphereScene("height_field"));
  double worstRigid = 0;
  for (const auto& v : rigid.coatMesh().mesh.positions)
    worstRigid = std::max(worstRigid, std::abs(double(glm::length(v)) - 1.0));
  EXPECT_LT(worst, 0.15) << "rigid " << worstRigid;  // corners rise to the need under them (conservative)
  EXPECT_GT(worstRigid, 2 * worst);
}

TEST(Drape, SameSceneGivesTheSameCoatBitForBit) {
  Pipeline a(sphereScene("drape")), b(sphereScene("drape"));
  EXPECT_EQ(a.coatMesh().mesh.positions, b.coatMesh().mesh.positions);
  EXPECT_EQ(a.coatMesh().mesh.indices, b.coatMesh().mesh.indices);
}

TEST(Drape, SameCoatWhateverTheThreadCount) {
  // Charts are gathered by whichever thread claims them first while the calling thread lays them in layer
  // order (drape.cpp): one thread, two, or more threads than cores give the same bits.
  auto withThreads = [](int threads) {
    Scene s = sphereScene("drape");
    s.packing["threads"] = threads;
    Pipeline p(std::move(s));
    return p.coatMesh().mesh;
  };
  const TriMesh one = withThreads(1);
  ASSERT_FALSE(one.empty());
  for (const int threads : {2, 5}) {
    const TriMesh m = withThreads(threads);
    EXPECT_EQ(m.positions, one.positions) << threads << " threads";
    EXPECT_EQ(m.indices, one.indices) << threads << " threads";
  }
}

TEST(Drape, UnpackedBaselineDependsOnTheInputOnly) {
  const QualityMetrics a = Pipeline(sphereScene("drape")).check();
  const QualityMetrics b = Pipeline(sphereScene("height_field")).check();
  const QualityMetrics c = Pipeline(sphereScene("drape", 0.01)).check();
  EXPECT_EQ(*a.intersectingPairsUnpacked, *b.intersectingPairsUnpacked);
  EXPECT_EQ(*a.intersectingPairsUnpacked, *c.intersectingPairsUnpacked);
  ASSERT_TRUE(b.elevationP50 && b.elevationP90);
  EXPECT_LE(*b.elevationP50, *b.elevationP90);
}

TEST(Drape, BareMeshScenesDrapeAndTheMethodRoundTrips) {
  Json j =
      Json::parse(R"({"pteryla": 1, "mesh": "meshes/sphere_250.obj", "feathers": {"contour": "feathers/contour.json"},
                         "packing": {"method": "drape", "drape_max_slope_deg": 10}})");
  const Scene s = sceneFromJson(j, std::string(PTERYLA_DATA_DIR) + "/scene_test.json");
  JsonReader r(s.packing, "scene_test.json", "packing");
  const coat::PackingSettings settings = coat::parsePackingSettings(r);
  const coat::PackOptions& o = settings.options;
  EXPECT_EQ(o.method, coat::PackMethod::Drape);
  EXPECT_EQ(o.drapeMaxSlopeDeg, 10.0);
  const Json written = coat::packingSettingsToJson(settings);  // the reader keeps a reference
  JsonReader back(written, "scene_test.json", "packing");
  const coat::PackOptions o2 = coat::parsePackingSettings(back).options;
  EXPECT_EQ(o2.method, coat::PackMethod::Drape);
  EXPECT_EQ(o2.drapeMaxSlopeDeg, 10.0);
  Json hf = j;
  hf["packing"]["method"] = "height_field";
  JsonReader rh(hf["packing"], "scene_test.json", "packing");
  const Json hfWritten = coat::packingSettingsToJson(coat::parsePackingSettings(rh));
  EXPECT_EQ(hfWritten.value("method", ""), "height_field");
  Json bad = j;
  bad["packing"]["method"] = "stack";
  const Scene sb = sceneFromJson(bad, std::string(PTERYLA_DATA_DIR) + "/scene_test.json");
  JsonReader rb(sb.packing, "scene_test.json", "packing");
  EXPECT_THROW(coat::parsePackingSettings(rb), Error);
  // No method: draped (a bare mesh, or a scene that does not choose).
  const Scene bare = loadScene(std::string(PTERYLA_DATA_DIR) + "/meshes/sphere_250.obj");
  const Json bareOptions = bare.packing.is_null() ? Json::object() : bare.packing;
  JsonReader rn(bareOptions, "sphere_250.obj", "packing");
  EXPECT_EQ(coat::parsePackingSettings(rn).options.method, coat::PackMethod::Drape);
  EXPECT_EQ(coat::PackOptions{}.method, coat::PackMethod::Drape);
}

// The corpus runs each real mesh bare (`pteryla check MESH.obj`) in CI; its "minimal" variant (the mesh
// plus one direction axis through the bounding box's centre along its longest axis, every other key a
// default) is the same coat as long as this holds: a bare mesh gets exactly that axis, for the feather
// directions and for the layer order, and nothing else differs.
TEST(Drape, ABareMeshIsTheMinimalSceneWithTheLongestBoundingBoxAxis) {
  const std::string mesh = std::string(PTERYLA_DATA_DIR) + "/meshes/wing.obj";
  Pipeline bare(loadScene(mesh));
  const coat::SkinMesh& skin = bare.restSkin();
  glm::dvec3 lo(1e300), hi(-1e300);
  for (const glm::dvec3& p : skin.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::dvec3 extent = hi - lo;
  const int ax = extent.x >= extent.y && extent.x >= extent.z ? 0 : extent.y >= extent.z ? 1 : 2;
  glm::dvec3 a = 0.5 * (lo + hi), b = a;
  a[ax] = lo[ax];
  b[ax] = hi[ax];
  Json j = {{"pteryla", 1}, {"mesh", mesh}, {"directions", {{"axis", {{a.x, a.y, a.z}, {b.x, b.y, b.z}}}}}};
  Pipeline minimal(sceneFromJson(j, std::string(PTERYLA_DATA_DIR) + "/minimal.json"));
  const coat::CoatFeathers& fb = bare.feathers();
  const coat::CoatFeathers& fm = minimal.feathers();
  ASSERT_GT(fb.size(), 1000u);
  ASSERT_EQ(fb.size(), fm.size());
  EXPECT_EQ(fb.layerOrder, fm.layerOrder);
  size_t differ = 0;
  for (size_t i = 0; i < fb.size(); ++i)
    if (glm::length(fb.frames[i].tangent - fm.frames[i].tangent) > 1e-9 ||
        glm::length(fb.frames[i].origin - fm.frames[i].origin) > 1e-12)
      ++differ;
  EXPECT_EQ(differ, 0u);
}

TEST(Drape, TheGuaranteeHoldsOnABareMeshWithABeakAndCreases) {
  // The bird's head as a bare mesh (beak, eye sockets, a neck rim): whatever the chart misses, the coat
  // that leaves the drape has no vertex in the skin and no crossing triangles, by the checker's own tests.
  Scene s = loadScene(std::string(PTERYLA_DATA_DIR) + "/meshes/head.obj");
  s.tracts[0]["count"] = 500;
  Pipeline p(std::move(s));
  const QualityMetrics m = p.check();
  EXPECT_EQ(*m.skinPenetrations, 0u);
  EXPECT_EQ(*m.intersectingPairs, 0u);
  EXPECT_GT(*m.intersectingPairsUnpacked, 0u);
  EXPECT_LT(*m.elevationP50, 25.0);
  EXPECT_GT(*m.coverage, 0.8);
  EXPECT_LT(*m.hiddenFeathers, 50u);
}

namespace {
// A thin disc (the unit sphere flattened to half a thickness of 0.03, like a wing or a fin), written next
// to a scene in a temporary directory: feathers on its faces that point across it reach its rim.
Scene discScene(const std::string& dir) {
  std::ifstream in(std::string(PTERYLA_DATA_DIR) + "/meshes/sphere_1600.obj");
  std::ofstream out(dir + "/disc.obj");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) {
      std::istringstream ls(line.substr(2));
      double x, y, z;
      ls >> x >> y >> z;
      out << "v " << x << ' ' << 0.03 * y << ' ' << z << '\n';
    } else {
      out << line << '\n';
    }
  }
  out.close();
  Json j = Json::parse(R"({"pteryla": 1, "seed": 5, "mesh": "disc.obj",
    "feathers": {"contour": ")" +
                       std::string(PTERYLA_DATA_DIR) + R"(/feathers/contour.json"},
    "tracts": [{"name": "all", "count": 500, "feather_scale": "auto", "feather_spacings": 3.0,
                "parameterization": {"method": "projection", "view_direction": [0, -1, 0]}}],
    "directions": {"axis": [[-1.5, 0, 0], [1.5, 0, 0]]},
    "packing": {"method": "drape"}})");
  return sceneFromJson(j, dir + "/disc.json");
}
}  // namespace

TEST(Drape, FeathersOverhangAThinPartsRimInsteadOfWrappingOrVanishing) {
  // Past the rim of a thin part the skin turns away under the feather: it goes straight on, like a flight
  // feather past the wing's edge. It neither wraps round onto the other side nor is trimmed away (the
  // old test "the body is thinner than twice the height" hid whole feathers on thin parts).
  const std::string dir = testing::TempDir() + "/pteryla_drape_disc";
  std::filesystem::create_directories(dir);
  Pipeline p(discScene(dir));
  const QualityMetrics m = p.check();
  EXPECT_EQ(*m.skinPenetrations, 0u);
  EXPECT_EQ(*m.intersectingPairs, 0u);
  EXPECT_LT(*m.hiddenFeathers, 10u);
  EXPECT_GT(*m.coverage, 0.9);
  const TriMesh& mesh = p.coatMesh().mesh;
  const coat::CoatFeathers& coat = p.feathers();
  size_t beyond = 0, wrapped = 0;
  std::vector<uint8_t> used(mesh.positions.size(), 0);
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    if (tri[0] == tri[1] && tri[1] == tri[2]) continue;  // trimmed
    for (int k = 0; k < 3; ++k) used[tri[k]] = 1;
  }
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    if (!used[v]) continue;
    const glm::vec3 q = mesh.positions[v];
    const coat::FeatherFrame& f = coat.frames[mesh.featherId[v]];
    if (std::abs(f.normal.y) < 0.9) continue;  // rooted on the rim itself
    // Wrapped round: under the disc on the other face's side.
    if (std::hypot(q.x, q.z) < 0.98 && f.normal.y * q.y < -0.03) ++wrapped;
    if (std::hypot(q.x, q.z) > 1.03) ++beyond;
  }
  EXPECT_GT(beyond, 1000u);
  EXPECT_EQ(wrapped, 0u);
}
