// The painting tools' core (paint.hpp, actions.hpp): which faces a brush covers, the density dab, tract
// face edits (kept as groups plus faces when only adding, a face list otherwise), new tracts from a face
// selection, and the painted density map through undo, `set` and Save / reload. No display.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include <glm/geometric.hpp>

#include "actions.hpp"
#include "document.hpp"
#include "fixtures.hpp"
#include "paint.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "scene_edit.hpp"

using namespace pteryla;
using namespace pteryla::viewer;
using viewer_test::scratchDir;
using viewer_test::smallPatch;

namespace {

std::shared_ptr<const coat::SkinMesh> restOf(Document& d) {
  EXPECT_TRUE(d.waitIdle());
  return d.snapshot().restSkin;
}

std::vector<uint32_t> allFaces(const coat::SkinMesh& m) {
  std::vector<uint32_t> out(m.sourceFace.begin(), m.sourceFace.end());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace

TEST(Paint, TheFaceBrushTakesExactlyTheTrianglesWhoseCentroidItCovers) {
  Document d;
  d.reset(smallPatch(), "");
  const auto rest = restOf(d);
  ASSERT_TRUE(rest);
  const glm::vec3 c(0.2f, 0.05f, -0.1f);
  const float r = 0.3f;
  const std::vector<uint32_t> faces = facesInBrush(*rest, {}, c, r);
  ASSERT_FALSE(faces.empty());
  EXPECT_TRUE(std::is_sorted(faces.begin(), faces.end()));
  EXPECT_EQ(std::adjacent_find(faces.begin(), faces.end()), faces.end());
  for (size_t t = 0; t < rest->faces.size(); ++t) {
    const auto& f = rest->faces[t];
    const glm::vec3 centroid = glm::vec3((rest->positions[f[0]] + rest->positions[f[1]] + rest->positions[f[2]]) / 3.0);
    const bool inside = glm::length(centroid - c) <= r;
    EXPECT_EQ(std::binary_search(faces.begin(), faces.end(), rest->sourceFace[t]), inside) << t;
  }
  // Measured on the posed vertices when given: moved away, the brush covers nothing.
  std::vector<glm::vec3> moved(rest->positions.size());
  for (size_t v = 0; v < moved.size(); ++v) moved[v] = glm::vec3(rest->positions[v]) + glm::vec3(0, 5, 0);
  EXPECT_TRUE(facesInBrush(*rest, moved, c, r).empty());
}

TEST(Paint, TheDensityDabFallsOffToNothingAtTheRim) {
  Document d;
  d.reset(smallPatch(), "");
  const auto rest = restOf(d);
  const glm::vec3 c = glm::vec3(rest->positions[220]);  // a vertex inside the sheet
  std::vector<float> f;
  densityDab(f, *rest, {}, c, 0.3f, 3.0f, 1.0f);
  ASSERT_EQ(f.size(), rest->positions.size());
  EXPECT_FLOAT_EQ(f[220], 3.0f);  // full strength at the centre
  for (size_t v = 0; v < f.size(); ++v) {
    const float dist = glm::length(glm::vec3(rest->positions[v]) - c);
    if (dist >= 0.3f) {
      EXPECT_EQ(f[v], 1.0f) << v;
    } else {
      EXPECT_GT(f[v], 1.0f) << v;
    }
    EXPECT_LE(f[v], 3.0f);
  }
  // Half strength goes half way at the centre.
  std::vector<float> g;
  densityDab(g, *rest, {}, c, 0.3f, 0.0f, 0.5f);
  EXPECT_FLOAT_EQ(g[220], 0.5f);
}

TEST(Paint, RemovingFacesTurnsTheTractIntoAFaceListAndAddingKeepsItsGroups) {
  Document d;
  d.reset(smallPatch(), "");
  const auto rest = restOf(d);
  const Json before = d.scene().tracts[0];
  const std::vector<uint32_t> all = allFaces(*rest);
  const std::vector<uint32_t> brush = facesInBrush(*rest, {}, {0.0f, 0.05f, 0.0f}, 0.35f);
  ASSERT_FALSE(brush.empty());
  // Adding faces the tract has changes nothing and records nothing.
  EXPECT_FALSE(actions::paintTractFaces(d, *rest, 0, brush, true));
  EXPECT_FALSE(d.canUndo());

  ASSERT_TRUE(actions::paintTractFaces(d, *rest, 0, brush, false));
  const Json& t = d.scene().tracts[0];
  EXPECT_FALSE(t.contains("groups"));
  ASSERT_TRUE(t.contains("faces"));
  EXPECT_EQ(t["faces"].get<std::vector<uint32_t>>(), faceDifference(all, brush));
  EXPECT_EQ(t["count"], before["count"]) << "the tract's own keys stay";
  // The pipeline reads the painted tract: its triangles are those of the remaining faces.
  ASSERT_TRUE(d.waitIdle());
  size_t expected = 0;
  for (uint32_t sf : rest->sourceFace) expected += std::binary_search(brush.begin(), brush.end(), sf) ? 0 : 1;
  EXPECT_EQ(d.snapshot().tractFaces[0].size(), expected);
  for (const glm::vec3& p : d.snapshot().follicle) EXPECT_GT(glm::length(p - glm::vec3(0, 0.05f, 0)), 0.2f);

  // One stroke, one undo step, exact.
  ASSERT_TRUE(d.undo());
  EXPECT_EQ(d.scene().tracts[0], before);
  ASSERT_TRUE(d.redo());

  // Painting back onto the face list appends (and the tract is whole again).
  ASSERT_TRUE(actions::paintTractFaces(d, *rest, 0, brush, true));
  EXPECT_EQ(actions::tractSourceFaces(d.scene(), *rest, 0), all);
}

TEST(Paint, AddingToAGroupTractListsOnlyTheNewFaces) {
  Document d;
  pipeline::Scene s = smallPatch();
  d.reset(s, "");
  const auto rest = restOf(d);
  const std::vector<uint32_t> strip = facesInBrush(*rest, {}, {-0.6f, 0.05f, 0.0f}, 0.3f);
  // A second tract with one face, then painted: it keeps `faces` as a list and gains the strip.
  actions::addTractFromFaces(d, "small", {strip.front()});
  EXPECT_EQ(d.scene().tracts[1]["feather"], "contour") << "the patch has two feathers: the tract names one";
  ASSERT_TRUE(actions::paintTractFaces(d, *rest, 1, strip, true));
  EXPECT_EQ(d.scene().tracts[1]["faces"].get<std::vector<uint32_t>>(), strip);
  // A tract of groups keeps them.
  d.edit("by groups", [&](pipeline::Scene& sc) {
    sc.tracts[1] = {{"name", "small"}, {"groups", {"patch"}}, {"feather", "contour"}, {"count", 10}};
  });
  EXPECT_FALSE(actions::paintTractFaces(d, *rest, 1, strip, true));  // the group has them all
  // Errors: removing every face, an existing name, an empty selection.
  const std::vector<uint32_t> all = allFaces(*rest);
  const Json beforeAll = d.scene().tracts;
  EXPECT_THROW(actions::paintTractFaces(d, *rest, 1, all, false), Error);
  EXPECT_EQ(d.scene().tracts, beforeAll);
  EXPECT_THROW(actions::addTractFromFaces(d, "small", strip), Error);
  EXPECT_THROW(actions::addTractFromFaces(d, "empty", {}), Error);
  ASSERT_TRUE(d.waitIdle());
}

TEST(Paint, ThePaintedDensityIsOneUndoStepSurvivesSetAndSavesNextToTheScene) {
  const std::string dir = scratchDir("paint_density");
  Document d;
  pipeline::Scene s = smallPatch();
  s.tracts[0].erase("count");
  s.tracts[0]["density"] = 40;
  d.reset(s, "");
  const auto rest = restOf(d);
  const size_t plain = d.snapshot().follicle.size();
  std::vector<float> f;
  densityDab(f, *rest, {}, {0.5f, 0.05f, 0.0f}, 0.6f, 4.0f, 0.8f);
  actions::setDensityFactors(d, f);
  ASSERT_TRUE(d.scene().densityFactor);
  for (float x : *d.scene().densityFactor) EXPECT_EQ(x, std::round(x * 1000.0f) / 1000.0f);
  ASSERT_TRUE(d.waitIdle());
  EXPECT_GT(d.snapshot().follicle.size(), plain + plain / 5) << "a factor up to 4 over a quarter of the sheet";

  // `set` re-reads the scene from JSON: the painted (unsaved) factors stay.
  d.edit("set", [&](pipeline::Scene& sc) { setScenePointer(sc, "/seed", 12); });
  ASSERT_TRUE(d.scene().densityFactor);
  EXPECT_TRUE(pipeline::sameDensityFactors(d.scene(), d.scene()));
  d.undo();
  ASSERT_TRUE(d.scene().densityFactor);

  ASSERT_TRUE(d.saveAs(dir + "/painted.json"));
  EXPECT_TRUE(std::filesystem::is_regular_file(dir + "/painted.density.json"));
  const pipeline::Scene back = pipeline::loadScene(dir + "/painted.json");
  ASSERT_TRUE(back.densityFactor);
  EXPECT_EQ(*back.densityFactor, *d.scene().densityFactor);
  ASSERT_TRUE(d.waitIdle());
  pipeline::Pipeline fresh(back);
  ASSERT_EQ(fresh.follicles().size(), d.snapshot().follicle.size());
  for (size_t i = 0; i < fresh.follicles().size(); ++i)
    EXPECT_EQ(glm::vec3(fresh.follicles().position[i]), d.snapshot().follicle[i]);

  // Clearing is one edit; undo brings the map back.
  actions::clearDensityMap(d);
  EXPECT_FALSE(d.scene().densityFactor);
  EXPECT_THROW(actions::clearDensityMap(d), Error);
  d.undo();
  EXPECT_TRUE(d.scene().densityFactor);
  d.undo();  // the paint itself
  EXPECT_FALSE(d.scene().densityFactor);
  ASSERT_TRUE(d.waitIdle());
  EXPECT_EQ(d.snapshot().follicle.size(), plain);
}
