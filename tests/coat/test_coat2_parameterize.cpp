// Tract parameterization (Streit 2003, 6.2.1): projection, LSCM/ARAP on disk-like tracts, rejection of
// tracts that are not disks.
#include <gtest/gtest.h>

#include "coat2_fixtures.hpp"
#include "pteryla/coat/parameterize.hpp"
#include "pteryla/core/error.hpp"

using namespace coat2test;

namespace {

void expectUnitSquare(const TractParameterization& p) {
  double maxCoord = 0;
  for (const auto& corners : p.cornerUv)
    for (const auto& uv : corners) {
      EXPECT_GE(uv.x, -1e-12);
      EXPECT_GE(uv.y, -1e-12);
      EXPECT_LE(uv.x, 1 + 1e-12);
      EXPECT_LE(uv.y, 1 + 1e-12);
      maxCoord = std::max({maxCoord, uv.x, uv.y});
    }
  EXPECT_NEAR(maxCoord, 1.0, 1e-12);
}

// The flat patch seen from above (orthographic along -z, y up): (u,v) = (x, y) / 2 on makeGridPatch(8, 4, 2, 1).
ParameterizeOptions topDown() {
  ParameterizeOptions o;
  o.method = ParamMethod::Projection;
  o.viewDirection = {0, 0, -1};
  o.up = {0, 1, 0};
  return o;
}

std::string errorText(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return {};
}

}  // namespace

TEST(Coat2Parameterize, LscmOnSphericalCapHasNoFlippedTriangles) {
  const SkinMesh sphere = makeIcosphere(3);
  const std::vector<Tract> tracts{tractWhere(sphere, "cap", [](const glm::dvec3& c) { return c.z > 0.2; })};
  const TractTopology topo = tractTopology(sphere, tracts[0]);
  EXPECT_TRUE(topo.isDisk());
  EXPECT_EQ(topo.boundaryLoops, 1u);
  EXPECT_EQ(topo.eulerCharacteristic(), 1);
  const Follicles fol = scatterTracts(sphere, tracts, 300);
  for (ParamMethod m : {ParamMethod::Lscm, ParamMethod::Arap, ParamMethod::Auto}) {
    ParameterizeOptions o;
    o.method = m;
    const TractParameterization p = parameterizeTract(sphere, tracts[0], 0, fol, o);
    EXPECT_EQ(p.method, m == ParamMethod::Arap ? ParamMethod::Arap : ParamMethod::Lscm);
    EXPECT_EQ(p.flippedFaces, 0u) << paramMethodName(m);
    for (double a : uvFaceAreas(p)) EXPECT_GT(a, 0.0);
    expectUnitSquare(p);
    EXPECT_EQ(p.follicles.size(), 300u);
    EXPECT_GT(p.scale, 0.5);  // the cap is ~1.7 units across
    EXPECT_LT(p.scale, 3.0);
  }
}

TEST(Coat2Parameterize, FollicleUvInterpolatesVertexUv) {
  const SkinMesh grid = makeGridPatch(8, 4, 2.0, 1.0);
  const std::vector<Tract> tracts{wholeMeshTract(grid)};
  const Follicles fol = scatterTracts(grid, tracts, 50);
  const TractParameterization p = parameterizeTract(grid, tracts[0], 0, fol, topDown());
  EXPECT_EQ(p.flippedFaces, 0u);
  EXPECT_NEAR(p.scale, 2.0, 1e-9);
  // Orthographic projection along -z of a flat patch: (u,v) = (x, y) / 2.
  for (size_t k = 0; k < p.follicles.size(); ++k) {
    const glm::dvec3 x = fol.position[p.follicles[k]];
    EXPECT_NEAR(p.follicleUv[k].x, x.x / 2.0, 1e-12);
    EXPECT_NEAR(p.follicleUv[k].y, x.y / 2.0, 1e-12);
  }
}

