// Pipeline::check on a real small scene (data/scenes/patch.json with 24 feathers, at full detail) against a
// reference without trees: the intersecting pairs of the coat mesh and of the unpacked proxy coat, and the
// feathers they belong to; progress "check" moves through the parts, and a callback returning false
// stops the check early (as does one that throws, the way the viewer and the host session cancel)
// without changing what a complete check reports afterwards.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "../../src/coat/spatial.hpp"
#include "pteryla/coat/check.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

using namespace pteryla;
using namespace pteryla::pipeline;

namespace {

// The bundled patch with `count` feathers (60 in the file).
Scene patch(int count = 60) {
  const std::string path = std::string(PTERYLA_DATA_DIR) + "/scenes/patch.json";
  std::ifstream in(path);
  Json j = Json::parse(in);
  j["tracts"][0]["count"] = count;
  return sceneFromJson(j, path);
}

struct Reference {
  size_t pairs = 0;
  std::set<uint32_t> feathers;
};

// Every pair of triangles of different feathers, Moeller's test on the lower index first: all pairs
// whose boxes overlap, found by sorting on the longest axis and sweeping (no tree; the full O(n^2) scan of the
// coat-level tests takes minutes on a real coat). Boxes padded by 1e-6 of the coat's size only skip pairs far apart
// (far more than the test's tolerance).
Reference bruteForce(const TriMesh& m) {
  const size_t nt = m.triangleCount();
  auto v = [&](size_t t, int k) { return glm::dvec3(m.positions[m.indices[3 * t + k]]); };
  auto feather = [&](size_t t) { return m.featherId[m.indices[3 * t]]; };
  coat::detail::Box all;
  std::vector<coat::detail::Box> box(nt);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) box[t].add(v(t, k)), all.add(v(t, k));
  const double pad = 1e-6 * (glm::length(all.hi - all.lo) + glm::length(glm::abs(all.lo) + glm::abs(all.hi)));
  for (auto& b : box) b.lo -= pad, b.hi += pad;
  const glm::dvec3 ext = all.hi - all.lo;
  const int ax = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
  std::vector<uint32_t> byX(nt);
  for (size_t t = 0; t < nt; ++t) byX[t] = static_cast<uint32_t>(t);
  std::sort(byX.begin(), byX.end(), [&](uint32_t a, uint32_t b) { return box[a].lo[ax] < box[b].lo[ax]; });
  Reference r;
  for (size_t i = 0; i < nt; ++i)
    for (size_t j = i + 1; j < nt && box[byX[j]].lo[ax] <= box[byX[i]].hi[ax]; ++j) {
      const size_t t = std::min(byX[i], byX[j]), u = std::max(byX[i], byX[j]);
      if (feather(t) == feather(u) || !box[t].overlaps(box[u])) continue;
      if (coat::detail::trianglesIntersect(v(t, 0), v(t, 1), v(t, 2), v(u, 0), v(u, 1), v(u, 2))) {
        ++r.pairs;
        r.feathers.insert(feather(t));
        r.feathers.insert(feather(u));
      }
    }
  return r;
}

}  // namespace

TEST(PipelineCheck, PairsAndFeathersAreTheBruteForceOnesOnARealScene) {
  Pipeline p(patch(24));
  const QualityMetrics m = p.check();
  ASSERT_TRUE(m.intersectingPairs && m.intersectingPairsUnpacked && m.skinPenetrations);
  p.setLod(1.0);
  const Reference coatRef = bruteForce(p.coatMesh().mesh);
  ASSERT_GT(coatRef.pairs, 0u);  // the patch's packed coat does cross (603 pairs with all 60 feathers)
  EXPECT_EQ(*m.intersectingPairs, coatRef.pairs);
  EXPECT_EQ(std::set<uint32_t>(m.intersectingFeathers.begin(), m.intersectingFeathers.end()), coatRef.feathers);
  EXPECT_TRUE(std::is_sorted(m.intersectingFeathers.begin(), m.intersectingFeathers.end()));
  EXPECT_EQ(m.penetratingFeathers.empty(), *m.skinPenetrations == 0);
  // The unpacked proxy coat: every feather at kUnpackedElevationDeg.
  const coat::CoatFeathers& c = p.feathers();
  const std::vector<double> flat(c.size(), kUnpackedElevationDeg * 3.14159265358979323846 / 180.0);
  EXPECT_EQ(*m.intersectingPairsUnpacked, bruteForce(coat::proxyCoatMesh(c, flat, c.params)).pairs);
}

