// Surface directions and follicle frames (Streit 2003, 6.3.1), including re-evaluation on a deformed skin;
// layer ordering (6.3, 9.2.1).
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <numeric>

#include "coat2_fixtures.hpp"
#include "pteryla/coat/directions.hpp"
#include "pteryla/coat/ordering.hpp"
#include "pteryla/core/error.hpp"

using namespace coat2test;

namespace {

void expectFrame(const FeatherFrame& f, double tol = 1e-6) {
  EXPECT_NEAR(glm::length(f.normal), 1.0, tol);
  EXPECT_NEAR(glm::length(f.tangent), 1.0, tol);
  EXPECT_NEAR(glm::length(f.binormal), 1.0, tol);
  EXPECT_NEAR(glm::dot(f.normal, f.tangent), 0.0, tol);
  EXPECT_NEAR(glm::dot(f.normal, f.binormal), 0.0, tol);
  EXPECT_NEAR(glm::dot(f.tangent, f.binormal), 0.0, tol);
  const glm::dvec3 b = glm::cross(f.normal, f.tangent);
  EXPECT_NEAR(glm::length(b - f.binormal), 0.0, tol);
}

// Feathers for every follicle without keys (directions/ordering tests don't need feathers).
CoatFeathers coatOf(const Follicles& fol) {
  CoatFeathers c;
  for (uint32_t i = 0; i < fol.size(); ++i) c.follicle.push_back(i), c.tract.push_back(fol.tract[i]);
  c.params.resize(fol.size());
  c.frames.resize(fol.size());
  c.age.assign(fol.size(), 1.0);
  c.present.assign(fol.size(), 1);
  return c;
}

}  // namespace

TEST(Coat2Directions, AxisFramesAreOrthonormalAndTangent) {
  const SkinMesh sphere = makeIcosphere(3);
  const std::vector<Tract> tracts{wholeMeshTract(sphere)};
  const Follicles fol = scatterTracts(sphere, tracts, 500);
  DirectionOptions opt;
  opt.field.axis = {{0, 0, 1.5}, {0, 0, 0}, {0, 0, -1.5}};  // head at +z, tail at -z
  const SurfaceDirections dirs = computeSurfaceDirections(sphere, tracts, fol, opt);
  CoatFeathers coat = coatOf(fol);
  evaluateFrames(sphere, fol, dirs, coat);
  for (size_t i = 0; i < coat.size(); ++i) {
    const FeatherFrame& f = coat.frames[i];
    expectFrame(f);
    EXPECT_NEAR(glm::dot(f.tangent, normalAt(sphere, fol.face[i], fol.bary[i])), 0.0, 1e-12);
    EXPECT_NEAR(glm::length(f.origin - fol.position[i]), 0.0, 1e-12);
    // Away from the poles the feathers point toward the tail (-z), as the projected axis does.
    const glm::dvec3 n = f.normal;
    if (std::abs(n.z) < 0.9) {
      const glm::dvec3 down(0, 0, -1);
      const glm::dvec3 expect = glm::normalize(down - glm::dot(down, n) * n);
      EXPECT_GT(glm::dot(f.tangent, expect), 0.999) << i;
    }
  }
}

