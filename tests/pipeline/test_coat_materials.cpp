// The coat's materials (src/pipeline/coat_materials.hpp; issue #30 item 2): a feather blended from key
// feathers gets the blend of their looks by its geometry's weights quantised to 1/8; copies of a key and
// blends of look-alike keys keep the key's own material; the number of materials is bounded; the
// pipeline's material list follows the rest coat and not the time.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <set>

#include "coat_materials.hpp"
#include "pteryla/coat/key_feathers.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

using namespace pteryla;
using namespace pteryla::pipeline;

namespace {

feather::FeatherParams coloured(const std::string& name, glm::dvec3 colour) {
  feather::FeatherParams p;
  p.name = name;
  p.material.baseColor = colour;
  return p;
}

// A coat whose feathers are named by the heaviest key, with the given key blends.
coat::CoatFeathers coatOf(const std::vector<std::string>& keyNames, const std::vector<coat::KeyBlend>& blends) {
  coat::CoatFeathers c;
  c.keyNames = keyNames;
  for (const coat::KeyBlend& b : blends) {
    size_t top = 0;
    for (size_t k = 1; k < b.count; ++k)
      if (b.weight[k] > b.weight[top]) top = k;
    feather::FeatherParams p;
    p.name = keyNames[b.key[top]];
    c.params.push_back(p);
    c.follicle.push_back(static_cast<uint32_t>(c.follicle.size()));
    c.keyBlend.push_back(b);
  }
  return c;
}

coat::KeyBlend blend2(uint32_t a, uint32_t b, double wa) {
  coat::KeyBlend k;
  k.key = {a, b, 0};
  k.weight = {wa, 1.0 - wa, 0};
  k.count = 2;
  return k;
}

}  // namespace

TEST(CoatMaterials, QuantisedWeightsSumToTheStepsAndFollowTheLargestRemainders) {
  EXPECT_EQ(quantiseWeights({0.5, 0.5}, 8), (std::vector<int>{4, 4}));
  EXPECT_EQ(quantiseWeights({1.0 / 3, 1.0 / 3, 1.0 / 3}, 8), (std::vector<int>{3, 3, 2}));
  EXPECT_EQ(quantiseWeights({0.05, 0.95}, 8), (std::vector<int>{0, 8}));
  EXPECT_EQ(quantiseWeights({0.2, 0.3, 0.5}, 8), (std::vector<int>{2, 2, 4}));  // 1.6, 2.4, 4
  Rng rng(7);
  for (int i = 0; i < 200; ++i) {
    std::vector<double> w = {rng.uniform(), rng.uniform(), rng.uniform()};
    const double s = w[0] + w[1] + w[2];
    for (double& x : w) x /= s;
    const std::vector<int> q = quantiseWeights(w, 8);
    EXPECT_EQ(std::accumulate(q.begin(), q.end(), 0), 8);
    for (size_t k = 0; k < 3; ++k) EXPECT_LE(std::abs(q[k] / 8.0 - w[k]), 1.0 / 8 + 1e-12);
  }
}

TEST(CoatMaterials, HalfwayFeatherGetsTheHalfwayBlendAndCopiesKeepTheirKey) {
  const coat::FeatherLibrary lib = {{"red", coloured("red", {0.9, 0.1, 0.1})},
                                    {"blue", coloured("blue", {0.1, 0.2, 0.9})}};
  coat::KeyBlend copy;
  copy.key = {1, 0, 0};
  const coat::CoatFeathers c = coatOf(
      {"red", "blue"}, {copy, blend2(0, 1, 0.5), blend2(0, 1, 0.48), blend2(0, 1, 1.0 - 1e-9), blend2(0, 1, 0.3)});
  const CoatMaterials m = coatMaterials({"red", "blue"}, lib, c);
  ASSERT_EQ(m.featherMaterial.size(), 5u);
  EXPECT_EQ(m.featherMaterial[0], 1u);  // a copy of blue
  EXPECT_EQ(m.featherMaterial[3], 0u);  // weights (1, 0) after quantisation: red's own material
  // 0.5 and 0.48 both quantise to 4/8 each: one shared material.
  EXPECT_EQ(m.featherMaterial[1], m.featherMaterial[2]);
  ASSERT_EQ(m.materials.size(), 4u);  // red, blue, 4/8 + 4/8, 2/8 + 6/8
  const CoatMaterial& half = m.materials[m.featherMaterial[1]];
  ASSERT_EQ(half.blend.size(), 2u);
  EXPECT_EQ(half.blend[0], (MaterialWeight{0, 0.5}));
  EXPECT_EQ(half.blend[1], (MaterialWeight{1, 0.5}));
  EXPECT_FLOAT_EQ(half.baseColor.x, 0.5f);
  EXPECT_FLOAT_EQ(half.baseColor.z, 0.5f);
  EXPECT_EQ(half.name, "red 1/2 + blue 1/2");
  const CoatMaterial& third = m.materials[m.featherMaterial[4]];
  EXPECT_EQ(third.blend[0], (MaterialWeight{0, 0.25}));  // 0.3 x 8 = 2.4 -> 2
  EXPECT_EQ(third.blend[1], (MaterialWeight{1, 0.75}));
  // The definitions' own materials come first, unchanged.
  EXPECT_EQ(m.materials[0], definitionMaterial("red", lib.at("red")));
  EXPECT_EQ(m.materials[1], definitionMaterial("blue", lib.at("blue")));
}

