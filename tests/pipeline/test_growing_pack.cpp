// Growing feathers are packed with their barbs as they will be meshed (computePack, docs/growth.md): a
// moulting coat with the default packing opening age has no coat vertex below the skin, at every stage
// of growth. Meshing the mature feather's packing (straight shafts for age < opening_age) grown afterwards
// left tens of thousands of vertices of the moult scene below the skin.
#include <gtest/gtest.h>

#include <array>
#include <string>

#include "pteryla/coat/check.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

using namespace pteryla;

TEST(GrowingPack, MoultingCoatStaysAboveSkinWithDefaultOpeningAge) {
  pipeline::Scene s = pipeline::loadScene(std::string(PTERYLA_DATA_DIR) + "/scenes/moult.json");
  s.packing.erase("opening_age");  // the packer's default (0.8)
  pipeline::Pipeline p(std::move(s));
  p.setLod(1.0);
  for (double t : {3.0, 4.0, 6.0}) {
    SCOPED_TRACE(t);
    p.setTime(t);
    const auto& c = p.feathers();
    // Growing feathers in every phase of the schedule: shaft growing, barbs growing closed, opening,
    // key barb shapes forming.
    std::array<size_t, 4> phase{};
    for (size_t i = 0; i < c.size(); ++i) {
      if (!c.present[i] || c.age[i] >= 1) continue;
      const double a = c.age[i];
      ++phase[a < 0.3 ? 0 : a < 0.5 ? 1 : a < 0.8 ? 2 : 3];
    }
    for (size_t k = 0; k < phase.size(); ++k) EXPECT_GE(phase[k], 3u) << "phase " << k;
    coat::CheckOptions co;
    co.intersections = false;
    co.coverage = false;
    coat::setFeatherBases(co, c, 0.08);  // the scene's packing base allowance
    const coat::CheckResult r = coat::check(p.posedSkin(), {}, p.coatMesh().mesh, co);
    EXPECT_GT(r.samplePoints, 100000u);
    EXPECT_EQ(r.skinPenetrations, 0u);
  }
}
