#include "arena.hpp"

#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <new>
#include <unordered_map>

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

// Large result buffers (allocateHugeBlock): freed blocks are kept for reuse up to kBlockPoolMax bytes, so
// a repack of the same coat writes its points into memory that is already mapped.
constexpr size_t kBlockPoolMax = size_t(128) << 20;

struct BlockPool {
  std::mutex m;
  std::vector<std::pair<char*, size_t>> free;  // oldest first
  size_t freeBytes = 0;
  std::unordered_map<char*, size_t> live;  // block -> mapped size
};

BlockPool& blockPool() {
  static BlockPool* p = new BlockPool;  // never destroyed, like pool()
  return *p;
}

}  // namespace

void* allocateHugeBlock(size_t bytes) {
  const size_t size = (bytes + kHuge - 1) & ~(kHuge - 1);
  BlockPool& p = blockPool();
  std::lock_guard<std::mutex> lock(p.m);
  // The smallest free block that holds it, within 8 MiB (larger ones stay for larger buffers); of equal
  // ones the last freed.
  size_t best = p.free.size();
  for (size_t k = 0; k < p.free.size(); ++k)
    if (p.free[k].second >= size && p.free[k].second <= size + (size_t(8) << 20) &&
        (best == p.free.size() || p.free[k].second <= p.free[best].second))
      best = k;
  char* c;
  size_t got;
  if (best < p.free.size()) {
    c = p.free[best].first;
    got = p.free[best].second;
    p.free.erase(p.free.begin() + static_cast<std::ptrdiff_t>(best));
    p.freeBytes -= got;
  } else {
    c = mapChunk(size);
    got = size;
  }
  p.live[c] = got;
  return c;
}

void freeHugeBlock(void* block) {
  if (!block) return;
  BlockPool& p = blockPool();
  char* c = static_cast<char*>(block);
  std::vector<std::pair<char*, size_t>> unmap;
  {
    std::lock_guard<std::mutex> lock(p.m);
    const auto it = p.live.find(c);
    if (it == p.live.end()) return;  // not ours: nothing to release
    const size_t size = it->second;
    p.live.erase(it);
    p.free.emplace_back(c, size);
    p.freeBytes += size;
    while (p.freeBytes > kBlockPoolMax) {  // the oldest go back to the system
      unmap.push_back(p.free.front());
      p.freeBytes -= p.free.front().second;
      p.free.erase(p.free.begin());
    }
  }
  for (const auto& [q, size] : unmap) munmap(q, size);
}

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
