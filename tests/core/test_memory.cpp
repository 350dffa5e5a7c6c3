#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "pteryla/core/memory.hpp"

#if defined(__GLIBC__)
TEST(Memory, FreedBlocksOfAFewMegabytesStayInTheProcess) {
#if defined(__SANITIZE_ADDRESS__)
  // tools/sanitize.sh: ASan's allocator replaces glibc malloc, so mallopt and mallinfo2 do not apply.
  GTEST_SKIP() << "AddressSanitizer replaces glibc malloc (mallopt/mallinfo2 have no effect)";
#endif
  ASSERT_TRUE(pteryla::keepFreedMemoryInProcess());
  // A 16 MiB block now comes from the heap, not from its own mapping (which free() would unmap).
  const size_t mapped = mallinfo2().hblkhd;
  void* p = std::malloc(16u << 20);
  ASSERT_NE(p, nullptr);
  std::memset(p, 1, 16u << 20);
  EXPECT_EQ(mapped, mallinfo2().hblkhd);
  std::free(p);
  // ... and stays mapped after free (below the trim threshold).
  EXPECT_GE(mallinfo2().fordblks, 16u << 20);
}
#endif
