// Overlapping tracts of one feather type (thesis 9.2.1): where two tracts share faces each scatters its
// own follicles there, doubling the density; "overlap_group" gives the shared faces one distribution.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/pipeline.hpp"

using namespace pteryla;
using namespace pteryla::pipeline;

namespace {

const std::string kData = PTERYLA_DATA_DIR;

// Two bands round the sphere, x < 0.25 and x > -0.25, overlapping in |x| < 0.25, same density.
struct Bands {
  coat::SkinMesh skin = coat::loadSkinMesh(kData + "/meshes/sphere_1600.obj");
  std::vector<uint32_t> a, b;
  std::vector<uint8_t> shared;
  Bands() {
    shared.assign(skin.faceCount(), 0);
    for (uint32_t f = 0; f < skin.faceCount(); ++f) {
      const auto& t = skin.faces[f];
      const double x = (skin.positions[t[0]].x + skin.positions[t[1]].x + skin.positions[t[2]].x) / 3;
      if (x < 0.25) a.push_back(f);
      if (x > -0.25) b.push_back(f);
      shared[f] = x < 0.25 && x > -0.25;
    }
  }
  Scene scene(bool grouped) const {
    Json j = Json::parse(R"({"pteryla": 1, "seed": 5, "mesh": "meshes/sphere_1600.obj",
      "feathers": {"contour": "feathers/contour.json"}})");
    for (int k = 0; k < 2; ++k) {
      Json t = {{"name", k ? "b" : "a"}, {"faces", k ? b : a}, {"density", 60.0}, {"relax", {{"iterations", 10}}}};
      if (grouped) t["overlap_group"] = "contour";
      j["tracts"].push_back(t);
    }
    return sceneFromJson(j, kData + "/scene_test.json");
  }
  // Follicles per unit area on the shared faces over the same on the rest.
  double densityRatio(const coat::Follicles& f) const {
    double areaShared = 0, areaRest = 0;
    for (uint32_t k = 0; k < skin.faceCount(); ++k) (shared[k] ? areaShared : areaRest) += skin.faceAreas[k];
    size_t inShared = 0;
    for (size_t k = 0; k < f.size(); ++k) inShared += shared[f.face[k]];
    return (double(inShared) / areaShared) / (double(f.size() - inShared) / areaRest);
  }
};

}  // namespace

TEST(OverlapTracts, AGroupGetsOneDistributionOnItsSharedFaces) {
  const Bands bands;
  Pipeline separate(bands.scene(false)), grouped(bands.scene(true));
  const coat::Follicles& fs = separate.follicles();
  const coat::Follicles& fg = grouped.follicles();
  EXPECT_NEAR(bands.densityRatio(fs), 2.0, 0.3);  // two tracts' follicles on the same faces
  EXPECT_NEAR(bands.densityRatio(fg), 1.0, 0.15);
  // The shared follicles join the tract they continue: on the -x side of the overlap mostly "a" (0).
  size_t left = 0, leftA = 0;
  for (size_t k = 0; k < fg.size(); ++k)
    if (bands.shared[fg.face[k]] && fg.position[k].x < -0.15) {
      ++left;
      leftA += fg.tract[k] == 0;
    }
  ASSERT_GT(left, 5u);
  EXPECT_GT(double(leftA) / left, 0.8);
  // Ids stay unique; the same scene gives the same follicles.
  std::vector<uint64_t> ids(fg.id.begin(), fg.id.end());
  std::sort(ids.begin(), ids.end());
  EXPECT_TRUE(std::adjacent_find(ids.begin(), ids.end()) == ids.end());
  Pipeline again(bands.scene(true));
  EXPECT_EQ(again.follicles().position, fg.position);
  EXPECT_EQ(again.follicles().tract, fg.tract);
}
