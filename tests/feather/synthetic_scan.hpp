#pragma once
// A synthetic flatbed scan of a known feather, rendered on the CPU: the vanes as a flat tone (the
// barbules; one colour per vane, so a test can tell left from right), every barb of generateBarbs() as a
// dark anti-aliased line over it, the rachis and calamus as darker tapered lines, on a light background
// with seeded scanner noise. Shared by tests/feather/test_scan.cpp and tests/cli/test_scan_cli.cpp.
#include <OpenImageIO/imageio.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/params.hpp"
#include "pteryla/feather/silhouette.hpp"

namespace pteryla::feather::testing {

// The feather the scans are made from (centimetres): asymmetric vanes, a laterally curved rachis, spacing
// and angles that change from base to tip. bendBase/bendTip: key barbs turned toward the tip by these
// angles (radians over the barb; 0 = straight).
inline FeatherParams scanTruth(double bendBase = 0, double bendTip = 0) {
  FeatherParams p;
  p.name = "scan truth";
  p.calamusLength = 0.35;
  p.calamusWidthRatio = 0.8;
  p.rachisLength = 3.0;
  p.rachisWidth = 0.045;
  p.rachisLateralCurvature = 0.2;
  p.spacingBase = 0.05;
  p.spacingTip = 0.04;
  p.left.baseAngle = 1.0;
  p.left.tipAngle = 0.55;
  p.right.baseAngle = 0.85;
  p.right.tipAngle = 0.45;
  auto arc = [](double bend) -> std::vector<glm::dvec3> {
    if (std::abs(bend) < 1e-9) return {{0, 0, 0}, {1.0 / 3, 0, 0}, {2.0 / 3, 0, 0}, {1, 0, 0}};
    const double r = 1 / (2 * std::sin(bend / 2)), h = 4.0 / 3 * std::tan(bend / 4) * r;
    const glm::dvec3 end(r * std::sin(bend), r * (1 - std::cos(bend)), 0), t(std::cos(bend), std::sin(bend), 0);
    return {{0, 0, 0}, {h, 0, 0}, end - h * t, end};
  };
  p.left.keyBarbs = {{0.0, arc(bendBase)}, {1.0, arc(bendTip)}};
  p.right.keyBarbs = p.left.keyBarbs;
  p.silhouette.left.points = {{0, 0.55}, {0.2, 0.95}, {0.5, 1.05}, {0.75, 0.85}, {0.9, 0.5}, {1, 0.1}};
  p.silhouette.right.points = {{0, 0.4}, {0.2, 0.6}, {0.5, 0.65}, {0.75, 0.55}, {0.9, 0.35}, {1, 0.08}};
  p.barbLength = 1.05;
  return p;
}

struct SyntheticScan {
  int width = 0, height = 0;
  std::vector<float> rgb;  // 3 floats per pixel, row 0 at the top
  double pixelsPerUnit = 0;
  glm::dvec2 base{0.0}, tip{0.0};  // rachis base (superior umbilicus) and tip, pixels
  GrayImage gray() const {         // luminance, as loadGrayImage computes it
    GrayImage g;
    g.width = width, g.height = height;
    g.pixels.resize(static_cast<size_t>(width) * height);
    for (size_t i = 0; i < g.pixels.size(); ++i)
      g.pixels[i] = 0.2126f * rgb[3 * i] + 0.7152f * rgb[3 * i + 1] + 0.0722f * rgb[3 * i + 2];
    return g;
  }
  bool save(const std::string& path) const {
    auto out = OIIO::ImageOutput::create(path);
    if (!out || !out->open(path, OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::UINT8))) return false;
    return out->write_image(OIIO::TypeDesc::FLOAT, rgb.data()) && out->close();
  }
};

