#include "arena.hpp"

#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <new>

#include <sys/mman.h>

namespace pteryla::coat::detail {

namespace {

constexpr size_t kHuge = size_t(2) << 20;
constexpr size_t kChunk = size_t(4) << 20;
constexpr size_t kPoolMax = 64;  // chunks kept for reuse (256 MiB)

// 2 MiB-aligned anonymous memory, advised as huge pages.
char* mapChunk(size_t size) {
  void* raw = mmap(nullptr, size + kHuge, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) throw std::bad_alloc();
  const uintptr_t a = reinterpret_cast<uintptr_t>(raw);
  const uintptr_t aligned = (a + kHuge - 1) & ~(uintptr_t(kHuge) - 1);
  if (aligned > a) munmap(raw, aligned - a);
  const uintptr_t end = a + size + kHuge, used = aligned + size;
  if (end > used) munmap(reinterpret_cast<void*>(used), end - used);
#ifdef MADV_HUGEPAGE
  madvise(reinterpret_cast<void*>(aligned), size, MADV_HUGEPAGE);  // a hint: without THP, plain pages
#endif
  return reinterpret_cast<char*>(aligned);
}

struct Pool {
  std::mutex m;
  std::vector<char*> free;  // chunks of kChunk bytes
};

Pool& pool() {
  static Pool* p = new Pool;  // never destroyed: arenas may be released during static destruction
  return *p;
}

char* takeChunk() {
  {
    Pool& p = pool();
    std::lock_guard<std::mutex> lock(p.m);
    if (!p.free.empty()) {
      char* c = p.free.back();
      p.free.pop_back();
      return c;
    }
  }
  return mapChunk(kChunk);
}

void giveChunk(char* c, size_t size) {
  if (size == kChunk) {
    Pool& p = pool();
    std::lock_guard<std::mutex> lock(p.m);
    if (p.free.size() < kPoolMax) {
      p.free.push_back(c);
      return;
    }
  }
  munmap(c, size);
}

}  // namespace

HugeArena::~HugeArena() {
  for (const Chunk& c : chunks_) giveChunk(c.base, c.size);
}

void* HugeArena::allocate(size_t bytes, size_t align) {
  const uintptr_t at = reinterpret_cast<uintptr_t>(cur_);
  const size_t pad = cur_ ? (align - at % align) % align : 0;
  if (!cur_ || pad + bytes > left_) {
    if (bytes + align > kChunk) {
      // A request larger than a chunk gets a chunk of its own; the current chunk stays open.
      const size_t size = (bytes + align + kHuge - 1) & ~(kHuge - 1);
      char* c = mapChunk(size);
      chunks_.push_back({c, size});
      return c;
    }
    char* c = takeChunk();
    chunks_.push_back({c, kChunk});
    cur_ = c;
    left_ = kChunk;
    return allocate(bytes, align);
  }
  char* p = cur_ + pad;
  cur_ = p + bytes;
  left_ -= pad + bytes;
  return p;
}

size_t HugeArena::reserved() const {
  size_t s = 0;
  for (const Chunk& c : chunks_) s += c.size;
  return s;
}

}  // namespace pteryla::coat::detail
