// The compact vertex attributes of TriMesh (core/packed.hpp): what each keeps of a float, exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <glm/geometric.hpp>
#include <glm/gtc/packing.hpp>
#include <limits>
#include <random>

#include "pteryla/core/packed.hpp"
#include "pteryla/core/trimesh.hpp"

using namespace pteryla;

TEST(PackedDir, RoundsEachComponentToTheNearest32767th) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.2f, 1.2f);
  for (int k = 0; k < 100000; ++k) {
    const float c = u(rng);
    const int16_t q = PackedDir::pack(c);
    // The same as std::lround of the clamped, scaled value (the renderer's rounding before #27).
    EXPECT_EQ(q, static_cast<int16_t>(std::lround(std::clamp(c, -1.0f, 1.0f) * 32767.0f))) << c;
    EXPECT_LE(std::abs(PackedDir::unpack(q) - std::clamp(c, -1.0f, 1.0f)), 0.5f / 32767.0f + 1e-7f) << c;
  }
  EXPECT_EQ(PackedDir::pack(1.0f), 32767);
  EXPECT_EQ(PackedDir::pack(-1.0f), -32767);
  EXPECT_EQ(PackedDir::pack(0.5f / 32767.0f), 1);  // halves away from zero
  EXPECT_EQ(PackedDir::pack(-0.5f / 32767.0f), -1);
}

TEST(PackedDir, EveryStoredValueReadsBackToItself) {
  for (int v = -32767; v <= 32767; ++v) {
    const int16_t q = static_cast<int16_t>(v);
    ASSERT_EQ(PackedDir::pack(PackedDir::unpack(q)), q) << v;
  }
}

TEST(PackedDir, NonFiniteComponentsStayNonFinite) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (float bad : {nan, inf, -inf}) {
    const glm::vec3 back = PackedDir(glm::vec3(0.0f, bad, 1.0f));
    EXPECT_TRUE(std::isnan(back.y)) << bad;  // so requireFinite refuses the mesh before export
    EXPECT_TRUE(std::isfinite(back.x) && std::isfinite(back.z)) << bad;
    if (std::isnan(bad)) {
      EXPECT_EQ(back.z, 1.0f);
    }
  }
}

TEST(PackedDir, AUnitVectorStaysUnitWithin3e5) {
  std::mt19937 rng(3);
  std::normal_distribution<float> g;
  for (int k = 0; k < 10000; ++k) {
    const glm::vec3 n = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
    const glm::vec3 back = PackedDir(n);
    EXPECT_LE(glm::length(back - n), 2.7e-5f);
    EXPECT_NEAR(glm::length(back), 1.0f, 2.7e-5f);
  }
}

// The nearest binary16 number, ties to the even one (IEEE 754's default, as F16C's conversion).
TEST(Half, RoundsToTheNearestTiesToEven) {
  std::mt19937 rng(11);
  auto check = [](float f) {
    const uint16_t h = Half::pack(f);
    const double err = std::abs(double(Half::unpack(h)) - double(f));
    for (int step : {-1, 1}) {
      const uint16_t o = static_cast<uint16_t>(h + step);
      if ((o & 0x7c00u) == 0x7c00u || (o & 0x8000u) != (h & 0x8000u)) continue;  // past infinity or the sign
      const double other = std::abs(double(Half::unpack(o)) - double(f));
      if (other < err || (other == err && (h & 1u))) return false;
    }
    return true;
  };
  std::uniform_int_distribution<uint32_t> bits;
  for (int k = 0; k < 200000; ++k) {
    const uint32_t x = bits(rng);
    float f;
    std::memcpy(&f, &x, 4);
    if (!std::isfinite(f) || std::abs(f) >= 65504.0f) continue;
    ASSERT_TRUE(check(f)) << f;
    // Away from ties, glm's conversion agrees.
    const float back = Half::unpack(Half::pack(f));
    const float next = Half::unpack(static_cast<uint16_t>(Half::pack(f) + (std::abs(f) > std::abs(back) ? 1 : -1)));
    if (std::abs(f - back) != std::abs(f - next)) {
      EXPECT_EQ(Half::pack(f), glm::packHalf1x16(f)) << f;
    }
  }
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  for (int k = 0; k < 200000; ++k) ASSERT_TRUE(check(u(rng)));
  // An exact tie: 1 + 2^-11 lies halfway between 1 and 1 + 2^-10; the even one is 1.
  EXPECT_EQ(static_cast<float>(Half(1.0f + 1.0f / 2048)), 1.0f);
  EXPECT_EQ(static_cast<float>(Half(1.0f + 3.0f / 2048)), 1.0f + 2.0f / 1024);
}

TEST(Half, EveryHalfReadsBackToItself) {
  for (uint32_t h = 0; h < 65536; ++h) {
    const float f = Half::unpack(static_cast<uint16_t>(h));
    if (std::isnan(f)) {
      EXPECT_TRUE(std::isnan(Half::unpack(Half::pack(f))));
      continue;
    }
    ASSERT_EQ(Half::pack(f), h) << h;
    EXPECT_EQ(f, glm::unpackHalf1x16(static_cast<uint16_t>(h))) << h;
  }
}

TEST(Half, BarbCountsAndTheirHalvesAreExact) {
  // A polygon's barb count is a kept barb's count or the mean of two neighbours' (halves).
  for (int twice = 0; twice <= 2048; ++twice) {
    const float c = 0.5f * static_cast<float>(twice);
    EXPECT_EQ(static_cast<float>(Half(c)), c);
  }
  EXPECT_EQ(static_cast<float>(Half(1.0f)), 1.0f);
  EXPECT_EQ(static_cast<float>(Half(0.0f)), 0.0f);
  EXPECT_LE(std::abs(static_cast<float>(Half(0.7f)) - 0.7f), 0.7f / 2048.0f);
  EXPECT_TRUE(std::isnan(static_cast<float>(Half(std::numeric_limits<float>::quiet_NaN()))));
  EXPECT_TRUE(std::isinf(static_cast<float>(Half(1e6f))));
}

TEST(TriMesh, AVertexHolds58Bytes) {
  const size_t perVertex =
      sizeof(glm::vec3) + 2 * sizeof(PackedDir) + 3 * sizeof(glm::vec2) + 3 * sizeof(Half) + sizeof(uint32_t);
  EXPECT_EQ(perVertex, 58u);  // docs/limits.md, "Bytes per coat triangle"
  TriMesh m;
  m.normals.push_back(glm::vec3(0, 0, 1));
  m.alpha.push_back(0.25f);
  EXPECT_EQ(glm::vec3(m.normals[0]), glm::vec3(0, 0, 1));
  EXPECT_EQ(static_cast<float>(m.alpha[0]), 0.25f);
}

TEST(PackedDir, ALongerVectorKeepsItsDirection) {
  // Producers may hand over unnormalized normals (a file's, a cross product): clamping each component
  // would turn them; scaling by the largest component does not.
  const glm::vec3 v(3.0f, -1.5f, 0.75f);
  const glm::vec3 back = PackedDir(v);
  EXPECT_LE(glm::length(glm::normalize(back) - glm::normalize(v)), 3e-5f);
  EXPECT_EQ(back.x, 1.0f);
  const glm::vec3 inf = PackedDir(glm::vec3(std::numeric_limits<float>::infinity(), 1.0f, 0.0f));
  EXPECT_TRUE(std::isnan(inf.x));
}
