#pragma once
// Bezier curves for barbs and the rachis (Streit 2003, 5.2.2). A curve of degree n is its n+1 control
// vertices; evaluation uses de Casteljau, degree elevation the rule cv'_i = i/(n+1) cv_{i-1} +
// (1 - i/(n+1)) cv_i, which leaves the curve unchanged. Templates take any glm vector type.
#include <glm/vec3.hpp>
#include <cstddef>
#include <vector>

namespace pteryla::feather {

// Point at parameter u in [0,1] of the curve with `count` control vertices (count >= 1).
template <class V>
V bezierPoint(const V* cvs, size_t count, double u);
// First derivative dC/du at u (zero for count < 2).
template <class V>
V bezierDerivative(const V* cvs, size_t count, double u);

glm::dvec3 bezierPoint(const std::vector<glm::dvec3>& cvs, double u);
glm::dvec3 bezierDerivative(const std::vector<glm::dvec3>& cvs, double u);
// Raises the degree by one (count + 1 control vertices), same curve.
std::vector<glm::dvec3> elevateDegree(const std::vector<glm::dvec3>& cvs);
// Repeated elevation up to `count` control vertices (no-op when already that many; count < size is a
// programming error).
std::vector<glm::dvec3> elevateTo(const std::vector<glm::dvec3>& cvs, size_t count);
// Polyline with segments+1 points sampled uniformly in u.
void sampleBezier(const std::vector<glm::dvec3>& cvs, int segments, std::vector<glm::dvec3>& out);

// ---- implementation of the templates ----
template <class V>
V bezierPoint(const V* cvs, size_t count, double u) {
  // de Casteljau on a small stack buffer; long curves fall back to Bernstein accumulation.
  constexpr size_t kStack = 16;
  if (count == 0) return V(0);
  if (count <= kStack) {
    V tmp[kStack];
    for (size_t i = 0; i < count; ++i) tmp[i] = cvs[i];
    using S = typename V::value_type;
    const S a = static_cast<S>(1.0 - u), b = static_cast<S>(u);
    for (size_t level = count - 1; level > 0; --level)
      for (size_t i = 0; i < level; ++i) tmp[i] = a * tmp[i] + b * tmp[i + 1];
    return tmp[0];
  }
  const size_t n = count - 1;
  V acc(0);
  double binom = 1.0;  // C(n, i)
  for (size_t i = 0; i <= n; ++i) {
    double w = binom;
    for (size_t k = 0; k < i; ++k) w *= u;
    for (size_t k = i; k < n; ++k) w *= (1.0 - u);
    acc += static_cast<typename V::value_type>(w) * cvs[i];
    binom = binom * static_cast<double>(n - i) / static_cast<double>(i + 1);
  }
  return acc;
}

template <class V>
V bezierDerivative(const V* cvs, size_t count, double u) {
  if (count < 2) return V(0);
  constexpr size_t kStack = 16;
  using S = typename V::value_type;
  const S n = static_cast<S>(count - 1);
  if (count - 1 <= kStack) {
    V d[kStack];
    for (size_t i = 0; i + 1 < count; ++i) d[i] = n * (cvs[i + 1] - cvs[i]);
    return bezierPoint(d, count - 1, u);
  }
  std::vector<V> d(count - 1);
  for (size_t i = 0; i + 1 < count; ++i) d[i] = n * (cvs[i + 1] - cvs[i]);
  return bezierPoint(d.data(), d.size(), u);
}

}  // namespace pteryla::feather
