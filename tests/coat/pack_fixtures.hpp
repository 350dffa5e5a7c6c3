#pragma once
// Fixtures for the packing tests and bench_pack: a coat of identical contour feathers on an icosphere
// (Fibonacci follicles in a latitude band, directions toward the south pole, layer order south to north,
// so each feather's vane lies over the follicles south of it), built without coat II so packing can be
// tested on its own.
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/feather/params.hpp"

namespace packtest {

using namespace pteryla;
using namespace pteryla::coat;

// A contour feather of total length ~ 0.42 * scale with ventral curvature and drooping key barbs.
inline feather::FeatherParams contourFeather(double scale) {
  feather::FeatherParams p;
  p.name = "contour";
  p.calamusLength = 0.02 * scale;
  p.rachisLength = 0.4 * scale;
  p.rachisWidth = 0.008 * scale;
  p.barbLength = 0.15 * scale;
  p.spacingBase = 0.01 * scale;
  p.spacingTip = 0.01 * scale;
  p.rachisVentralDorsalCurvature = 0.35;
  p.left.baseAngle = p.right.baseAngle = 0.9;
  p.left.tipAngle = p.right.tipAngle = 0.45;
  const std::vector<glm::dvec3> droop = {{0, 0, 0}, {0.35, 0.03, 0.02}, {0.7, 0.05, -0.02}, {0.98, 0.05, -0.12}};
  p.left.keyBarbs = {{0.5, droop}};
  p.right.keyBarbs = {{0.5, droop}};
  return p;
}

// `count` follicles on a Fibonacci spiral, kept where |z| < zMax, projected onto the skin.
inline CoatFeathers sphereCoat(const SkinMesh& skin, size_t count, double scale, double zMax = 0.8,
                               double radius = 1.0) {
  CoatFeathers c;
  const double golden = 3.14159265358979323846 * (3.0 - std::sqrt(5.0));
  const feather::FeatherParams p = contourFeather(scale);
  for (size_t k = 0; k < count; ++k) {
    const double z = 1 - 2 * (k + 0.5) / count;
    if (std::abs(z) >= zMax) continue;
    const double r = std::sqrt(1 - z * z), th = golden * k;
    const glm::dvec3 q = radius * glm::dvec3(r * std::cos(th), r * std::sin(th), z);
    const SurfacePoint sp = closestSurfacePoint(skin, q);
    FeatherFrame f;
    f.origin = pointAt(skin, sp);
    f.normal = normalAt(skin, sp.face, sp.bary);
    const glm::dvec3 t = glm::dvec3(0, 0, -1) - glm::dot(glm::dvec3(0, 0, -1), f.normal) * f.normal;
    f.tangent = glm::normalize(t);
    f.binormal = glm::normalize(glm::cross(f.normal, f.tangent));
    c.follicle.push_back(static_cast<uint32_t>(c.follicle.size()));
    c.tract.push_back(0);
    c.params.push_back(p);
    c.frames.push_back(f);
    c.age.push_back(1.0);
    c.present.push_back(1);
  }
  c.layerOrder.resize(c.size());
  std::iota(c.layerOrder.begin(), c.layerOrder.end(), 0u);
  std::stable_sort(c.layerOrder.begin(), c.layerOrder.end(),
                   [&](uint32_t a, uint32_t b) { return c.frames[a].origin.z < c.frames[b].origin.z; });
  return c;
}

}  // namespace packtest
