// Key-feather interpolation (Streit 2003, 6.2): Delaunay of key follicles in (u,v), barycentric weights,
// hull and degenerate cases, exact key feathers, scale jitter, JSON.
#include <gtest/gtest.h>

#include <numeric>

#include "coat2_fixtures.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/feather/interpolate.hpp"

using namespace coat2test;

namespace {

double weightSum(const BlendWeights& w) { return w.weight[0] + w.weight[1] + w.weight[2]; }

glm::dvec2 reconstruct(const KeyTriangulation& t, const BlendWeights& w) {
  glm::dvec2 p(0.0);
  for (int i = 0; i < w.count; ++i) p += w.weight[static_cast<size_t>(i)] * t.keys[w.key[static_cast<size_t>(i)]];
  return p;
}

struct GridCoat {
  SkinMesh mesh = makeGridPatch(12, 6, 2.0, 1.0);
  std::vector<Tract> tracts{wholeMeshTract(mesh)};
  Follicles follicles;
  TractParameterization param;
  GridCoat() {
    follicles = scatterTracts(mesh, tracts, 200);
    ParameterizeOptions o;
    o.method = ParamMethod::Projection;
    o.viewDirection = {0, 0, -1};
    o.up = {0, 1, 0};
    param = parameterizeTract(mesh, tracts[0], 0, follicles, o);
  }
};

}  // namespace

TEST(Coat2Keys, WeightsInsideTheHullAreBarycentric) {
  Rng rng(3);
  std::vector<glm::dvec2> keys;
  for (int i = 0; i < 12; ++i) keys.emplace_back(rng.uniform(), rng.uniform());
  keys.emplace_back(0, 0), keys.emplace_back(1, 0), keys.emplace_back(1, 1), keys.emplace_back(0, 1);
  const KeyTriangulation tri = triangulateKeys(keys);
  EXPECT_EQ(tri.hullEdges.size(), 4u);
  EXPECT_EQ(tri.triangles.size(), 2 * keys.size() - 2 - 4);  // 2n - 2 - h
  for (int i = 0; i < 2000; ++i) {
    const glm::dvec2 p(rng.uniform(), rng.uniform());
    const BlendWeights w = locateInKeys(tri, p);
    EXPECT_TRUE(w.inside);
    EXPECT_NEAR(weightSum(w), 1.0, 1e-12);
    for (double x : w.weight) EXPECT_GE(x, 0.0);
    const glm::dvec2 q = reconstruct(tri, w);
    EXPECT_NEAR(q.x, p.x, 1e-12);
    EXPECT_NEAR(q.y, p.y, 1e-12);
  }
  // At a key: that key alone.
  const BlendWeights atKey = locateInKeys(tri, keys[5]);
  EXPECT_EQ(atKey.count, 1);
  EXPECT_EQ(atKey.key[0], 5u);
  EXPECT_EQ(atKey.weight[0], 1.0);
}

TEST(Coat2Keys, OutsideTheHullUsesTheNearestEdge) {
  const std::vector<glm::dvec2> keys{{0, 0}, {1, 0}, {0, 1}};
  const KeyTriangulation tri = triangulateKeys(keys);
  BlendWeights w = locateInKeys(tri, {0.25, -0.5});  // below edge 0-1
  EXPECT_FALSE(w.inside);
  EXPECT_EQ(w.count, 2);
  EXPECT_NEAR(weightSum(w), 1.0, 1e-15);
  const glm::dvec2 q = reconstruct(tri, w);
  EXPECT_NEAR(q.x, 0.25, 1e-12);
  EXPECT_NEAR(q.y, 0.0, 1e-12);
  w = locateInKeys(tri, {-1, -1});  // beyond corner 0: clamps to that key
  EXPECT_EQ(w.count, 1);
  EXPECT_EQ(w.key[0], 0u);
  w = locateInKeys(tri, {1, 1});  // beyond the hypotenuse, projects to its middle
  EXPECT_EQ(w.count, 2);
  EXPECT_NEAR(w.weight[0], 0.5, 1e-12);
  EXPECT_NEAR(w.weight[1], 0.5, 1e-12);
}

