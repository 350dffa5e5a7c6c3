// The coat checker's triangle pairs (check.hpp: intersectingTrianglePairs, countIntersectingPairs) come
// from a dual traversal of the BVH against itself with per-feather pruning, on a tree built in parallel.
// Against brute force on a soup large enough for the parallel build: the same pairs, exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "../../src/coat/drape_internal.hpp"
#include "../../src/coat/spatial.hpp"
#include "pteryla/coat/check.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/core/trimesh.hpp"

namespace {

using glm::dvec3;
using pteryla::TriMesh;

// `feathers` clusters of thin, long triangles (barb-like), crowded so that clusters cross each other.
TriMesh soup(size_t triangles, uint32_t feathers, uint64_t seed) {
  pteryla::Rng rng(seed);
  TriMesh m;
  for (size_t t = 0; t < triangles; ++t) {
    const uint32_t f = static_cast<uint32_t>(t * feathers / triangles);  // contiguous, like the coat mesh
    const dvec3 c(rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 0.2));
    const dvec3 d = glm::normalize(dvec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-0.3, 0.3)));
    const dvec3 e = glm::normalize(dvec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
    const double len = rng.uniform(0.01, 0.06);
    for (const dvec3& p : {c, c + len * d, c + 0.004 * e}) {
      m.positions.emplace_back(p);
      m.featherId.push_back(f);
    }
    for (int k = 0; k < 3; ++k) m.indices.push_back(static_cast<uint32_t>(3 * t + k));
  }
  m.normals.assign(m.positions.size(), glm::vec3(0, 0, 1));
  return m;
}

std::vector<uint64_t> bruteForce(const TriMesh& m) {
  const size_t nt = m.triangleCount();
  auto v = [&](size_t t, int k) { return dvec3(m.positions[m.indices[3 * t + k]]); };
  std::vector<pteryla::coat::detail::Box> box(nt);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) box[t].add(v(t, k));
  std::vector<uint64_t> out;
  for (size_t t = 0; t < nt; ++t)
    for (size_t u = t + 1; u < nt; ++u) {
      if (m.featherId[m.indices[3 * t]] == m.featherId[m.indices[3 * u]] || !box[t].overlaps(box[u])) continue;
      if (pteryla::coat::detail::trianglesIntersect(v(t, 0), v(t, 1), v(t, 2), v(u, 0), v(u, 1), v(u, 2)))
        out.push_back((uint64_t(t) << 32) | u);
    }
  return out;
}

}  // namespace

TEST(TrianglePairs, DualTraversalFindsExactlyTheBruteForcePairs) {
  // 12,000 triangles: above the parallel build's threshold (8,192), so both halves of the root are built
  // concurrently and stitched.
  const TriMesh m = soup(12000, 300, 7);
  const std::vector<uint64_t> want = bruteForce(m);
  ASSERT_GT(want.size(), 500u);  // the soup does cross
  EXPECT_EQ(pteryla::coat::intersectingTrianglePairs(m), want);
  EXPECT_EQ(pteryla::coat::countIntersectingPairs(m), want.size());
  EXPECT_EQ(pteryla::coat::countIntersectingPairs(m, 1), want.size());  // one thread: the same answer
}

TEST(TrianglePairs, OneFeatherHasNoPairsAndEveryTriangleIsVisitedOnce) {
  TriMesh m = soup(3000, 1, 3);
  EXPECT_EQ(pteryla::coat::countIntersectingPairs(m), 0u);  // pruned at the root: one group
  // Without pruning (every triangle its own feather), the traversal visits each overlapping pair once.
  for (size_t v = 0; v < m.featherId.size(); ++v) m.featherId[v] = static_cast<uint32_t>(v / 3);
  const std::vector<uint64_t> want = bruteForce(m);
  const std::vector<uint64_t> got = pteryla::coat::intersectingTrianglePairs(m);
  EXPECT_EQ(got, want);
  EXPECT_TRUE(std::adjacent_find(got.begin(), got.end()) == got.end());
}