TEST(Coat2Directions, DegenerateDirectionsUseTheFallback) {
  const SkinMesh grid = makeGridPatch(5, 5);
  const std::vector<Tract> tracts{wholeMeshTract(grid)};
  const Follicles fol = scatterTracts(grid, tracts, 40);
  DirectionOptions opt;
  opt.field.axis = {{0.5, 0.5, 1}, {0.5, 0.5, -1}};  // along the normal everywhere
  opt.field.fallback = {0, 1, 0};
  SurfaceDirections dirs = computeSurfaceDirections(grid, tracts, fol, opt);
  EXPECT_EQ(dirs.fallbacks, fol.size());
  CoatFeathers coat = coatOf(fol);
  evaluateFrames(grid, fol, dirs, coat);
  for (const auto& f : coat.frames) {
    expectFrame(f);
    EXPECT_NEAR(glm::length(f.tangent - glm::dvec3(0, 1, 0)), 0.0, 1e-12);
  }
  // Fallback along the normal too: still a valid frame (from the face edge).
  opt.field.fallback = {0, 0, 1};
  dirs = computeSurfaceDirections(grid, tracts, fol, opt);
  evaluateFrames(grid, fol, dirs, coat);
  for (const auto& f : coat.frames) expectFrame(f);
  // No field at all: the fallback.
  DirectionOptions none;
  none.field.fallback = {1, 0, 0};
  dirs = computeSurfaceDirections(grid, tracts, fol, none);
  evaluateFrames(grid, fol, dirs, coat);
  for (const auto& f : coat.frames) EXPECT_NEAR(glm::length(f.tangent - glm::dvec3(1, 0, 0)), 0.0, 1e-12);
}

TEST(Coat2Directions, StylingVectorsBlendSmoothly) {
  const SkinMesh grid = makeGridPatch(20, 10, 10.0, 5.0);
  DirectionSpec s;
  s.vectors = {{{2, 2.5, 0}, {1, 0, 0}}, {{8, 2.5, 0}, {0, 3, 0}}};
  // Inverse-distance-squared: equal weights half way.
  glm::dvec3 d = glm::normalize(fieldDirection(s, {5, 2.5, 0}));
  EXPECT_NEAR(glm::length(d - glm::normalize(glm::dvec3(1, 1, 0))), 0.0, 1e-12);
  d = glm::normalize(fieldDirection(s, {2.1, 2.5, 0}));
  EXPECT_GT(d.x, 0.99);
  // Gaussian falloff: the nearest vector dominates, far from both too (no underflow).
  s.falloff = 0.5;
  d = glm::normalize(fieldDirection(s, {7, 2.5, 0}));
  EXPECT_GT(d.y, 0.999);
  d = glm::normalize(fieldDirection(s, {-100, 2.5, 0}));
  EXPECT_GT(d.x, 0.999);

  const std::vector<Tract> tracts{wholeMeshTract(grid)};
  const Follicles fol = scatterTracts(grid, tracts, 300);
  DirectionOptions opt;
  opt.field = s;
  const SurfaceDirections dirs = computeSurfaceDirections(grid, tracts, fol, opt);
  EXPECT_EQ(dirs.fallbacks, 0u);
  CoatFeathers coat = coatOf(fol);
  evaluateFrames(grid, fol, dirs, coat);
  for (size_t i = 0; i < coat.size(); ++i) {
    expectFrame(coat.frames[i]);
    const glm::dvec3 expect = glm::normalize(fieldDirection(s, fol.position[i]));
    EXPECT_NEAR(glm::length(coat.frames[i].tangent - expect), 0.0, 1e-9);
  }
}

