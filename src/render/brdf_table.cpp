// Poulin & Fournier 1990 anisotropic reflection from parallel cylinders, as used for barbules in
// Streit 2003, 7.1.3 (tabulated into a 2D texture over the angles of the projected light and view
// from the binormal). Formulas (1)-(4) of shared/reference/poulin-fournier.md.
#include "pteryla/render/brdf_table.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "pteryla/core/error.hpp"

namespace pteryla::render {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHalfPi = 0.5 * kPi;

struct Geometry {
  double thetaM;  // largest normal deviation from N on the exposed cylinder
  double floor;   // floor length per period
};

Geometry geometry(double d, double h) {
  h = std::max(0.0, h);
  const double phiD = d < 2.0 ? std::asin(d / 2.0) : kHalfPi;
  const double phiH = std::acos(std::min(1.0, h));
  const double tM = std::min(phiD, phiH);
  return {tM, std::max(0.0, d - 2.0 * std::sin(tM))};
}

// Integral of cos(phi - pL) cos(phi - pV) over [a, b].
double arcIntegral(double a, double b, double pL, double pV) {
  if (b <= a) return 0.0;
  return 0.5 * (b - a) * std::cos(pL - pV) + 0.25 * (std::sin(2 * b - pL - pV) - std::sin(2 * a - pL - pV));
}

double floorOverlap(const ExposedSet& l, const ExposedSet& v) {
  return std::max(0.0, std::min(l.floorHi, v.floorHi) - std::max(l.floorLo, v.floorLo));
}

// 64-point Gauss-Legendre nodes and weights on [-1, 1] by Newton iteration on P_64.
struct GaussLegendre {
  static constexpr int kN = 64;
  std::array<double, kN> x{}, w{};
  GaussLegendre() {
    for (int i = 0; i < kN; ++i) {
      double z = std::cos(kPi * (i + 0.75) / (kN + 0.5));
      double dp = 1.0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1.0, p1 = z;
        for (int k = 2; k <= kN; ++k) {
          const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = kN * (z * p1 - p0) / (z * z - 1.0);
        const double dz = p1 / dp;
        z -= dz;
        if (std::abs(dz) < 1e-16) break;
      }
      x[i] = z;
      w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
  }
};

const GaussLegendre& gaussLegendre() {
  static const GaussLegendre gl;
  return gl;
}

}  // namespace

void validate(const BarbuleParams& p) {
  if (!(p.d > 0.0) || !std::isfinite(p.d)) throw Error("barbule spacing d must be > 0", {}, "d");
  if (!(p.h >= 0.0 && p.h < 1.0)) throw Error("barbule floor height h must be in [0, 1)", {}, "h");
  if (!(p.sigma > 0.0) || !std::isfinite(p.sigma)) throw Error("specular lobe width sigma must be > 0", {}, "sigma");
}

ExposedSet exposedSet(double phi, double d, double h) {
  const Geometry g = geometry(d, h);
  const double tM = g.thetaM, F = g.floor, p = std::abs(phi);
  const double hf = std::cos(tM);
  const double lo = std::max(-tM, p - kHalfPi);
  const double cst = d * std::cos(p) - std::sin(std::min(tM + p, kHalfPi));
  double hi, fe;
  if (cst >= std::sin(tM - p)) {
    hi = tM;
    if (tM + p <= kHalfPi) {
      fe = F;
    } else {
      const double c = std::cos(p);
      const double shadow = c > 1e-300 ? (1.0 - hf * std::sin(p)) / c - std::sin(tM) : F;
      fe = std::clamp(F - shadow, 0.0, F);
    }
  } else {
    hi = p + std::asin(std::max(-1.0, cst));
    fe = 0.0;
  }
  hi = std::max(hi, lo);
  if (phi >= 0.0) return {lo, hi, 0.0, fe};
  return {-hi, -lo, F - fe, F};
}

double barbuleDiffuse(double pL, double pV, double d, double h) {
  const ExposedSet l = exposedSet(pL, d, h), v = exposedSet(pV, d, h);
  const double a = std::max(l.arcLo, v.arcLo), b = std::min(l.arcHi, v.arcHi);
  const double num = arcIntegral(a, b, pL, pV) + floorOverlap(l, v) * std::cos(pL) * std::cos(pV);
  const double den = d * std::cos(pV);
  if (!(den > 0.0)) return 0.0;
  return std::max(0.0, num / den);
}

double barbuleSpecular(double pL, double pV, double d, double h, double sigma) {
  const ExposedSet l = exposedSet(pL, d, h), v = exposedSet(pV, d, h);
  const double a = std::max(l.arcLo, v.arcLo), b = std::min(l.arcHi, v.arcHi);
  const double pH = 0.5 * (pL + pV);
  const double inv2s2 = 1.0 / (2.0 * sigma * sigma);
  auto integrand = [&](double t) {
    const double x = t - pH;
    return std::exp(-x * x * inv2s2) * std::cos(t - pL) * std::cos(t - pV);
  };
  const GaussLegendre& gl = gaussLegendre();
  double integral = 0.0;
  if (b > a) {
    double pts[3] = {a, pH, b};
    int n = 3;
    if (!(a < pH && pH < b)) {
      pts[1] = b;
      n = 2;
    }
    for (int s = 0; s + 1 < n; ++s) {
      const double u = pts[s], w = pts[s + 1];
      const double mid = 0.5 * (u + w), half = 0.5 * (w - u);
      double sum = 0.0;
      for (int i = 0; i < GaussLegendre::kN; ++i) sum += gl.w[i] * integrand(mid + half * gl.x[i]);
      integral += half * sum;
    }
  }
  const double g0 = std::exp(-pH * pH * inv2s2);
  integral += floorOverlap(l, v) * g0 * std::cos(pL) * std::cos(pV);
  const double den = d * std::cos(pV);
  if (!(den > 0.0)) return 0.0;
  return std::max(0.0, integral / den);
}

float BrdfTable::sample(double alphaL, double alphaV, int channel) const {
  // Texture coordinate s = alpha / pi; texel i has its centre at (i + 1/2) / N.
  auto axis = [this](double alpha, int& i0, int& i1, double& f) {
    const double x = alpha / kPi * size - 0.5;
    const double fl = std::floor(x);
    f = x - fl;
    i0 = std::clamp(static_cast<int>(fl), 0, size - 1);
    i1 = std::clamp(static_cast<int>(fl) + 1, 0, size - 1);
  };
  int l0, l1, v0, v1;
  double fl, fv;
  axis(alphaL, l0, l1, fl);
  axis(alphaV, v0, v1, fv);
  const double top = (1 - fl) * at(l0, v0, channel) + fl * at(l1, v0, channel);
  const double bot = (1 - fl) * at(l0, v1, channel) + fl * at(l1, v1, channel);
  return static_cast<float>((1 - fv) * top + fv * bot);
}

BrdfTable buildBrdfTable(const BarbuleParams& params, int size) {
  validate(params);
  if (size < 2 || size > 4096) throw Error("BRDF table size must be in [2, 4096]", {}, "size");
  BrdfTable t;
  t.size = size;
  t.data.assign(static_cast<size_t>(size) * size * 2, 0.0f);
  for (int iV = 0; iV < size; ++iV) {
    const double phiV = kHalfPi - (iV + 0.5) * kPi / size;
    for (int iL = 0; iL < size; ++iL) {
      const double phiL = kHalfPi - (iL + 0.5) * kPi / size;
      double dv = barbuleDiffuse(phiL, phiV, params.d, params.h);
      double sv = barbuleSpecular(phiL, phiV, params.d, params.h, params.sigma);
      if (!std::isfinite(dv)) dv = 0.0;
      if (!std::isfinite(sv)) sv = 0.0;
      const size_t k = (static_cast<size_t>(iV) * size + iL) * 2;
      t.data[k] = static_cast<float>(dv);
      t.data[k + 1] = static_cast<float>(sv);
    }
  }
  return t;
}

}  // namespace pteryla::render