TEST(PipelineCheck, ProgressMovesAndStoppingLeavesTheNextCheckWhole) {
  std::vector<double> seen;
  bool stopAt30 = false, stopped = false;
  size_t afterStop = 0;
  Pipeline p(patch(), [&](const std::string& stage, double f) {
    if (stage != "check") return true;
    if (stopped) ++afterStop;
    seen.push_back(f);
    if (stopAt30 && f > 0.3) stopped = true;
    return !stopped;
  });
  p.setLod(0.5);
  const QualityMetrics full = p.check();
  ASSERT_TRUE(full.intersectingPairs && full.intersectingPairsUnpacked);
  ASSERT_GE(seen.size(), 6u);
  EXPECT_EQ(seen.front(), 0.0);
  EXPECT_EQ(seen.back(), 1.0);
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  // Distinct values inside (0, 1): the bar moves between the ends.
  EXPECT_GE(std::count_if(seen.begin(), seen.end(), [](double f) { return f > 0 && f < 1; }), 4);
  EXPECT_EQ(p.lod(), 0.5);
  // Stopped past 30%: inside the checker, so its numbers are missing; the level of detail is restored.
  seen.clear();
  stopAt30 = true;
  const QualityMetrics cut = p.check();
  EXPECT_TRUE(stopped);
  EXPECT_EQ(afterStop, 0u);
  EXPECT_FALSE(cut.intersectingPairs);
  EXPECT_FALSE(cut.intersectingPairsUnpacked);
  EXPECT_EQ(cut.follicles, full.follicles);
  EXPECT_EQ(p.lod(), 0.5);
  // A complete check afterwards reports what the first one did.
  stopAt30 = stopped = false;
  const QualityMetrics again = p.check();
  EXPECT_EQ(again.intersectingPairs, full.intersectingPairs);
  EXPECT_EQ(again.intersectingPairsUnpacked, full.intersectingPairsUnpacked);
  EXPECT_EQ(again.intersectingPairsProxy, full.intersectingPairsProxy);
  EXPECT_EQ(again.skinPenetrations, full.skinPenetrations);
  EXPECT_EQ(again.coverage, full.coverage);
  EXPECT_EQ(again.intersectingFeathers, full.intersectingFeathers);
}

TEST(PipelineCheck, AThrowingCallbackLeavesTheCheckAndTheNextOneIsWhole) {
  // The viewer and the host session cancel by throwing from the progress callback.
  struct Cancelled {};
  bool cancel = false;
  bool thrown = false;
  Pipeline p(patch(), [&](const std::string& stage, double f) {
    if (cancel && stage == "check" && f > 0.5) {
      thrown = true;
      throw Cancelled{};
    }
    return true;
  });
  const QualityMetrics full = p.check();
  cancel = true;
  EXPECT_THROW(p.check(), Cancelled);
  EXPECT_TRUE(thrown);
  cancel = false;
  const QualityMetrics again = p.check();
  EXPECT_EQ(again.intersectingPairs, full.intersectingPairs);
  EXPECT_EQ(again.intersectingPairsUnpacked, full.intersectingPairsUnpacked);
  EXPECT_EQ(again.skinPenetrations, full.skinPenetrations);
  EXPECT_EQ(again.coverage, full.coverage);
}

namespace {

// A small draped scene: the sphere with 150 feathers.
Scene drapedSphere() {
  Json j = Json::parse(R"({"pteryla": 1, "seed": 3, "mesh": "meshes/sphere_1600.obj",
    "feathers": {"contour": "feathers/contour.json"},
    "tracts": [{"name": "all", "count": 150, "feather_scale": "auto", "feather_spacings": 3.0,
                "parameterization": {"method": "projection", "view_direction": [0, -1, 0]}}],
    "directions": {"axis": [[0, 1.5, 0], [0, -1.5, 0]]},
    "ordering": {"method": "axis", "axis": [[0, 1.5, 0], [0, -1.5, 0]]},
    "packing": {"method": "drape"}})");
  return sceneFromJson(j, std::string(PTERYLA_DATA_DIR) + "/scene_test.json");
}