TEST(TrianglePairs, TheBvhIsTheSameWhateverTheThreadCount) {
  // The parallel build stitches subtrees in the serial depth-first layout: nearest queries (whose ties
  // the drape depends on) give the same triangles with one thread and with all.
  const TriMesh m = soup(20000, 50, 11);
  pteryla::coat::detail::TriangleBvh all, one;
  all.build(m.positions.data(), m.indices.data(), m.triangleCount());
  tbb::task_arena arena(1);
  arena.execute([&] { one.build(m.positions.data(), m.indices.data(), m.triangleCount()); });
  pteryla::Rng rng(5);
  for (int q = 0; q < 2000; ++q) {
    const dvec3 p(rng.uniform(-0.2, 1.4), rng.uniform(-0.2, 1.2), rng.uniform(-0.2, 0.4));
    dvec3 ba, bo;
    double da = 0, dd = 0;
    ASSERT_EQ(all.nearest(p, 1e9, ba, da), one.nearest(p, 1e9, bo, dd)) << q;
    EXPECT_EQ(da, dd);
  }
  EXPECT_EQ(all.pairTasks(64), one.pairTasks(64));
}

TEST(TrianglePairs, ARefittedTreeFindsWhatAFreshTreeFindsAndSkipsCollapsedTriangles) {
  // Two clusters' trees built over one placement, then every corner moved (a turn and a stretch, as a
  // pose moves a feather) and some triangles collapsed: refitted, the trees give exactly the box-overlap
  // pairs of trees built afresh over the moved corners, less every pair with a collapsed triangle.
  TriMesh m = soup(4000, 2, 13);
  std::vector<uint32_t> ia(m.indices.begin(), m.indices.begin() + 3 * 2000),
      ib(m.indices.begin() + 3 * 2000, m.indices.end());
  pteryla::coat::detail::TriangleBvh a, b;
  a.build(m.positions.data(), ia.data(), 2000);
  b.build(m.positions.data(), ib.data(), 2000);
  for (glm::vec3& p : m.positions)
    p = glm::vec3(p.x * 1.3f - p.y * 0.4f, p.y * 0.9f + p.x * 0.4f, p.z + 0.2f * p.x * p.x);
  for (uint32_t t : {5u, 77u, 1999u}) ia[3 * t + 1] = ia[3 * t + 2] = ia[3 * t];
  for (uint32_t t : {0u, 640u}) ib[3 * t + 1] = ib[3 * t + 2] = ib[3 * t];
  a.refit(m.positions.data(), ia.data());
  b.refit(m.positions.data(), ib.data());
  auto pairsOf = [](const pteryla::coat::detail::TriangleBvh& x, const pteryla::coat::detail::TriangleBvh& y) {
    std::vector<uint64_t> out;
    x.overlappingPairs(y, [&](uint32_t s, uint32_t t) { out.push_back((uint64_t(s) << 32) | t); });
    std::sort(out.begin(), out.end());
    return out;
  };
  const std::vector<uint64_t> got = pairsOf(a, b);
  pteryla::coat::detail::TriangleBvh fa, fb;
  fa.build(m.positions.data(), ia.data(), 2000);
  fb.build(m.positions.data(), ib.data(), 2000);
  fa.makePrimBoxes();
  fb.makePrimBoxes();
  std::vector<uint64_t> want;
  auto collapsed = [](const std::vector<uint32_t>& idx, uint64_t t) { return idx[3 * t] == idx[3 * t + 1]; };
  for (uint64_t k : pairsOf(fa, fb))
    if (!collapsed(ia, k >> 32) && !collapsed(ib, k & 0xffffffffu)) want.push_back(k);
  ASSERT_GT(want.size(), 500u);  // the moved clusters still meet
  EXPECT_EQ(got, want);
  // The bounds are the live triangles' own.
  glm::vec3 lo, hi;
  ASSERT_TRUE(a.bounds(lo, hi));
  pteryla::coat::detail::Box live;
  for (size_t t = 0; t < 2000; ++t)
    if (!collapsed(ia, t))
      for (int c = 0; c < 3; ++c) live.add(dvec3(m.positions[ia[3 * t + c]]));
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(lo[k], live.lo[k]);
    EXPECT_GE(hi[k], live.hi[k]);
    EXPECT_NEAR(lo[k], live.lo[k], 1e-6);
    EXPECT_NEAR(hi[k], live.hi[k], 1e-6);
  }
}

