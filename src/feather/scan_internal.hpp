#pragma once
// Shared by silhouette.cpp, scan.cpp (measurement) and scan_texture.cpp (texture): image sampling and the
// fitted rachis arc in scan pixels.
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace pteryla::feather::scanning {

// Left of a direction in image pixels (y down), as seen by the viewer with the direction pointing up.
inline glm::dvec2 imageLeft(glm::dvec2 t) { return {t.y, -t.x}; }

inline double sample(const std::vector<float>& img, int w, int h, double x, double y) {
  x = std::clamp(x, 0.0, w - 1.0);
  y = std::clamp(y, 0.0, h - 1.0);
  const int x0 = std::min(static_cast<int>(x), std::max(0, w - 2)),
            y0 = std::min(static_cast<int>(y), std::max(0, h - 2));
  const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
  const double fx = x - x0, fy = y - y0;
  const auto at = [&](int xx, int yy) { return static_cast<double>(img[static_cast<size_t>(yy) * w + xx]); };
  return (at(x0, y0) * (1 - fx) + at(x1, y0) * fx) * (1 - fy) + (at(x0, y1) * (1 - fx) + at(x1, y1) * fx) * fy;
}

// The fitted rachis as an arc in pixels, parameterized by arc length s from the base; beyond [0, len]
// it continues along the end tangents (the calamus below the base).
struct PixelArc {
  glm::dvec2 start{0.0}, t0{0.0}, n0{0.0};
  double theta = 0, len = 0;
  PixelArc(const std::vector<glm::dvec2>& samples, double turning, double length) : theta(turning), len(length) {
    start = samples.front();
    const glm::dvec2 e = glm::normalize(samples.back() - samples.front()), nl = imageLeft(e);
    t0 = std::cos(-theta / 2) * e + std::sin(-theta / 2) * nl;
    n0 = imageLeft(t0);
  }
  glm::dvec2 tangent(double s) const {
    const double phi = theta * std::clamp(s, 0.0, len) / len;
    return std::cos(phi) * t0 + std::sin(phi) * n0;
  }
  glm::dvec2 point(double s) const {
    const double c = std::clamp(s, 0.0, len);
    glm::dvec2 p = start + c * t0;
    if (std::abs(theta) > 1e-9) {
      const double phi = theta * c / len;
      p = start + (len / theta) * (std::sin(phi) * t0 + (1 - std::cos(phi)) * n0);
    }
    return p + (s - c) * tangent(s);
  }
  // Unit normal toward vane v (0 left, 1 right) at s.
  glm::dvec2 side(int v, double s) const { return (v == 0 ? 1.0 : -1.0) * imageLeft(tangent(s)); }
};

}  // namespace pteryla::feather::scanning
