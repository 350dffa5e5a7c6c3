#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include "pteryla/core/rng.hpp"
#include "pteryla/feather/bezier.hpp"

using namespace pteryla;
using namespace pteryla::feather;

TEST(Bezier, EndpointsInterpolated) {
  const std::vector<glm::dvec3> cvs{{0, 0, 0}, {1, 2, 0}, {3, -1, 1}, {4, 0, 2}};
  EXPECT_EQ(bezierPoint(cvs, 0.0), cvs.front());
  EXPECT_NEAR(glm::length(bezierPoint(cvs, 1.0) - cvs.back()), 0.0, 1e-15);
}

TEST(Bezier, DegreeElevationLeavesCurveUnchanged) {
  Rng rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const size_t n = 2 + rng.below(8);
    std::vector<glm::dvec3> cvs(n);
    for (auto& c : cvs) c = {rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-2, 2)};
    const auto once = elevateDegree(cvs);
    ASSERT_EQ(once.size(), n + 1);
    const auto many = elevateTo(cvs, n + 5);
    ASSERT_EQ(many.size(), n + 5);
    for (int i = 0; i < 100; ++i) {
      const double u = i / 99.0;
      const glm::dvec3 ref = bezierPoint(cvs, u);
      EXPECT_LT(glm::length(bezierPoint(once, u) - ref), 1e-9);
      EXPECT_LT(glm::length(bezierPoint(many, u) - ref), 1e-9);
    }
  }
}

TEST(Bezier, DerivativeMatchesFiniteDifference) {
  const std::vector<glm::dvec3> cvs{{0, 0, 0}, {1, 2, 0}, {3, -1, 1}, {4, 0, 2}, {5, 1, 1}};
  for (double u : {0.1, 0.5, 0.77}) {
    const double h = 1e-6;
    const glm::dvec3 fd = (bezierPoint(cvs, u + h) - bezierPoint(cvs, u - h)) / (2 * h);
    EXPECT_LT(glm::length(bezierDerivative(cvs, u) - fd), 1e-6);
  }
}

TEST(Bezier, LongCurvesUseBernsteinPathConsistently) {
  std::vector<glm::dvec3> cvs(20);
  for (size_t i = 0; i < cvs.size(); ++i) cvs[i] = {double(i), std::sin(double(i)), 0};
  // Elevating a 12-point curve to 20 points (Bernstein path) must match the de Casteljau path.
  std::vector<glm::dvec3> small(12);
  for (size_t i = 0; i < small.size(); ++i) small[i] = {double(i), std::cos(double(i)), 0.5 * i};
  const auto big = elevateTo(small, 20);
  for (int i = 0; i <= 20; ++i) EXPECT_LT(glm::length(bezierPoint(big, i / 20.0) - bezierPoint(small, i / 20.0)), 1e-9);
}
