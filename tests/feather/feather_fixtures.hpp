#pragma once
// Shared feather fixtures for the feather tests.
#include "pteryla/feather/params.hpp"

namespace pteryla::feather::testing {

inline KeyBarb straightKey(double rp, double chord = 1.0) {
  return {rp, {{0, 0, 0}, {chord / 3, 0, 0}, {2 * chord / 3, 0, 0}, {chord, 0, 0}}};
}

// A contour-like feather with explicit key barbs on both vanes.
inline FeatherParams contourParams() {
  FeatherParams p;
  p.name = "fixture contour";
  p.calamusLength = 0.2;
  p.rachisLength = 2.0;
  p.rachisWidth = 0.03;
  p.rachisVentralDorsalCurvature = 0.3;
  p.barbLength = 0.6;
  p.spacingBase = 0.03;
  p.spacingTip = 0.02;
  p.left.baseAngle = 1.0;
  p.left.tipAngle = 0.5;
  p.left.keyBarbs = {{0.1, {{0, 0, 0}, {0.3, -0.1, 0.2}, {0.6, 0.2, -0.1}, {0.9, -0.1, 0.3}}},
                     {0.5, {{0, 0, 0}, {0.35, 0.05, 0.02}, {0.7, 0.08, 0.0}, {1.0, 0.1, -0.05}}},
                     {0.9, {{0, 0, 0}, {0.5, 0.1, 0.0}, {1.0, 0.1, -0.02}}}};
  p.right = p.left;
  p.seed = 42;
  return p;
}

}  // namespace pteryla::feather::testing
