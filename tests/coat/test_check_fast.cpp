// The coat checker's fast paths (check.hpp) against brute-force references on small coats: the pair
// search (feathers whose bounds meet, tree against tree) finds exactly the pairs of an O(n^2) scan, in any
// triangle order; the coverage rays (a tree over the feathers' trees) hit exactly what a scan of every
// triangle hits; the skin test (nearest face searched from the last vertex's face) counts exactly the
// vertices inside; progress moves through the parts and a callback returning false stops the check.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "../../src/coat/spatial.hpp"
#include "pteryla/coat/check.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/core/trimesh.hpp"

namespace {

using glm::dvec3;
using pteryla::TriMesh;
namespace coat = pteryla::coat;
namespace detail = pteryla::coat::detail;
constexpr double kPi = 3.14159265358979323846;

// `feathers` clusters of thin, long triangles (barb-like) crossing each other inside [0,1]^2 x [0,0.2];
// `shuffled` scatters each feather's triangles through the mesh instead of keeping them together.
TriMesh soup(size_t triangles, uint32_t feathers, uint64_t seed, bool shuffled = false) {
  pteryla::Rng rng(seed);
  std::vector<uint32_t> featherOf(triangles);
  for (size_t t = 0; t < triangles; ++t) featherOf[t] = static_cast<uint32_t>(t * feathers / triangles);
  if (shuffled)
    for (size_t t = triangles; t-- > 1;)
      std::swap(featherOf[t], featherOf[static_cast<size_t>(rng.uniform(0, double(t) + 1)) % (t + 1)]);
  TriMesh m;
  for (size_t t = 0; t < triangles; ++t) {
    const dvec3 c(rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 0.2));
    const dvec3 d = glm::normalize(dvec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-0.3, 0.3)));
    const dvec3 e = glm::normalize(dvec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
    const double len = rng.uniform(0.02, 0.1);
    for (const dvec3& p : {c, c + len * d, c + 0.01 * e}) {
      m.positions.emplace_back(p);
      m.featherId.push_back(featherOf[t]);
    }
    for (int k = 0; k < 3; ++k) m.indices.push_back(static_cast<uint32_t>(3 * t + k));
  }
  m.normals.assign(m.positions.size(), glm::vec3(0, 0, 1));
  return m;
}

dvec3 vert(const TriMesh& m, size_t t, int k) { return dvec3(m.positions[m.indices[3 * t + k]]); }
uint32_t featherOfTriangle(const TriMesh& m, size_t t) {
  return m.featherId.empty() ? 0 : m.featherId[m.indices[3 * t]];
}

// Every pair of triangles of different feathers, Moeller's test on the lower index first: (t << 32 | u).
std::vector<uint64_t> bruteForcePairs(const TriMesh& m) {
  const size_t nt = m.triangleCount();
  std::vector<uint64_t> out;
  for (size_t t = 0; t < nt; ++t)
    for (size_t u = t + 1; u < nt; ++u) {
      if (featherOfTriangle(m, t) == featherOfTriangle(m, u)) continue;
      if (detail::trianglesIntersect(vert(m, t, 0), vert(m, t, 1), vert(m, t, 2), vert(m, u, 0), vert(m, u, 1),
                                     vert(m, u, 2)))
        out.push_back((uint64_t(t) << 32) | u);
    }
  return out;
}

// A closed UV sphere of radius r around the origin.
coat::SkinMesh sphereSkin(double r, int rings, int segments) {
  std::vector<dvec3> p;
  std::vector<std::array<uint32_t, 3>> f;
  p.push_back({0, 0, r});
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = kPi * i / rings, ph = 2 * kPi * j / segments;
      p.push_back({r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)});
    }
  p.push_back({0, 0, -r});
  const uint32_t south = static_cast<uint32_t>(p.size() - 1);
  auto at = [&](int i, int j) { return static_cast<uint32_t>(1 + (i - 1) * segments + (j % segments)); };
  for (int j = 0; j < segments; ++j) f.push_back({0, at(1, j), at(1, j + 1)});
  for (int i = 1; i < rings - 1; ++i)
    for (int j = 0; j < segments; ++j) {
      f.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      f.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  for (int j = 0; j < segments; ++j) f.push_back({at(rings - 1, j), south, at(rings - 1, j + 1)});
  return coat::makeSkinMesh(std::move(p), std::move(f));
}

}  // namespace

