// Renderer tests in an OSMesa context: analytic coverage, draw-order and blending rules (7.1.2, 7.2),
// textures, the BRDF's Lambert limit (7.1.3), errors, and golden images.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "gl_fixture.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/render/image_texture.hpp"
#include "pteryla/render/osmesa_context.hpp"
#include "pteryla/render/pattern.hpp"
#include "pteryla/render/renderer.hpp"
#include "pteryla/render/synthetic.hpp"

using namespace pteryla;
using namespace pteryla::render;

namespace {

using gltest::context;

// Quad centred at c spanning c +- a +- b, normal n, tangent t; uv (0,0) at c - a - b, (1,1) at c + a + b.
TriMesh quad(glm::vec3 c, glm::vec3 a, glm::vec3 b, float alpha = 1.0f, glm::vec3 t = {1, 0, 0},
             float barbCount = 1.0f) {
  TriMesh m;
  const glm::vec3 n = glm::normalize(glm::cross(a, b));
  const glm::vec2 uv[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const glm::vec3 p[4] = {c - a - b, c + a - b, c + a + b, c - a + b};
  for (int i = 0; i < 4; ++i) {
    m.positions.push_back(p[i]);
    m.normals.push_back(n);
    m.tangents.push_back(t);
    m.uvGlobal.push_back(uv[i]);
    m.uvBarb.push_back(uv[i]);
    m.alpha.push_back(alpha);
    m.barbCount.push_back(barbCount);
  }
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

Camera frontCamera(float dist = 5.0f, float fov = 40.0f) {
  Camera c;
  c.eye = {0, 0, dist};
  c.target = {0, 0, 0};
  c.fovYDegrees = fov;
  c.zNear = 0.1f;
  c.zFar = 100.0f;
  return c;
}

RenderSettings flatSettings(int size = 64) {
  RenderSettings s;
  s.width = s.height = size;
  s.background = {0, 0, 0, 1};
  s.ambient = glm::vec3(0.0f);
  return s;
}

const std::vector<Light> kFrontLight{Light{{0, 0, 1}, {1, 1, 1}}};

FeatherMaterial lambert(glm::vec3 color) {
  FeatherMaterial m;
  m.baseColor = color;
  m.useBrdf = false;
  m.translucency = 0.0f;
  return m;
}

FeatherDrawRange whole(const TriMesh& m, uint32_t first = 0, uint32_t material = 0) {
  FeatherDrawRange r;
  r.firstIndex = first;
  r.indexCount = static_cast<uint32_t>(m.indices.size()) - first;
  r.material = material;
  return r;
}

const uint8_t* centre(const Image& img) { return img.pixel(img.width / 2, img.height / 2); }

}  // namespace

TEST(Renderer, ContextIsCoreProfile33) {
  EXPECT_TRUE(context().isCoreProfile());
  Renderer r(context());
  EXPECT_NE(r.glVersion().find("Mesa"), std::string::npos) << r.glVersion();
}

TEST(Renderer, ClearsToBackgroundAtAnySize) {
  Renderer r(context());
  RenderSettings s = flatSettings();
  s.width = 200;
  s.height = 100;
  s.background = {0.2f, 0.4f, 0.6f, 1.0f};
  const Image img = r.renderImage(frontCamera(), kFrontLight, s);
  ASSERT_EQ(img.width, 200);
  ASSERT_EQ(img.height, 100);
  for (size_t i = 0; i < img.rgba.size(); i += 4) {
    ASSERT_NEAR(img.rgba[i], 51, 1);
    ASSERT_NEAR(img.rgba[i + 1], 102, 1);
    ASSERT_NEAR(img.rgba[i + 2], 153, 1);
  }
}

TEST(Renderer, ReadbackIsTopRowFirstAndMatchesDefaultFramebuffer) {
  Renderer r(context());
  // Skin quad covering only the upper half of the view.
  r.setSkin(quad({0, 1, 0}, {3, 0, 0}, {0, 1, 0}));
  RenderSettings s = flatSettings(64);
  s.skinColor = {1, 1, 1};
  const Image img = r.renderImage(frontCamera(), kFrontLight, s);
  EXPECT_GT(img.pixel(32, 5)[0], 200);  // top row area covered
  EXPECT_EQ(img.pixel(32, 58)[0], 0);   // bottom is background
  // The same frame drawn into the context's own framebuffer reads back identically.
  r.render(frontCamera(), kFrontLight, s);
  const Image direct = r.readPixels(64, 64);
  EXPECT_EQ(meanAbsoluteError(img, direct), 0.0);
}

TEST(Renderer, FlatQuadCoverageMatchesProjectedArea) {
  Renderer r(context());
  const float dist = 5.0f, fov = 40.0f, half = 0.6f;
  const TriMesh q = quad({0, 0, 0}, {half, 0, 0}, {0, half, 0});
  r.setCoat(q, {whole(q)});
  r.setMaterials({lambert({1, 1, 1})});
  RenderSettings s = flatSettings(256);
  const Image img = r.renderImage(frontCamera(dist, fov), kFrontLight, s);
  const double ndcHalf = half / (dist * std::tan(fov * 0.5 * 3.14159265358979 / 180.0));
  const uint8_t black[3] = {0, 0, 0};
  EXPECT_NEAR(coveredFraction(img, black), ndcHalf * ndcHalf, 0.004);
  // Tilted 60 degrees about y, seen from far away with a narrow field (nearly orthographic): area x cos.
  const float c60 = 0.5f, s60 = std::sqrt(3.0f) / 2.0f;
  const TriMesh t = quad({0, 0, 0}, {half * c60, 0, -half * s60}, {0, half, 0});
  r.setCoat(t, {whole(t)});
  const float far = 100.0f, narrow = 2.0f;
  const double h = half / (far * std::tan(narrow * 0.5 * 3.14159265358979 / 180.0));
  RenderSettings s2 = s;
  Camera cam = frontCamera(far, narrow);
  cam.zFar = 200.0f;
  const Image tilted = r.renderImage(cam, {Light{{0, 0, 1}, {1, 1, 1}}}, s2);
  EXPECT_NEAR(coveredFraction(tilted, black), h * h * c60, 0.006);
}

TEST(Renderer, SkinWritesDepthFeathersTestButDoNotWriteDepth) {
  Renderer r(context());
  RenderSettings s = flatSettings(32);
  s.skinColor = {0.0f, 0.0f, 1.0f};
  r.setSkin(quad({0, 0, 0}, {2, 0, 0}, {0, 2, 0}));
  // Layer order: A behind the skin, B in front (alpha 0.5), C between skin and B drawn after B.
  TriMesh coat = quad({0, 0, -0.5f}, {2, 0, 0}, {0, 2, 0}, 1.0f);
  coat.append(quad({0, 0, 0.5f}, {2, 0, 0}, {0, 2, 0}, 0.5f));
  coat.append(quad({0, 0, 0.3f}, {2, 0, 0}, {0, 2, 0}, 0.5f));
  std::vector<FeatherDrawRange> ranges = {whole(coat), whole(coat), whole(coat)};
  for (int i = 0; i < 3; ++i) {
    ranges[i].firstIndex = 6 * i;
    ranges[i].indexCount = 6;
    ranges[i].material = i;
  }
  r.setCoat(coat, ranges);
  r.setMaterials({lambert({1, 1, 0}), lambert({1, 0, 0}), lambert({0, 1, 0})});
  const Image img = r.renderImage(frontCamera(), kFrontLight, s);  // p points into it: keep it alive
  const uint8_t* p = centre(img);
  // A (yellow) is hidden by the skin; B (red, 0.5) over blue; C (green, 0.5) drawn over that although
  // it is behind B: B wrote no depth.
  const double red = 0.5 * 0.5, green = 0.5, blue = 0.5 * 0.5;
  EXPECT_NEAR(p[0], 255 * red, 2);
  EXPECT_NEAR(p[1], 255 * green, 2);
  EXPECT_NEAR(p[2], 255 * blue, 2);
}

TEST(Renderer, LayerOrderFollowsDrawRanges) {
  Renderer r(context());
  RenderSettings s = flatSettings(32);
  TriMesh coat = quad({0, 0, 0.1f}, {2, 0, 0}, {0, 2, 0}, 0.5f);
  coat.append(quad({0, 0, 0.0f}, {2, 0, 0}, {0, 2, 0}, 0.5f));
  FeatherDrawRange a = whole(coat), b = whole(coat);
  a.indexCount = b.indexCount = 6;
  b.firstIndex = 6;
  b.material = 1;
  r.setMaterials({lambert({1, 0, 0}), lambert({0, 1, 0})});
  r.setCoat(coat, {a, b});
  const Image ab = r.renderImage(frontCamera(), kFrontLight, s);
  r.setCoat(coat, {b, a});
  const Image ba = r.renderImage(frontCamera(), kFrontLight, s);
  // Last drawn dominates: red then green -> green 0.5, red 0.25; reversed -> red 0.5, green 0.25.
  EXPECT_NEAR(centre(ab)[0], 64, 2);
  EXPECT_NEAR(centre(ab)[1], 128, 2);
  EXPECT_NEAR(centre(ba)[0], 128, 2);
  EXPECT_NEAR(centre(ba)[1], 64, 2);
}

TEST(Renderer, OctantRuleOrdersVanesAndBarbsByViewDirection) {
  Renderer r(context());
  RenderSettings s = flatSettings(32);
  // One feather: shaft (empty), left vane (red) and right vane (green) overlapping on screen.
  TriMesh coat = quad({0, 0, 0.01f}, {2, 0, 0}, {0, 2, 0}, 0.5f);
  coat.append(quad({0, 0, 0.0f}, {2, 0, 0}, {0, 2, 0}, 0.5f));
  FeatherDrawRange f = whole(coat);
  f.partCount[1] = 6;                                            // left vane: red through the colour texture
  f.partCount[2] = 6;                                            // right vane: green
  for (int i = 0; i < 4; ++i) coat.uvGlobal[i] = {0.25f, 0.5f};  // left vane samples red
  for (int i = 4; i < 8; ++i) coat.uvGlobal[i] = {0.75f, 0.5f};  // right vane samples green
  Image tex(2, 1);
  tex.pixel(0, 0)[0] = 255, tex.pixel(0, 0)[1] = 0, tex.pixel(0, 0)[2] = 0;
  tex.pixel(1, 0)[0] = 0, tex.pixel(1, 0)[1] = 255, tex.pixel(1, 0)[2] = 0;
  FeatherMaterial m = lambert({1, 1, 1});
  m.colorImage = tex;
  r.setMaterials({m});
  f.origin = {0, 0, 0};
  f.axisX = {1, 0, 0};
  f.axisY = {0, 1, 0};
  r.setCoat(coat, {f});
  auto look = [&](glm::vec3 eye, bool ordered) {
    Camera c = frontCamera();
    c.eye = eye;
    RenderSettings t = s;
    t.viewDependentOrder = ordered;
    const Image img = r.renderImage(c, kFrontLight, t);
    return std::pair<int, int>(centre(img)[0], centre(img)[1]);
  };
  // Viewer on the left-vane side (+y): the right vane is farther and drawn first, left on top.
  auto [rl, gl] = look({0, 1.0f, 5}, true);
  EXPECT_GT(rl, gl + 40);
  // Viewer on the right-vane side: left first, right on top.
  auto [rr, gr] = look({0, -1.0f, 5}, true);
  EXPECT_GT(gr, rr + 40);
  // Without view-dependent order the stored order (left then right) is always used.
  auto [ru, gu] = look({0, 1.0f, 5}, false);
  EXPECT_GT(gu, ru + 40);
  // Barb order: forward when the tip (+x) side faces the viewer, backward otherwise.
  look({2, 0.5f, 5}, true);
  EXPECT_EQ(r.lastStats().backwardParts, 0u);
  look({-2, 0.5f, 5}, true);
  EXPECT_EQ(r.lastStats().backwardParts, 2u);
  EXPECT_EQ(r.lastStats().drawCalls, 1u);  // both vanes backward are contiguous: one submission
}

TEST(Renderer, ColourTextureOrientationAndUvSets) {
  Renderer r(context());
  // Texture: top half (v = 1) red, bottom half blue.
  Image tex(4, 4);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      uint8_t* p = tex.pixel(x, y);
      p[0] = y < 2 ? 255 : 0;
      p[1] = 0;
      p[2] = y < 2 ? 0 : 255;
    }
  FeatherMaterial m = lambert({1, 1, 1});
  m.colorImage = tex;
  r.setMaterials({m});
  const TriMesh q = quad({0, 0, 0}, {2, 0, 0}, {0, 2, 0});
  r.setCoat(q, {whole(q)});
  const Image img = r.renderImage(frontCamera(), kFrontLight, flatSettings(64));
  EXPECT_GT(img.pixel(32, 10)[0], 200);
  EXPECT_LT(img.pixel(32, 10)[2], 50);
  EXPECT_GT(img.pixel(32, 54)[2], 200);
  EXPECT_LT(img.pixel(32, 54)[0], 50);
  // The growth uv set (absent here, so 0,0 -> bottom-left texel: blue) is selected per material.
  m.colorUv = ColorUv::Growth;
  r.setMaterials({m});
  const Image g = r.renderImage(frontCamera(), kFrontLight, flatSettings(64));
  EXPECT_GT(g.pixel(32, 10)[2], 200);
}

TEST(Renderer, AlphaMaskRepeatsBarbCountTimesAcrossPolygon) {
  Renderer r(context());
  Image mask(8, 1);
  for (int x = 0; x < 8; ++x) {
    uint8_t* p = mask.pixel(x, 0);
    p[0] = p[1] = p[2] = p[3] = x < 4 ? 255 : 0;
  }
  FeatherMaterial m = lambert({1, 1, 1});
  m.alphaImage = mask;
  r.setMaterials({m});
  const TriMesh q = quad({0, 0, 0}, {1.5f, 0, 0}, {0, 1.5f, 0}, 1.0f, {0, 1, 0}, 4.0f);
  r.setCoat(q, {whole(q)});
  RenderSettings s = flatSettings(256);
  const Image img = r.renderImage(frontCamera(), kFrontLight, s);
  // Count dark/bright transitions along the middle row inside the quad: 4 repeats -> 8 edges.
  int transitions = 0;
  bool prev = img.pixel(0, 128)[0] > 128;
  for (int x = 1; x < 256; ++x) {
    const bool cur = img.pixel(x, 128)[0] > 128;
    transitions += cur != prev;
    prev = cur;
  }
  EXPECT_GE(transitions, 7);
  EXPECT_LE(transitions, 8);
  s.useAlphaTexture = false;
  const Image solid = r.renderImage(frontCamera(), kFrontLight, s);
  EXPECT_GT(centre(solid)[0], 250);
}

class RendererBrdf : public ::testing::TestWithParam<bool> {};

TEST_P(RendererBrdf, ReducesToLambertForThinBarbulesAndIsAnisotropic) {
  Renderer r(context());
  const TriMesh q = quad({0, 0, 0}, {2, 0, 0}, {0, 2, 0});
  r.setCoat(q, {whole(q)});
  const std::vector<Light> light{Light{{0.7f, 0.2f, 0.6f}, {1, 1, 1}}};
  Camera cam = frontCamera();
  cam.eye = {-1, 0.5f, 5};
  RenderSettings s = flatSettings(32);
  s.brdfPerFragment = GetParam();
  FeatherMaterial m = lambert({0.8f, 0.8f, 0.8f});
  r.setMaterials({m});
  const Image lam = r.renderImage(cam, light, s);
  m.useBrdf = true;
  m.specular = 0.0f;
  m.barbules = {0.01, 0.0, 0.2};
  r.setMaterials({m});
  const Image thin = r.renderImage(cam, light, s);
  EXPECT_LT(meanAbsoluteError(lam, thin), 1.0 / 255.0);
  EXPECT_NEAR(centre(lam)[0], centre(thin)[0], 2);
  // Dense cylinders (d = 1.9) shade differently depending on the barb direction.
  m.barbules = {1.9, 0.0, 0.2};
  m.barbuleAngle = 0.0f;
  r.setMaterials({m});
  const Image alongX = r.renderImage(cam, light, s);
  TriMesh turned = q;
  for (auto& t : turned.tangents) t = {0, 1, 0};
  r.setCoat(turned, {whole(turned)});
  const Image alongY = r.renderImage(cam, light, s);
  EXPECT_GT(std::abs(int(centre(alongX)[0]) - int(centre(alongY)[0])), 8);
  // ... while a Lambertian vane does not care.
  s.useBrdf = false;
  const Image lamY = r.renderImage(cam, light, s);
  EXPECT_EQ(meanAbsoluteError(lam, lamY), 0.0);
}

INSTANTIATE_TEST_SUITE_P(PerVertexAndPerFragment, RendererBrdf, ::testing::Values(false, true));

TEST(Renderer, PerVertexAndPerFragmentShadingAgreeOnFineGeometry) {
  Renderer r(context());
  FeatherMaterial m;
  m.barbules = {1.5, 0.1, 0.2};
  m.specular = 0.4f;
  r.setMaterials({m});
  const SyntheticFeather f = makeSyntheticFeather(SyntheticFeatherParams());
  FeatherDrawRange range;
  range.indexCount = static_cast<uint32_t>(f.mesh.indices.size());
  r.setCoat(f.mesh, {range});
  Camera cam;
  cam.eye = {0.3f, -0.5f, 1.5f};
  cam.target = {0.5f, 0.0f, 0.0f};
  RenderSettings s;
  s.width = s.height = 96;
  const Image v = r.renderImage(cam, {Light{}}, s);
  s.brdfPerFragment = true;
  const Image p = r.renderImage(cam, {Light{}}, s);
  EXPECT_LT(meanAbsoluteError(v, p), 0.01);
}

TEST(Renderer, OcclusionCullingSkipsHiddenFeathersWithoutChangingTheImage) {
  Renderer r(context());
  SyntheticCoatParams cp;
  cp.featherCount = 200;
  cp.featherLength = 0.5f;
  cp.featherWidth = 0.15f;
  cp.feather.barbsPerVane = 6;
  const Camera cam = gltest::showCoat(r, makeSyntheticCoat(cp));
  RenderSettings s;
  s.width = s.height = 128;
  const Image culled = r.renderImage(cam, {Light{}}, s);
  const size_t hidden = r.lastStats().occludedFeathers;
  const size_t hiddenTriangles = r.lastStats().occludedTriangles;  // of feathers partly behind the body
  const size_t drawn = r.lastStats().triangles;
  s.occlusionCulling = false;
  const Image all = r.renderImage(cam, {Light{}}, s);
  EXPECT_EQ(r.lastStats().occludedFeathers, 0u);
  EXPECT_EQ(r.lastStats().occludedTriangles, 0u);
  EXPECT_GT(hiddenTriangles, 0u);
  EXPECT_LT(drawn + hiddenTriangles, r.lastStats().triangles);
  EXPECT_GT(hidden, 10u);  // feathers on the far side of the body
  EXPECT_LT(hidden, 160u);
  EXPECT_EQ(meanAbsoluteError(culled, all), 0.0);
}

TEST(Renderer, FastTextureFilteringStaysCloseToBilinear) {
  Renderer r(context());
  FeatherMaterial m;
  const std::vector<NamedImage> textures = standardTextures(1);
  m.colorImage = textures[2].image;  // spotted: high contrast
  m.alphaImage = textures[7].image;
  r.setMaterials({m});
  SyntheticFeatherParams fp;
  fp.lodFraction = 0.5f;
  const SyntheticFeather f = makeSyntheticFeather(fp);
  FeatherDrawRange range;
  range.indexCount = static_cast<uint32_t>(f.mesh.indices.size());
  r.setCoat(f.mesh, {range});
  Camera cam;
  cam.eye = {0.5f, 0.0f, 2.5f};
  cam.target = {0.5f, 0.0f, 0.0f};
  RenderSettings s;
  s.width = s.height = 64;  // the 128x256 texture is minified
  const Image fast = r.renderImage(cam, {Light{}}, s);
  s.fastTextureFiltering = false;
  const Image smooth = r.renderImage(cam, {Light{}}, s);
  EXPECT_GT(meanAbsoluteError(fast, smooth), 0.0);
  EXPECT_LT(meanAbsoluteError(fast, smooth), 0.01);
}

TEST(Renderer, CullsFeathersOutsideTheView) {
  Renderer r(context());
  TriMesh coat = quad({0, 0, 0}, {0.5f, 0, 0}, {0, 0.5f, 0});
  coat.append(quad({50, 0, 0}, {0.5f, 0, 0}, {0, 0.5f, 0}));
  FeatherDrawRange a = whole(coat), b = whole(coat);
  a.indexCount = b.indexCount = 6;
  b.firstIndex = 6;
  r.setCoat(coat, {a, b});
  const Image img = r.renderImage(frontCamera(), kFrontLight, flatSettings(32));
  EXPECT_EQ(r.lastStats().culledFeathers, 1u);
  EXPECT_EQ(r.lastStats().triangles, 2u);
  const uint8_t black[3] = {0, 0, 0};
  EXPECT_GT(coveredFraction(img, black), 0.0);
}

TEST(Renderer, MissingOrUnreadableTextureNamesTheFile) {
  Renderer r(context());
  FeatherMaterial m;
  m.name = "contour";
  m.colorTexture = "/nonexistent/pteryla/texture.png";
  try {
    r.setMaterials({FeatherMaterial{}, m});
    FAIL() << "expected pteryla::Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), m.colorTexture);
    EXPECT_EQ(e.element(), "materials[1].colorTexture");
    EXPECT_NE(std::string(e.what()).find("contour"), std::string::npos) << e.what();
  }
  const std::string bad = std::string(PTERYLA_BUILD_DIR) + "/tests/render/not_an_image.png";
  std::filesystem::create_directories(std::filesystem::path(bad).parent_path());
  std::ofstream(bad) << "this is not a PNG";
  m.colorTexture.clear();
  m.alphaTexture = bad;
  try {
    r.setMaterials({m});
    FAIL() << "expected pteryla::Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), bad);
    EXPECT_EQ(e.element(), "materials[0].alphaTexture");
  }
  // The renderer is still usable with its previous materials.
  EXPECT_NO_THROW(r.renderImage(frontCamera(), kFrontLight, flatSettings(16)));
}

TEST(Renderer, RejectsOverlappingRanges) {
  Renderer r(context());
  TriMesh m = quad({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  m.append(quad({0, 0, 1}, {1, 0, 0}, {0, 1, 0}));
  // A range over both quads and one over the second: each triangle would be drawn twice.
  try {
    r.setCoat(m, {whole(m, 0), whole(m, 6)});
    FAIL() << "overlapping ranges accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "ranges[1]");
    EXPECT_NE(std::string(e.what()).find("overlaps ranges[0]"), std::string::npos) << e.what();
  }
}

TEST(Renderer, RejectsInvalidRangesAndMeshes) {
  Renderer r(context());
  const TriMesh q = quad({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  FeatherDrawRange f = whole(q);
  f.indexCount = 9;
  EXPECT_THROW(r.setCoat(q, {f}), Error);
  f = whole(q);
  f.partCount[1] = 3;
  try {
    r.setCoat(q, {whole(q), f});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "ranges[1].partCount");
  }
  TriMesh broken = q;
  broken.indices[2] = 99;
  EXPECT_THROW(r.setSkin(broken), Error);
  broken = q;
  broken.alpha.pop_back();
  EXPECT_THROW(r.setCoat(broken, {}), Error);
  f = whole(q);
  f.material = 3;
  r.setCoat(q, {f});
  EXPECT_THROW(r.renderImage(frontCamera(), kFrontLight, flatSettings(16)), Error);
}

TEST(Renderer, MsaaSmoothsEdges) {
  Renderer r(context());
  const TriMesh q = quad({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  TriMesh tilted = q;
  for (auto& p : tilted.positions) p = glm::vec3(p.x * 0.8f - p.y * 0.6f, p.x * 0.6f + p.y * 0.8f, 0);
  r.setCoat(tilted, {whole(tilted)});
  r.setMaterials({lambert({1, 1, 1})});
  RenderSettings s = flatSettings(64);
  auto partial = [](const Image& img) {
    int n = 0;
    for (size_t i = 0; i < img.rgba.size(); i += 4) n += img.rgba[i] > 10 && img.rgba[i] < 245;
    return n;
  };
  const Image plain = r.renderImage(frontCamera(), kFrontLight, s);
  s.msaaSamples = 4;
  const Image smooth = r.renderImage(frontCamera(), kFrontLight, s);
  EXPECT_EQ(partial(plain), 0);
  EXPECT_GT(partial(smooth), 20);
  const uint8_t black[3] = {0, 0, 0};
  EXPECT_NEAR(coveredFraction(plain, black), coveredFraction(smooth, black), 0.02);
}

TEST(Renderer, FewerBarbsWithTexturesStayCloseToFullGeometry) {
  // 7.1.3: lower geometric detail with alpha + BRDF textures keeps the look; error grows as detail drops.
  Renderer r(context());
  const std::vector<NamedImage> textures = standardTextures(1);
  FeatherMaterial m;
  m.colorImage = textures[0].image;
  m.alphaImage = textures[7].image;
  m.baseColor = glm::vec3(1.0f);
  r.setMaterials({m});
  Camera cam;
  cam.eye = {0.5f, -0.3f, 2.0f};
  cam.target = {0.5f, 0.0f, 0.0f};
  RenderSettings s;
  s.width = s.height = 128;
  auto renderAt = [&](float lod) {
    SyntheticFeatherParams p;
    p.lodFraction = lod;
    const SyntheticFeather f = makeSyntheticFeather(p);
    FeatherDrawRange range;
    range.indexCount = static_cast<uint32_t>(f.mesh.indices.size());
    std::copy(f.partCount, f.partCount + 4, range.partCount);
    r.setCoat(f.mesh, {range});
    return r.renderImage(cam, {Light{}}, s);
  };
  const Image full = renderAt(1.0f), sixty = renderAt(0.6f), fifth = renderAt(0.2f);
  const double e60 = meanAbsoluteError(full, sixty), e20 = meanAbsoluteError(full, fifth);
  EXPECT_LT(e60, 0.05);
  EXPECT_LT(e60, e20);
}

// renderImage draws off screen and must leave the caller's framebuffer bound (the viewer draws into
// framebuffer 0 right after taking a screenshot).
TEST(RendererState, RenderImageRestoresTheCallersFramebuffer) {
  pteryla::render::OsMesaContext ctx(32, 32);
  pteryla::render::Renderer r(ctx);
  pteryla::render::RenderSettings s;
  s.width = 48;  // a new size forces the off-screen target to be (re)created
  s.height = 40;
  using GetIntegervFn = void (*)(unsigned, int*);
  auto getIntegerv = reinterpret_cast<GetIntegervFn>(ctx.getProcAddress("glGetIntegerv"));
  ASSERT_NE(getIntegerv, nullptr);
  int before = -1, after = -1;
  getIntegerv(0x8CA6 /* GL_FRAMEBUFFER_BINDING */, &before);
  r.renderImage(pteryla::render::Camera{}, {pteryla::render::Light{}}, s);
  getIntegerv(0x8CA6, &after);
  EXPECT_EQ(before, 0);
  EXPECT_EQ(after, before);
}

TEST(Renderer, SubpixelCullingDropsTrianglesThatCoverNoPixelCentreWithoutChangingTheImage) {
  // A coat seen from afar: many barb triangles are thinner than a pixel and cover no pixel centre.
  // Dropping them before the rasterizer leaves the image bit-identical.
  Renderer r(context());
  SyntheticCoatParams cp;
  cp.featherCount = 300;
  cp.featherLength = 0.4f;
  cp.featherWidth = 0.12f;
  const Camera cam = gltest::showCoat(r, makeSyntheticCoat(cp));
  for (const int size : {96, 200}) {
    RenderSettings s;
    s.width = s.height = size;
    const Image culled = r.renderImage(cam, {Light{}}, s);
    const RenderStats on = r.lastStats();
    s.subpixelCulling = false;
    const Image all = r.renderImage(cam, {Light{}}, s);
    const RenderStats off = r.lastStats();
    EXPECT_EQ(off.subpixelTriangles, 0u);
    EXPECT_GT(on.subpixelTriangles, off.triangles / 10) << size << " px";
    EXPECT_EQ(on.triangles + on.subpixelTriangles, off.triangles) << size << " px";
    EXPECT_EQ(on.occludedTriangles, off.occludedTriangles);
    EXPECT_EQ(meanAbsoluteError(culled, all), 0.0) << size << " px";
  }
}

// With multisampling (renderImage's target), both cullings still run: occlusion against the farthest
// depth of each pixel's samples, sub-pixel culling at the rasterizer's sample positions. The image is
// the one drawn with neither.
TEST(Renderer, MultisampledCullingLeavesTheImageUnchanged) {
  Renderer r(context());
  SyntheticCoatParams cp;
  cp.featherCount = 300;
  cp.featherLength = 0.4f;
  cp.featherWidth = 0.12f;
  const Camera cam = gltest::showCoat(r, makeSyntheticCoat(cp));
  for (const int size : {96, 200}) {
    RenderSettings s;
    s.width = s.height = size;
    s.msaaSamples = 4;
    const Image culled = r.renderImage(cam, {Light{}}, s);
    const RenderStats on = r.lastStats();
    s.subpixelCulling = false;
    s.occlusionCulling = false;
    const Image all = r.renderImage(cam, {Light{}}, s);
    const RenderStats off = r.lastStats();
    EXPECT_GT(on.occludedFeathers + on.occludedTriangles, 0u) << size << " px";
    EXPECT_GT(on.subpixelTriangles, 0u) << size << " px";
    EXPECT_LT(on.triangles, off.triangles) << size << " px";
    EXPECT_EQ(meanAbsoluteError(culled, all), 0.0) << size << " px";
  }
}

// ------------------------------------------------------------------ key light shadows (#29)
namespace {

// Feather A lies flat at z = 0 over x in [-1, 0.5]; feather B lies 0.1 above it over x in [0, 1.5]. The
// key light comes from +x, 26.6 degrees above the plane, so B's left edge (x = 0) casts a shadow on A's
// exposed part over x in [-0.2, 0]. The camera looks straight down: world x maps to pixel columns exactly.
struct Overlap {
  TriMesh lower = quad({-0.25f, 0, 0}, {0.75f, 0, 0}, {0, 0.5f, 0});
  TriMesh upper;
  std::vector<Light> lights{Light{glm::vec3(1.0f, 0.0f, 0.5f), glm::vec3(1.0f)}};
  static constexpr int kSize = 256;
  explicit Overlap(float upperAlpha = 1.0f) : upper(quad({0.75f, 0, 0.1f}, {0.75f, 0, 0}, {0, 0.5f, 0}, upperAlpha)) {}
  RenderSettings settings(bool shadows, bool perFragment = false) const {
    RenderSettings s = flatSettings(kSize);
    s.ambient = glm::vec3(0.2f);
    s.shadows = shadows;
    s.shadowStrength = 1.0f;
    s.brdfPerFragment = perFragment;
    s.useAlphaTexture = false;
    return s;
  }
  // The two quads of `coat` (lower, then upper) as two feathers in that layer order.
  static std::vector<FeatherDrawRange> twoFeathers(const TriMesh& coat) {
    std::vector<FeatherDrawRange> r{whole(coat, 0), whole(coat, 6)};
    r[0].indexCount = 6;
    return r;
  }
  // Uploads both feathers as the coat of `r`.
  void upload(Renderer& r) const {
    TriMesh coat = lower;
    coat.append(upper);
    r.setCoat(coat, twoFeathers(coat));
  }
  // Mean red channel over world x in [x0, x1], y in [-0.3, 0.3].
  static double band(const Image& img, float x0, float x1) {
    const float half = 5.0f * std::tan(20.0f * 3.14159265f / 180.0f);
    auto px = [&](float x) { return int(std::lround((x / half * 0.5f + 0.5f) * kSize)); };
    double sum = 0;
    int n = 0;
    for (int y = px(-0.3f); y < px(0.3f); ++y)
      for (int x = px(x0); x < px(x1); ++x) sum += img.pixel(x, y)[0], ++n;
    return sum / std::max(n, 1);
  }
};

}  // namespace

TEST(RendererShadows, AnOverlappingFeatherDarkensTheExposedEdgeBelowIt) {
  for (const bool perFragment : {false, true}) {
    Renderer r(context());
    r.setMaterials({lambert({1, 1, 1})});
    const Overlap o;
    o.upload(r);
    const Image off = r.renderImage(frontCamera(), o.lights, o.settings(false, perFragment));
    const Image on = r.renderImage(frontCamera(), o.lights, o.settings(true, perFragment));
    // Just under B's edge, in its shadow, against the exposed middle of the same feather.
    const double edgeOn = Overlap::band(on, -0.16f, -0.04f), openOn = Overlap::band(on, -0.9f, -0.5f);
    const double edgeOff = Overlap::band(off, -0.16f, -0.04f), openOff = Overlap::band(off, -0.9f, -0.5f);
    EXPECT_NEAR(edgeOff, openOff, 0.02 * openOff) << "without shadows the flat feather is evenly lit";
    EXPECT_NEAR(openOn, openOff, 0.02 * openOff) << "the exposed part is not in shadow";
    EXPECT_LT(edgeOn, 0.6 * openOn) << "perFragment " << perFragment;
    // Beyond the shadow's reach (x < -0.2) A is lit again.
    EXPECT_NEAR(Overlap::band(on, -0.45f, -0.3f), openOn, 0.02 * openOn);
  }
}

TEST(RendererShadows, FeathersShadowTheSkinAndTransparentOnesCastNone) {
  Renderer r(context());
  r.setMaterials({lambert({1, 1, 1})});
  const Overlap o;
  RenderSettings s = o.settings(true);
  s.skinColor = glm::vec3(1.0f);
  r.setSkin(o.lower);  // A as skin: feathers shadow the body too
  r.setCoat(o.upper, {whole(o.upper)});
  Image img = r.renderImage(frontCamera(), o.lights, s);
  EXPECT_LT(Overlap::band(img, -0.16f, -0.04f), 0.6 * Overlap::band(img, -0.9f, -0.5f));

  // A feather below the alpha cut (0.5) casts no shadow: shadows follow what the colour pass shows.
  const Overlap faint(0.3f);
  r.setSkin(TriMesh());
  faint.upload(r);
  img = r.renderImage(frontCamera(), faint.lights, s);
  EXPECT_NEAR(Overlap::band(img, -0.16f, -0.04f), Overlap::band(img, -0.9f, -0.5f),
              0.02 * Overlap::band(img, -0.9f, -0.5f));
}

TEST(RendererShadows, TheMapIsDrawnAgainOnlyWhenWhatCastsItChanges) {
  Renderer r(context());
  r.setMaterials({lambert({1, 1, 1})});
  const Overlap o;
  o.upload(r);
  TriMesh coat = o.lower;
  coat.append(o.upper);
  const Image first = r.renderImage(frontCamera(), o.lights, o.settings(true));
  EXPECT_TRUE(r.lastStats().shadowMapRendered);
  Camera moved = frontCamera(4.0f);  // a new view: the light's map is still valid
  r.renderImage(moved, o.lights, o.settings(true));
  EXPECT_FALSE(r.lastStats().shadowMapRendered);
  const Image again = r.renderImage(frontCamera(), o.lights, o.settings(true));
  EXPECT_FALSE(r.lastStats().shadowMapRendered);
  EXPECT_EQ(first.rgba, again.rgba);
  r.renderImage(frontCamera(), {Light{glm::vec3(-1.0f, 0.0f, 0.5f), glm::vec3(1.0f)}}, o.settings(true));
  EXPECT_TRUE(r.lastStats().shadowMapRendered) << "another key light direction";
  r.setCoat(coat, Overlap::twoFeathers(coat));
  r.renderImage(frontCamera(), {Light{glm::vec3(-1.0f, 0.0f, 0.5f), glm::vec3(1.0f)}}, o.settings(true));
  EXPECT_TRUE(r.lastStats().shadowMapRendered) << "a new coat";
  r.renderImage(frontCamera(), o.lights, o.settings(false));
  EXPECT_FALSE(r.lastStats().shadowMapRendered);
}

// The shadow pass drops coat triangles that cover no texel centre of the map (they write no depth):
// with a small map most of a fine coat's triangles go, and the image (map included) is the same as with
// every triangle drawn into it.
TEST(RendererShadows, SubpixelCullingThinsTheShadowPassWithoutChangingTheImage) {
  SyntheticCoatParams cp;
  cp.featherCount = 300;
  cp.featherLength = 0.4f;
  cp.featherWidth = 0.12f;
  const SyntheticCoat coat = makeSyntheticCoat(cp);
  RenderSettings s;
  s.width = s.height = 160;
  s.shadows = true;
  s.shadowMapSize = 128;
  const std::vector<Light> lights{Light{glm::vec3(0.3f, 1.0f, 0.6f), glm::vec3(1.0f)}};
  Renderer culledR(context());
  const Camera cam = gltest::showCoat(culledR, coat);
  const Image culled = culledR.renderImage(cam, lights, s);
  const RenderStats on = culledR.lastStats();
  Renderer allR(context());
  gltest::showCoat(allR, coat);
  s.subpixelCulling = false;
  const Image all = allR.renderImage(cam, lights, s);
  const RenderStats off = allR.lastStats();
  ASSERT_TRUE(on.shadowMapRendered && off.shadowMapRendered);
  EXPECT_EQ(off.shadowTriangles, coat.coat.triangleCount());
  EXPECT_LT(on.shadowTriangles, off.shadowTriangles / 2);
  EXPECT_GT(on.shadowTriangles, 0u);
  EXPECT_EQ(meanAbsoluteError(culled, all), 0.0);
}

// ------------------------------------------------------------------ tone and ground (#29 item 3)

// A white Lambert quad facing a unit front light, no ambient: linear output is the light, 2^exposure
// scales it, and the filmic curve maps it through Narkowicz's ACES fit.
TEST(RendererTone, ExposureAndFilmicCurveFollowTheirFormulas) {
  Renderer r(context());
  const TriMesh q = quad({0, 0, 0}, {0.6f, 0, 0}, {0, 0.6f, 0});
  r.setCoat(q, {whole(q)});
  r.setMaterials({lambert({1, 1, 1})});
  auto value = [&](float exposure, bool filmic, float light) {
    RenderSettings s = flatSettings(32);
    s.exposure = exposure;
    s.filmic = filmic;
    return int(centre(r.renderImage(frontCamera(), {Light{{0, 0, 1}, glm::vec3(light)}}, s))[0]);
  };
  auto aces = [](double x) { return std::clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0); };
  EXPECT_NEAR(value(0.0f, false, 0.5f), 128, 1);
  EXPECT_NEAR(value(-1.0f, false, 0.5f), 64, 1);
  EXPECT_EQ(value(1.0f, false, 0.75f), 255);  // linear clips
  for (const float light : {0.1f, 0.5f, 1.0f, 2.0f})
    EXPECT_NEAR(value(0.0f, true, light), 255 * aces(light), 1.5) << light;
  EXPECT_LT(value(0.0f, true, 2.0f), 255);  // filmic keeps highlights below white
}

// A feather floating above the ground, lit from straight above: the ground under it is in its shadow,
// the ground beside it is lit, and without `ground` the background shows there.
TEST(RendererTone, TheGroundTakesTheModelsContactShadow) {
  Renderer r(context());
  r.setMaterials({lambert({1, 1, 1})});
  // A horizontal feather 0.3 above the ground, which touches the lowest point of the bounds: a tiny
  // second feather at y = 0 sets it.
  TriMesh coat = quad({0, 0.3f, 0}, {0.3f, 0, 0}, {0, 0, 0.3f});
  coat.append(quad({1.2f, 0.0f, 1.2f}, {0.01f, 0, 0}, {0, 0, 0.01f}));
  std::vector<FeatherDrawRange> ranges{whole(coat, 0), whole(coat, 6)};
  ranges[0].indexCount = 6;
  r.setCoat(coat, ranges);
  Camera cam;
  cam.eye = {0.0f, 4.0f, 0.01f};
  cam.target = {0, 0, 0};
  cam.up = {0, 0, -1};
  cam.zNear = 0.1f;
  RenderSettings s = flatSettings(128);
  s.background = {0, 0, 1, 1};
  s.ambient = glm::vec3(0.1f);
  s.shadows = true;
  s.shadowStrength = 1.0f;
  s.ground = true;
  s.groundNormal = {0, 1, 0};
  s.groundColor = glm::vec3(1.0f);
  const std::vector<Light> fromAbove{Light{{0.0f, 1.0f, 0.0f}, glm::vec3(1.0f)}};
  const Image img = r.renderImage(cam, fromAbove, s);
  // Lit from above the shadow hides under the feather; tilted, it shows beside it.
  const std::vector<Light> tilted{Light{glm::normalize(glm::vec3(1.0f, 2.0f, 0.0f)), glm::vec3(1.0f)}};
  const Image t = r.renderImage(cam, tilted, s);
  // The shadow is cast toward -x by 0.3 / 2 = 0.15 beyond the feather's edge at x = -0.3: sample x = -0.38.
  auto at = [&](const Image& im, float x, float z) {
    const glm::vec4 q = cam.projection(1.0f) * cam.view() * glm::vec4(x, 0.0f, z, 1.0f);
    const int px = int((q.x / q.w * 0.5f + 0.5f) * 128), py = int((1.0f - (q.y / q.w * 0.5f + 0.5f)) * 128);
    return int(im.pixel(px, py)[0]);
  };
  EXPECT_LT(at(t, -0.38f, 0.0f), at(t, -0.9f, 0.0f) / 2) << "contact shadow next to the feather";
  EXPECT_GT(at(img, -0.9f, 0.0f), 200) << "lit ground";
  s.ground = false;
  const Image none = r.renderImage(cam, tilted, s);
  EXPECT_EQ(at(none, -0.9f, 0.0f), 0) << "background (blue) without a ground";
  EXPECT_EQ(int(none.pixel(64, 127)[2]), 255);
}

// A wireframe draws the quad's three edges' worth of lines: the outline and the diagonal cover a thin
// fraction of what the filled quad covers, and the pixel at the quad's centre (off the diagonal) is empty.
TEST(RendererWireframe, DrawsEdgesOnlyAndLeavesTheStateFilled) {
  Renderer r(context());
  const TriMesh q = quad({0, 0, 0}, {0.6f, 0, 0}, {0, 0.6f, 0});
  r.setCoat(q, {whole(q)});
  r.setMaterials({lambert({1, 1, 1})});
  RenderSettings s = flatSettings(128);
  const uint8_t black[3] = {0, 0, 0};
  const double filled = coveredFraction(r.renderImage(frontCamera(), kFrontLight, s), black);
  s.wireframe = true;
  const Image lines = r.renderImage(frontCamera(), kFrontLight, s);
  const double edges = coveredFraction(lines, black);
  EXPECT_GT(edges, 0.0);
  EXPECT_LT(edges, 0.25 * filled);
  EXPECT_EQ(lines.pixel(64 + 10, 64 - 10)[0], 0);  // inside the quad, away from the diagonal
  // The next filled frame is filled again: the mode is not left behind in the context.
  s.wireframe = false;
  EXPECT_NEAR(coveredFraction(r.renderImage(frontCamera(), kFrontLight, s), black), filled, 1e-12);
}

TEST(RendererWindow, ClearWindowFillsTheContextsOwnFramebuffer) {
  Renderer r(context());
  r.clearWindow(64, 64, {0.0f, 1.0f, 0.0f});
  const Image img = r.readPixels(64, 64);
  EXPECT_EQ(img.pixel(0, 0)[0], 0);
  EXPECT_EQ(img.pixel(0, 0)[1], 255);
  EXPECT_EQ(img.pixel(63, 63)[1], 255);
  EXPECT_THROW(r.clearWindow(0, 64, {0, 0, 0}), Error);
}

TEST(ImageTexture, UploadsReplacesAndResizes) {
  ImageTexture t(context());
  EXPECT_EQ(t.id(), 0u);
  EXPECT_TRUE(t.download().empty());
  Image a(3, 2, 10, 20, 30, 255);
  a.pixel(2, 1)[0] = 200;
  t.upload(a);
  const uint32_t id = t.id();
  EXPECT_NE(id, 0u);
  EXPECT_EQ(t.download().rgba, a.rgba);
  Image b(3, 2, 1, 2, 3, 4);  // same size: replaced in place
  t.upload(b);
  EXPECT_EQ(t.id(), id);
  EXPECT_EQ(t.download().rgba, b.rgba);
  const Image c(5, 7, 9, 8, 7, 6);  // new size: reallocated
  t.upload(c);
  EXPECT_EQ(t.width(), 5);
  EXPECT_EQ(t.height(), 7);
  EXPECT_EQ(t.download().rgba, c.rgba);
  Image bad(2, 2);
  bad.rgba.pop_back();
  EXPECT_THROW(t.upload(bad), Error);
  EXPECT_EQ(t.download().rgba, c.rgba);  // a refused upload keeps the texture
}
