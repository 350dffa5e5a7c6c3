// Poulin-Fournier barbule table against shared/reference/poulin-fournier.md (section 6 values).
#include <gtest/gtest.h>

#include <cmath>

#include "pteryla/core/error.hpp"
#include "pteryla/render/brdf_table.hpp"

using namespace pteryla::render;

namespace {
constexpr double kPi = 3.14159265358979323846;
double rad(double deg) { return deg * kPi / 180.0; }

struct Ref {
  double pl, pv, v[4];
};
// D(phi_L, phi_V) for (d,h) = (1,0), (3,0), (2.5,0.3), (1.9,0.8).
const Ref kRefs[] = {
    {0, 0, {0.956611, 0.856932, 0.857763, 0.959737}},     {30, 0, {0.828450, 0.705225, 0.736815, 0.831157}},
    {0, 30, {0.956611, 0.814324, 0.850800, 0.959737}},    {45, 45, {0.740480, 0.811283, 0.818363, 0.739486}},
    {60, -30, {0.433013, 0.192450, 0.238564, 0.437411}},  {-30, 60, {0.750000, 0.333333, 0.413205, 0.757618}},
    {80, 10, {0.174373, 0.160200, 0.164647, 0.170056}},   {30, -30, {0.802300, 0.567559, 0.627865, 0.806316}},
    {-70, -20, {0.353300, 0.320798, 0.334992, 0.350088}},
};
const double kD[4] = {1.0, 3.0, 2.5, 1.9};
const double kH[4] = {0.0, 0.0, 0.3, 0.8};
}  // namespace

TEST(BrdfTable, DiffuseMatchesReferenceValues) {
  for (const Ref& r : kRefs)
    for (int c = 0; c < 4; ++c)
      EXPECT_NEAR(barbuleDiffuse(rad(r.pl), rad(r.pv), kD[c], kH[c]), r.v[c], 2e-6)
          << "phiL=" << r.pl << " phiV=" << r.pv << " d=" << kD[c] << " h=" << kH[c];
  // Closed forms quoted by the reference.
  EXPECT_NEAR(barbuleDiffuse(0, 0, 1, 0), kPi / 6 + std::sqrt(3.0) / 4, 1e-9);
  EXPECT_NEAR(barbuleDiffuse(rad(60), rad(-30), 1, 0), std::sqrt(3.0) / 4, 1e-9);
}

TEST(BrdfTable, SpecularMatchesReferenceValues) {
  EXPECT_NEAR(barbuleSpecular(0, 0, 1, 0, 0.2), 0.478981, 2e-6);
  EXPECT_NEAR(barbuleSpecular(rad(30), rad(-30), 1, 0, 0.2), 0.409640, 2e-6);
  EXPECT_NEAR(barbuleSpecular(rad(45), rad(45), 1, 0, 0.2), 0.059043, 2e-6);
  EXPECT_NEAR(barbuleSpecular(rad(80), rad(10), 1, 0, 0.2), 0.008720, 2e-6);
}

TEST(BrdfTable, ExposedSetsMatchReference) {
  ExposedSet e = exposedSet(rad(30), 1, 0);
  EXPECT_NEAR(e.arcLo, rad(-30), 1e-9);
  EXPECT_NEAR(e.arcHi, rad(30), 1e-9);
  e = exposedSet(rad(75), 1, 0);
  EXPECT_NEAR(e.arcLo, rad(-15), 1e-6);
  EXPECT_NEAR(e.arcHi, rad(27.1679), 1e-5);
  e = exposedSet(rad(89), 1, 0);
  EXPECT_NEAR(e.arcHi, rad(9.7201), 1e-5);
  e = exposedSet(rad(45), 3, 0.5);
  EXPECT_NEAR(e.arcLo, rad(-45), 1e-9);
  EXPECT_NEAR(e.arcHi, rad(60), 1e-9);
  EXPECT_NEAR(e.floorHi - e.floorLo, 1.21976, 1e-5);
  EXPECT_NEAR(exposedSet(rad(60), 3, 0.5).floorHi, 1.0, 1e-5);
  EXPECT_NEAR(exposedSet(rad(75), 3, 0.5).floorHi, 0.13630, 1e-5);
  e = exposedSet(rad(89), 3, 0.5);
  EXPECT_NEAR(e.arcHi, rad(17.6226), 1e-5);
  EXPECT_EQ(e.floorHi - e.floorLo, 0.0);
  // Negative angles mirror the set: arc negated, floor measured from the other end.
  const ExposedSet m = exposedSet(rad(-45), 3, 0.5);
  EXPECT_NEAR(m.arcLo, rad(-60), 1e-9);
  EXPECT_NEAR(m.arcHi, rad(45), 1e-9);
  EXPECT_NEAR(m.floorHi - m.floorLo, 1.21976, 1e-5);
}

TEST(BrdfTable, ReciprocityRangeAndMonotonicity) {
  const double ds[] = {0.5, 1.0, 1.9, 3.0}, hs[] = {0.0, 0.3, 0.8};
  for (double d : ds) {
    for (double h : hs) {
      for (int i = -8; i <= 8; ++i) {
        for (int j = -8; j <= 8; ++j) {
          const double pl = rad(i * 10.5), pv = rad(j * 10.5);
          const double a = barbuleDiffuse(pl, pv, d, h), b = barbuleDiffuse(pv, pl, d, h);
          EXPECT_GE(a, 0.0);
          EXPECT_LE(a, 1.0 + 1e-12);
          EXPECT_NEAR(a / std::cos(pl), b / std::cos(pv), 1e-9) << d << " " << h << " " << i << " " << j;
        }
        // D(., 0) does not grow as |phi_L| grows.
        if (i > 0) {
          EXPECT_LE(barbuleDiffuse(rad(std::abs(i) * 10.5), 0, d, h),
                    barbuleDiffuse(rad((std::abs(i) - 1) * 10.5), 0, d, h) + 1e-12);
        }
      }
    }
  }
}