TEST(FastCheck, PairsAreTheBruteForcePairsWhateverTheTriangleOrder) {
  for (const bool shuffled : {false, true}) {
    for (const uint64_t seed : {1u, 2u, 3u}) {
      const TriMesh m = soup(2500, seed == 3 ? 7 : 120, seed, shuffled);
      const std::vector<uint64_t> want = bruteForcePairs(m);
      ASSERT_GT(want.size(), 50u) << "the soup must cross";
      EXPECT_EQ(coat::intersectingTrianglePairs(m), want) << "shuffled " << shuffled << " seed " << seed;
      EXPECT_EQ(coat::countIntersectingPairs(m), want.size());
      EXPECT_EQ(coat::countIntersectingPairs(m, 1), want.size());
      // Per pair of feathers, as the brute force groups them.
      std::map<std::pair<uint32_t, uint32_t>, uint32_t> perFeather;
      for (const uint64_t k : want) {
        const uint32_t a = featherOfTriangle(m, k >> 32), b = featherOfTriangle(m, k & 0xffffffffu);
        ++perFeather[{std::min(a, b), std::max(a, b)}];
      }
      const std::vector<coat::FeatherPairCount> got = coat::intersectingFeatherPairs(m);
      ASSERT_EQ(got.size(), perFeather.size());
      size_t i = 0;
      for (const auto& [ab, n] : perFeather) {
        EXPECT_EQ(got[i].a, ab.first);
        EXPECT_EQ(got[i].b, ab.second);
        EXPECT_EQ(got[i].pairs, n);
        ++i;
      }
    }
  }
  // Without feather ids the coat is one feather: nothing to pair.
  TriMesh one = soup(800, 40, 9);
  one.featherId.clear();
  EXPECT_EQ(coat::countIntersectingPairs(one), 0u);
}

