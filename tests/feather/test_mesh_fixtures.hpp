#pragma once
// Fixtures for the feather geometry tests (mesh, LOD, growth).
#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "pteryla/core/trimesh.hpp"
#include "pteryla/feather/params.hpp"

namespace pteryla::feather::geomtest {

inline KeyBarb key(double rp, std::vector<glm::dvec3> cvs) { return {rp, std::move(cvs)}; }

// A contour feather of about 3,000 triangles at full detail (4 segments per barb, Fig. 5.8): ~91 barbs
// per vane, a silhouette outline, key barbs on both vanes. Flat (no rachis curvature) when `flat`.
inline FeatherParams contour(bool flat = true) {
  FeatherParams p;
  p.name = "geometry contour";
  p.calamusLength = 0.2;
  p.calamusWidthRatio = 0.8;
  p.rachisLength = 2.0;
  p.rachisWidth = 0.04;
  p.spacingBase = 0.022;
  p.spacingTip = 0.022;
  p.barbLength = 0.5;
  p.silhouette.left.points = {{0.0, 0.25}, {0.3, 0.6}, {0.7, 0.55}, {1.0, 0.05}};
  p.silhouette.right.points = {{0.0, 0.2}, {0.3, 0.45}, {0.7, 0.4}, {1.0, 0.05}};
  p.left.baseAngle = 1.1;
  p.left.tipAngle = 0.5;
  p.right.baseAngle = 1.0;
  p.right.tipAngle = 0.45;
  p.left.keyBarbs = {key(0.25, {{0, 0, 0}, {0.35, 0.05, 0.02}, {0.7, 0.08, 0.0}, {1.0, 0.1, -0.03}}),
                     key(0.6, {{0, 0, 0}, {0.33, -0.04, 0.01}, {0.66, -0.02, 0.0}, {1.0, 0.05, -0.02}})};
  p.right.keyBarbs = {key(0.4, {{0, 0, 0}, {0.3, 0.06, 0.0}, {0.7, 0.1, 0.0}, {1.0, 0.12, -0.02}})};
  if (!flat) {
    p.rachisVentralDorsalCurvature = 0.35;
    p.rachisLateralCurvature = 0.1;
  }
  p.seed = 7;
  return p;
}

// 2D convex hull area (monotone chain).
inline double hullArea(std::vector<glm::dvec2> pts) {
  if (pts.size() < 3) return 0;
  std::sort(pts.begin(), pts.end(),
            [](const glm::dvec2& a, const glm::dvec2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  auto cross = [](const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  };
  std::vector<glm::dvec2> h(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], pts[i - 1]) <= 0) --k;
    h[k++] = pts[i - 1];
  }
  h.resize(k - 1);
  double a = 0;
  for (size_t i = 0; i < h.size(); ++i) {
    const glm::dvec2& p = h[i];
    const glm::dvec2& q = h[(i + 1) % h.size()];
    a += p.x * q.y - q.x * p.y;
  }
  return 0.5 * std::abs(a);
}

// Connected components of the triangles in index range [first, first + count) (shared vertices).
inline size_t components(const TriMesh& m, size_t first, size_t count) {
  std::vector<uint32_t> parent(m.positions.size());
  for (size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<uint32_t>(i);
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (size_t i = first; i < first + count; i += 3) {
    const uint32_t a = find(m.indices[i]), b = find(m.indices[i + 1]), c = find(m.indices[i + 2]);
    parent[b] = a;
    parent[find(c)] = find(a);
  }
  std::vector<uint32_t> roots;
  for (size_t i = first; i < first + count; ++i) roots.push_back(find(m.indices[i]));
  std::sort(roots.begin(), roots.end());
  return static_cast<size_t>(std::unique(roots.begin(), roots.end()) - roots.begin());
}

}  // namespace pteryla::feather::geomtest