TEST(CoatMaterials, KeysThatLookAlikeDoNotBlend) {
  // Same material under two names (the bird's primary and secondary): the feather keeps its heaviest
  // key's material, as before blending existed. A "down" name looks different (its barb mask).
  const coat::FeatherLibrary lib = {{"a", coloured("a", {0.3, 0.3, 0.3})},
                                    {"b", coloured("b", {0.3, 0.3, 0.3})},
                                    {"down", coloured("down", {0.3, 0.3, 0.3})}};
  const coat::CoatFeathers c = coatOf({"a", "b", "down"}, {blend2(0, 1, 0.4), blend2(0, 2, 0.5)});
  const CoatMaterials m = coatMaterials({"a", "b", "down"}, lib, c);
  EXPECT_EQ(m.featherMaterial[0], 1u);  // "b", the heaviest
  EXPECT_EQ(m.materials.size(), 4u);
  EXPECT_EQ(m.featherMaterial[1], 3u);
}

TEST(CoatMaterials, AtMostFortyTwoBlendsPerTriangleOfKeys) {
  // Every weight over a triangle of three different keys: 21 blends of all three (compositions of 8
  // into three positive parts) and 7 of each pair.
  const coat::FeatherLibrary lib = {
      {"a", coloured("a", {1, 0, 0})}, {"b", coloured("b", {0, 1, 0})}, {"c", coloured("c", {0, 0, 1})}};
  std::vector<coat::KeyBlend> blends;
  const int n = 60;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      coat::KeyBlend k;
      k.key = {0, 1, 2};
      k.weight = {double(i) / n, double(j) / n, double(n - i - j) / n};
      k.count = 3;
      blends.push_back(k);
    }
  const CoatMaterials m = coatMaterials({"a", "b", "c"}, lib, coatOf({"a", "b", "c"}, blends));
  EXPECT_EQ(m.materials.size(), 3u + 21u + 3u * 7u);
  std::set<std::vector<std::pair<uint32_t, double>>> distinct;
  for (size_t k = 3; k < m.materials.size(); ++k) {
    const CoatMaterial& mat = m.materials[k];
    ASSERT_GE(mat.blend.size(), 2u);
    double sum = 0;
    std::vector<std::pair<uint32_t, double>> key;
    for (const MaterialWeight& w : mat.blend) {
      EXPECT_LT(w.material, 3u);
      EXPECT_EQ(w.weight * 8, std::round(w.weight * 8));
      sum += w.weight;
      key.emplace_back(w.material, w.weight);
    }
    EXPECT_DOUBLE_EQ(sum, 1.0);
    distinct.insert(key);
  }
  EXPECT_EQ(distinct.size(), m.materials.size() - 3);
}

TEST(CoatMaterials, PipelineBlendsThePatchKeysAndKeepsTheListOverTime) {
  Scene scene = loadScene(std::string(PTERYLA_DATA_DIR) + "/scenes/patch.json");
  scene.moult = Json::parse(R"({"start": 0.5, "duration": 2})");
  Pipeline p(std::move(scene));
  p.setLod(0.2);
  const CoatMesh& mesh = p.coatMesh();
  const coat::CoatFeathers& f = p.feathers();
  ASSERT_EQ(f.keyBlend.size(), f.size());
  ASSERT_GT(mesh.materials.size(), 2u);  // contour, covert and blends of the two
  EXPECT_EQ(mesh.materials[0].name, "contour");
  EXPECT_EQ(mesh.materials[1].name, "covert");
  size_t blended = 0;
  for (const CoatDrawRange& r : mesh.ranges) {
    const coat::KeyBlend& kb = f.keyBlend[r.feather];
    ASSERT_LT(r.material, mesh.materials.size());
    const CoatMaterial& m = mesh.materials[r.material];
    if (kb.count == 1) {
      EXPECT_EQ(m.name, f.keyNames[kb.key[0]]);  // key feathers and copies: their own material
      continue;
    }
    // The material's weights are the geometry's, quantised.
    std::vector<double> w(kb.weight.begin(), kb.weight.begin() + kb.count);
    const std::vector<int> q = quantiseWeights(w, kMaterialWeightSteps);
    for (size_t k = 0; k < kb.count; ++k) {
      if (q[k] == 0) continue;
      const uint32_t def = f.keyNames[kb.key[k]] == "contour" ? 0u : 1u;
      double inMaterial = m.blend.empty() ? (r.material == def ? 1.0 : 0.0) : 0.0;
      for (const MaterialWeight& mw : m.blend)
        if (mw.material == def) inMaterial += mw.weight;
      double inGeometry = 0;
      for (size_t j = 0; j < kb.count; ++j)
        if (f.keyNames[kb.key[j]] == f.keyNames[kb.key[k]]) inGeometry += q[j] / double(kMaterialWeightSteps);
      EXPECT_DOUBLE_EQ(inMaterial, inGeometry) << "feather " << r.feather;
    }
    blended += !m.blend.empty();
  }
  EXPECT_GT(blended, 10u);
  const std::vector<CoatMaterial> before = mesh.materials;
  p.setTime(1.5);  // feathers moult out and grow: the materials stay
  EXPECT_LT(p.coatMesh().ranges.size(), f.size());
  EXPECT_EQ(p.coatMesh().materials, before);
}