TEST(FastCheck, CheckCountsAreTheBruteForceCounts) {
  // Barb-like triangles in a shell around a sphere: some cross each other, some dip inside the skin.
  const coat::SkinMesh skin = sphereSkin(1.0, 16, 24);
  pteryla::Rng rng(21);
  TriMesh m;
  size_t inside = 0;
  for (uint32_t f = 0; f < 60; ++f)
    for (int k = 0; k < 30; ++k) {
      const dvec3 dir = glm::normalize(dvec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
      // Vertices clearly inside (radius <= 0.9) or clearly outside (>= 1.05): the expected count is exact.
      const bool dip = rng.uniform(0, 1) < 0.1;
      const double r = dip ? rng.uniform(0.5, 0.9) : rng.uniform(1.05, 1.3);
      const dvec3 c = r * dir;
      const dvec3 side =
          glm::normalize(glm::cross(dir, dvec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1))));
      const dvec3 a = c + 0.2 * side, b = c + 0.03 * glm::normalize(glm::cross(dir, side));
      for (const dvec3& p : {c, a, b}) {
        m.positions.emplace_back(p);
        m.featherId.push_back(f);
        if (glm::length(p) < 1.0) ++inside;
      }
      for (int c3 = 0; c3 < 3; ++c3) m.indices.push_back(static_cast<uint32_t>(m.positions.size() - 3 + c3));
    }
  m.normals.assign(m.positions.size(), glm::vec3(0, 0, 1));
  // Every vertex strictly inside or strictly outside by 0.05 (the skin's chords lie within 0.02 of r).
  for (const auto& p : m.positions) ASSERT_TRUE(glm::length(dvec3(p)) < 0.98 || glm::length(dvec3(p)) > 1.02);
  coat::CheckOptions o;
  o.coverageSamples = 3000;
  o.seed = 5;
  o.attribute = true;
  const coat::CheckResult r = coat::check(skin, {}, m, o);
  ASSERT_TRUE(r.complete);
  EXPECT_EQ(r.intersectingPairs, bruteForcePairs(m).size());
  EXPECT_GT(inside, 0u);
  EXPECT_EQ(r.skinPenetrations, inside);
  EXPECT_EQ(r.samplePoints, m.positions.size());
  // Coverage: the same samples, each ray tested against every triangle.
  std::vector<double> cdf(skin.faces.size());
  double acc = 0;
  for (size_t k = 0; k < skin.faces.size(); ++k) cdf[k] = acc += skin.faceAreas[k];
  double diag = 0;
  {
    detail::Box b;
    for (const auto& p : skin.positions) b.add(p);
    diag = glm::length(b.hi - b.lo);
  }
  size_t covered = 0;
  for (size_t s = 0; s < o.coverageSamples; ++s) {
    const double x = pteryla::hashUniform(o.seed, s, 0) * acc;
    const size_t k =
        std::min(static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin()), cdf.size() - 1);
    double a = pteryla::hashUniform(o.seed, s, 1), b = pteryla::hashUniform(o.seed, s, 2);
    if (a + b > 1) {
      a = 1 - a;
      b = 1 - b;
    }
    const dvec3 bary(1 - a - b, a, b);
    const uint32_t f = static_cast<uint32_t>(k);
    const dvec3 origin = coat::pointAt(skin, f, bary) + 1e-6 * diag * skin.faceNormals[f];
    const dvec3 dir = coat::normalAt(skin, f, bary);
    bool hit = false;
    for (size_t t = 0; t < m.triangleCount() && !hit; ++t) {
      const double h = detail::rayTriangle(origin, dir, vert(m, t, 0), vert(m, t, 1), vert(m, t, 2));
      hit = h > 0 && h <= std::numeric_limits<double>::infinity();
    }
    covered += hit;
  }
  EXPECT_GT(covered, 0u);
  EXPECT_LT(covered, o.coverageSamples);
  EXPECT_EQ(r.coveredSamples, covered);
  EXPECT_EQ(r.coverageSamples, o.coverageSamples);
  // Attribution: every intersecting pair is counted once for its two feathers.
  size_t sum = 0;
  for (const auto& p : r.featherPairs) sum += p.pairs;
  EXPECT_EQ(sum, r.intersectingPairs);
}

TEST(FastCheck, NearestFaceIsTheLinearScansFace) {
  // The skin test's nearest-face search (node distances kept on the stack, searched from a bound given
  // by another face) against a scan of every face: the same face, ties to the lower index.
  const coat::SkinMesh skin = sphereSkin(1.0, 12, 18);
  std::vector<uint32_t> flat;
  for (const auto& f : skin.faces) flat.insert(flat.end(), f.begin(), f.end());
  detail::TriangleBvh bvh;
  bvh.build(skin.positions.data(), flat.data(), skin.faces.size());
  pteryla::Rng rng(4);
  for (int q = 0; q < 3000; ++q) {
    const dvec3 p(rng.uniform(-1.6, 1.6), rng.uniform(-1.6, 1.6), rng.uniform(-1.6, 1.6));
    int64_t want = -1;
    double wantD = std::numeric_limits<double>::infinity();
    for (size_t f = 0; f < skin.faces.size(); ++f) {
      const auto& t = skin.faces[f];
      const dvec3 d =
          coat::closestPointOnTriangle(p, skin.positions[t[0]], skin.positions[t[1]], skin.positions[t[2]]) - p;
      const double dd = glm::dot(d, d);
      if (dd < wantD) {
        wantD = dd;
        want = static_cast<int64_t>(f);
      }
    }
    dvec3 bary;
    double d2 = 0;
    ASSERT_EQ(bvh.nearest(p, std::numeric_limits<double>::infinity(), bary, d2), want) << q;
    EXPECT_EQ(d2, wantD);
    // Bounded by an arbitrary face's distance: still the nearest.
    const auto& t = skin.faces[static_cast<size_t>(q) % skin.faces.size()];
    const dvec3 d =
        coat::closestPointOnTriangle(p, skin.positions[t[0]], skin.positions[t[1]], skin.positions[t[2]]) - p;
    EXPECT_EQ(bvh.nearest(p, glm::dot(d, d), bary, d2), want) << q;
  }
}