TEST(Coat2Parameterize, LscmOfFlatPatchIsASimilarity) {
  const SkinMesh grid = makeGridPatch(6, 6, 3.0, 1.5);
  const std::vector<Tract> tracts{wholeMeshTract(grid)};
  const Follicles fol = scatterTracts(grid, tracts, 40);
  ParameterizeOptions o;
  o.method = ParamMethod::Lscm;
  const TractParameterization p = parameterizeTract(grid, tracts[0], 0, fol, o);
  EXPECT_EQ(p.flippedFaces, 0u);
  const double ratio0 = glm::length(p.follicleUv[1] - p.follicleUv[0]) /
                        glm::length(fol.position[p.follicles[1]] - fol.position[p.follicles[0]]);
  for (size_t k = 2; k < p.follicles.size(); ++k) {
    const double r = glm::length(p.follicleUv[k] - p.follicleUv[0]) /
                     glm::length(fol.position[p.follicles[k]] - fol.position[p.follicles[0]]);
    EXPECT_NEAR(r, ratio0, 1e-6);
  }
  EXPECT_NEAR(p.scale, 1.0 / ratio0, 1e-6);
}

TEST(Coat2Parameterize, ClosedSphereIsRejectedByLscmAndCutByAuto) {
  const SkinMesh sphere = makeIcosphere(2);
  const std::vector<Tract> tracts{wholeMeshTract(sphere)};
  const Follicles fol = scatterTracts(sphere, tracts, 20);
  const TractTopology topo = tractTopology(sphere, tracts[0]);
  EXPECT_EQ(topo.boundaryLoops, 0u);
  EXPECT_EQ(topo.eulerCharacteristic(), 2);
  for (ParamMethod m : {ParamMethod::Lscm, ParamMethod::Arap}) {
    ParameterizeOptions o;
    o.method = m;
    const std::string msg = errorText([&] { parameterizeTract(sphere, tracts[0], 0, fol, o); });
    EXPECT_NE(msg.find("not a topological disk"), std::string::npos) << msg;
    EXPECT_NE(msg.find("split"), std::string::npos) << msg;
    EXPECT_NE(msg.find("projection"), std::string::npos) << msg;
  }
  // Auto without seams has nothing else to try on a closed sphere.
  ParameterizeOptions noSeams;
  noSeams.autoSeams = false;
  EXPECT_NE(errorText([&] { parameterizeTract(sphere, tracts[0], 0, fol, noSeams); }).find("not a topological disk"),
            std::string::npos);
  // Auto cuts it open along one seam path and flattens it.
  const TractParameterization p = parameterizeTract(sphere, tracts[0], 0, fol);
  EXPECT_EQ(p.method, ParamMethod::Lscm);
  EXPECT_GT(p.seamEdges, 2u);
  EXPECT_EQ(p.flippedFaces, 0u);
  expectUnitSquare(p);
  // Projection without a view direction has nothing to look along on a closed sphere.
  ParameterizeOptions o;
  o.method = ParamMethod::Projection;
  EXPECT_THROW(parameterizeTract(sphere, tracts[0], 0, fol, o), Error);
}

TEST(Coat2Parameterize, AnnulusAndCylinderAreRejectedByLscmAndCutByAuto) {
  const SkinMesh grid = makeGridPatch(10, 10, 1.0, 1.0);
  const std::vector<Tract> ring{tractWhere(
      grid, "ring", [](const glm::dvec3& c) { return std::abs(c.x - 0.5) > 0.2 || std::abs(c.y - 0.5) > 0.2; })};
  const TractTopology topo = tractTopology(grid, ring[0]);
  EXPECT_EQ(topo.boundaryLoops, 2u);
  EXPECT_EQ(topo.eulerCharacteristic(), 0);
  EXPECT_FALSE(topo.isDisk());
  const Follicles fol = scatterTracts(grid, ring, 30);
  ParameterizeOptions lscm;
  lscm.method = ParamMethod::Lscm;
  const std::string msg = errorText([&] { parameterizeTract(grid, ring[0], 0, fol, lscm); });
  EXPECT_NE(msg.find("2 boundary loop"), std::string::npos) << msg;
  // Auto: cut open along a seam joining the two boundary loops, then LSCM.
  const TractParameterization p = parameterizeTract(grid, ring[0], 0, fol, ParameterizeOptions{});
  EXPECT_EQ(p.method, ParamMethod::Lscm);
  EXPECT_GE(p.seamEdges, 3u);  // the hole is 3 edges away from the outer border
  EXPECT_FALSE(p.note.empty());
  EXPECT_EQ(p.flippedFaces, 0u);
  expectUnitSquare(p);
  // A flat annulus is conformally itself: the cut map is a similarity (the seam closes up again).
  const double ratio0 = glm::length(p.follicleUv[1] - p.follicleUv[0]) /
                        glm::length(fol.position[p.follicles[1]] - fol.position[p.follicles[0]]);
  for (size_t k = 2; k < p.follicles.size(); ++k)
    EXPECT_NEAR(glm::length(p.follicleUv[k] - p.follicleUv[0]) /
                    glm::length(fol.position[p.follicles[k]] - fol.position[p.follicles[0]]),
                ratio0, 1e-6);

  const SkinMesh tube = makeCylinder(12, 6);
  const std::vector<Tract> all{wholeMeshTract(tube)};
  const Follicles tf = scatterTracts(tube, all, 10);
  EXPECT_THROW(parameterizeTract(tube, all[0], 0, tf, lscm), Error);
  const TractParameterization tp = parameterizeTract(tube, all[0], 0, tf, ParameterizeOptions{});
  EXPECT_EQ(tp.flippedFaces, 0u);
  EXPECT_GT(tp.seamEdges, 0u);
}

