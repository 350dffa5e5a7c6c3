// Pattern synthesis, image I/O, image metrics and camera helpers (pure CPU code).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "pteryla/core/error.hpp"
#include "pteryla/render/camera.hpp"
#include "pteryla/render/image.hpp"
#include "pteryla/render/pattern.hpp"

using namespace pteryla;
using namespace pteryla::render;

namespace {
std::string scratchDir(const std::string& name) {
  const std::string d = std::string(PTERYLA_BUILD_DIR) + "/tests/render/" + name;
  std::filesystem::create_directories(d);
  return d;
}
}  // namespace

TEST(Pattern, DeterministicAndSeedDependent) {
  PatternParams p;
  p.kind = PatternKind::Spotted;
  p.seed = 5;
  const Image a = generatePattern(p), b = generatePattern(p);
  EXPECT_EQ(a.rgba, b.rgba);
  p.seed = 6;
  EXPECT_NE(generatePattern(p).rgba, a.rgba);
  EXPECT_EQ(a.width, 128);
  EXPECT_EQ(a.height, 256);
}

TEST(Pattern, OutlineIsOpaqueAtRachisTransparentAtCorners) {
  PatternParams p;
  const Image img = generatePattern(p);
  EXPECT_EQ(img.pixel(64, 128)[3], 255);  // middle of the vane
  EXPECT_EQ(img.pixel(0, 0)[3], 0);       // tip corner
  EXPECT_EQ(img.pixel(127, 255)[3], 0);   // base corner
  p.outline = false;
  EXPECT_EQ(generatePattern(p).pixel(0, 0)[3], 255);
}

TEST(Pattern, BarsAlternateAlongTheShaft) {
  PatternParams p;
  p.kind = PatternKind::Barred;
  p.frequency = 4.0f;
  p.markWidth = 0.5f;
  p.noise = 0.0f;
  p.shaftDarken = 0.0f;
  p.tipDarken = 0.0f;
  const Image img = generatePattern(p);
  // Along a column off the rachis, luminance alternates about 2 * frequency times.
  int changes = 0;
  bool prev = img.pixel(40, 20)[0] > 90;
  for (int y = 20; y < 240; ++y) {
    const bool cur = img.pixel(40, y)[0] > 90;
    changes += cur != prev;
    prev = cur;
  }
  EXPECT_GE(changes, 6);
  EXPECT_LE(changes, 9);
}

TEST(Pattern, EyespotHasDarkPupilNearTip) {
  PatternParams p;
  p.kind = PatternKind::Eyespot;
  p.noise = 0.0f;
  p.baseColor = {0.5f, 0.5f, 0.5f};
  p.markColor = {0, 0, 0};
  p.accentColor = {1, 1, 0};
  p.shaftDarken = 0;
  p.tipDarken = 0;
  const Image img = generatePattern(p);
  const int pupilY = static_cast<int>((1.0f - 0.76f) * 256);
  EXPECT_LT(img.pixel(64, pupilY)[0], 20);
  EXPECT_NEAR(img.pixel(20, 200)[0], 128, 3);  // base colour far from the ocellus
}

TEST(Pattern, BarbAlphaFallsOffQuadraticallyNearTipEarlierAtEdges) {
  BarbAlphaParams p;
  const Image a = generateBarbAlpha(p);
  const int cx = p.width / 2;
  EXPECT_EQ(a.pixel(cx, p.height - 1)[0], 255);                          // barb core at the rachis
  EXPECT_LT(a.pixel(cx, 0)[0], 20);                                      // tip transparent
  EXPECT_LT(a.pixel(1, p.height / 2)[0], a.pixel(cx, p.height / 2)[0]);  // fringe lighter than the barb
  // Just before the core starts to fade (t = 1 - tipFalloff), the fringe edge already fades (edgeLead).
  const int row = static_cast<int>(p.tipFalloff * p.height);  // t slightly below 1 - tipFalloff
  EXPECT_EQ(a.pixel(cx, row)[0], 255);
  EXPECT_LT(a.pixel(0, row)[0] + 3, a.pixel(0, p.height / 2)[0]);
  p.edgeLead = 0.0f;
  const Image noLead = generateBarbAlpha(p);
  EXPECT_EQ(noLead.pixel(0, row)[0], noLead.pixel(0, p.height / 2)[0]);
}

TEST(Pattern, StandardSetWritesReadablePngs) {
  const std::string dir = scratchDir("patterns");
  const std::vector<std::string> paths = writeStandardTextures(dir, 1);
  const char* expected[] = {"barred_brown", "scalloped_grey", "spotted",    "eyespot",   "plain_white",
                            "down_grey",    "flight_dark",    "barb_alpha", "down_alpha"};
  ASSERT_EQ(paths.size(), 9u);
  for (size_t i = 0; i < paths.size(); ++i) {
    EXPECT_EQ(paths[i], dir + "/" + expected[i] + ".png");
    const Image img = loadImage(paths[i]);
    EXPECT_GT(img.width, 0);
  }
  // The committed textures are this generator's output for seed 1.
  const std::vector<NamedImage> set = standardTextures(1);
  for (const NamedImage& t : set) {
    const std::string committed = std::string(PTERYLA_DATA_DIR) + "/textures/" + t.name + ".png";
    const Image c = loadImage(committed);
    EXPECT_EQ(c.rgba, t.image.rgba) << committed << " is stale: run pteryla_patterns --out data/textures";
  }
}

