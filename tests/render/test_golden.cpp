// Golden images (labels render + golden): a skin sphere, a synthetic feather with alpha and
// tangents (BRDF), a small layered coat, and the scratchboard style, rendered headless with OSMesa.
// Update with PTERYLA_UPDATE_GOLDEN=1 ctest -L golden; see golden/README.md for the Mesa version.
#include <gtest/gtest.h>

#include "gl_fixture.hpp"
#include "golden.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/feather/mesh.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/render/scene_view.hpp"
#include "pteryla/render/osmesa_context.hpp"
#include "pteryla/render/pattern.hpp"
#include "pteryla/render/renderer.hpp"
#include "pteryla/render/scratchboard.hpp"
#include "pteryla/render/synthetic.hpp"

using namespace pteryla;
using namespace pteryla::render;

namespace {
using gltest::context;
}  // namespace

TEST(RendererGolden, SkinSphere) {
  Renderer r(context());
  r.setSkin(makeUvSphere(1.0f, 24, 48));
  Camera cam;
  cam.eye = {1.0f, 1.5f, 4.0f};
  cam.frameBounds(glm::vec3(-1), glm::vec3(1), 1.0f, 0.7f);
  RenderSettings s;
  s.width = s.height = 128;
  s.background = {0.1f, 0.12f, 0.15f, 1.0f};
  EXPECT_TRUE(
      golden::matchesGolden(r.renderImage(cam, {Light{{0.5f, 0.8f, 0.6f}, {0.9f, 0.9f, 0.85f}}}, s), "skin_sphere"));
}

TEST(RendererGolden, SyntheticFeatherWithAlphaAndBrdf) {
  Renderer r(context());
  const std::vector<NamedImage> textures = standardTextures(1);
  FeatherMaterial m;
  m.colorImage = textures[0].image;  // barred_brown
  m.alphaImage = textures[7].image;  // barb_alpha
  m.barbules = {1.5, 0.1, 0.2};
  m.specular = 0.4f;
  r.setMaterials({m});
  SyntheticFeatherParams p;
  p.width = 0.3f;
  const SyntheticFeather f = makeSyntheticFeather(p);
  FeatherDrawRange range;
  range.indexCount = static_cast<uint32_t>(f.mesh.indices.size());
  std::copy(f.partCount, f.partCount + 4, range.partCount);
  r.setCoat(f.mesh, {range});
  Camera cam;
  cam.eye = {0.2f, -0.6f, 1.6f};
  cam.target = {0.5f, 0.0f, 0.0f};
  cam.up = {1, 0, 0};
  RenderSettings s;
  s.width = s.height = 256;
  s.fastTextureFiltering = false;  // bilinear texels: less sensitive to rasteriser differences
  const Image img = r.renderImage(cam, {Light{{0.3f, 0.4f, 1.0f}, {1, 1, 1}}}, s);
  EXPECT_TRUE(golden::matchesGolden(img, "synthetic_feather"));
}

TEST(RendererGolden, SmallCoatOnSkin) {
  Renderer r(context());
  const std::vector<NamedImage> textures = standardTextures(1);
  std::vector<FeatherMaterial> mats(3);
  mats[0].colorImage = textures[0].image;
  mats[1].colorImage = textures[1].image;
  mats[2].colorImage = textures[4].image;
  for (auto& m : mats) m.alphaImage = textures[7].image;
  r.setMaterials(mats);
  SyntheticCoatParams cp;
  cp.featherCount = 150;
  cp.featherLength = 0.7f;
  cp.featherWidth = 0.22f;
  cp.materialCount = 3;
  cp.feather.barbsPerVane = 10;
  const SyntheticCoat coat = makeSyntheticCoat(cp);
  r.setSkin(coat.skin);
  r.setCoat(coat.coat, coat.ranges);
  Camera cam;
  cam.eye = {1.0f, 1.2f, 2.5f};
  glm::vec3 lo, hi;
  coat.coat.bounds(lo, hi);
  cam.frameBounds(lo, hi, 1.0f, 0.65f);
  RenderSettings s;
  s.width = s.height = 256;
  s.fastTextureFiltering = false;  // bilinear texels: less sensitive to rasteriser differences
  EXPECT_TRUE(golden::matchesGolden(r.renderImage(cam, {Light{}}, s), "small_coat"));
}

TEST(ScratchboardGolden, SmallCoat) {
  SyntheticCoatParams cp;
  cp.featherCount = 120;
  cp.featherLength = 0.75f;
  cp.featherWidth = 0.25f;
  cp.feather.barbsPerVane = 12;
  const SyntheticCoat coat = makeSyntheticCoat(cp);
  Camera cam;
  cam.eye = {1.0f, 1.2f, 2.5f};
  glm::vec3 lo, hi;
  coat.coat.bounds(lo, hi);
  cam.frameBounds(lo, hi, 1.0f, 0.65f);
  ScratchboardSettings s;
  s.width = s.height = 256;
  const Image img = renderScratchboard(coat.coat, coat.skin, cam, {Light{}}, s);
  EXPECT_TRUE(golden::matchesGolden(img, "scratchboard_coat"));
}

// Bundled feather types at full detail and at 30% (the alpha mask repeated over merged barbs keeps
// the look, 7.1.3), as `pteryla feather F.json --out F.png` draws them.
TEST(FeatherGolden, BundledTypesAtTwoLevels) {
  for (const char* type : {"contour", "primary", "down"}) {
    const feather::FeatherParams p =
        feather::loadFeather(std::string(PTERYLA_DATA_DIR) + "/feathers/" + type + ".json");
    for (const double lod : {1.0, 0.3}) {
      const std::string name = std::string("feather_") + type + (lod == 1.0 ? "_100" : "_30");
      const Image img = renderFeatherImage(context(), p, feather::buildFeatherMesh(p, 1.0, lod), 96, 160);
      EXPECT_TRUE(golden::matchesGolden(img, name)) << name;
    }
  }
}

// A packed patch through the scene path the CLI renders (Pipeline + SceneView): relaxed follicles,
// interpolated key feathers, height-field packing, meshing, textures, layer and octant order. Every
// feather at 50% (a fixed level, not the default levels by screen size): the golden is of that mesh.
TEST(SceneGolden, PackedPatch) {
  pipeline::Scene scene = pipeline::loadScene(std::string(PTERYLA_DATA_DIR) + "/scenes/patch.json");
  scene.render.lodByScreenSize = false;
  pipeline::Pipeline p(scene);
  p.setLod(0.5);
  SceneView view(context());
  EXPECT_TRUE(golden::matchesGolden(view.render(p, 224, 128), "packed_patch"));
}