// A soup's feathers in order 0..n-1 and each one's triangles (CSR), as a drape's CoatLayout holds them.
struct SoupLayout {
  std::vector<uint32_t> order, trisOf, tris;
  SoupLayout(const TriMesh& m, uint32_t n) : order(n), trisOf(n + 1, 0), tris(m.triangleCount()) {
    const size_t nt = m.triangleCount();
    for (uint32_t i = 0; i < n; ++i) order[i] = i;
    for (size_t t = 0; t < nt; ++t) ++trisOf[m.featherId[m.indices[3 * t]] + 1];
    for (uint32_t i = 0; i < n; ++i) trisOf[i + 1] += trisOf[i];
    std::vector<uint32_t> fill(trisOf.begin(), trisOf.end() - 1);
    for (size_t t = 0; t < nt; ++t) tris[fill[m.featherId[m.indices[3 * t]]]++] = static_cast<uint32_t>(t);
  }
};

TEST(TrianglePairs, KeptTreesFindTheChangedTrianglesPairsOfAFreshSearch) {
  // A carried frame's pair search (pairsWithChanged with a PairTrees cache, drape_trim.cpp) against the
  // search that builds every tree afresh, over three frames of one cache: feathers moved (their trees
  // refitted), triangles collapsed (left out), and one feather losing triangles (its tree built again).
  namespace dr = pteryla::coat::draping;
  TriMesh m = soup(6000, 60, 21);
  pteryla::Rng rng(4);
  dr::PairTrees cache;
  for (int frame = 0; frame < 3; ++frame) {
    const size_t nt = m.triangleCount();
    const uint32_t n = 60;
    const SoupLayout L(m, n);
    const std::vector<uint32_t>&order = L.order, &trisOf = L.trisOf, &tris = L.tris;
    std::vector<uint8_t> changedTri(nt, 0);
    for (uint32_t i = 0; i < n; ++i)
      if (rng.uniform(0, 1) < 0.3)
        for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) changedTri[tris[q]] = 1;
    const std::vector<uint64_t> fresh = dr::pairsWithChanged(m, order, trisOf, tris, changedTri, pteryla::ProgressFn{});
    const std::vector<uint64_t> kept = dr::pairsWithChanged(m, order, trisOf, tris, changedTri, cache);
    if (frame == 0) {
      ASSERT_GT(fresh.size(), 50u);  // the changed feathers do cross others
    }
    EXPECT_EQ(kept, fresh) << "frame " << frame;
    // The next frame: a third of the feathers moved, a few triangles collapsed, feather 5 shorter.
    for (uint32_t i = 0; i < n; i += 3) {
      const glm::vec3 shift(static_cast<float>(rng.uniform(-0.02, 0.02)), static_cast<float>(rng.uniform(-0.02, 0.02)),
                            static_cast<float>(rng.uniform(-0.01, 0.01)));
      for (size_t v = 0; v < m.positions.size(); ++v)
        if (m.featherId[v] == i) m.positions[v] += shift;
    }
    for (int c = 0; c < 40; ++c) {
      const size_t t = static_cast<size_t>(rng.uniform(0, double(m.triangleCount()) - 1));
      m.indices[3 * t + 1] = m.indices[3 * t + 2] = m.indices[3 * t];
    }
    std::vector<uint32_t> indices;
    int dropped = 0;
    for (size_t t = 0; t < m.triangleCount(); ++t) {
      if (m.featherId[m.indices[3 * t]] == 5 && dropped < 10) {
        ++dropped;
        continue;
      }
      indices.insert(indices.end(), m.indices.begin() + 3 * t, m.indices.begin() + 3 * t + 3);
    }
    m.indices = indices;
  }
}

