// Bezier evaluation and degree elevation for barbs and the rachis (Streit 2003, 5.2.2; elevation rule
// from Rogers & Adams via [RC96]).
#include "pteryla/feather/bezier.hpp"

#include "pteryla/core/error.hpp"

namespace pteryla::feather {

glm::dvec3 bezierPoint(const std::vector<glm::dvec3>& cvs, double u) { return bezierPoint(cvs.data(), cvs.size(), u); }

glm::dvec3 bezierDerivative(const std::vector<glm::dvec3>& cvs, double u) {
  return bezierDerivative(cvs.data(), cvs.size(), u);
}

std::vector<glm::dvec3> elevateDegree(const std::vector<glm::dvec3>& cvs) {
  PTERYLA_CHECK(!cvs.empty(), "cannot elevate an empty curve");
  const size_t n = cvs.size() - 1;  // degree
  std::vector<glm::dvec3> out(n + 2);
  out[0] = cvs[0];
  out[n + 1] = cvs[n];
  for (size_t i = 1; i <= n; ++i) {
    const double a = static_cast<double>(i) / static_cast<double>(n + 1);
    out[i] = a * cvs[i - 1] + (1.0 - a) * cvs[i];
  }
  return out;
}

std::vector<glm::dvec3> elevateTo(const std::vector<glm::dvec3>& cvs, size_t count) {
  PTERYLA_CHECK_GE(count, cvs.size(), "elevateTo cannot lower the degree");
  std::vector<glm::dvec3> out = cvs;
  while (out.size() < count) out = elevateDegree(out);
  return out;
}

void sampleBezier(const std::vector<glm::dvec3>& cvs, int segments, std::vector<glm::dvec3>& out) {
  PTERYLA_CHECK_GE(segments, 1, "need at least one segment");
  out.resize(static_cast<size_t>(segments) + 1);
  for (int i = 0; i <= segments; ++i) out[i] = bezierPoint(cvs, static_cast<double>(i) / segments);
}

}  // namespace pteryla::feather
