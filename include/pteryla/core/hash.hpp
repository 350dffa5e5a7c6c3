#pragma once
// FNV-1a, 64-bit: a small, stable hash of bytes for keys and names (not for security, not for bulk data).
#include <cstddef>
#include <cstdint>

namespace pteryla {

struct Fnv1a64 {
  uint64_t h = 1469598103934665603ull;
  void add(const void* data, size_t size) {
    const unsigned char* c = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) {
      h ^= c[i];
      h *= 1099511628211ull;
    }
  }
  // The eight bytes of v, least significant first (the same on every machine).
  void add(uint64_t v) {
    for (int i = 0; i < 8; ++i) {
      h ^= (v >> (8 * i)) & 0xffu;
      h *= 1099511628211ull;
    }
  }
};

inline uint64_t fnv1a64(const void* data, size_t size) {
  Fnv1a64 f;
  f.add(data, size);
  return f.h;
}

}  // namespace pteryla