TEST(Coat2Directions, FramesFollowTheDeformedSkin) {
  const SkinMesh rest = makeIcosphere(3);
  const std::vector<Tract> tracts{wholeMeshTract(rest)};
  const Follicles fol = scatterTracts(rest, tracts, 400);
  DirectionOptions opt;
  opt.field.vectors = {{{1, 0, 0}, {0, 1, 0}}, {{-1, 0, 0}, {0, 0, 1}}, {{0, 1, 0}, {1, 0, 1}}};
  const SurfaceDirections dirs = computeSurfaceDirections(rest, tracts, fol, opt);
  CoatFeathers restCoat = coatOf(fol), moved = coatOf(fol), stretched = coatOf(fol);
  evaluateFrames(rest, fol, dirs, restCoat);

  // Rigid motion: every frame moves with it.
  const glm::dmat4 m = glm::translate(glm::dmat4(1.0), glm::dvec3(3, -1, 2)) *
                       glm::rotate(glm::dmat4(1.0), 0.7, glm::normalize(glm::dvec3(1, 2, 3)));
  const glm::dmat3 rot(m);
  SkinMesh posed = rest;
  for (auto& p : posed.positions) p = glm::dvec3(m * glm::dvec4(p, 1.0));
  recomputeGeometry(posed);
  evaluateFrames(posed, fol, dirs, moved);
  for (size_t i = 0; i < fol.size(); ++i) {
    expectFrame(moved.frames[i]);
    EXPECT_NEAR(glm::length(moved.frames[i].origin - glm::dvec3(m * glm::dvec4(restCoat.frames[i].origin, 1.0))), 0,
                1e-9);
    EXPECT_NEAR(glm::length(moved.frames[i].normal - rot * restCoat.frames[i].normal), 0, 1e-9);
    EXPECT_NEAR(glm::length(moved.frames[i].tangent - rot * restCoat.frames[i].tangent), 0, 1e-9);
  }
  // Non-uniform stretch: frames stay orthonormal and tangent; directions turn only moderately.
  SkinMesh squashed = rest;
  for (auto& p : squashed.positions) p *= glm::dvec3(2.0, 1.0, 0.6);
  recomputeGeometry(squashed);
  evaluateFrames(squashed, fol, dirs, stretched);
  for (size_t i = 0; i < fol.size(); ++i) {
    expectFrame(stretched.frames[i]);
    EXPECT_NEAR(glm::dot(stretched.frames[i].tangent, normalAt(squashed, fol.face[i], fol.bary[i])), 0.0, 1e-12);
    // The rest direction, stretched with the skin, then projected: same sense.
    const glm::dvec3 t = restCoat.frames[i].tangent * glm::dvec3(2.0, 1.0, 0.6);
    EXPECT_GT(glm::dot(stretched.frames[i].tangent, glm::normalize(t)), 0.8);
  }
}

TEST(Coat2Directions, PerTractFieldsAndParsing) {
  const Json j = Json::parse(R"({
    "axis": [[0, 0, 1], [0, 0, -1]],
    "fallback": [0, 1, 0],
    "tracts": {"wing": {"vectors": [{"at": [1, 0, 0], "direction": [1, 0, 0]}], "falloff": 0.3}}})");
  JsonReader r(j, "scene.json", "directions");
  const DirectionOptions o = parseDirections(r);
  EXPECT_EQ(o.field.axis.size(), 2u);
  EXPECT_EQ(o.field.fallback, glm::dvec3(0, 1, 0));
  ASSERT_EQ(o.tracts.size(), 1u);
  EXPECT_EQ(o.tracts[0].first, "wing");
  EXPECT_EQ(o.tracts[0].second.vectors.size(), 1u);
  EXPECT_EQ(o.tracts[0].second.falloff, 0.3);

  const SkinMesh grid = makeGridPatch(8, 4, 2.0, 1.0);
  std::vector<Tract> tracts{tractWhere(grid, "body", [](const glm::dvec3& c) { return c.x < 1; }),
                            tractWhere(grid, "wing", [](const glm::dvec3& c) { return c.x >= 1; })};
  const Follicles fol = scatterTracts(grid, tracts, 30);
  DirectionOptions two;
  two.field.axis = {{0, 1, 0}, {0, -1, 0}};  // -y on the body
  two.tracts.push_back({"wing", DirectionSpec{}});
  two.tracts.back().second.fallback = {1, 0, 0};  // +x on the wing
  const SurfaceDirections dirs = computeSurfaceDirections(grid, tracts, fol, two);
  CoatFeathers coat = coatOf(fol);
  evaluateFrames(grid, fol, dirs, coat);
  for (size_t i = 0; i < fol.size(); ++i)
    EXPECT_NEAR(glm::length(coat.frames[i].tangent - (fol.tract[i] == 0 ? glm::dvec3(0, -1, 0) : glm::dvec3(1, 0, 0))),
                0, 1e-12);
  two.tracts[0].first = "tail";
  EXPECT_THROW(computeSurfaceDirections(grid, tracts, fol, two), Error);

  for (const char* bad :
       {R"({"axis": [[0,0,0]]})", R"({"axis": [[0,0,0],[0,0,0]]})",
        R"({"axis": [[0,0,0],[1,0,0]], "vectors": [{"at": [0,0,0], "direction": [1,0,0]}]})",
        R"({"vectors": [{"at": [0,0,0], "direction": [0,0,0]}]})",
        R"({"vectors": [{"at": [0,0,0], "direction": [1,0,0], "weight": 2}]})", R"({"axes": []})",
        R"({"tracts": {"wing": {"tracts": {}}}})", R"({"falloff": -1})",
        R"({"vectors": [{"at": [0,0,0], "direction": [1,0,0], "radius": 0.5}]})",
        R"({"axis": [[0,0,0],[1,0,0]], "vectors": [{"at": [0,0,0], "direction": [1,0,0], "radius": -1}]})"}) {
    const Json b = Json::parse(bad);
    JsonReader br(b, "scene.json", "directions");
    EXPECT_THROW(parseDirections(br), Error) << bad;
  }
}