TEST(TrianglePairs, FeathersOnDifferentPiecesArePairedAsIfChanged) {
  // A carried frame's feathers moved with rigid pieces of skin (drape_carry.cpp): two feathers on one
  // piece keep their rest pairs, so the search finds the pairs with a changed triangle and every pair of
  // two feathers on different pieces, no others; with the kept trees too.
  namespace dr = pteryla::coat::draping;
  const TriMesh m = soup(6000, 60, 23);
  pteryla::Rng rng(9);
  const size_t nt = m.triangleCount();
  const uint32_t n = 60;
  const SoupLayout L(m, n);
  const std::vector<uint32_t>&order = L.order, &trisOf = L.trisOf, &tris = L.tris;
  std::vector<uint8_t> changedTri(nt, 0);
  std::vector<int32_t> piece(n, 0);
  for (uint32_t i = 0; i < n; ++i) {
    piece[i] = static_cast<int32_t>(rng.uniform(0, 2.999));
    if (rng.uniform(0, 1) < 0.1)
      for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) changedTri[tris[q]] = 1;
  }
  std::vector<uint64_t> want;
  size_t apart = 0;
  for (uint64_t pr : pteryla::coat::intersectingTrianglePairs(m)) {
    const size_t t = pr >> 32, u = pr & 0xffffffffu;
    const uint32_t ft = m.featherId[m.indices[3 * t]], fu = m.featherId[m.indices[3 * u]];
    if (changedTri[t] || changedTri[u]) {
      want.push_back(pr);
    } else if (piece[ft] != piece[fu]) {
      want.push_back(pr);
      ++apart;
    }
  }
  ASSERT_GT(apart, 50u);  // pairs found only because their pieces differ
  dr::PairTrees cache;
  EXPECT_EQ(dr::pairsWithChanged(m, order, trisOf, tris, changedTri, pteryla::ProgressFn{}, &piece), want);
  EXPECT_EQ(dr::pairsWithChanged(m, order, trisOf, tris, changedTri, cache, &piece), want);
}

TEST(TrianglePairs, OutwardRoundingStepsAsNextafterDoes) {
  // The boxes' outward rounding (detail::nextUp / nextDown, inline) against std::nextafter toward the
  // infinities: zeros, subnormals, the largest float, infinities, NaN and random floats of both signs.
  using pteryla::coat::detail::nextDown;
  using pteryla::coat::detail::nextUp;
  constexpr float inf = std::numeric_limits<float>::infinity();
  std::vector<float> xs = {0.0f,
                           -0.0f,
                           std::numeric_limits<float>::denorm_min(),
                           -std::numeric_limits<float>::denorm_min(),
                           std::numeric_limits<float>::min(),
                           std::numeric_limits<float>::max(),
                           -std::numeric_limits<float>::max(),
                           inf,
                           -inf,
                           1.0f,
                           -1.0f};
  pteryla::Rng rng(9);
  for (int k = 0; k < 20000; ++k)
    xs.push_back(static_cast<float>(rng.uniform(-1e6, 1e6) * std::pow(10.0, rng.uniform(-30, 30))));
  auto same = [](float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  for (float x : xs) {
    EXPECT_TRUE(same(nextUp(x), std::nextafter(x, inf))) << x;
    EXPECT_TRUE(same(nextDown(x), std::nextafter(x, -inf))) << x;
  }
  EXPECT_TRUE(std::isnan(nextUp(std::nanf(""))));
  EXPECT_TRUE(std::isnan(nextDown(std::nanf(""))));
}