// Renders `p` (flat: its ventral-dorsal curvature must be 0) at `pixelsPerUnit`, the shaft turned by
// `rotation` radians from pointing up (counter-clockwise on screen), the left vane (+y) on the viewer's
// left. Noise: uniform in +-noise per pixel from `seed`.
inline SyntheticScan renderScan(const FeatherParams& p, double pixelsPerUnit, double rotation, uint64_t seed,
                                double noise = 0.02) {
  const FeatherCurves c = generateBarbs(p);
  const double k = pixelsPerUnit, cr = std::cos(rotation), sr = std::sin(rotation);
  // Feather-local (x along the shaft, y left) -> pixels before the translation.
  auto toPx0 = [&](glm::dvec2 q) {
    const glm::dvec2 up(-q.y * k, -q.x * k);  // unrotated: +x up, +y left
    return glm::dvec2(cr * up.x + sr * up.y, -sr * up.x + cr * up.y);
  };
  glm::dvec2 lo(1e300), hi(-1e300);
  auto grow = [&](glm::dvec2 q) { lo = glm::min(lo, toPx0(q)), hi = glm::max(hi, toPx0(q)); };
  grow({0, 0});
  for (const auto& v : c.cvs) grow({v.x, v.y});
  for (const auto& v : c.shafts[0].points) grow({v.x, v.y});
  const double margin = 40;
  SyntheticScan s;
  s.pixelsPerUnit = k;
  s.width = static_cast<int>(std::ceil(hi.x - lo.x + 2 * margin));
  s.height = static_cast<int>(std::ceil(hi.y - lo.y + 2 * margin));
  const glm::dvec2 shift = glm::dvec2(margin) - lo;
  auto toPx = [&](glm::dvec3 q) { return toPx0({q.x, q.y}) + shift; };
  s.base = toPx(rachisFrame(p, 0).point);
  s.tip = toPx(rachisFrame(p, 1).point);

  const std::array<float, 3> paper{0.95f, 0.95f, 0.93f}, ink{0.22f, 0.2f, 0.18f}, shaft{0.1f, 0.09f, 0.08f};
  const std::array<std::array<float, 3>, 2> vane{{{0.78f, 0.44f, 0.34f}, {0.34f, 0.46f, 0.74f}}};
  s.rgb.resize(static_cast<size_t>(s.width) * s.height * 3);
  for (size_t i = 0; i < s.rgb.size(); i += 3) std::copy(paper.begin(), paper.end(), s.rgb.begin() + i);
  auto blend = [&](int x, int y, const std::array<float, 3>& col, double a) {
    if (x < 0 || y < 0 || x >= s.width || y >= s.height || a <= 0) return;
    float* px = &s.rgb[(static_cast<size_t>(y) * s.width + x) * 3];
    for (int ch = 0; ch < 3; ++ch) px[ch] = static_cast<float>(px[ch] * (1 - a) + col[ch] * a);
  };

  // Vanes: polygon roots (base to tip) + barb tips (tip to base), 4x4 supersampled scanline fill.
  constexpr int kSS = 4;
  for (int v = 0; v < 2; ++v) {
    std::vector<glm::dvec2> poly;
    std::vector<glm::dvec2> tips;
    std::vector<glm::vec3> line;
    for (uint32_t i = c.barbBegin[0]; i < c.barbEnd[0]; ++i) {
      const BarbCurve& b = c.barbs[i];
      if (b.vane != v) continue;
      barbPolyline(c, b, 16, line);
      poly.push_back(toPx(glm::dvec3(line.front())));
      tips.push_back(toPx(glm::dvec3(line.back())));
    }
    poly.insert(poly.end(), tips.rbegin(), tips.rend());
    std::vector<float> cover(static_cast<size_t>(s.width) * s.height, 0.0f);
    std::vector<double> xs;
    for (int sy = 0; sy < s.height * kSS; ++sy) {
      const double y = (sy + 0.5) / kSS - 0.5;
      xs.clear();
      for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
        const glm::dvec2 a = poly[j], b = poly[i];
        if ((a.y > y) != (b.y > y)) xs.push_back(a.x + (y - a.y) * (b.x - a.x) / (b.y - a.y));
      }
      std::sort(xs.begin(), xs.end());
      for (size_t m = 0; m + 1 < xs.size(); m += 2)
        for (int sx = std::max(0, static_cast<int>(std::ceil((xs[m] + 0.5) * kSS - 0.5)));
             sx < s.width * kSS && (sx + 0.5) / kSS - 0.5 < xs[m + 1]; ++sx)
          cover[static_cast<size_t>(sy / kSS) * s.width + sx / kSS] += 1.0f / (kSS * kSS);
    }
    for (int y = 0; y < s.height; ++y)
      for (int x = 0; x < s.width; ++x)
        blend(x, y, vane[v], std::min(1.0f, cover[static_cast<size_t>(y) * s.width + x]));
  }
  // Anti-aliased segment of width `w` pixels: coverage = clamp(w/2 + 0.5 - distance, 0, 1).
  std::vector<float> dark(static_cast<size_t>(s.width) * s.height);
  auto segment = [&](glm::dvec2 a, glm::dvec2 b, double wa, double wb) {
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min(a.x, b.x) - wa - 2)));
    const int x1 = std::min(s.width - 1, static_cast<int>(std::ceil(std::max(a.x, b.x) + wa + 2)));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min(a.y, b.y) - wa - 2)));
    const int y1 = std::min(s.height - 1, static_cast<int>(std::ceil(std::max(a.y, b.y) + wa + 2)));
    const glm::dvec2 e = b - a;
    const double ee = std::max(1e-12, glm::dot(e, e));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double t = std::clamp(glm::dot(glm::dvec2(x, y) - a, e) / ee, 0.0, 1.0);
        const double d = glm::length(glm::dvec2(x, y) - (a + t * e)), wdt = wa + t * (wb - wa);
        float& o = dark[static_cast<size_t>(y) * s.width + x];
        o = std::max(o, static_cast<float>(std::clamp(0.5 * wdt + 0.5 - d, 0.0, 1.0)));
      }
  };
  std::vector<glm::vec3> line;
  for (uint32_t i = c.barbBegin[0]; i < c.barbEnd[0]; ++i) {
    barbPolyline(c, c.barbs[i], 16, line);
    for (size_t j = 0; j + 1 < line.size(); ++j)
      segment(toPx(glm::dvec3(line[j])), toPx(glm::dvec3(line[j + 1])), 1.4, 1.4);
  }
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) blend(x, y, ink, dark[static_cast<size_t>(y) * s.width + x]);
  std::fill(dark.begin(), dark.end(), 0.0f);
  // Shaft: calamus (width ratio x rachis width at the follicle) and rachis (tapering to the tip).
  const ShaftCurve& sh = c.shafts[0];
  for (size_t j = 0; j + 1 < sh.points.size(); ++j)
    segment(toPx(glm::dvec3(sh.points[j])), toPx(glm::dvec3(sh.points[j + 1])), sh.widths[j] * k, sh.widths[j + 1] * k);
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) blend(x, y, shaft, dark[static_cast<size_t>(y) * s.width + x]);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> jitter(static_cast<float>(-noise), static_cast<float>(noise));
  for (auto& v : s.rgb) v = std::clamp(v + jitter(rng), 0.0f, 1.0f);
  return s;
}

}  // namespace pteryla::feather::testing