TEST(FastCheck, ProgressMovesAndAFalseReturnStops) {
  const coat::SkinMesh skin = sphereSkin(1.0, 10, 16);
  TriMesh m = soup(6000, 200, 13);
  for (auto& p : m.positions) p = glm::vec3(dvec3(p) * 2.0 - dvec3(1, 1, 0.2));
  std::vector<double> seen;
  coat::CheckOptions o;
  o.coverageSamples = 2000;
  o.progress = [&](const std::string& stage, double f) {
    EXPECT_EQ(stage, "check");
    seen.push_back(f);
    return true;
  };
  const coat::CheckResult full = coat::check(skin, {}, m, o);
  ASSERT_TRUE(full.complete);
  ASSERT_GE(seen.size(), 8u);
  EXPECT_EQ(seen.front(), 0.0);
  EXPECT_EQ(seen.back(), 1.0);
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  // The counts do not depend on whether progress is reported.
  coat::CheckOptions quiet = o;
  quiet.progress = {};
  const coat::CheckResult q = coat::check(skin, {}, m, quiet);
  EXPECT_EQ(q.intersectingPairs, full.intersectingPairs);
  EXPECT_EQ(q.skinPenetrations, full.skinPenetrations);
  EXPECT_EQ(q.coveredSamples, full.coveredSamples);
  EXPECT_GT(full.intersectingPairs, 0u);
  // Stop at the first report past 10%: no further report, and the result says it is incomplete.
  size_t calls = 0, afterStop = 0;
  bool stopped = false;
  o.progress = [&](const std::string&, double f) {
    ++calls;
    if (stopped) ++afterStop;
    if (f > 0.1) stopped = true;
    return !stopped;
  };
  const coat::CheckResult cut = coat::check(skin, {}, m, o);
  EXPECT_FALSE(cut.complete);
  EXPECT_TRUE(stopped);
  EXPECT_EQ(afterStop, 0u);
  EXPECT_LT(calls, seen.size());
  // The counting overload: nullopt when stopped, the count otherwise.
  EXPECT_EQ(coat::countIntersectingPairs(m, pteryla::ProgressFn([](const std::string&, double f) { return f < 0.5; })),
            std::nullopt);
  EXPECT_EQ(coat::countIntersectingPairs(m, pteryla::ProgressFn([](const std::string&, double) { return true; })),
            std::optional<size_t>(full.intersectingPairs));
}