// A combed axis (the viewer's comb): styling vectors over a body axis turn the field near them and leave
// the axis everywhere else.
TEST(Coat2Directions, StylingVectorsCombAnAxisLocally) {
  const Json j = Json::parse(R"({
    "axis": [[0, 0, 0], [10, 0, 0]],
    "vectors": [{"at": [5, 0, 0], "direction": [0, 2, 0], "radius": 0.5},
                {"at": [9, 0, 0], "direction": [0, 0, 1]}],
    "falloff": 0.8})");
  JsonReader r(j, "scene.json", "directions");
  const DirectionSpec s = parseDirections(r).field;
  ASSERT_EQ(s.axis.size(), 2u);
  ASSERT_EQ(s.vectors.size(), 2u);
  EXPECT_EQ(s.vectors[0].radius, 0.5);
  EXPECT_EQ(s.vectors[1].radius, 0.0);  // the field's falloff
  auto dirAt = [&](glm::dvec3 p) { return glm::normalize(fieldDirection(s, p)); };
  // At a vector: its direction (its coverage is 1), up to the other vector's tail (exp(-12.5) here).
  EXPECT_NEAR(glm::length(dirAt({5, 0, 0}) - glm::dvec3(0, 1, 0)), 0.0, 1e-5);
  EXPECT_NEAR(glm::length(dirAt({9, 0, 0}) - glm::dvec3(0, 0, 1)), 0.0, 1e-9);
  // Far from both: the axis (the remaining weight is exp(-d^2 / 2r^2), below 1e-9 here).
  EXPECT_NEAR(glm::length(dirAt({0.5, 0, 0}) - glm::dvec3(1, 0, 0)), 0.0, 1e-9);
  // One radius from the first vector: weight exp(-1/2) on it (the second's tail is exp(-15.8)).
  const double g = std::exp(-0.5);
  const glm::dvec3 expect = glm::normalize((1 - g) * glm::dvec3(1, 0, 0) + g * glm::dvec3(0, 1, 0));
  EXPECT_NEAR(glm::length(dirAt({4.5, 0, 0}) - expect), 0.0, 1e-6);
  // The axis itself is unchanged without vectors.
  DirectionSpec bare = s;
  bare.vectors.clear();
  EXPECT_EQ(fieldDirection(bare, {5, 0, 0}), glm::dvec3(1, 0, 0));
  // Over an axis, every vector needs a reach: a radius, or the field's falloff.
  const Json noReach =
      Json::parse(R"({"axis": [[0,0,0],[1,0,0]], "vectors": [{"at": [0,0,0], "direction": [0,1,0]}]})");
  JsonReader nr(noReach, "scene.json", "directions");
  try {
    parseDirections(nr);
    ADD_FAILURE() << "a vector over an axis without a reach was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("radius"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("directions.vectors"), std::string::npos) << e.what();
  }
  DirectionSpec direct = s;
  direct.falloff = 0;
  direct.vectors[1].radius = 0;
  const SkinMesh grid = makeGridPatch(4, 4);
  const std::vector<Tract> tracts{wholeMeshTract(grid)};
  const Follicles fol = scatterTracts(grid, tracts, 10);
  DirectionOptions o;
  o.field = direct;
  EXPECT_THROW(computeSurfaceDirections(grid, tracts, fol, o), Error);
}