TEST(Coat2Keys, DegenerateKeySets) {
  // One key: constant.
  const KeyTriangulation one = triangulateKeys({{0.3, 0.3}});
  EXPECT_EQ(locateInKeys(one, {0.9, 0.1}).count, 1);
  // Collinear keys: linear along the chain.
  const KeyTriangulation line = triangulateKeys({{1, 0}, {0, 0}, {0.5, 0}});
  EXPECT_TRUE(line.triangles.empty());
  EXPECT_EQ(line.hullEdges.size(), 2u);
  const BlendWeights w = locateInKeys(line, {0.8, 0.3});
  EXPECT_EQ(w.count, 2);
  EXPECT_TRUE(w.inside);
  EXPECT_NEAR(reconstruct(line, w).x, 0.8, 1e-12);
  EXPECT_NEAR(weightSum(w), 1.0, 1e-15);
  // Cocircular keys (a square) are triangulated deterministically.
  const std::vector<glm::dvec2> sq{{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  EXPECT_EQ(triangulateKeys(sq).triangles, triangulateKeys(sq).triangles);
  EXPECT_EQ(triangulateKeys(sq).triangles.size(), 2u);
}

TEST(Coat2Keys, FollicleAtAKeyGetsExactlyThatFeather) {
  GridCoat g;
  const FeatherLibrary lib = testLibrary();
  std::vector<KeyFeatherSpec> specs(4);
  const char* names[] = {"short", "long", "mid", "wide"};
  const glm::dvec3 at[] = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0.2, 0.9, 0}};
  for (int i = 0; i < 4; ++i) specs[i].feather = names[i], specs[i].at = at[i];
  specs[2].byFollicle = true;  // one by id
  specs[2].follicleId = g.follicles.id[g.param.follicles[77]];
  const auto keys = resolveKeyFeathers(g.follicles, g.param, specs, lib, "all");
  ASSERT_EQ(keys.size(), 4u);
  EXPECT_EQ(keys[2].follicle, g.param.follicles[77]);

  std::vector<TractKeys> tk(1);
  tk[0].param = &g.param;
  tk[0].keys = keys;
  tk[0].scaleJitter = 0.2;  // key feathers are exempt
  CoatFeathers coat;
  const InterpolateStats st = interpolateCoatFeathers(g.follicles, tk, lib, {}, coat);
  EXPECT_EQ(st.feathers, 200u);
  EXPECT_EQ(coat.size(), 200u);
  EXPECT_GT(st.blended, 150u);
  for (const auto& k : keys) {
    const auto it = std::find(coat.follicle.begin(), coat.follicle.end(), k.follicle);
    ASSERT_NE(it, coat.follicle.end());
    EXPECT_EQ(coat.params[static_cast<size_t>(it - coat.follicle.begin())], lib.at(k.feather)) << k.feather;
  }
  // Every blended scalar lies within the keys' range (a convex combination), jitter aside.
  tk[0].scaleJitter = 0.0;
  interpolateCoatFeathers(g.follicles, tk, lib, {}, coat);
  for (const auto& p : coat.params) {
    EXPECT_GE(p.rachisLength, 0.5 - 1e-12);
    EXPECT_LE(p.rachisLength, 2.0 + 1e-12);
    EXPECT_GE(p.rachisLateralCurvature, -0.2 - 1e-12);
    EXPECT_LE(p.rachisLateralCurvature, 0.3 + 1e-12);
  }
  EXPECT_EQ(coat.age, std::vector<double>(200, 1.0));
  EXPECT_EQ(coat.present, std::vector<uint8_t>(200, 1));
}