TEST(FastCheck, TriangleTestWithShapesIsTheFullTest) {
  // The overload that takes each triangle's square roots made once answers exactly as the plain test,
  // on random pairs and on the cases its tolerances decide: touching at a vertex or an edge, coplanar
  // overlapping and apart, a vertex 1e-13 off the other's plane, degenerate and collapsed triangles.
  auto both = [](const dvec3& a0, const dvec3& a1, const dvec3& a2, const dvec3& b0, const dvec3& b1, const dvec3& b2) {
    const bool plain = detail::trianglesIntersect(a0, a1, a2, b0, b1, b2);
    const bool shaped = detail::trianglesIntersect(a0, a1, a2, detail::triangleShape(a0, a1, a2), b0, b1, b2,
                                                   detail::triangleShape(b0, b1, b2));
    EXPECT_EQ(plain, shaped);
    return plain;
  };
  const dvec3 a0(0, 0, 0), a1(1, 0, 0), a2(0, 1, 0);
  EXPECT_TRUE(both(a0, a1, a2, {0.2, 0.2, -1}, {0.3, 0.2, 1}, {0.2, 0.3, 1}));     // crossing
  EXPECT_TRUE(both(a0, a1, a2, {1, 0, 0}, {2, 0, 1}, {2, 1, 1}));                  // a shared vertex
  EXPECT_TRUE(both(a0, a1, a2, {0, 0, 0}, {1, 0, 0}, {0.5, -1, 0.5}));             // a shared edge
  EXPECT_TRUE(both(a0, a1, a2, {0.1, 0.1, 0}, {2, 0.1, 0}, {0.1, 2, 0}));          // coplanar, overlapping
  EXPECT_FALSE(both(a0, a1, a2, {1, 1, 0}, {2, 1, 0}, {1, 2, 0}));                 // coplanar, apart
  EXPECT_TRUE(both(a0, a1, a2, {0.2, 0.2, 1e-13}, {0.3, 0.2, 1}, {0.2, 0.3, 1}));  // touching within eps
  EXPECT_FALSE(both(a0, a1, a2, {0.2, 0.2, 1e-6}, {0.3, 0.2, 1}, {0.2, 0.3, 1}));  // just above
  {
    // A triangle lying flat over the other at heights around the tolerance (1e-12 of the longest edge,
    // here sqrt 2 x 2): within it they touch, beyond it they are apart, also where the test rejects
    // without dividing (beyond twice the tolerance) and between the two.
    const double eps = 1e-12 * std::sqrt(2.0) * 2;
    const dvec3 b0(-0.5, -0.5, 0), b1(1.5, -0.5, 0), b2(-0.5, 1.5, 0);
    for (double f : {0.5, 0.9, 0.99})
      EXPECT_TRUE(both(a0, a1, a2, b0 + dvec3(0, 0, f * eps), b1 + dvec3(0, 0, f * eps), b2 + dvec3(0, 0, f * eps)))
          << f;
    for (double f : {1.01, 1.5, 1.99, 2.0, 2.01, 3.0, -1.5, -2.5})
      EXPECT_FALSE(both(a0, a1, a2, b0 + dvec3(0, 0, f * eps), b1 + dvec3(0, 0, f * eps), b2 + dvec3(0, 0, f * eps)))
          << f;
  }
  EXPECT_FALSE(both(a0, a1, a2, {0.2, 0.2, -1}, {0.2, 0.2, 0}, {0.2, 0.2, 1}));  // degenerate (a segment)
  EXPECT_FALSE(both(a0, a1, a2, {0.2, 0.2, 0}, {0.2, 0.2, 0}, {0.2, 0.2, 0}));   // collapsed to a point
  pteryla::Rng rng(17);
  size_t crossing = 0;
  for (int k = 0; k < 20000; ++k) {
    dvec3 p[6];
    for (auto& q : p) q = dvec3(rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 1));
    if (k % 4 == 0) p[3] = p[0];            // share a vertex
    if (k % 4 == 1) p[5].z = p[2].z = 0.5;  // vertices on one level
    crossing += both(p[0], p[1], p[2], p[3], p[4], p[5]);
  }
  EXPECT_GT(crossing, 1000u);
}

namespace {

// Every number check() gives, fast against CheckOptions::reference (one tree over the coat, from-scratch
// triangle tests, unbounded nearest-skin searches).
void expectSameAsReference(const coat::SkinMesh& skin, const std::vector<uint32_t>& tractFaces, const TriMesh& m,
                           coat::CheckOptions o) {
  o.attribute = true;
  o.reference = false;
  const coat::CheckResult fast = coat::check(skin, tractFaces, m, o);
  o.reference = true;
  const coat::CheckResult ref = coat::check(skin, tractFaces, m, o);
  ASSERT_TRUE(fast.complete);
  ASSERT_TRUE(ref.complete);
  EXPECT_EQ(fast.intersectingPairs, ref.intersectingPairs);
  EXPECT_EQ(fast.coatTriangles, ref.coatTriangles);
  EXPECT_EQ(fast.skinPenetrations, ref.skinPenetrations);
  EXPECT_EQ(fast.samplePoints, ref.samplePoints);
  EXPECT_EQ(fast.penetratingFeathers, ref.penetratingFeathers);
  EXPECT_EQ(fast.coverage, ref.coverage);
  EXPECT_EQ(fast.coveredSamples, ref.coveredSamples);
  EXPECT_EQ(fast.featherPenetrations, ref.featherPenetrations);
  EXPECT_EQ(fast.faceSamples, ref.faceSamples);
  EXPECT_EQ(fast.faceUncovered, ref.faceUncovered);
  ASSERT_EQ(fast.featherPairs.size(), ref.featherPairs.size());
  for (size_t k = 0; k < fast.featherPairs.size(); ++k) {
    EXPECT_EQ(fast.featherPairs[k].a, ref.featherPairs[k].a);
    EXPECT_EQ(fast.featherPairs[k].b, ref.featherPairs[k].b);
    EXPECT_EQ(fast.featherPairs[k].pairs, ref.featherPairs[k].pairs);
  }
}

}  // namespace

