// The coat checker's triangle pairs (check.hpp: intersectingTrianglePairs, countIntersectingPairs) come
// from a dual traversal of the BVH against itself with per-feather pruning, on a tree built in parallel.
// Against brute force on a soup large enough for the parallel build: the same pairs, exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

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