TEST(Pattern, RejectsBadParameters) {
  PatternParams p;
  p.width = 0;
  EXPECT_THROW(generatePattern(p), Error);
  p = PatternParams();
  p.markWidth = 1.5f;
  EXPECT_THROW(generatePattern(p), Error);
  BarbAlphaParams b;
  b.barbWidth = 0.0f;
  EXPECT_THROW(generateBarbAlpha(b), Error);
}

TEST(ImageIo, RoundTripsLosslessFormatsAndReadsJpeg) {
  PatternParams p;
  p.kind = PatternKind::Spotted;
  const Image img = generatePattern(p);
  const std::string dir = scratchDir("io");
  for (const char* ext : {".png", ".tif"}) {
    saveImage(dir + "/x" + ext, img);
    EXPECT_EQ(loadImage(dir + "/x" + ext).rgba, img.rgba) << ext;
  }
  saveImage(dir + "/x.exr", img);
  EXPECT_LT(meanAbsoluteError(loadImage(dir + "/x.exr"), img), 1.0 / 255.0);
  saveImage(dir + "/x.jpg", img);
  const Image j = loadImage(dir + "/x.jpg");
  EXPECT_EQ(j.pixel(3, 3)[3], 255);  // JPEG has no alpha
  EXPECT_LT(meanAbsoluteError(j, img), 0.03);
}

TEST(ImageIo, ErrorsNameTheFile) {
  try {
    loadImage("/nonexistent/a.png");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "/nonexistent/a.png");
  }
  try {
    saveImage("/nonexistent/dir/a.png", Image(2, 2));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "/nonexistent/dir/a.png");
  }
  EXPECT_THROW(saveImage(scratchDir("io") + "/empty.png", Image()), Error);
}

TEST(ImageMetrics, MeanAbsoluteErrorAndCoverage) {
  Image a(10, 10, 0, 0, 0), b(10, 10, 255, 255, 255);
  EXPECT_DOUBLE_EQ(meanAbsoluteError(a, b), 1.0);
  EXPECT_DOUBLE_EQ(meanAbsoluteError(a, a), 0.0);
  for (int x = 0; x < 5; ++x) b.pixel(x, 0)[0] = 0;
  EXPECT_NEAR(meanAbsoluteError(a, b), 1.0 - 5.0 / 300.0, 1e-12);
  EXPECT_THROW(meanAbsoluteError(a, Image(5, 5)), Error);
  const uint8_t black[3] = {0, 0, 0};
  Image c(10, 10, 0, 0, 0);
  for (int x = 0; x < 10; ++x) c.pixel(x, 3)[1] = 200;
  EXPECT_DOUBLE_EQ(coveredFraction(c, black), 0.1);
}

TEST(Camera, FrameBoundsKeepsTheBoxInView) {
  Camera cam;
  cam.eye = {3, 2, 1};
  const glm::vec3 lo(-1, -0.5f, -2), hi(2, 1, 0.5f);
  for (float aspect : {0.5f, 1.0f, 2.0f}) {
    cam.frameBounds(lo, hi, aspect);
    const glm::mat4 vp = cam.projection(aspect) * cam.view();
    for (int i = 0; i < 8; ++i) {
      const glm::vec3 p(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
      const glm::vec4 c = vp * glm::vec4(p, 1);
      ASSERT_GT(c.w, 0);
      EXPECT_LE(std::abs(c.x / c.w), 1.0f);
      EXPECT_LE(std::abs(c.y / c.w), 1.0f);
      EXPECT_GT(c.z / c.w, -1.0f);
      EXPECT_LT(c.z / c.w, 1.0f);
    }
  }
  // The viewing direction is kept.
  EXPECT_NEAR(glm::dot(cam.forward(), glm::normalize(glm::vec3(-3, -2, -1))), 1.0f, 1e-5f);
}

TEST(Camera, ScreenSizeAndLodFraction) {
  Camera cam;
  cam.eye = {0, 0, 10};
  cam.fovYDegrees = 40;
  const float r = 1.0f / std::sqrt(3.0f);  // box half-diagonal 1
  const float px = screenSizeOf(glm::vec3(-r), glm::vec3(r), cam, {1280, 720});
  const float expected = 720.0f * std::tan(std::asin(0.1f)) / std::tan(20.0f * 3.14159265f / 180.0f);
  EXPECT_NEAR(px, expected, 0.01f);
  cam.eye = {0, 0, 20};
  EXPECT_NEAR(screenSizeOf(glm::vec3(-r), glm::vec3(r), cam, {1280, 720}), expected / 2, 0.5f);
  cam.eye = {0, 0, 0.5f};
  EXPECT_EQ(screenSizeOf(glm::vec3(-r), glm::vec3(r), cam, {1280, 720}), 720.0f);
  EXPECT_EQ(lodFraction(800.0f, 400.0f), 1.0f);
  EXPECT_NEAR(lodFraction(240.0f, 400.0f), 0.6f, 1e-6f);
  EXPECT_NEAR(lodFraction(1.0f, 400.0f, 0.1f), 0.1f, 1e-6f);
}
