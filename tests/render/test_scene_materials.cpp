// The coat's materials as the scene path hands them to the renderer (render::sceneMaterials): a
// feather definition's material.brdf overrides the scene's render.brdf; a blended material is the
// blend of its parts' looks, unset barbule parameters counting as the scene's (issue #30 item 2).
#include <gtest/gtest.h>

#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/render/material_blend.hpp"
#include "pteryla/render/scene_view.hpp"

using namespace pteryla;
using namespace pteryla::render;

namespace {

pipeline::CoatMesh twoKeysAndTheirBlend() {
  pipeline::CoatMesh coat;
  pipeline::CoatMaterial a, b, ab;
  a.name = "a";
  a.baseColor = {0.8f, 0.2f, 0.1f};
  a.brdfD = 3.0;
  a.brdfH = 0.5;
  b.name = "b";
  b.baseColor = {0.2f, 0.4f, 0.9f};  // no brdf: the scene's
  ab.name = "a 1/4 + b 3/4";
  ab.blend = {{0, 0.25}, {1, 0.75}};
  coat.materials = {a, b, ab};
  return coat;
}

}  // namespace

TEST(SceneMaterials, FeatherBrdfOverridesTheSceneAndBlendsWithIt) {
  pipeline::Scene scene;
  scene.render.brdfD = 1.0;
  scene.render.brdfH = 0.1;
  const std::vector<FeatherMaterial> m = sceneMaterials(scene, twoKeysAndTheirBlend());
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0].barbules.d, 3.0);
  EXPECT_EQ(m[0].barbules.h, 0.5);
  EXPECT_EQ(m[1].barbules.d, 1.0);
  EXPECT_EQ(m[1].barbules.h, 0.1);
  EXPECT_DOUBLE_EQ(m[2].barbules.d, 0.25 * 3.0 + 0.75 * 1.0);
  EXPECT_DOUBLE_EQ(m[2].barbules.h, 0.25 * 0.5 + 0.75 * 0.1);
  EXPECT_EQ(m[2].name, "a 1/4 + b 3/4");
  EXPECT_FLOAT_EQ(m[2].baseColor.x, 0.25f * 0.8f + 0.75f * 0.2f);
  EXPECT_FLOAT_EQ(m[2].baseColor.z, 0.25f * 0.1f + 0.75f * 0.9f);
  EXPECT_TRUE(m[2].colorImage.empty());                   // plain colours: no texture to bake
  EXPECT_EQ(m[2].alphaImage.rgba, m[0].alphaImage.rgba);  // the same barb mask
}

TEST(SceneMaterials, DefinitionsLookAsBeforeAndBlendsOfLookAlikesAreTheirLook) {
  pipeline::Scene scene;
  pipeline::CoatMesh coat = twoKeysAndTheirBlend();
  coat.materials[1] = coat.materials[0];
  coat.materials[1].name = "a2";
  const std::vector<FeatherMaterial> m = sceneMaterials(scene, coat);
  EXPECT_TRUE(sameLook(m[2], m[0]));
  EXPECT_EQ(m[2].baseColor, m[0].baseColor);
}

TEST(SceneMaterials, BadBlendsAreRefusedNamingTheMaterial) {
  pipeline::Scene scene;
  pipeline::CoatMesh coat = twoKeysAndTheirBlend();
  coat.materials[2].blend[1].material = 2;  // a blend of a blend
  try {
    sceneMaterials(scene, coat);
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "materials[2].blend");
  }
  coat = twoKeysAndTheirBlend();
  coat.materials[0].texture = "/nonexistent/texture.png";
  try {
    sceneMaterials(scene, coat);
    FAIL() << "accepted";
  } catch (const Error& e) {
    // Named as the renderer names an unreadable texture: the key's material, not the blend.
    EXPECT_EQ(e.element(), "materials[0].colorTexture");
    EXPECT_EQ(e.file(), "/nonexistent/texture.png");
  }
}
