// The packer's huge-page bump arena: copies are exact and aligned, runs larger than a chunk get their own
// chunk, and released chunks are reused by the next arena.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "../../src/coat/arena.hpp"

using pteryla::coat::detail::ArenaArray;
using pteryla::coat::detail::HugeArena;

TEST(HugeArena, CopiesAreExactAlignedAndStable) {
  HugeArena a;
  std::vector<ArenaArray<glm::dvec3>> runs;
  std::vector<std::vector<glm::dvec3>> src;
  for (int k = 0; k < 2000; ++k) {
    std::vector<glm::dvec3> v(static_cast<size_t>(1 + k % 37));
    for (size_t i = 0; i < v.size(); ++i) v[i] = glm::dvec3(k, i, 0.5 * k - i);
    src.push_back(v);
    runs.push_back(a.copy(v));
    // A byte in between, so the next run has to be realigned.
    a.allocate(1, 1);
  }
  for (size_t k = 0; k < runs.size(); ++k) {
    ASSERT_EQ(src[k].size(), runs[k].size());
    EXPECT_EQ(0u, reinterpret_cast<uintptr_t>(runs[k].data()) % alignof(glm::dvec3));
    for (size_t i = 0; i < runs[k].size(); ++i) EXPECT_EQ(src[k][i], runs[k][i]);
    EXPECT_EQ(src[k].back(), runs[k].back());
  }
  EXPECT_TRUE(a.copy(std::vector<double>{}).empty());
}

TEST(HugeArena, LargeRunsGetTheirOwnChunkAndTheOpenChunkStaysInUse) {
  HugeArena a;
  const ArenaArray<double> small = a.copy(std::vector<double>{1, 2, 3});
  const size_t before = a.reserved();
  std::vector<double> big(3u << 20, 7.0);  // 24 MiB, more than a chunk
  const ArenaArray<double> b = a.copy(big);
  ASSERT_EQ(big.size(), b.size());
  EXPECT_EQ(7.0, b[0]);
  EXPECT_EQ(7.0, b.back());
  EXPECT_GE(a.reserved(), before + big.size() * sizeof(double));
  // The next small run still comes from the first chunk.
  const size_t mid = a.reserved();
  const ArenaArray<double> s2 = a.copy(std::vector<double>{4, 5});
  EXPECT_EQ(mid, a.reserved());
  EXPECT_EQ(3.0, small[2]);
  EXPECT_EQ(5.0, s2[1]);
}

TEST(HugeArena, ReleasedChunksAreReused) {
  const void* first = nullptr;
  {
    HugeArena a;
    first = a.allocate(64, 64);
  }
  HugeArena b;
  // The pool is a stack: the chunk just released is the next one handed out.
  EXPECT_EQ(first, b.allocate(64, 64));
}
