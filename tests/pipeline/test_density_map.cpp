// Painted follicle density (scene "density_map", docs/scene-format.md): the per-vertex factor reaches the
// distribution stage (follicle counts follow it), survives saveScene/loadScene bit for bit through its side
// file, re-runs the distribution when it changes, and bad files are errors naming the file and element.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "pteryla/core/error.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/pipeline/scene_stages.hpp"

using namespace pteryla;
using pipeline::Pipeline;
using pipeline::Scene;

namespace {

std::string tempDir(const std::string& name) {
  const std::string d =
      (std::filesystem::path(testing::TempDir()) / ("density_map_" + name)).lexically_normal().string();
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

// The patch (a gently curved 2 x 2 sheet over x, z in [-1, 1], 441 vertices), one tract at a density,
// scattered only (`iterations`) or relaxed.
Scene patchScene(const std::string& tract, int iterations) {
  return pipeline::sceneFromJson(Json::parse(R"({"pteryla": 1, "seed": 4, "mesh": "../meshes/patch.obj",
        "feathers": {"contour": "../feathers/contour.json"},
        "tracts": [)" + tract + R"(], "packing": {"method": "height_field"}})")
                                     .patch(Json::parse(
                                         R"([{"op": "add", "path": "/tracts/0/relax", "value": {"iterations": )" +
                                         std::to_string(iterations) + "}}]")),
                                 std::string(PTERYLA_DATA_DIR) + "/scenes/density_map_test_in_memory.json");
}

// Factor `right` on the vertices with x > 0, `left` elsewhere.
std::shared_ptr<const std::vector<float>> halves(const Scene& s, float left, float right) {
  Pipeline p(s);
  const auto& rest = p.restSkin();
  auto f = std::make_shared<std::vector<float>>(rest.positions.size());
  for (size_t v = 0; v < rest.positions.size(); ++v) (*f)[v] = rest.positions[v].x > 1e-9 ? right : left;
  return f;
}

struct Split {
  size_t left = 0, right = 0, total = 0;
};
// Follicles clearly on either side (|x| > 0.15: off the one band of faces where the factor ramps).
Split split(Pipeline& p) {
  Split s;
  const auto& f = p.follicles();
  s.total = f.size();
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.position[i].x > 0.15) ++s.right;
    if (f.position[i].x < -0.15) ++s.left;
  }
  return s;
}

}  // namespace

TEST(DensityMap, ThePaintedFactorScalesTheFollicleCountWhereItIsPainted) {
  const std::string tract = R"({"name": "patch", "groups": ["patch"], "density": 150})";
  for (int iterations : {0, 20}) {
    SCOPED_TRACE("relax iterations " + std::to_string(iterations));
    Scene plain = patchScene(tract, iterations);
    Pipeline p0(plain);
    const Split a = split(p0);
    // 150 per unit area over the ~4.1 square units of the sheet.
    EXPECT_NEAR(double(a.total), 150 * 4.1, 40);
    EXPECT_NEAR(double(a.right) / double(a.left), 1.0, 0.15);

    Scene painted = plain;
    painted.densityFactor = halves(plain, 1.0f, 3.0f);
    Pipeline p1(painted);
    const Split b = split(p1);
    // Three times the follicles on the right, the left as before: twice as many in all.
    EXPECT_NEAR(double(b.right) / double(b.left), 3.0, 0.45);
    EXPECT_NEAR(double(b.left), double(a.left), 0.12 * double(a.left));
    EXPECT_NEAR(double(b.total) / double(a.total), 2.0, 0.12);

    // Zero on the left: no follicle there at all.
    Scene bare = plain;
    bare.densityFactor = halves(plain, 0.0f, 1.0f);
    Pipeline p2(bare);
    const Split c = split(p2);
    EXPECT_EQ(c.left, 0u);
    EXPECT_NEAR(double(c.right), double(a.right), 0.15 * double(a.right));
  }
}

TEST(DensityMap, WithACountTheFactorOnlyMovesFollicles) {
  Scene s = patchScene(R"({"name": "patch", "groups": ["patch"], "count": 400})", 10);
  s.densityFactor = halves(s, 1.0f, 4.0f);
  Pipeline p(s);
  const Split b = split(p);
  EXPECT_EQ(b.total, 400u);
  EXPECT_NEAR(double(b.right) / double(b.left), 4.0, 0.8);
}

