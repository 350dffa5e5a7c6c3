// Bump allocation of short-lived working memory in huge-page chunks.
//
// The packer's per-feather working geometry (about 45 MB for the 3,150-feather bird) used to be thousands
// of small vectors. In a fresh process each new 4 KiB page of the heap costs a page fault, and on this
// VM a fault costs about 11 us: the first pack paid some 70 ms for faults alone. Chunks here are 2 MiB
// aligned and advised as transparent huge pages (one fault per 2 MiB where the kernel allows it), and
// released chunks go to a process-wide pool, so later packs reuse them without faulting.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

namespace pteryla::coat::detail {

// A read-only view of a run of T in an arena: what LocalFeather keeps of the vectors it was built from.
template <class T>
class ArenaArray {
 public:
  size_t size() const { return n_; }
  bool empty() const { return n_ == 0; }
  const T* data() const { return p_; }
  const T& operator[](size_t i) const { return p_[i]; }
  const T& front() const { return p_[0]; }
  const T& back() const { return p_[n_ - 1]; }
  const T* begin() const { return p_; }
  const T* end() const { return p_ + n_; }

 private:
  friend class HugeArena;
  const T* p_ = nullptr;
  size_t n_ = 0;
};

// allocateHugeBlock / freeHugeBlock (large result buffers) are declared in pteryla/coat/pack.hpp.

// Not thread-safe: one arena per thread. Memory lives until the arena is destroyed.
class HugeArena {
 public:
  HugeArena() = default;
  ~HugeArena();
  HugeArena(const HugeArena&) = delete;
  HugeArena& operator=(const HugeArena&) = delete;

  void* allocate(size_t bytes, size_t align);

  template <class T>
  ArenaArray<T> copy(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>, "arena arrays hold trivially copyable values");
    ArenaArray<T> a;
    if (v.empty()) return a;
    T* p = static_cast<T*>(allocate(v.size() * sizeof(T), alignof(T)));
    std::memcpy(static_cast<void*>(p), v.data(), v.size() * sizeof(T));
    a.p_ = p;
    a.n_ = v.size();
    return a;
  }

  // Bytes in chunks this arena holds (for tests).
  size_t reserved() const;

 private:
  struct Chunk {
    char* base;
    size_t size;
  };
  std::vector<Chunk> chunks_;
  char* cur_ = nullptr;
  size_t left_ = 0;
};

}  // namespace pteryla::coat::detail