TEST(Coat2Parameterize, AutoProjectsFlatPiecesAndRejectsHandles) {
  // Two separate strips of a flat patch: not one surface, but seen from the front: projected.
  const SkinMesh grid = makeGridPatch(10, 4, 1.0, 0.4);
  const std::vector<Tract> pieces{
      tractWhere(grid, "pieces", [](const glm::dvec3& c) { return c.x < 0.3 || c.x > 0.7; })};
  EXPECT_EQ(tractTopology(grid, pieces[0]).components, 2u);
  const Follicles fol = scatterTracts(grid, pieces, 20);
  const TractParameterization p = parameterizeTract(grid, pieces[0], 0, fol);
  EXPECT_EQ(p.method, ParamMethod::Projection);
  EXPECT_EQ(p.flippedFaces, 0u);
  // A torus has a handle: no seams are tried, and it cannot be projected.
  const SkinMesh torus = makeTorus(16, 8);
  const std::vector<Tract> all{wholeMeshTract(torus)};
  const Follicles tf = scatterTracts(torus, all, 10);
  const std::string msg = errorText([&] { parameterizeTract(torus, all[0], 0, tf); });
  EXPECT_NE(msg.find("Euler characteristic 0"), std::string::npos) << msg;
}

TEST(Coat2Parameterize, BowTieTractIsNotADisk) {
  // Two opposite corner quads of a 2x2 grid touch only at the centre vertex.
  const SkinMesh grid = makeGridPatch(2, 2, 2.0, 2.0);
  const Tract t = tractWhere(grid, "bowtie", [](const glm::dvec3& c) { return (c.x < 1) == (c.y < 1); });
  const TractTopology topo = tractTopology(grid, t);
  EXPECT_FALSE(topo.isDisk());
}

TEST(Coat2Parameterize, FollicleOutsideTractIsAnError) {
  const SkinMesh grid = makeGridPatch(4, 4);
  const std::vector<Tract> tracts{tractWhere(grid, "left", [](const glm::dvec3& c) { return c.x < 0.5; })};
  Follicles fol = scatterTracts(grid, {wholeMeshTract(grid)}, 40);  // all on tract index 0, some outside "left"
  EXPECT_THROW(parameterizeTract(grid, tracts[0], 0, fol), Error);
}

TEST(Coat2Parameterize, ParseRejectsUnknownKeysAndMethods) {
  const Json good = Json::parse(R"({"method": "projection", "view_direction": [0, 0, -1], "up": [0, 1, 0]})");
  JsonReader r(good, "scene.json", "tracts[0].parameterization");
  const ParameterizeOptions o = parseParameterization(r);
  EXPECT_EQ(o.method, ParamMethod::Projection);
  EXPECT_EQ(o.viewDirection, glm::dvec3(0, 0, -1));
  const Json unknown = Json::parse(R"({"method": "lscm", "metod": 1})");
  JsonReader r2(unknown, "scene.json", "p");
  EXPECT_THROW(parseParameterization(r2), Error);
  const Json badMethod = Json::parse(R"({"method": "conformal"})");
  JsonReader r3(badMethod, "scene.json", "p");
  EXPECT_THROW(parseParameterization(r3), Error);
}

