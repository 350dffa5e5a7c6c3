#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <filesystem>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/silhouette.hpp"

using namespace pteryla;
using namespace pteryla::feather;
namespace fs = std::filesystem;

namespace {

// Outline of a vane with a blunt base and a pointed tip around the shaft, feather-local (x along the shaft, y left);
// the right half is narrower (asymmetric feather).
std::vector<glm::dvec2> ovalOutline(double c, double L, double wl, double wr, int n = 200) {
  std::vector<glm::dvec2> pts;
  for (int i = 0; i <= n; ++i) {  // left edge, base to tip
    const double u = double(i) / n;
    pts.emplace_back(c + L * u, wl * std::sin(kPi * (0.1 + 0.9 * std::pow(u, 0.8))));
  }
  for (int i = n; i >= 0; --i) {  // right edge, tip to base
    const double u = double(i) / n;
    pts.emplace_back(c + L * u, -wr * std::sin(kPi * (0.1 + 0.9 * std::pow(u, 0.8))));
  }
  return pts;
}

}  // namespace

TEST(Silhouette, OutlineOfRectangleGivesHalfWidths) {
  FeatherParams p;
  p.calamusLength = 0.1;
  p.rachisLength = 1.0;
  p.rachisWidth = 0;
  p.left.baseAngle = p.left.tipAngle = kPi / 2;
  p.right.baseAngle = p.right.tipAngle = kPi / 6;  // ray at 30 deg reaches y = -0.2 after 0.4
  const std::vector<glm::dvec2> rect{{0.0, 0.3}, {2.0, 0.3}, {2.0, -0.2}, {0.0, -0.2}};
  const Silhouette s = silhouetteFromOutline(rect, p, 11);
  ASSERT_EQ(s.left.points.size(), 11u);
  for (const auto& q : s.left.points) EXPECT_NEAR(q.y, 0.3, 1e-12);
  for (const auto& q : s.right.points) EXPECT_NEAR(q.y, 0.4, 1e-12);
  // Outside the outline the barbs vanish.
  const std::vector<glm::dvec2> small{{0.0, 0.3}, {0.6, 0.3}, {0.6, -0.2}, {0.0, -0.2}};
  const Silhouette s2 = silhouetteFromOutline(small, p, 11);
  EXPECT_EQ(s2.left.points.back().y, 0.0);
  EXPECT_NEAR(s2.left.points[2].y, 0.3, 1e-12);
}

TEST(Silhouette, GeneratedBarbsReachTheOutline) {
  FeatherParams p;
  p.calamusLength = 0.2;
  p.rachisLength = 2.0;
  p.rachisWidth = 0.02;
  p.spacingBase = p.spacingTip = 0.02;
  p.left.baseAngle = 1.2;
  p.left.tipAngle = 0.6;
  p.right.baseAngle = 1.0;
  p.right.tipAngle = 0.5;
  p.left.keyBarbs = {{0, {{0, 0, 0}, {1, 0, 0}}}, {1, {{0, 0, 0}, {1, 0, 0}}}};
  p.right.keyBarbs = p.left.keyBarbs;
  const auto outline = ovalOutline(0.2, 2.0, 0.5, 0.25);
  p.silhouette = silhouetteFromOutline(outline, p, 65);
  const FeatherCurves c = generateBarbs(p);
  // Straight unit key barbs: every barb tip lies on the outline (up to the profile's sampling).
  double worst = 0;
  for (const BarbCurve& b : c.barbs) {
    if (b.rp > 0.97 || b.rp < 0.03) continue;
    const glm::vec3 tip = c.cvs[b.cvOffset + b.cvCount - 1];
    const glm::dvec2 t(tip.x, tip.y);
    double d = 1e9;
    for (size_t i = 0, j = outline.size() - 1; i < outline.size(); j = i++) {
      const glm::dvec2 a = outline[j], e = outline[i] - outline[j];
      const double s = std::clamp(glm::dot(t - a, e) / std::max(1e-300, glm::dot(e, e)), 0.0, 1.0);
      d = std::min(d, glm::length(a + s * e - t));
    }
    worst = std::max(worst, d);
  }
  EXPECT_LT(worst, 0.01 * p.totalLength());
}

