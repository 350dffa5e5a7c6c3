#pragma once
// Deterministic, platform-independent random numbers. std::uniform_*_distribution differ between
// standard libraries, so pteryla never uses them: every stochastic step takes an explicit seed and draws
// from Rng, giving the same coat bit for bit for the same scene and seed.
#include <cstdint>

namespace pteryla {

// SplitMix64 mixer: good avalanche, used to derive independent streams from (seed, id) pairs.
constexpr uint64_t mix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// xoshiro256** generator seeded through SplitMix64.
class Rng {
 public:
  explicit Rng(uint64_t seed = 0, uint64_t stream = 0) {
    uint64_t x = mix64(seed) ^ mix64(stream + 0x5851F42D4C957F2Dull);
    for (auto& s : s_) {
      x = mix64(x);
      s = x;
    }
  }
  uint64_t next() {
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  // Uniform in [0,1) with 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [0, n).
  uint64_t below(uint64_t n) { return n == 0 ? 0 : next() % n; }
  // Standard normal (Box-Muller, deterministic).
  double normal();

 private:
  static constexpr uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4];
};

// Hash-derived uniform in [0,1) for (seed, a, b): stateless per-element randomness.
inline double hashUniform(uint64_t seed, uint64_t a, uint64_t b = 0) {
  return static_cast<double>(mix64(mix64(seed ^ mix64(a)) ^ (b * 0xD6E8FEB86659FD93ull)) >> 11) * 0x1.0p-53;
}

}  // namespace pteryla