TEST(FastCheck, AdversarialCoatsGiveTheReferenceNumbers) {
  const coat::SkinMesh skin = sphereSkin(1.0, 14, 20);
  coat::CheckOptions o;
  o.coverageSamples = 1500;
  o.seed = 3;
  // Feathers as fans of quads over the sphere, each touching the next along a shared edge position
  // (separate vertices, equal coordinates), the next one's tip pushed under the skin, and every third
  // feather with triangles collapsed to a point (as the drape trims them) and one hidden entirely.
  TriMesh m;
  const int feathers = 24;
  for (int f = 0; f < feathers; ++f) {
    const double ph = 2 * kPi * f / feathers, ph1 = 2 * kPi * (f + 1) / feathers;
    const uint32_t base = static_cast<uint32_t>(m.positions.size());
    for (int k = 0; k <= 6; ++k) {
      const double th = 0.3 + 0.15 * k;
      const double r = (f % 5 == 1 && k == 6) ? 0.8 : 1.05 + 0.01 * (f % 2);  // a tip under the skin
      for (const double p : {ph, ph1}) {
        m.positions.emplace_back(
            dvec3(r * std::sin(th) * std::cos(p), r * std::sin(th) * std::sin(p), r * std::cos(th)));
        m.featherId.push_back(static_cast<uint32_t>(f));
      }
    }
    for (uint32_t k = 0; k < 6; ++k) {
      const uint32_t a = base + 2 * k, b = a + 1, c = a + 2, d = a + 3;
      m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
    }
    // A cross-piece standing through the previous feather's fan.
    const uint32_t s = static_cast<uint32_t>(m.positions.size());
    for (const double r : {0.98, 1.12})
      for (const double th : {0.6, 0.9}) {
        m.positions.emplace_back(
            dvec3(r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)));
        m.featherId.push_back(static_cast<uint32_t>(f));
      }
    m.indices.insert(m.indices.end(), {s, s + 1, s + 3, s, s + 3, s + 2});
    if (f % 3 == 0)
      for (size_t t = m.indices.size() / 3 - 4; t < m.indices.size() / 3; ++t)
        m.indices[3 * t + 1] = m.indices[3 * t + 2] = m.indices[3 * t];
    if (f == 7)
      for (size_t t = (m.indices.size() - 3 * 14) / 3; t < m.indices.size() / 3; ++t)
        m.indices[3 * t + 1] = m.indices[3 * t + 2] = m.indices[3 * t];
  }
  m.normals.assign(m.positions.size(), glm::vec3(0, 0, 1));
  const coat::CheckResult r = coat::check(skin, {}, m, o);
  ASSERT_TRUE(r.complete);
  EXPECT_GT(r.intersectingPairs, 0u) << "neighbours touch and cross-pieces cross";
  EXPECT_GT(r.skinPenetrations, 0u) << "tips under the skin";
  expectSameAsReference(skin, {}, m, o);
  // With the calamus exemption and a tract of half the faces.
  std::vector<uint32_t> half;
  for (uint32_t f = 0; f < skin.faces.size(); f += 2) half.push_back(f);
  coat::CheckOptions bases = o;
  for (int f = 0; f < feathers; ++f) {
    bases.featherOrigins.push_back(dvec3(m.positions[static_cast<size_t>(f) * 18]));
    bases.featherBaseRadius.push_back(0.1);
  }
  expectSameAsReference(skin, half, m, bases);
  // The soups, grouped and shuffled, over a sphere.
  for (const bool shuffled : {false, true}) {
    TriMesh s = soup(3000, 90, 11, shuffled);
    for (auto& p : s.positions) p = glm::vec3(dvec3(p) * 2.0 - dvec3(1, 1, 0.2));
    expectSameAsReference(skin, {}, s, o);
  }
}