TEST(Silhouette, FromSyntheticImageMatchesOutline) {
  for (double lateral : {0.0, 0.35}) {
    SCOPED_TRACE(lateral);
    // The feather the image is drawn from.
    FeatherParams truth;
    truth.calamusLength = 0.2;
    truth.rachisLength = 2.0;
    truth.rachisWidth = 0.01;
    truth.rachisLateralCurvature = lateral;
    truth.left.baseAngle = 1.1;
    truth.left.tipAngle = 0.6;
    truth.right.baseAngle = 0.8;
    truth.right.tipAngle = 0.4;
    // Outline follows the curved rachis: offset the straight oval by the rachis displacement.
    std::vector<glm::dvec2> outline = ovalOutline(0.2, 2.0, 0.55, 0.3);
    for (auto& q : outline) {
      const double rp = std::clamp((q.x - 0.2) / 2.0, 0.0, 1.0);
      const RachisFrame f = rachisFrame(truth, rp);
      q = glm::dvec2(f.point) + q.y * glm::dvec2(f.left);
    }
    const Silhouette expected = silhouetteFromOutline(outline, truth, 33);

    // Rasterize: x up, y to the viewer's left; 4x4 supersampling; vane grey, rachis dark, background white.
    const double scale = 180;  // pixels per unit
    GrayImage img;
    img.width = 300;
    img.height = 480;
    img.pixels.assign(size_t(img.width) * img.height, 1.0f);
    const glm::dvec2 origin(150, 440);  // follicle in pixels
    auto toLocal = [&](double px, double py) { return glm::dvec2((origin.y - py) / scale, (origin.x - px) / scale); };
    // Supersampled canvas: scanline-fill the outline, stamp the rachis and calamus, then box-filter.
    constexpr int kSS = 4;
    const int sw = img.width * kSS, sh = img.height * kSS;
    std::vector<float> canvas(size_t(sw) * sh, 1.0f);
    auto subToLocal = [&](double sx, double sy) { return toLocal((sx + 0.5) / kSS - 0.5, (sy + 0.5) / kSS - 0.5); };
    std::vector<double> xs;
    for (int sy = 0; sy < sh; ++sy) {
      const double ly = subToLocal(0, sy).x;  // local x is constant along an image row
      xs.clear();
      for (size_t i = 0, j = outline.size() - 1; i < outline.size(); j = i++) {
        const glm::dvec2 a = outline[j], b = outline[i];
        if ((a.x > ly) != (b.x > ly)) xs.push_back(a.y + (ly - a.x) * (b.y - a.y) / (b.x - a.x));
      }
      std::sort(xs.begin(), xs.end());
      for (size_t k = 0; k + 1 < xs.size(); k += 2)
        for (int sx = 0; sx < sw; ++sx) {
          const double lyy = subToLocal(sx, sy).y;
          if (lyy > xs[k] && lyy < xs[k + 1]) canvas[size_t(sy) * sw + sx] = 0.55f;
        }
    }
    const double radius = 1.5 / scale;
    for (int i = -100; i <= 2000; ++i) {
      // rachis (i >= 0) and calamus (i < 0) centre line
      const glm::dvec2 c =
          i >= 0 ? glm::dvec2(rachisFrame(truth, i / 2000.0).point) : glm::dvec2(0.2 * (i + 100) / 100.0, 0);
      const double cx = (origin.x - c.y * scale) * kSS, cy = (origin.y - c.x * scale) * kSS;
      const int r = int(std::ceil(radius * scale * kSS)) + 1;
      for (int sy = int(cy) - r; sy <= int(cy) + r; ++sy)
        for (int sx = int(cx) - r; sx <= int(cx) + r; ++sx) {
          if (sx < 0 || sy < 0 || sx >= sw || sy >= sh) continue;
          if (glm::length(subToLocal(sx, sy) - c) < radius) canvas[size_t(sy) * sw + sx] = 0.2f;
        }
    }
    for (int py = 0; py < img.height; ++py)
      for (int px = 0; px < img.width; ++px) {
        double acc = 0;
        for (int sy = 0; sy < kSS; ++sy)
          for (int sx = 0; sx < kSS; ++sx) acc += canvas[size_t(py * kSS + sy) * sw + px * kSS + sx];
        img.pixels[size_t(py) * img.width + px] = float(acc / (kSS * kSS));
      }
    const std::string path =
        (fs::path(PTERYLA_BUILD_DIR) / ("test_feather_silhouette_" + std::to_string(int(lateral * 100)) + ".png"))
            .string();
    saveGrayImage(path, img);

    // The user marks the rachis with a straight line from base to tip; refinement finds the curve.
    auto toPixel = [&](glm::dvec3 p) { return glm::dvec2(origin.x - p.y * scale, origin.y - p.x * scale); };
    SilhouetteImageOptions opt;
    opt.rachis = {toPixel(rachisFrame(truth, 0).point), toPixel(rachisFrame(truth, 1).point)};
    opt.searchRadius = 12;
    FeatherParams built;
    built.calamusLength = 0.2;
    built.rachisLength = 2.0;
    built.rachisWidth = 0.01;
    built.left = truth.left;
    built.right = truth.right;
    const SilhouetteImageResult res = applySilhouetteImage(built, path, opt);
    EXPECT_NEAR(res.rachisLengthPixels / scale, truth.rachisLength, 0.02 * truth.totalLength());
    EXPECT_NEAR(built.rachisLateralCurvature, lateral, 0.05);
    for (int v = 0; v < 2; ++v) {
      const LengthProfile& got = v == 0 ? built.silhouette.left : built.silhouette.right;
      const LengthProfile& want = v == 0 ? expected.left : expected.right;
      ASSERT_EQ(got.points.size(), want.points.size());
      double worst = 0;
      for (size_t i = 0; i < got.points.size(); ++i) {
        worst = std::max(worst, std::abs(got.points[i].y - want.points[i].y));
      }
      EXPECT_LT(worst, 0.02 * truth.totalLength()) << "vane " << v;
      EXPECT_GT(want.points[16].y, 0.2);  // the test is not vacuous
    }
  }
}

TEST(Silhouette, BadImageInputIsRejected) {
  GrayImage flat;
  flat.width = flat.height = 16;
  flat.pixels.assign(256, 1.0f);
  SilhouetteImageOptions opt;
  opt.rachis = {{8, 14}, {8, 2}};
  EXPECT_THROW(extractSilhouette(flat, opt), Error);
  opt.rachis = {{8, 14}};
  flat.pixels[8 * 16 + 8] = 0;
  EXPECT_THROW(extractSilhouette(flat, opt), Error);
  EXPECT_THROW(loadGrayImage("/nonexistent/feather.png"), Error);
}
