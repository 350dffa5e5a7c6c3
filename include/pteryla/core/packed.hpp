#pragma once
// Compact vertex attributes of TriMesh (docs/limits.md, "Bytes per coat triangle"): unit vectors in three
// signed normalized 16-bit integers (the GPU's own format for them, GL_SHORT normalized) and small scalars
// in IEEE half floats (GL_HALF_FLOAT). Each converts implicitly from and to its float type, so code that
// writes `mesh.normals[v] = n` or reads `glm::vec3 n = mesh.normals[v]` is unchanged; the renderer
// uploads the arrays as they are.
#include <glm/vec3.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace pteryla {

// A unit vector (normal, tangent): each component c in [-1, 1] stored as round(c x 32767), rounding
// halves away from zero (error at most 1.6e-5). A non-finite component is stored as -32768, which no
// finite one uses, and reads back as NaN, so the finiteness checks before export still see it (the GPU
// reads -32768 as -1).
struct PackedDir {
  int16_t q[3] = {0, 0, 0};

  static constexpr int16_t kNonFinite = -32768;

  static int16_t pack(float c) {
    if (!(std::abs(c) <= 1.0f)) {  // (NaN too)
      if (!std::isfinite(c)) return kNonFinite;
      c = c > 0.0f ? 1.0f : -1.0f;
    }
    // y +- 0.5 is exact for |y| <= 32767 (both are multiples of y's last place, the sum below 2^15), so
    // truncating it rounds to the nearest integer, halves away from zero (std::lround), without a call.
    const float y = c * 32767.0f;
    return static_cast<int16_t>(static_cast<int>(y + std::copysign(0.5f, y)));
  }
  static float unpack(int16_t v) {
    return v == kNonFinite ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(v) * (1.0f / 32767.0f);
  }

  PackedDir() = default;
  // A longer vector keeps its direction: it is scaled so its largest component is +-1.
  PackedDir(const glm::vec3& v) { set(v.x, v.y, v.z); }  // NOLINT: implicit by design
  PackedDir(float x, float y, float z) { set(x, y, z); }
  operator glm::vec3() const { return {unpack(q[0]), unpack(q[1]), unpack(q[2])}; }  // NOLINT
  glm::vec3 get() const { return *this; }

 private:
  void set(float x, float y, float z) {
    const float m = std::max(std::abs(x), std::max(std::abs(y), std::abs(z)));
    if (m > 1.0f) {  // (false for NaN; an infinite component makes NaN below, kept as non-finite)
      const float s = 1.0f / m;
      x *= s;
      y *= s;
      z *= s;
    }
    q[0] = pack(x);
    q[1] = pack(y);
    q[2] = pack(z);
  }

 public:
  friend bool operator==(const PackedDir& a, const PackedDir& b) {
    return a.q[0] == b.q[0] && a.q[1] == b.q[1] && a.q[2] == b.q[2];
  }
  friend bool operator!=(const PackedDir& a, const PackedDir& b) { return !(a == b); }
};
static_assert(sizeof(PackedDir) == 6, "three 16-bit components");

// An IEEE 754 binary16 number (11 significant bits: relative error at most 2^-11; integers up to 2048
// and halves up to 1024 exact), rounded to nearest even; infinities and NaN are kept.
struct Half {
  uint16_t bits = 0;

  static uint16_t pack(float f) {
    uint32_t x;
    std::memcpy(&x, &f, 4);
    const uint32_t sign = (x >> 16) & 0x8000u, ax = x & 0x7fffffffu;
    if (ax >= 0x7f800000u) return static_cast<uint16_t>(sign | 0x7c00u | (ax > 0x7f800000u ? 0x200u : 0u));
    if (ax >= 0x477ff000u) return static_cast<uint16_t>(sign | 0x7c00u);  // >= 65520 rounds to infinity
    if (ax < 0x38800000u) {  // below 2^-14: a subnormal half, in units of 2^-24 (exact in float)
      float a;
      std::memcpy(&a, &ax, 4);
      return static_cast<uint16_t>(sign | static_cast<uint32_t>(std::nearbyint(a * 16777216.0f)));
    }
    uint32_t h = (ax - 0x38000000u) >> 13;  // exponent bias 127 -> 15, 23 -> 10 significand bits
    const uint32_t rest = ax & 0x1fffu;
    if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;  // a carry rolls into the exponent
    return static_cast<uint16_t>(sign | h);
  }
  static float unpack(uint16_t h) {
    const uint32_t sign = static_cast<uint32_t>(h & 0x8000u) << 16, e = (h >> 10) & 0x1fu, m = h & 0x3ffu;
    uint32_t x;
    if (e == 0) {
      const float v = static_cast<float>(m) * (1.0f / 16777216.0f);
      return sign ? -v : v;
    }
    if (e == 31)
      x = sign | 0x7f800000u | (m << 13);
    else
      x = sign | ((e + 112u) << 23) | (m << 13);
    float f;
    std::memcpy(&f, &x, 4);
    return f;
  }

  Half() = default;
  Half(float f) : bits(pack(f)) {}                 // NOLINT: implicit by design
  operator float() const { return unpack(bits); }  // NOLINT (compared as floats)
};
static_assert(sizeof(Half) == 2, "16 bits");

}  // namespace pteryla
