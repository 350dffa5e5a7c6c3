// Blended feather looks (render/material_blend.hpp; issue #30 item 2), on the CPU: colours and
// textures blend by the weights, alpha-weighted; equal parts stay exact; BRDF parameters blend linearly;
// masks of different sizes are resampled; bad weights are refused.
#include <gtest/gtest.h>

#include <map>

#include "pteryla/core/error.hpp"
#include "pteryla/render/material_blend.hpp"
#include "pteryla/render/pattern.hpp"

using namespace pteryla;
using namespace pteryla::render;

namespace {

Image solid(int w, int h, uint8_t r, uint8_t g, uint8_t b, uint8_t a = 255) { return Image(w, h, r, g, b, a); }

const ImageLoader kNoFiles = [](const std::string& path) -> const Image& {
  throw Error("no files in this test", path);
};

FeatherMaterial textured(const Image& img, glm::vec3 base = glm::vec3(1.0f)) {
  FeatherMaterial m;
  m.colorImage = img;
  m.baseColor = base;
  m.alphaImage = generateBarbAlpha({});
  return m;
}

}  // namespace

TEST(MaterialBlend, ResampleKeepsSizeAndInterpolatesBilinearly) {
  Image two(2, 1);
  two.pixel(0, 0)[0] = 0;
  two.pixel(1, 0)[0] = 200;
  EXPECT_EQ(resampleImage(two, 2, 1).rgba, two.rgba);
  const Image four = resampleImage(two, 4, 1);
  // Texel centres 0.125, 0.375, 0.625, 0.875 of the source's 0.25 and 0.75 (clamped at the ends).
  EXPECT_EQ(four.pixel(0, 0)[0], 0);
  EXPECT_EQ(four.pixel(1, 0)[0], 50);
  EXPECT_EQ(four.pixel(2, 0)[0], 150);
  EXPECT_EQ(four.pixel(3, 0)[0], 200);
  EXPECT_THROW(resampleImage(Image(), 4, 4), Error);
  EXPECT_THROW(resampleImage(two, 0, 4), Error);
}

TEST(MaterialBlend, HalfwayBetweenTwoPatternsIsTheirMeanTexelByTexel) {
  const FeatherMaterial a = textured(solid(4, 8, 200, 40, 0), {1.0f, 0.5f, 1.0f});
  const FeatherMaterial b = textured(solid(4, 8, 0, 120, 255), {0.5f, 1.0f, 1.0f});
  const FeatherMaterial m = blendFeatherMaterials({a, b}, {0.5, 0.5}, "ab", kNoFiles);
  EXPECT_EQ(m.name, "ab");
  ASSERT_EQ(m.colorImage.width, 4);
  ASSERT_EQ(m.colorImage.height, 8);
  EXPECT_EQ(m.baseColor, glm::vec3(1.0f));  // the base colours are baked into the texture
  // base x texture: a = (200, 20, 0), b = (0, 120, 255); the mean (100, 70, 127.5).
  const uint8_t* p = m.colorImage.pixel(2, 3);
  EXPECT_EQ(p[0], 100);
  EXPECT_EQ(p[1], 70);
  EXPECT_NEAR(p[2], 127.5, 0.5);
  EXPECT_EQ(p[3], 255);
  // A quarter of the way: 3/4 a + 1/4 b.
  const FeatherMaterial q = blendFeatherMaterials({a, b}, {0.75, 0.25}, "q", kNoFiles);
  EXPECT_EQ(q.colorImage.pixel(0, 0)[0], 150);
  EXPECT_EQ(q.colorImage.pixel(0, 0)[1], 45);
  // The same alpha mask: kept as it is.
  EXPECT_EQ(m.alphaImage.rgba, a.alphaImage.rgba);
}

TEST(MaterialBlend, TransparentTexelsDoNotTintTheBlend) {
  // Outside b's vane outline (alpha 0) the blend is a's colour at half the opacity.
  const FeatherMaterial a = textured(solid(2, 2, 200, 100, 50, 255));
  const FeatherMaterial b = textured(solid(2, 2, 0, 0, 0, 0));
  const FeatherMaterial m = blendFeatherMaterials({a, b}, {0.5, 0.5}, "ab", kNoFiles);
  const uint8_t* p = m.colorImage.pixel(1, 1);
  EXPECT_EQ(p[0], 200);
  EXPECT_EQ(p[1], 100);
  EXPECT_EQ(p[2], 50);
  EXPECT_EQ(p[3], 128);  // 127.5 rounded
}

TEST(MaterialBlend, PlainColoursBlendWithoutATexture) {
  FeatherMaterial a, b;
  a.baseColor = {0.8f, 0.2f, 0.0f};
  b.baseColor = {0.0f, 0.4f, 1.0f};
  const FeatherMaterial m = blendFeatherMaterials({a, b}, {0.25, 0.75}, "ab", kNoFiles);
  EXPECT_TRUE(m.colorImage.empty());
  EXPECT_TRUE(m.colorTexture.empty());
  EXPECT_FLOAT_EQ(m.baseColor.x, 0.2f);
  EXPECT_FLOAT_EQ(m.baseColor.y, 0.35f);
  EXPECT_FLOAT_EQ(m.baseColor.z, 0.75f);
  // A plain part against a textured one: the plain part is its colour, opaque.
  const FeatherMaterial t = textured(solid(2, 2, 255, 255, 255, 0));
  const FeatherMaterial mixed = blendFeatherMaterials({a, t}, {0.5, 0.5}, "at", kNoFiles);
  EXPECT_EQ(mixed.colorImage.pixel(0, 0)[0], 204);  // a's 0.8, alone where t is transparent
  EXPECT_EQ(mixed.colorImage.pixel(0, 0)[3], 128);
}

