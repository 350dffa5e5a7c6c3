// Instancing (feather/instancing.hpp): which feathers may be meshed from another's curves. Checked on
// analytic displacements (a copy moved by a known distance) and a family of feathers of growing length.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "feather_fixtures.hpp"
#include "pteryla/feather/instancing.hpp"

using namespace pteryla::feather;

namespace {

FeatherCurves curvesOf(const FeatherParams& p) { return generateBarbs(p); }

// Every point of the curves moved by d (widths, positions along the rachis and directions kept).
FeatherCurves moved(FeatherCurves c, const glm::vec3& d) {
  for (ShaftCurve& s : c.shafts) {
    for (glm::vec3& p : s.points) p += d;
    for (glm::vec3& p : s.rachisCvs) p += d;
  }
  for (BarbCurve& b : c.barbs) b.root += d;
  for (glm::vec3& p : c.cvs) p += d;
  return c;
}

}  // namespace

TEST(ShareCurves, OffSharesNothingNotEvenIdenticalCurves) {
  const FeatherCurves a = curvesOf(pteryla::feather::testing::contourParams());
  const std::vector<const FeatherCurves*> list{&a, &a, &a};
  for (double tol : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()})
    EXPECT_EQ(shareCurves(list, tol), (std::vector<uint32_t>{0, 1, 2})) << tol;
  EXPECT_EQ(shareCurves(list, 1e-9), (std::vector<uint32_t>{0, 0, 0}));
}

// A copy moved by d differs by |d| exactly: shared when |d| <= tolerance x its extent, not beyond.
TEST(ShareCurves, AMovedCopySharesExactlyWithinTheTolerance) {
  const FeatherCurves a = curvesOf(pteryla::feather::testing::contourParams());
  const double tol = 0.01;
  for (double f : {0.5, 0.95, 1.05, 2.0}) {
    // The extent of the moved copy depends on the move: fix the move from a's extent, then compare.
    const double d = f * tol * curveExtent(a);
    const FeatherCurves b = moved(a, glm::vec3(0, 0, static_cast<float>(d)));
    const double limit = tol * curveExtent(b);
    EXPECT_TRUE(sameCurveStructure(a, b));
    EXPECT_NEAR(curveDistance(b, a, curveExtent(b), std::numeric_limits<double>::infinity()), d, 1e-6 * d);
    const std::vector<uint32_t> rep = shareCurves({&a, &b}, tol);
    EXPECT_EQ(rep[1], d <= limit ? 0u : 1u) << "move " << f << " x tolerance";
  }
  // An early stop reports a difference above the limit.
  const FeatherCurves far = moved(a, glm::vec3(0.5f, 0, 0));
  EXPECT_GT(curveDistance(far, a, curveExtent(far), 0.01), 0.01);
}

TEST(ShareCurves, DifferentBarbCountsNeverShare) {
  FeatherParams p = pteryla::feather::testing::contourParams();
  const FeatherCurves a = curvesOf(p);
  p.rachisLength *= 1.1;
  const FeatherCurves b = curvesOf(p);
  ASSERT_NE(a.barbs.size(), b.barbs.size());
  EXPECT_FALSE(sameCurveStructure(a, b));
  EXPECT_EQ(curveDistance(a, b, curveExtent(a), 1.0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(shareCurves({&a, &b}, 0.1), (std::vector<uint32_t>{0, 1}));
  // A null entry stands alone and is never a representative.
  EXPECT_EQ(shareCurves({&a, nullptr, &a}, 0.1), (std::vector<uint32_t>{0, 1, 0}));
}

// Feathers of slowly growing length: each takes an earlier leader within tolerance of it, leaders are
// their own representatives, the result repeats, and a larger tolerance needs no more leaders.
TEST(ShareCurves, AFamilyClustersAroundEarlierLeaders) {
  std::vector<FeatherCurves> family;
  for (int k = 0; k < 40; ++k) {
    FeatherParams p = pteryla::feather::testing::contourParams();
    p.barbLength *= 1.0 + 0.002 * k;
    p.rachisVentralDorsalCurvature += 0.003 * k;
    family.push_back(curvesOf(p));
  }
  std::vector<const FeatherCurves*> list;
  for (const FeatherCurves& c : family) list.push_back(&c);
  size_t lastLeaders = list.size() + 1;
  for (double tol : {0.005, 0.01, 0.03}) {
    const std::vector<uint32_t> rep = shareCurves(list, tol);
    EXPECT_EQ(rep, shareCurves(list, tol));
    size_t leaders = 0;
    for (size_t k = 0; k < rep.size(); ++k) {
      ASSERT_LE(rep[k], k);
      EXPECT_EQ(rep[rep[k]], rep[k]);
      leaders += rep[k] == k;
      const double e = curveExtent(family[k]);
      EXPECT_LE(curveDistance(family[k], family[rep[k]], e, std::numeric_limits<double>::infinity()), tol * e);
    }
    EXPECT_LT(leaders, list.size()) << tol;
    EXPECT_LE(leaders, lastLeaders) << tol;
    lastLeaders = leaders;
  }
}

// The windowed search (representatives sorted by tip) finds what scanning every earlier representative in
// order finds: the same representative for every feather, over a family with two varying parameters and
// repeats, at tolerances from tiny to wide.
TEST(ShareCurves, WindowedSearchEqualsThePlainScan) {
  std::vector<FeatherCurves> family;
  for (int k = 0; k < 120; ++k) {
    FeatherParams p = pteryla::feather::testing::contourParams();
    p.barbLength *= 1.0 + 0.001 * ((k * 37) % 23);
    p.rachisVentralDorsalCurvature += 0.002 * ((k * 11) % 17);
    family.push_back(curvesOf(p));
  }
  std::vector<const FeatherCurves*> list;
  for (const FeatherCurves& c : family) list.push_back(&c);
  list[5] = nullptr;
  for (double tol : {1e-6, 0.001, 0.004, 0.01, 0.05}) {
    std::vector<uint32_t> plain(list.size());
    std::vector<uint32_t> leaders;
    for (size_t k = 0; k < list.size(); ++k) {
      plain[k] = static_cast<uint32_t>(k);
      if (!list[k]) continue;
      const double e = curveExtent(*list[k]);
      for (uint32_t r : leaders)
        if (sameCurveStructure(*list[k], *list[r]) && curveDistance(*list[k], *list[r], e, tol * e) <= tol * e) {
          plain[k] = r;
          break;
        }
      if (plain[k] == k) leaders.push_back(static_cast<uint32_t>(k));
    }
    EXPECT_EQ(shareCurves(list, tol), plain) << tol;
  }
}