TEST(BrdfTable, LambertLimits) {
  for (int i = -8; i <= 8; ++i) {
    for (int j = -8; j <= 8; ++j) {
      const double pl = rad(i * 10.0), pv = rad(j * 10.0);
      EXPECT_NEAR(barbuleDiffuse(pl, pv, 0.01, 0.0), std::cos(pl), 1.2e-4);  // d -> 0
      EXPECT_NEAR(barbuleDiffuse(pl, pv, 1.0, 0.999), std::cos(pl), 1e-3);   // h -> 1
    }
  }
}

TEST(BrdfTable, EnergyBounded) {
  for (double d : {0.5, 1.0, 3.0}) {
    for (int i = 0; i <= 8; ++i) {
      const double pl = rad(i * 10.0);
      double sum = 0.0;
      const int n = 2000;
      for (int k = 0; k < n; ++k) {
        const double pv = -kPi / 2 + (k + 0.5) * kPi / n;
        sum += barbuleDiffuse(pl, pv, d, 0.0) * std::cos(pv) * kPi / n;
      }
      EXPECT_LE(sum / (2.0 * std::cos(pl)), 1.0) << "d=" << d << " phiL=" << i * 10;
    }
  }
}

TEST(BrdfTable, TableFiniteNonNegativeAndAccurate) {
  const BrdfTable t = buildBrdfTable({1.0, 0.0, 0.1}, 128);
  ASSERT_EQ(t.size, 128);
  ASSERT_EQ(t.data.size(), 128u * 128u * 2u);
  for (float v : t.data) {
    ASSERT_TRUE(std::isfinite(v));
    ASSERT_GE(v, 0.0f);
  }
  // Bilinear look-ups against the closed form. The reference quotes 2.7e-3 over 4000 random pairs
  // with |phi| < 80 degrees; a dense grid reaches the steeper corner near (-80, -80) too.
  auto maxError = [&](int limit) {
    double maxErr = 0.0;
    for (int i = -limit; i <= limit; ++i) {
      for (int j = -limit; j <= limit; ++j) {
        const double pl = rad(i), pv = rad(j);
        const double exact = barbuleDiffuse(pl, pv, 1.0, 0.0);
        const double table = t.sample(kPi / 2 - pl, kPi / 2 - pv, 0);
        maxErr = std::max(maxErr, std::abs(exact - table));
      }
    }
    return maxErr;
  };
  EXPECT_LT(maxError(60), 2e-4);
  EXPECT_LT(maxError(70), 3e-3);
  EXPECT_LT(maxError(79), 7e-3);
  // Table layout: channel 0 at cell (iL, iV) is D at the cell centre angles.
  const int iL = 40, iV = 90;
  const double pl = kPi / 2 - (iL + 0.5) * kPi / 128, pv = kPi / 2 - (iV + 0.5) * kPi / 128;
  EXPECT_NEAR(t.at(iL, iV, 0), barbuleDiffuse(pl, pv, 1.0, 0.0), 1e-6);
  EXPECT_NEAR(t.at(iL, iV, 1), barbuleSpecular(pl, pv, 1.0, 0.0, 0.1), 1e-6);
}

TEST(BrdfTable, GrazingAnglesStayFinite) {
  for (double d : {0.01, 1.0, 2.0, 4.0}) {
    for (double h : {0.0, 0.5, 0.99}) {
      const double g = kPi / 2 - 1e-9;
      for (double pl : {-g, -1.0, 0.0, 1.0, g}) {
        for (double pv : {-g, -0.5, 0.0, 0.5, g}) {
          const double dv = barbuleDiffuse(pl, pv, d, h), sv = barbuleSpecular(pl, pv, d, h, 0.2);
          EXPECT_TRUE(std::isfinite(dv) && dv >= 0.0) << d << " " << h << " " << pl << " " << pv;
          EXPECT_TRUE(std::isfinite(sv) && sv >= 0.0) << d << " " << h << " " << pl << " " << pv;
        }
      }
      const BrdfTable t = buildBrdfTable({d, h, 0.2}, 16);
      for (float v : t.data) EXPECT_TRUE(std::isfinite(v) && v >= 0.0f);
    }
  }
  // Grazing view with the crest lit converges toward cos(phi_L).
  EXPECT_NEAR(barbuleDiffuse(rad(30), rad(90 - 0.01), 1, 0), 0.8721, 2e-3);
}

TEST(BrdfTable, RejectsBadParameters) {
  EXPECT_THROW(buildBrdfTable({0.0, 0.0, 0.2}), pteryla::Error);
  EXPECT_THROW(buildBrdfTable({1.0, 1.0, 0.2}), pteryla::Error);
  EXPECT_THROW(buildBrdfTable({1.0, -0.1, 0.2}), pteryla::Error);
  EXPECT_THROW(buildBrdfTable({1.0, 0.0, 0.0}), pteryla::Error);
  try {
    validate({1.0, 0.0, -1.0});
    FAIL();
  } catch (const pteryla::Error& e) {
    EXPECT_EQ(e.element(), "sigma");
  }
}
