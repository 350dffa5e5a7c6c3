// Distribution metrics against known point sets: a perfect hexagonal lattice, random points, a stretched
// lattice.
#include <gtest/gtest.h>

#include <cmath>

#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/metrics.hpp"
#include "pteryla/coat/primitives.hpp"

using namespace pteryla;
using namespace pteryla::coat;

namespace {

// Hexagonal lattice with spacing a (stretched by `sx` along x) inside the unit square.
Follicles lattice(const SkinMesh& m, double a, double sx) {
  Follicles f;
  const Tract t = wholeMeshTract(m);
  const double dy = a * std::sqrt(3.0) / 2;
  for (int j = 0; j * dy < 1.0; ++j)
    for (int i = -1; (i * a + 0.5 * a * (j % 2)) * sx < 1.0; ++i) {
      const double x = (i * a + 0.5 * a * (j % 2)) * sx + 0.013, y = j * dy + 0.011;
      if (x <= 0 || x >= 1 || y >= 1) continue;
      const SurfacePoint p = closestSurfacePoint(m, {x, y, 0}, &t.faces);
      f.push(m, p.face, p.bary, 0, f.size());
    }
  return f;
}

}  // namespace

TEST(Metrics, PerfectHexLatticeScoresOne) {
  const SkinMesh m = makeGridPatch(10, 10);
  const Follicles f = lattice(m, 0.04, 1.0);
  const DistributionMetrics d = measureDistribution(m, wholeMeshTract(m), f);
  EXPECT_GT(d.interior, 300u);
  EXPECT_LT(d.interior, f.size());  // boundary follicles are left out
  EXPECT_DOUBLE_EQ(d.hexFraction, 1.0);
  EXPECT_NEAR(d.nnCv, 0.0, 1e-9);
  EXPECT_NEAR(d.meanDegree, 6.0, 1e-12);
  EXPECT_NEAR(d.psi6, 1.0, 1e-9);
  EXPECT_NEAR(d.nnMean, 1.0, 0.05);  // lattice spacing ~ hexagonal spacing of the density
  const FollicleNeighbours nb = delaunayNeighbours(f, d.spacing);
  size_t six = 0, complete = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    complete += nb.complete[i];
    six += nb.offsets[i + 1] - nb.offsets[i] == 6;
  }
  EXPECT_GT(six, f.size() / 2);
}

TEST(Metrics, RandomPointsMatchPoissonValues) {
  const SkinMesh m = makeGridPatch(10, 10);
  const Tract t = wholeMeshTract(m);
  double hex = 0, cv = 0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    ScatterOptions o;
    o.count = 3000;
    o.seed = seed;
    const DistributionMetrics d = measureDistribution(m, t, scatterFollicles(m, t, o));
    hex += d.hexFraction / 3;
    cv += d.nnCv / 3;
    EXPECT_NEAR(d.meanDegree, 6.0, 0.1);  // Euler: mean Delaunay degree 6
  }
  EXPECT_NEAR(hex, 0.295, 0.03);  // Poisson-Voronoi
  EXPECT_NEAR(cv, 0.52, 0.03);    // lloyd.md table
}

TEST(Metrics, DirectionalSpacingSeesStretch) {
  const SkinMesh m = makeGridPatch(10, 10);
  const Tract t = wholeMeshTract(m);
  const DirectionalSpacing iso = directionalSpacing(m, t, lattice(m, 0.04, 1.0), {1, 0, 0});
  EXPECT_NEAR(iso.along, iso.across, 1e-9);
  const DirectionalSpacing squeezed = directionalSpacing(m, t, lattice(m, 0.05, 0.6), {1, 0, 0});
  EXPECT_NEAR(squeezed.along / squeezed.across, 0.6 * 0.05 / std::hypot(0.3 * 0.05, 0.05 * std::sqrt(3.0) / 2), 1e-6);
}