// coat::check with Pipeline::check's options on the pipeline's full-detail coat, fast and reference.
void expectFastIsReference(Pipeline& p) {
  p.setLod(1.0);
  const TriMesh& mesh = p.coatMesh().mesh;
  std::vector<uint32_t> tractFaces;
  for (const auto& t : p.tracts()) tractFaces.insert(tractFaces.end(), t.faces.begin(), t.faces.end());
  std::sort(tractFaces.begin(), tractFaces.end());
  tractFaces.erase(std::unique(tractFaces.begin(), tractFaces.end()), tractFaces.end());
  coat::CheckOptions o;
  o.seed = p.scene().seed;
  o.attribute = true;
  coat::setFeatherBases(o, p.feathers(), coat::PackOptions{}.baseAllowance);
  const coat::CheckResult fast = coat::check(p.posedSkin(), tractFaces, mesh, o);
  o.reference = true;
  const coat::CheckResult ref = coat::check(p.posedSkin(), tractFaces, mesh, o);
  EXPECT_EQ(fast.intersectingPairs, ref.intersectingPairs);
  EXPECT_EQ(fast.skinPenetrations, ref.skinPenetrations);
  EXPECT_EQ(fast.penetratingFeathers, ref.penetratingFeathers);
  EXPECT_EQ(fast.featherPenetrations, ref.featherPenetrations);
  EXPECT_EQ(fast.coverage, ref.coverage);
  EXPECT_EQ(fast.faceUncovered, ref.faceUncovered);
  ASSERT_EQ(fast.featherPairs.size(), ref.featherPairs.size());
  for (size_t k = 0; k < fast.featherPairs.size(); ++k) {
    EXPECT_EQ(fast.featherPairs[k].a, ref.featherPairs[k].a);
    EXPECT_EQ(fast.featherPairs[k].b, ref.featherPairs[k].b);
    EXPECT_EQ(fast.featherPairs[k].pairs, ref.featherPairs[k].pairs);
  }
}

}  // namespace

TEST(PipelineCheck, FastCheckerGivesTheReferenceNumbersOnSmallScenes) {
  // The packed patch (its coat crosses) and a draped sphere (trimmed, collapsed triangles).
  Pipeline patchScene(patch(24));
  expectFastIsReference(patchScene);
  Pipeline sphere(drapedSphere());
  expectFastIsReference(sphere);
}

TEST(PipelineCheck, TheDrapeMovesTheMeshStagesProgressAndLaysTheSameCoat) {
  std::vector<double> mesh;
  Pipeline watched(drapedSphere(), [&](const std::string& stage, double f) {
    if (stage == "mesh") mesh.push_back(f);
    return true;
  });
  Pipeline quiet(drapedSphere());
  EXPECT_EQ(watched.coatMesh().mesh.positions, quiet.coatMesh().mesh.positions);
  EXPECT_EQ(watched.coatMesh().mesh.indices, quiet.coatMesh().mesh.indices);
  ASSERT_FALSE(mesh.empty());
  EXPECT_EQ(mesh.front(), 0.0);
  EXPECT_EQ(mesh.back(), 1.0);
  EXPECT_TRUE(std::is_sorted(mesh.begin(), mesh.end()));
  // The drape's steps and its checks' batches: many values between the ends.
  EXPECT_GE(std::count_if(mesh.begin(), mesh.end(), [](double f) { return f > 0.1 && f < 1; }), 10);
}

TEST(PipelineCheck, ACancelInsideTheDrapeLeavesTheNextMeshWhole) {
  // The drape now reports progress, so a host can cancel (throw) half way through it: the mesh stage
  // stays dirty, and the next evaluation lays the coat of a fresh pipeline, bit for bit.
  struct Cancelled {};
  bool cancel = true, thrown = false;
  Pipeline p(drapedSphere(), [&](const std::string& stage, double f) {
    if (cancel && stage == "mesh" && f > 0.6) {
      thrown = true;
      throw Cancelled{};
    }
    return true;
  });
  EXPECT_THROW(p.coatMesh(), Cancelled);
  EXPECT_TRUE(thrown);
  cancel = false;
  Pipeline fresh(drapedSphere());
  const TriMesh& a = p.coatMesh().mesh;
  const TriMesh& b = fresh.coatMesh().mesh;
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_EQ(a.indices, b.indices);
  EXPECT_EQ(p.check().intersectingPairs, fresh.check().intersectingPairs);
}
