// A blended feather renders between its key feathers (issue #30 item 2): a vane quad drawn with key
// feather A's look, key feather B's, and the halfway blend of the two (material_blend.hpp) in an OSMesa
// context. Shading is linear in the albedo, so the blend's pixel is the mean of the keys' pixels.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include "gl_fixture.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/render/material_blend.hpp"
#include "pteryla/render/pattern.hpp"
#include "pteryla/render/renderer.hpp"

using namespace pteryla;
using namespace pteryla::render;

namespace {

using gltest::context;

// A vane quad facing the camera: barb tangent along x, both uv sets over [0,1]^2.
TriMesh vane() {
  TriMesh m;
  const glm::vec3 p[4] = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  const glm::vec2 uv[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int i = 0; i < 4; ++i) {
    m.positions.push_back(p[i]);
    m.normals.push_back({0, 0, 1});
    m.tangents.push_back({1, 0, 0});
    m.uvGlobal.push_back(uv[i]);
    m.uvBarb.push_back(uv[i]);
    m.alpha.push_back(1.0f);
    m.barbCount.push_back(1.0f);
  }
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

Image renderWith(const FeatherMaterial& m) {
  Renderer r(context());
  const TriMesh q = vane();
  FeatherDrawRange range;
  range.indexCount = 6;
  r.setCoat(q, {range});
  r.setMaterials({m});
  Camera c;
  c.eye = {0.3f, 0.2f, 4.0f};
  c.target = {0, 0, 0};
  c.fovYDegrees = 40.0f;
  RenderSettings s;
  s.width = s.height = 32;
  s.background = {0, 0, 0, 1};
  s.ambient = glm::vec3(0.1f);
  s.fastTextureFiltering = false;
  return r.renderImage(c, {Light{glm::normalize(glm::vec3(0.2f, 0.4f, 1.0f)), {0.8f, 0.8f, 0.8f}}}, s);
}

// An opaque pattern in two colours (the outline off, so the centre is covered).
FeatherMaterial patterned(PatternKind kind, glm::vec3 base, glm::vec3 mark) {
  PatternParams p;
  p.kind = kind;
  p.baseColor = base;
  p.markColor = mark;
  p.outline = false;
  p.noise = 0.0f;
  FeatherMaterial m;
  m.colorImage = generatePattern(p);
  m.alphaImage = Image(4, 4, 255, 255, 255, 255);
  m.translucency = 0.0f;
  return m;
}

}  // namespace

TEST(MaterialBlendRender, HalfwayFeatherRendersBetweenItsKeyFeathers) {
  const FeatherMaterial a = patterned(PatternKind::Barred, {0.8f, 0.3f, 0.1f}, {0.2f, 0.1f, 0.05f});
  const FeatherMaterial b = patterned(PatternKind::Spotted, {0.1f, 0.4f, 0.7f}, {0.9f, 0.9f, 0.9f});
  const Image ia = renderWith(a), ib = renderWith(b);
  const Image half = renderWith(blendFeatherMaterials({a, b}, {0.5, 0.5}, "half", {}));
  const Image quarter = renderWith(blendFeatherMaterials({a, b}, {0.75, 0.25}, "quarter", {}));
  int checked = 0;
  for (int y = 6; y < 26; y += 3)
    for (int x = 6; x < 26; x += 3) {
      const uint8_t *pa = ia.pixel(x, y), *pb = ib.pixel(x, y), *ph = half.pixel(x, y), *pq = quarter.pixel(x, y);
      for (int c = 0; c < 3; ++c) {
        // The keys differ visibly here, and the blend sits at the weights between them (8-bit texels
        // and framebuffer: within 2 levels).
        EXPECT_NEAR(ph[c], 0.5 * (pa[c] + pb[c]), 2.0) << x << "," << y << " channel " << c;
        EXPECT_NEAR(pq[c], 0.75 * pa[c] + 0.25 * pb[c], 2.0) << x << "," << y << " channel " << c;
      }
      checked += std::abs(pa[0] - pb[0]) > 20;
    }
  EXPECT_GT(checked, 10);  // the test looks at pixels where the keys really differ
  // Weights 1/0: the key's material, the key's image bit for bit.
  const Image one = renderWith(blendFeatherMaterials({a}, {1.0}, "a", {}));
  EXPECT_EQ(one.rgba, ia.rgba);
}

TEST(MaterialBlendRender, BlendedBarbuleParametersChangeTheReflection) {
  FeatherMaterial a = patterned(PatternKind::Plain, {0.6f, 0.6f, 0.6f}, {0.6f, 0.6f, 0.6f});
  FeatherMaterial b = a;
  a.barbules = {0.5, 0.0, 0.2};
  b.barbules = {4.0, 0.8, 0.2};
  const FeatherMaterial m = blendFeatherMaterials({a, b}, {0.5, 0.5}, "ab", {});
  EXPECT_DOUBLE_EQ(m.barbules.d, 2.25);
  EXPECT_DOUBLE_EQ(m.barbules.h, 0.4);
  const Image ia = renderWith(a), ib = renderWith(b), im = renderWith(m);
  EXPECT_NE(im.rgba, ia.rgba);
  EXPECT_NE(im.rgba, ib.rgba);
}
