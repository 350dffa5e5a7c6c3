// Scratchboard style (7.3): tone preservation, strokes follow barbs, determinism, golden image.
#include <gtest/gtest.h>

#include <cmath>

#include "pteryla/core/error.hpp"
#include "pteryla/render/scratchboard.hpp"

using namespace pteryla;
using namespace pteryla::render;

namespace {

TriMesh flatQuad(glm::vec3 tangent, float size = 2.0f) {
  TriMesh m;
  const glm::vec3 p[4] = {{-size, -size, 0}, {size, -size, 0}, {size, size, 0}, {-size, size, 0}};
  for (const auto& q : p) {
    m.positions.push_back(q);
    m.normals.push_back({0, 0, 1});
    m.tangents.push_back(tangent);
    m.featherId.push_back(0);
  }
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

Camera front() {
  Camera c;
  c.eye = {0, 0, 5};
  return c;
}

double meanWhite(const Image& img, int x0, int y0, int x1, int y1) {
  double s = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) s += img.pixel(x, y)[0];
  return s / (255.0 * (x1 - x0) * (y1 - y0));
}

}  // namespace

TEST(Scratchboard, WhiteFractionFollowsTone) {
  const TriMesh q = flatQuad({1, 0, 0});
  ScratchboardSettings s;
  s.width = s.height = 256;
  s.ambient = 0.0f;
  s.drawSkin = false;
  for (float tone : {0.15f, 0.4f, 0.7f}) {
    s.coatAlbedo = tone;
    const Image img = renderScratchboard(q, TriMesh(), front(), {Light{{0, 0, 1}, {1, 1, 1}}}, s);
    const Image toneImg = scratchboardTone(q, TriMesh(), front(), {Light{{0, 0, 1}, {1, 1, 1}}}, s);
    EXPECT_NEAR(meanWhite(toneImg, 64, 64, 192, 192), tone, 0.01);
    EXPECT_NEAR(meanWhite(img, 64, 64, 192, 192), tone, 0.08) << "tone " << tone;
  }
}

TEST(Scratchboard, StrokesRunAlongBarbs) {
  ScratchboardSettings s;
  s.width = s.height = 128;
  s.drawSkin = false;
  s.coatAlbedo = 0.4f;
  auto runs = [&](const Image& img, bool horizontal) {
    // Mean length of white runs along rows (horizontal) or columns.
    int runsCount = 0, whiteCount = 0;
    for (int a = 32; a < 96; ++a) {
      bool prev = false;
      for (int b = 32; b < 96; ++b) {
        const bool w = (horizontal ? img.pixel(b, a) : img.pixel(a, b))[0] > 128;
        whiteCount += w;
        runsCount += w && !prev;
        prev = w;
      }
    }
    return runsCount ? double(whiteCount) / runsCount : 0.0;
  };
  const Image h = renderScratchboard(flatQuad({1, 0, 0}), TriMesh(), front(), {Light{{0, 0, 1}, {1, 1, 1}}}, s);
  const Image v = renderScratchboard(flatQuad({0, 1, 0}), TriMesh(), front(), {Light{{0, 0, 1}, {1, 1, 1}}}, s);
  EXPECT_GT(runs(h, true), 2.0 * runs(h, false));
  EXPECT_GT(runs(v, false), 2.0 * runs(v, true));
}

TEST(Scratchboard, DeterministicPerSeed) {
  ScratchboardSettings s;
  s.width = s.height = 96;
  const TriMesh q = flatQuad({1, 1, 0});
  const Image a = renderScratchboard(q, TriMesh(), front(), {Light{}}, s);
  EXPECT_EQ(a.rgba, renderScratchboard(q, TriMesh(), front(), {Light{}}, s).rgba);
  s.seed = 2;
  EXPECT_NE(a.rgba, renderScratchboard(q, TriMesh(), front(), {Light{}}, s).rgba);
  s.strokeSpacing = 0.0f;
  EXPECT_THROW(renderScratchboard(q, TriMesh(), front(), {Light{}}, s), Error);
}