// The key blend each feather records (what its material blends by, issue #30 item 2) is the one its
// geometry was blended with: blending the named keys by the recorded weights gives the feather again.
TEST(Coat2Keys, RecordedKeyBlendReproducesEveryFeather) {
  GridCoat g;
  const FeatherLibrary lib = testLibrary();
  std::vector<KeyFeatherSpec> specs(4);
  const char* names[] = {"short", "long", "mid", "short"};  // one feather on two keys
  const glm::dvec3 at[] = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0.2, 0.9, 0}};
  for (int i = 0; i < 4; ++i) specs[i].feather = names[i], specs[i].at = at[i];
  std::vector<TractKeys> tk(1);
  tk[0].param = &g.param;
  tk[0].keys = resolveKeyFeathers(g.follicles, g.param, specs, lib, "all");
  CoatFeathers coat;
  interpolateCoatFeathers(g.follicles, tk, lib, {}, coat);
  ASSERT_EQ(coat.keyBlend.size(), coat.size());
  EXPECT_EQ(coat.keyNames, (std::vector<std::string>{"short", "long", "mid"}));
  size_t blended = 0;
  for (size_t i = 0; i < coat.size(); ++i) {
    const KeyBlend& kb = coat.keyBlend[i];
    ASSERT_GE(kb.count, 1);
    ASSERT_LE(kb.count, 3);
    std::vector<const feather::FeatherParams*> fs;
    std::vector<double> ws;
    double sum = 0;
    for (size_t k = 0; k < kb.count; ++k) {
      ASSERT_LT(kb.key[k], coat.keyNames.size());
      EXPECT_GT(kb.weight[k], 0.0);
      fs.push_back(&lib.at(coat.keyNames[kb.key[k]]));
      ws.push_back(kb.weight[k]);
      sum += kb.weight[k];
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    // Equal up to rounding (blendFeathers normalises the recorded weights once more).
    const feather::FeatherParams again = feather::blendFeathers(fs, ws);
    const feather::FeatherParams& p = coat.params[i];
    EXPECT_EQ(again.name, p.name) << "feather " << i;  // the heaviest key
    EXPECT_NEAR(again.rachisLength, p.rachisLength, 1e-12) << "feather " << i;
    EXPECT_NEAR(again.rachisLateralCurvature, p.rachisLateralCurvature, 1e-12) << "feather " << i;
    EXPECT_NEAR(again.barbLength, p.barbLength, 1e-12) << "feather " << i;
    EXPECT_NEAR(again.left.baseAngle, p.left.baseAngle, 1e-12) << "feather " << i;
    blended += kb.count > 1;
  }
  EXPECT_GT(blended, 150u);
}

TEST(Coat2Keys, OneAndTwoKeyTracts) {
  GridCoat g;
  const FeatherLibrary lib = testLibrary();
  std::vector<TractKeys> tk(1);
  tk[0].param = &g.param;
  // No key feathers: the tract's "feather".
  tk[0].keys = resolveKeyFeathers(g.follicles, g.param, {}, lib, "all", "mid");
  CoatFeathers coat;
  interpolateCoatFeathers(g.follicles, tk, lib, {}, coat);
  for (const auto& p : coat.params) EXPECT_EQ(p, lib.at("mid"));
  // Without "feather" and several feathers in the library it is an error naming the tract.
  EXPECT_THROW(resolveKeyFeathers(g.follicles, g.param, {}, lib, "all"), Error);

  // Two keys at the ends of the patch: rachis length linear in the projection onto the segment.
  std::vector<KeyFeatherSpec> specs(2);
  specs[0].feather = "short", specs[0].at = {0, 0.5, 0};
  specs[1].feather = "long", specs[1].at = {2, 0.5, 0};
  tk[0].keys = resolveKeyFeathers(g.follicles, g.param, specs, lib, "all");
  interpolateCoatFeathers(g.follicles, tk, lib, {}, coat);
  glm::dvec2 a(0.0), b(0.0);
  for (size_t k = 0; k < g.param.follicles.size(); ++k) {
    if (g.param.follicles[k] == tk[0].keys[0].follicle) a = g.param.follicleUv[k];
    if (g.param.follicles[k] == tk[0].keys[1].follicle) b = g.param.follicleUv[k];
  }
  for (size_t i = 0; i < coat.size(); ++i) {
    const glm::dvec2 uv = g.param.follicleUv[i];  // one tract: feather i = follicle i = param slot i
    ASSERT_EQ(coat.follicle[i], g.param.follicles[i]);
    const double t = std::clamp(glm::dot(uv - a, b - a) / glm::dot(b - a, b - a), 0.0, 1.0);
    EXPECT_NEAR(coat.params[i].rachisLength, 0.5 + t * 1.5, 1e-9);
  }
}