TEST(DensityMap, SaveWritesTheSideFileAndTheSceneReloadsToTheSameFollicles) {
  const std::string dir = tempDir("save");
  Scene s = patchScene(R"({"name": "patch", "groups": ["patch"], "density": 120})", 5);
  auto f = std::make_shared<std::vector<float>>(*halves(s, 0.5f, 2.0f));
  (*f)[7] = 0.123f;  // not a short binary fraction: the side file must keep the float exactly
  s.densityFactor = f;
  // A scene file in another directory than the mesh: paths stay relative and right.
  const std::string file = dir + "/painted.json";
  pipeline::saveScene(file, s);
  ASSERT_TRUE(std::filesystem::is_regular_file(dir + "/painted.density.json"));
  const Json j = readJsonFile(file);
  EXPECT_EQ(j.at("density_map"), "painted.density.json");

  const Scene back = pipeline::loadScene(file);
  ASSERT_TRUE(back.densityFactor);
  EXPECT_EQ(*back.densityFactor, *s.densityFactor);
  EXPECT_EQ(back.densityMap, dir + "/painted.density.json");
  EXPECT_FALSE(pipeline::earliestChangedStage(s, back)) << "the same factors from a file are the same scene";
  Pipeline a(s), b(back);
  ASSERT_EQ(a.follicles().size(), b.follicles().size());
  for (size_t i = 0; i < a.follicles().size(); ++i) ASSERT_EQ(a.follicles().position[i], b.follicles().position[i]);
}

TEST(DensityMap, AChangedFactorReRunsTheDistribution) {
  Scene s = patchScene(R"({"name": "patch", "groups": ["patch"], "density": 120})", 5);
  Scene t = s;
  t.densityFactor = halves(s, 1.0f, 2.0f);
  EXPECT_EQ(pipeline::earliestChangedStage(s, t), pipeline::Stage::Distribute);
  Scene u = t;
  auto g = std::make_shared<std::vector<float>>(*t.densityFactor);
  (*g)[0] = 1.5f;
  u.densityFactor = g;
  EXPECT_EQ(pipeline::earliestChangedStage(t, u), pipeline::Stage::Distribute);

  // Re-running from the distribution gives what a fresh pipeline gives.
  Pipeline p(s);
  p.follicles();
  p.editScene(pipeline::Stage::Distribute, [&](Scene& x) { x = t; });
  Pipeline fresh(t);
  ASSERT_EQ(p.follicles().size(), fresh.follicles().size());
  for (size_t i = 0; i < fresh.follicles().size(); ++i)
    ASSERT_EQ(p.follicles().position[i], fresh.follicles().position[i]);
}

TEST(DensityMap, BadFilesNameTheFileAndTheElement) {
  const std::string dir = tempDir("bad");
  auto errorOf = [](const std::function<void()>& fn) -> std::string {
    try {
      fn();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return "no error";
  };
  const std::string bad = dir + "/bad.density.json";
  std::ofstream(bad) << R"({"pteryla_density": 1, "vertices": 3, "factor": [1, 2, -1]})";
  std::string m = errorOf([&] { pipeline::readDensityMap(bad); });
  EXPECT_NE(m.find(bad), std::string::npos) << m;
  EXPECT_NE(m.find("factor[2]"), std::string::npos) << m;

  std::ofstream(bad) << R"({"pteryla_density": 1, "vertices": 4, "factor": [1, 2, 1]})";
  m = errorOf([&] { pipeline::readDensityMap(bad); });
  EXPECT_NE(m.find("3 factors for 4 vertices"), std::string::npos) << m;

  std::ofstream(bad) << R"({"pteryla_density": 1, "vertices": 3, "factor": [1, 2, 1], "extra": 0})";
  m = errorOf([&] { pipeline::readDensityMap(bad); });
  EXPECT_NE(m.find("extra"), std::string::npos) << m;

  // A scene naming a missing map; a map that does not fit the mesh (checked when distributing).
  const std::string scene = dir + "/s.json";
  std::ofstream(scene) << R"({"pteryla": 1, "mesh": ")" << PTERYLA_DATA_DIR
                       << R"(/meshes/patch.obj", "density_map": "nope.density.json"})";
  m = errorOf([&] { pipeline::loadScene(scene); });
  EXPECT_NE(m.find("density_map"), std::string::npos) << m;
  EXPECT_NE(m.find("nope.density.json"), std::string::npos) << m;

  std::ofstream(bad) << R"({"pteryla_density": 1, "vertices": 3, "factor": [1, 2, 1]})";
  std::ofstream(scene) << R"({"pteryla": 1, "mesh": ")" << PTERYLA_DATA_DIR
                       << R"(/meshes/patch.obj", "density_map": "bad.density.json"})";
  const Scene s = pipeline::loadScene(scene);
  m = errorOf([&] {
    Pipeline p(s);
    p.follicles();
  });
  EXPECT_NE(m.find(bad), std::string::npos) << m;
  EXPECT_NE(m.find("3 factors for a mesh of 441 vertices"), std::string::npos) << m;
}
