// A tract's "removed_follicles" (docs/scene-format.md): follicles deleted by hand leave the coat after
// relaxation, so the others keep their places bit for bit (a gap, as an artist expects).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/pipeline.hpp"

using namespace pteryla;
using namespace pteryla::pipeline;

namespace {

const std::string kData = PTERYLA_DATA_DIR;

// Two tracts over the whole sphere (they need not be apart), counted, lightly relaxed.
Json sceneJson(const Json& removedA = Json(), const Json& removedB = Json()) {
  Json j = Json::parse(R"({"pteryla": 1, "seed": 9, "mesh": "meshes/sphere_1600.obj",
    "feathers": {"contour": "feathers/contour.json"},
    "tracts": [{"name": "a", "all": true, "count": 120, "relax": {"iterations": 8}},
               {"name": "b", "all": true, "count": 90, "relax": {"iterations": 8}}]})");
  if (!removedA.is_null()) j["tracts"][0]["removed_follicles"] = removedA;
  if (!removedB.is_null()) j["tracts"][1]["removed_follicles"] = removedB;
  return j;
}

Scene scene(const Json& j) { return sceneFromJson(j, kData + "/scene_test.json"); }

}  // namespace

TEST(RemovedFollicles, DropExactlyThoseAndKeepTheOthersBitForBit) {
  Pipeline full(scene(sceneJson()));
  const coat::Follicles all = full.follicles();
  const size_t n = all.size();
  ASSERT_EQ(n, 210u);
  ASSERT_EQ(full.feathers().size(), n);
  // Three follicles of tract a, two of tract b (by id), plus one id of tract b listed under tract a:
  // a follicle goes only when its own tract lists it.
  std::vector<uint64_t> goneA, goneB;
  for (size_t k = 0; k < n; ++k) {
    if (all.tract[k] == 0 && (k == 3 || k == 50 || k == 119)) goneA.push_back(all.id[k]);
    if (all.tract[k] == 1 && (k == 130 || k == 200)) goneB.push_back(all.id[k]);
  }
  ASSERT_EQ(goneA.size(), 3u);
  ASSERT_EQ(goneB.size(), 2u);
  uint64_t idOfB = 0;
  for (size_t k = 0; k < n; ++k)
    if (all.tract[k] == 1 && std::find(goneB.begin(), goneB.end(), all.id[k]) == goneB.end()) idOfB = all.id[k];
  Json listA = goneA;
  listA.push_back(idOfB);         // not tract a's: ignored
  listA.push_back(999999999999);  // names no follicle: ignored
  listA.push_back(goneA[0]);      // a duplicate: the same
  Pipeline cut(scene(sceneJson(listA, goneB)));
  const coat::Follicles& kept = cut.follicles();
  ASSERT_EQ(kept.size(), n - 5);
  EXPECT_EQ(cut.feathers().size(), n - 5);
  std::map<uint64_t, size_t> before;
  for (size_t k = 0; k < n; ++k) before[all.id[k]] = k;
  for (size_t k = 0; k < kept.size(); ++k) {
    EXPECT_EQ(std::count(goneA.begin(), goneA.end(), kept.id[k]) + std::count(goneB.begin(), goneB.end(), kept.id[k]),
              0);
    const auto it = before.find(kept.id[k]);
    ASSERT_NE(it, before.end());
    const size_t j = it->second;
    EXPECT_EQ(kept.tract[k], all.tract[j]);
    EXPECT_EQ(kept.face[k], all.face[j]);
    // Bit for bit: the removal comes after relaxation.
    EXPECT_EQ(kept.bary[k], all.bary[j]);
    EXPECT_EQ(kept.position[k], all.position[j]);
    EXPECT_EQ(kept.normal[k], all.normal[j]);
  }
}

TEST(RemovedFollicles, RoundTripThroughSaveAndLoad) {
  const std::string path = (std::filesystem::temp_directory_path() / "pteryla_removed_follicles.json").string();
  Scene s = scene(sceneJson(Json::array({7, 3}), Json::array({125})));
  saveScene(path, s);
  const Scene back = loadScene(path);
  std::filesystem::remove(path);
  EXPECT_EQ(back.tracts.at(0).at("removed_follicles"), Json::array({7, 3}));
  EXPECT_EQ(back.tracts.at(1).at("removed_follicles"), Json::array({125}));
  Pipeline a(s), b(scene(sceneToJson(back, kData + "/scene_test.json")));
  EXPECT_EQ(a.follicles().id, b.follicles().id);
  EXPECT_EQ(a.follicles().size(), 210u - 3u);
}

TEST(RemovedFollicles, NonIntegersAreErrorsNamingTheElement) {
  for (const Json& bad : {Json::array({1, 2.5}), Json::array({1, -4}), Json::array({1, "3"}), Json(5)}) {
    Pipeline p(scene(sceneJson(bad)));
    try {
      p.follicles();
      FAIL() << "accepted " << bad.dump();
    } catch (const Error& e) {
      EXPECT_NE(e.file().find("scene_test.json"), std::string::npos);
      EXPECT_EQ(e.element(), bad.is_array() ? "tracts[0].removed_follicles[1]" : "tracts[0].removed_follicles")
          << e.what();
    }
  }
}

TEST(RemovedFollicles, RemovingEveryFollicleOfATractLeavesItBare) {
  Pipeline full(scene(sceneJson()));
  Json every = Json::array();
  for (size_t k = 0; k < full.follicles().size(); ++k)
    if (full.follicles().tract[k] == 1) every.push_back(full.follicles().id[k]);
  Pipeline bare(scene(sceneJson(Json(), every)));
  EXPECT_EQ(bare.follicles().size(), 120u);
  EXPECT_EQ(bare.feathers().size(), 120u);
}