TEST(Coat2Ordering, TotalOrderDownstreamFirst) {
  const SkinMesh grid = makeGridPatch(10, 4, 5.0, 2.0);
  const std::vector<Tract> tracts{wholeMeshTract(grid)};
  const Follicles fol = scatterTracts(grid, tracts, 150);
  ParameterizeOptions po;
  po.method = ParamMethod::Lscm;
  const std::vector<TractParameterization> params{parameterizeTract(grid, tracts[0], 0, fol, po)};
  DirectionOptions dopt;
  dopt.field.axis = {{0, 1, 0}, {5, 1, 0}};  // feathers point along +x
  const SurfaceDirections dirs = computeSurfaceDirections(grid, tracts, fol, dopt);
  CoatFeathers coat = coatOf(fol);
  evaluateFrames(grid, fol, dirs, coat);
  const OrderResult r = orderLayers(grid, tracts, params, fol, dirs, OrderOptions{}, coat);
  // A permutation of the feathers.
  std::vector<uint32_t> sorted = coat.layerOrder;
  std::sort(sorted.begin(), sorted.end());
  std::vector<uint32_t> all(coat.size());
  std::iota(all.begin(), all.end(), 0u);
  EXPECT_EQ(sorted, all);
  // Bottom layer first = furthest along +x first: x never increases along the order.
  for (size_t k = 0; k + 1 < coat.size(); ++k) {
    const glm::dvec3 a = fol.position[coat.follicle[coat.layerOrder[k]]];
    const glm::dvec3 b = fol.position[coat.follicle[coat.layerOrder[k + 1]]];
    EXPECT_GE(a.x, b.x - 1e-9) << k;
    EXPECT_GE(r.key[coat.layerOrder[k]], r.key[coat.layerOrder[k + 1]]);
  }
  const glm::dvec3 t0 = coat.frames[coat.layerOrder[0]].tangent;
  EXPECT_GT(t0.x, 0.999);
  // Deterministic.
  CoatFeathers again = coat;
  orderLayers(grid, tracts, params, fol, dirs, OrderOptions{}, again);
  EXPECT_EQ(again.layerOrder, coat.layerOrder);
}

TEST(Coat2Ordering, TiesBrokenByFollicleId) {
  // Follicles placed on a column share x: the key ties, so ids decide.
  const SkinMesh grid = makeGridPatch(4, 4, 4.0, 4.0);
  const std::vector<Tract> tracts{wholeMeshTract(grid)};
  Follicles fol;
  const uint64_t ids[] = {50, 10, 40, 20, 30};
  for (int k = 0; k < 5; ++k) {
    const SurfacePoint sp = closestSurfacePoint(grid, glm::dvec3(2.5, 0.3 + 0.8 * k, 0));
    fol.push(grid, sp.face, sp.bary, 0, ids[k]);
  }
  ParameterizeOptions po;
  po.method = ParamMethod::Projection;
  po.viewDirection = {0, 0, -1};
  const std::vector<TractParameterization> params{parameterizeTract(grid, tracts[0], 0, fol, po)};
  DirectionOptions dopt;
  dopt.field.fallback = {1, 0, 0};
  const SurfaceDirections dirs = computeSurfaceDirections(grid, tracts, fol, dopt);
  CoatFeathers coat = coatOf(fol);
  orderLayers(grid, tracts, params, fol, dirs, OrderOptions{}, coat);
  std::vector<uint64_t> got;
  for (uint32_t i : coat.layerOrder) got.push_back(fol.id[coat.follicle[i]]);
  EXPECT_EQ(got, (std::vector<uint64_t>{10, 20, 30, 40, 50}));
}

