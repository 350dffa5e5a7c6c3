// The packer's huge-page bump arena: copies are exact and aligned, runs larger than a chunk get their own
// chunk, and released chunks are reused by the next arena.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "../../src/coat/arena.hpp"
#include "pteryla/coat/pack.hpp"

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

TEST(HugeBlock, LargeBuffersAreWholeHugePagesAndReusedAfterRelease) {
  const size_t bytes = (5u << 20) + 123;  // rounds up to 6 MiB
  char* a = static_cast<char*>(pteryla::coat::detail::allocateHugeBlock(bytes));
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(0u, reinterpret_cast<uintptr_t>(a) % (2u << 20));
  a[0] = 1;
  a[bytes - 1] = 2;
  pteryla::coat::detail::freeHugeBlock(a);
  // Of the smallest free blocks that fit, the last freed is handed out next: this one.
  char* b = static_cast<char*>(pteryla::coat::detail::allocateHugeBlock(bytes));
  EXPECT_EQ(a, b);
  EXPECT_EQ(2, b[bytes - 1]);  // the same, already written memory (the allocator does not clear it)
  pteryla::coat::detail::freeHugeBlock(b);
  pteryla::coat::detail::freeHugeBlock(nullptr);  // no-op
}

TEST(HugeBlock, UninitializedAllocatorUsesThemForLargeVectorsOnly) {
  std::vector<double, pteryla::coat::UninitializedAllocator<double>> big, small;
  big.resize(1u << 20);  // 8 MiB
  small.resize(16);
  EXPECT_EQ(0u, reinterpret_cast<uintptr_t>(big.data()) % (2u << 20));
  for (size_t i = 0; i < big.size(); i += 4096) big[i] = static_cast<double>(i);
  EXPECT_EQ(4096.0, big[4096]);
  big.push_back(1.0);  // regrowth copies and releases the old block
  EXPECT_EQ(4096.0, big[4096]);
  EXPECT_EQ(1.0, big.back());
}
