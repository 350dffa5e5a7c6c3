// Mirror left/right (mirror.hpp): reflected copies of a tract's faces, brushes, controls and styling
// vectors as one undo step, nothing on the plane or already mirrored copied again, names swapped, and
// the symmetry plane of a symmetric skin found. No display.
#include <gtest/gtest.h>

#include <algorithm>

#include <glm/geometric.hpp>

#include "actions.hpp"
#include "document.hpp"
#include "fixtures.hpp"
#include "mirror.hpp"
#include "paint.hpp"
#include "pteryla/core/error.hpp"
#include "scene_edit.hpp"

using namespace pteryla;
using namespace pteryla::viewer;
using viewer_test::smallPatch;

namespace {

// Mean x of the triangle centroids of these source faces.
double meanX(const coat::SkinMesh& m, const std::vector<uint32_t>& faces) {
  double sum = 0;
  size_t n = 0;
  for (size_t t = 0; t < m.faces.size(); ++t)
    if (std::binary_search(faces.begin(), faces.end(), m.sourceFace[t])) {
      const auto& f = m.faces[t];
      sum += (m.positions[f[0]].x + m.positions[f[1]].x + m.positions[f[2]].x) / 3.0;
      ++n;
    }
  return n ? sum / double(n) : 0.0;
}

}  // namespace

TEST(Mirror, NamesSwapSides) {
  EXPECT_EQ(mirroredName("wing_left"), "wing_right");
  EXPECT_EQ(mirroredName("RightWing"), "LeftWing");
  EXPECT_EQ(mirroredName("wing_l"), "wing_r");
  EXPECT_EQ(mirroredName("R_leg"), "L_leg");
  EXPECT_EQ(mirroredName("crest"), "crest_mirror");
}

TEST(Mirror, CopiesEverythingAcrossThePlaneInOneUndoStep) {
  Document d;
  d.reset(smallPatch(), "");
  ASSERT_TRUE(d.waitIdle());
  const auto rest = d.snapshot().restSkin;
  ASSERT_TRUE(rest);
  const std::vector<uint32_t> band = facesInBrush(*rest, {}, {0.6f, 0.05f, 0.3f}, 0.3f);
  actions::addTractFromFaces(d, "band_left", band);
  d.endGesture();
  actions::setTractCount(d, 1, 8);
  actions::addBrush(d, {0.5, 0.05, -0.4}, 0.2, 40);
  actions::addControl(d, {0.7, 0.05, 0.5}, 0.3);
  d.edit("control tracts", [](pipeline::Scene& s) { s.controls[0]["tracts"] = {"band_left"}; });
  actions::addStylingVector(d, {0.4, 0.05, 0.2}, {1, 0, 1});  // the patch's own vector sits on x = 0
  const Json before = sceneJson(d.scene());
  d.endGesture();

  MirrorRequest q;
  q.tracts = {1};
  q.brushes = q.controls = q.vectors = true;
  const MirrorResult r = mirrorScene(d, *rest, q);
  EXPECT_EQ(r.tracts, 1u);
  EXPECT_EQ(r.brushes, 1u);
  EXPECT_EQ(r.controls, 1u);
  EXPECT_EQ(r.vectors, 1u) << "the vector on the plane gets no copy";
  const pipeline::Scene& s = d.scene();
  ASSERT_EQ(s.tracts.size(), 3u);
  EXPECT_EQ(s.tracts[2]["name"], "band_right");
  EXPECT_EQ(s.tracts[2]["count"], 8);
  const auto mirrored = s.tracts[2]["faces"].get<std::vector<uint32_t>>();
  EXPECT_NEAR(double(mirrored.size()), double(band.size()), 0.1 * double(band.size()));
  EXPECT_NEAR(meanX(*rest, mirrored), -meanX(*rest, band), 0.02);
  EXPECT_EQ(actions::jsonVec3(s.packing["styling"][1]["center"]), glm::dvec3(-0.5, 0.05, -0.4));
  EXPECT_EQ(actions::jsonVec3(s.controls[1]["at"]), glm::dvec3(-0.7, 0.05, 0.5));
  EXPECT_EQ(s.controls[1]["tracts"], Json::array({"band_right"}));
  const Json& v = s.directions["vectors"].back();
  EXPECT_EQ(actions::jsonVec3(v["at"]), glm::dvec3(-0.4, 0.05, 0.2));
  EXPECT_NEAR(actions::jsonVec3(v["direction"]).x, -actions::jsonVec3(s.directions["vectors"][1]["direction"]).x,
              1e-12);
  ASSERT_TRUE(d.waitIdle()) << d.takeError().value_or("");

  // Mirroring again adds no brush, control or vector; the tract's copy exists, so that is an error.
  q.tracts.clear();
  d.endGesture();
  const MirrorResult again = mirrorScene(d, *rest, q);
  EXPECT_EQ(again.brushes, 0u);
  EXPECT_EQ(again.controls, 0u);
  EXPECT_EQ(again.vectors, 0u);
  q.tracts = {1};
  EXPECT_THROW(mirrorScene(d, *rest, q), Error);

  // One undo step takes all of it back.
  ASSERT_TRUE(d.undo());
  EXPECT_EQ(sceneJson(d.scene()), before);
}

TEST(Mirror, TheSymmetryPlaneOfTheSymmetricPatchIsXOrZEqualsZero) {
  Document d;
  d.reset(smallPatch(), "");
  ASSERT_TRUE(d.waitIdle());
  const MirrorPlane p = symmetryPlane(*d.snapshot().restSkin);
  // The patch is curved in y over x and z; a plane across y cannot be a symmetry plane.
  EXPECT_NE(p.axis, 1);
  EXPECT_NEAR(p.offset, 0.0, 1e-9);
  // Shifted mesh: the plane moves with it.
  coat::SkinMesh shifted = *d.snapshot().restSkin;
  for (auto& v : shifted.positions) v.x += 2.0;
  const MirrorPlane q = symmetryPlane(shifted);
  EXPECT_NE(q.axis, 1);
  EXPECT_NEAR(q.offset, q.axis == 0 ? 2.0 : 0.0, 1e-9);
}