TEST(Coat2Ordering, TractOrderAndBodyAxis) {
  const SkinMesh sphere = makeIcosphere(3);
  std::vector<Tract> tracts{tractWhere(sphere, "front", [](const glm::dvec3& c) { return c.z > 0.1; }),
                            tractWhere(sphere, "back", [](const glm::dvec3& c) { return c.z < -0.1; })};
  const Follicles fol = scatterTracts(sphere, tracts, 120);
  std::vector<TractParameterization> params;
  for (uint32_t t = 0; t < 2; ++t) params.push_back(parameterizeTract(sphere, tracts[t], t, fol));
  DirectionOptions dopt;
  dopt.field.axis = {{0, 0, 2}, {0, 0, -2}};
  const SurfaceDirections dirs = computeSurfaceDirections(sphere, tracts, fol, dopt);
  CoatFeathers coat = coatOf(fol);
  evaluateFrames(sphere, fol, dirs, coat);

  OrderOptions o;
  o.tractOrder = {"back"};  // back first, then the unlisted "front"
  orderLayers(sphere, tracts, params, fol, dirs, o, coat);
  for (size_t k = 0; k < coat.size(); ++k) EXPECT_EQ(coat.tract[coat.layerOrder[k]], k < 120 ? 1u : 0u);
  o.tractOrder = {"nope"};
  EXPECT_THROW(orderLayers(sphere, tracts, params, fol, dirs, o, coat), Error);

  // Body axis: tail (-z) first, across tracts.
  o = OrderOptions{};
  o.method = OrderMethod::Axis;
  o.axis = dopt.field.axis;
  orderLayers(sphere, tracts, params, fol, dirs, o, coat);
  for (size_t k = 0; k + 1 < coat.size(); ++k)
    EXPECT_LE(fol.position[coat.follicle[coat.layerOrder[k]]].z,
              fol.position[coat.follicle[coat.layerOrder[k + 1]]].z + 1e-12);

  // Body axis with a listed tract: "front" is packed first (the bottom layer, e.g. flight feathers under
  // their coverts), each group in the axis order; without the list the order is the global axis order.
  const std::vector<uint32_t> global = coat.layerOrder;
  o.tractOrder = {"front"};
  orderLayers(sphere, tracts, params, fol, dirs, o, coat);
  std::vector<uint32_t> expect;
  for (uint32_t t : {0u, 1u})
    for (uint32_t i : global)
      if (coat.tract[i] == t) expect.push_back(i);
  EXPECT_EQ(coat.layerOrder, expect);
  o.tractOrder = {"nope"};
  EXPECT_THROW(orderLayers(sphere, tracts, params, fol, dirs, o, coat), Error);
  o.tractOrder.clear();

  const Json j = Json::parse(R"({"method": "axis", "axis": [[0,0,1],[0,0,-1]], "tracts": ["a", "b"]})");
  JsonReader r(j, "scene.json", "ordering");
  const OrderOptions parsed = parseOrdering(r);
  EXPECT_EQ(parsed.method, OrderMethod::Axis);
  EXPECT_EQ(parsed.tractOrder, (std::vector<std::string>{"a", "b"}));
  for (const char* bad :
       {R"({"method": "axis"})", R"({"method": "random"})", R"({"order": []})", R"({"tracts": [1]})"}) {
    const Json b = Json::parse(bad);
    JsonReader br(b, "scene.json", "ordering");
    EXPECT_THROW(parseOrdering(br), Error) << bad;
  }
}
