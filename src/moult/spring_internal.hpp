// Internals of the damped spring shared by the closed-form lag (controls.cpp) and the shaft chains
// (chain.cpp). Not installed.
#pragma once

#include <cmath>

namespace pteryla::moult::spring {

constexpr double kPi = 3.14159265358979323846;

// Homogeneous solution of h'' + 2a h' + w^2 h = 0 over time s as a 2x2 map of (h0, h0').
struct SpringMap {
  double a, b, c, d;  // h = a h0 + b h0', h' = c h0 + d h0'
};

inline SpringMap springMap(double w, double zeta, double s) {
  const double a = zeta * w;
  const double e = std::exp(-a * s);
  if (std::abs(zeta - 1.0) < 1e-9) {
    return {e * (1 + a * s), e * s, -e * a * a * s, e * (1 - a * s)};
  }
  if (zeta < 1.0) {
    const double wd = w * std::sqrt(1 - zeta * zeta);
    const double cs = std::cos(wd * s), sn = std::sin(wd * s);
    return {e * (cs + a / wd * sn), e * sn / wd, -e * (w * w / wd) * sn, e * (cs - a / wd * sn)};
  }
  const double q = w * std::sqrt(zeta * zeta - 1);
  const double r1 = -a + q, r2 = -a - q;
  const double e1 = std::exp(r1 * s), e2 = std::exp(r2 * s), k = 1.0 / (r1 - r2);
  return {k * (-r2 * e1 + r1 * e2), k * (e1 - e2), k * r1 * r2 * (e2 - e1), k * (r1 * e1 - r2 * e2)};
}

}  // namespace pteryla::moult::spring