TEST(Coat2Keys, ScaleJitterIsSeededAndUniform) {
  GridCoat g;
  const FeatherLibrary lib = testLibrary();
  std::vector<KeyFeatherSpec> specs(3);
  specs[0].feather = "short", specs[0].at = {0, 0, 0};
  specs[1].feather = "long", specs[1].at = {2, 0, 0};
  specs[2].feather = "wide", specs[2].at = {1, 1, 0};
  std::vector<TractKeys> tk(1);
  tk[0].param = &g.param;
  tk[0].keys = resolveKeyFeathers(g.follicles, g.param, specs, lib, "all");
  CoatFeathers plain, jit, jit2, other;
  interpolateCoatFeathers(g.follicles, tk, lib, {}, plain);
  tk[0].scaleJitter = 0.25;
  InterpolateOptions o;
  o.seed = 11;
  interpolateCoatFeathers(g.follicles, tk, lib, o, jit);
  interpolateCoatFeathers(g.follicles, tk, lib, o, jit2);
  o.seed = 12;
  interpolateCoatFeathers(g.follicles, tk, lib, o, other);
  size_t changed = 0, differs = 0;
  for (size_t i = 0; i < plain.size(); ++i) {
    EXPECT_EQ(jit.params[i], jit2.params[i]);
    const double s = jit.params[i].rachisLength / plain.params[i].rachisLength;
    EXPECT_GE(s, 0.75 - 1e-12);
    EXPECT_LE(s, 1.25 + 1e-12);
    EXPECT_NEAR(jit.params[i].barbLength / plain.params[i].barbLength, s, 1e-12);
    EXPECT_NEAR(jit.params[i].calamusLength / plain.params[i].calamusLength, s, 1e-12);
    EXPECT_NEAR(jit.params[i].rachisWidth / plain.params[i].rachisWidth, s, 1e-12);
    EXPECT_NEAR(jit.params[i].spacingBase / plain.params[i].spacingBase, s, 1e-12);
    EXPECT_EQ(jit.params[i].rachisLateralCurvature, plain.params[i].rachisLateralCurvature);  // angles unchanged
    changed += std::abs(s - 1.0) > 1e-6;
    differs += other.params[i].rachisLength != jit.params[i].rachisLength;
  }
  EXPECT_GT(changed, plain.size() / 2);
  EXPECT_GT(differs, plain.size() / 2);
}

TEST(Coat2Keys, ResolveRejectsBadKeys) {
  GridCoat g;
  const FeatherLibrary lib = testLibrary();
  std::vector<KeyFeatherSpec> specs(2);
  specs[0].feather = "short", specs[0].at = {0, 0, 0};
  specs[1].feather = "long", specs[1].at = {0.0001, 0, 0};  // same nearest follicle
  EXPECT_THROW(resolveKeyFeathers(g.follicles, g.param, specs, lib, "all"), Error);
  specs.resize(1);
  specs[0].feather = "nonesuch";
  EXPECT_THROW(resolveKeyFeathers(g.follicles, g.param, specs, lib, "all"), Error);
  specs[0].feather = "short";
  specs[0].byFollicle = true;
  specs[0].follicleId = 999999999;
  try {
    resolveKeyFeathers(g.follicles, g.param, specs, lib, "all", {}, "scene.json");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "scene.json");
    EXPECT_NE(std::string(e.what()).find("999999999"), std::string::npos);
  }
}

TEST(Coat2Keys, ParseKeyFeathers) {
  const Json tract = Json::parse(R"({"name": "spinal", "density": 40,
    "parameterization": {"method": "lscm"},
    "key_feathers": [{"feather": "contour", "follicle": 12}, {"feather": "covert", "at": [0, 1, 2]}],
    "scale_jitter": 0.1, "feather": "contour"})");
  JsonReader r(tract, "scene.json", "tracts[0]");
  const TractFeatherOptions o = parseTractFeatherOptions(r);
  EXPECT_EQ(o.parameterization.method, ParamMethod::Lscm);
  ASSERT_EQ(o.keys.size(), 2u);
  EXPECT_TRUE(o.keys[0].byFollicle);
  EXPECT_EQ(o.keys[0].follicleId, 12u);
  EXPECT_FALSE(o.keys[1].byFollicle);
  EXPECT_EQ(o.keys[1].at, glm::dvec3(0, 1, 2));
  EXPECT_EQ(o.keys[1].element, "tracts[0].key_feathers[1]");
  EXPECT_EQ(o.scaleJitter, 0.1);
  EXPECT_EQ(o.feather, "contour");
  // The tract's own keys are left for the scene parser: finish() now complains about them.
  EXPECT_THROW(r.finish(), Error);

  for (const char* bad : {R"({"feather": "a", "follicle": 1, "at": [0,0,0]})", R"({"feather": "a"})",
                          R"({"feather": "a", "follicle": 1, "scale": 2})", R"({"feather": "a", "follicle": -1})",
                          R"({"follicle": 1})"}) {
    const Json j = Json::parse(bad);
    JsonReader k(j, "scene.json", "k");
    EXPECT_THROW(parseKeyFeather(k), Error) << bad;
  }
  const Json notArray = Json::parse(R"({"key_feathers": {"feather": "a"}})");
  JsonReader na(notArray, "scene.json", "tracts[1]");
  EXPECT_THROW(parseKeyFeathers(na), Error);
}