TEST(MaterialBlend, SharedTextureKeepsItsFileAndBlendsBaseColours) {
  FeatherMaterial a, b;
  a.colorTexture = b.colorTexture = "/textures/barred.png";
  a.baseColor = {1.0f, 1.0f, 1.0f};
  b.baseColor = {0.5f, 0.0f, 1.0f};
  const FeatherMaterial m = blendFeatherMaterials({a, b}, {0.5, 0.5}, "ab", kNoFiles);  // nothing is loaded
  EXPECT_EQ(m.colorTexture, "/textures/barred.png");
  EXPECT_TRUE(m.colorImage.empty());
  EXPECT_FLOAT_EQ(m.baseColor.x, 0.75f);
  EXPECT_FLOAT_EQ(m.baseColor.y, 0.5f);
}

TEST(MaterialBlend, FileTexturesOfDifferentSizesAreLoadedAndResampled) {
  std::map<std::string, Image> files = {{"/a.png", solid(2, 4, 255, 0, 0)}, {"/b.png", solid(8, 16, 0, 0, 255)}};
  int loads = 0;
  const ImageLoader load = [&](const std::string& path) -> const Image& {
    ++loads;
    return files.at(path);
  };
  FeatherMaterial a, b;
  a.colorTexture = "/a.png";
  b.colorTexture = "/b.png";
  const FeatherMaterial m = blendFeatherMaterials({a, b}, {0.5, 0.5}, "ab", load);
  EXPECT_EQ(loads, 2);
  EXPECT_TRUE(m.colorTexture.empty());
  ASSERT_EQ(m.colorImage.width, 8);
  ASSERT_EQ(m.colorImage.height, 16);
  EXPECT_NEAR(m.colorImage.pixel(5, 9)[0], 128, 1);
  EXPECT_NEAR(m.colorImage.pixel(5, 9)[2], 128, 1);
}

TEST(MaterialBlend, AlphaMasksBlend) {
  FeatherMaterial a, b;
  BarbAlphaParams down;
  down.fluff = 1.0f;
  a.alphaImage = generateBarbAlpha({});
  b.alphaImage = generateBarbAlpha(down);
  const FeatherMaterial m = blendFeatherMaterials({a, b}, {0.5, 0.5}, "ab", kNoFiles);
  ASSERT_EQ(m.alphaImage.width, a.alphaImage.width);
  for (int y = 0; y < m.alphaImage.height; y += 7)
    for (int x = 0; x < m.alphaImage.width; x += 3) {
      const double mean = 0.5 * (a.alphaImage.pixel(x, y)[0] + b.alphaImage.pixel(x, y)[0]);
      EXPECT_NEAR(m.alphaImage.pixel(x, y)[0], mean, 0.5 + 1e-9) << x << "," << y;
      EXPECT_EQ(m.alphaImage.pixel(x, y)[3], m.alphaImage.pixel(x, y)[0]);
    }
}

TEST(MaterialBlend, BrdfParametersBlendLinearly) {
  FeatherMaterial a, b;
  a.barbules = {1.0, 0.0, 0.2};
  b.barbules = {3.0, 0.5, 0.2};
  a.specular = 0.25f;
  b.specular = 0.75f;
  const FeatherMaterial m = blendFeatherMaterials({a, b}, {0.375, 0.625}, "ab", kNoFiles);
  EXPECT_DOUBLE_EQ(m.barbules.d, 0.375 * 1.0 + 0.625 * 3.0);
  EXPECT_DOUBLE_EQ(m.barbules.h, 0.625 * 0.5);
  EXPECT_DOUBLE_EQ(m.barbules.sigma, 0.2);  // equal: kept exactly
  EXPECT_FLOAT_EQ(m.specular, 0.5625f);
}

TEST(MaterialBlend, PartsThatLookAlikeGiveTheFirstPartExactly) {
  FeatherMaterial a = textured(generatePattern({}), {0.3f, 0.2f, 0.1f});
  a.barbules = {1.7, 0.1, 0.2};
  a.name = "a";
  FeatherMaterial b = a;
  b.name = "b";
  const FeatherMaterial m = blendFeatherMaterials({a, b}, {0.375, 0.625}, "ab", kNoFiles);
  EXPECT_TRUE(sameLook(m, a));
  EXPECT_EQ(m.colorImage.rgba, a.colorImage.rgba);
  EXPECT_EQ(m.baseColor, a.baseColor);  // no 0.375 x + 0.625 x rounding
  EXPECT_EQ(m.barbules.d, a.barbules.d);
  // One part with all the weight: that part.
  FeatherMaterial c;
  c.baseColor = {0.9f, 0.1f, 0.4f};
  const FeatherMaterial one = blendFeatherMaterials({c}, {1.0}, "c", kNoFiles);
  EXPECT_TRUE(sameLook(one, c));
}

TEST(MaterialBlend, BadWeightsAreRefused) {
  FeatherMaterial a, b;
  b.baseColor = glm::vec3(0.5f);
  EXPECT_THROW(blendFeatherMaterials({}, {}, "x", kNoFiles), Error);
  EXPECT_THROW(blendFeatherMaterials({a, b}, {1.0}, "x", kNoFiles), Error);
  EXPECT_THROW(blendFeatherMaterials({a, b}, {0.5, 0.6}, "x", kNoFiles), Error);
  try {
    blendFeatherMaterials({a, b}, {1.0, 0.0}, "x", kNoFiles);
    FAIL() << "a zero weight was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "weights[1]");
  }
}