TEST(Coat2Parameterize, BundledBirdTractsFlattenWithoutFolds) {
  const SkinMesh bird = loadSkinMesh(std::string(PTERYLA_DATA_DIR) + "/meshes/bird.obj");
  const Follicles none;
  size_t tracts = 0, cut = 0;
  for (const auto& g : bird.groupNames) {
    if (g.rfind("apteria", 0) == 0) continue;
    ++tracts;
    const Tract t = tractFromGroups(bird, g, {g});
    const TractParameterization p = parameterizeTract(bird, t, 0, none);
    EXPECT_EQ(p.method, ParamMethod::Lscm) << g;
    EXPECT_EQ(p.flippedFaces, 0u) << g;
    cut += p.seamEdges > 0;
  }
  EXPECT_EQ(tracts, 18u);  // the thesis' 18 tracts (9.2.1)
  EXPECT_EQ(cut, 3u);      // ventral and both crural tracts are bands around a hole
}

TEST(Coat2Parameterize, GridDistortionCarriesTheGridAlongWithTheMove) {
  // Flat patch seen from above: undistorted (u,v) = (x, y) / 2. One handle moves the grid around
  // (0.5, 0.25) by (0.06, 0.02) within 0.2: a follicle at g then has the grid coordinate q with
  // q + D(q) = g, follicles outside the radius keep theirs exactly, and the grid point under the handle's
  // centre is found where the centre moved to.
  const SkinMesh grid = makeGridPatch(8, 4, 2.0, 1.0);
  const std::vector<Tract> tracts{wholeMeshTract(grid)};
  const Follicles fol = scatterTracts(grid, tracts, 400);
  ParameterizeOptions o = topDown();
  const TractParameterization plain = parameterizeTract(grid, tracts[0], 0, fol, o);
  const GridDistortion h{{0.5, 0.25}, {0.06, 0.02}, 0.2};
  o.distortion = {h};
  const TractParameterization warped = parameterizeTract(grid, tracts[0], 0, fol, o);
  ASSERT_EQ(warped.follicles, plain.follicles);
  size_t moved = 0;
  for (size_t k = 0; k < plain.follicles.size(); ++k) {
    const glm::dvec2 g = plain.follicleUv[k], q = warped.follicleUv[k];
    const glm::dvec2 back = q + gridDisplacement(o.distortion, q);
    EXPECT_NEAR(back.x, g.x, 1e-12);
    EXPECT_NEAR(back.y, g.y, 1e-12);
    if (glm::length(g - h.at) > h.radius + glm::length(h.move)) {
      EXPECT_EQ(q, g);  // untouched outside the handle
    } else if (q != g) {
      ++moved;
    }
  }
  EXPECT_GT(moved, 10u);
  // The centre's grid point sits at centre + move on the surface.
  const glm::dvec2 c = undistortUv(o.distortion, h.at + h.move, "test");
  EXPECT_NEAR(c.x, h.at.x, 1e-12);
  EXPECT_NEAR(c.y, h.at.y, 1e-12);
  // Corners are undistorted the same way, so faceUv-based consumers (layer ordering) agree.
  EXPECT_EQ(warped.projectedCornerUv, plain.cornerUv);
  EXPECT_NE(warped.cornerUv, plain.cornerUv);
}

TEST(Coat2Parameterize, GridDistortionIsReadAndFoldsAreRefused) {
  const Json good =
      Json::parse(R"({"method": "projection", "distortion": [{"at": [0.5, 0.5], "move": [0.05, 0], "radius": 0.2}]})");
  JsonReader r(good, "scene.json", "tracts[0].parameterization");
  const ParameterizeOptions o = parseParameterization(r);
  ASSERT_EQ(o.distortion.size(), 1u);
  EXPECT_EQ(o.distortion[0].move, glm::dvec2(0.05, 0));
  EXPECT_EQ(o.distortion[0].radius, 0.2);
  // One handle moving further than 0.6 x its radius would fold the grid: refused, naming the key.
  const Json far = Json::parse(R"({"distortion": [{"at": [0.5, 0.5], "move": [0.2, 0], "radius": 0.2}]})");
  JsonReader r2(far, "scene.json", "tracts[0].parameterization");
  const std::string e = errorText([&] { parseParameterization(r2); });
  EXPECT_NE(e.find("distortion[0]"), std::string::npos) << e;
  EXPECT_NE(e.find("move"), std::string::npos) << e;
  // Stacked handles that together fold the grid: an Error, not a wrong answer or a hang.
  std::vector<GridDistortion> stacked(6, GridDistortion{{0.5, 0.5}, {0.11, 0}, 0.2});
  EXPECT_THROW(undistortUv(stacked, {0.55, 0.5}, "tracts.t.parameterization.distortion"), Error);
}
