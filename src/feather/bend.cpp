// A feather bent along its shaft by the dynamic chain (bend.hpp): the smooth, inextensible centre line
// through the displaced joints and rotation minimizing frames that carry every vertex.
#include "pteryla/feather/bend.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <cmath>

#include "mesh_internal.hpp"

namespace pteryla::feather {

namespace {

constexpr int kSamplesPerSegment = 4;

glm::dvec3 catmullRom(const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2, const glm::dvec3& p3,
                      double u) {
  return 0.5 * (2.0 * p1 + (p2 - p0) * u + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * (u * u) +
                (3.0 * p1 - p0 - 3.0 * p2 + p3) * (u * u * u));
}

glm::dvec3 unitOr(const glm::dvec3& v, const glm::dvec3& fallback) {
  const double l = glm::length(v);
  return l > 1e-300 ? v / l : fallback;
}

// The rotation taking unit a to unit b about a x b (identity when they are opposite: not a bend).
glm::dmat3 minimalRotation(const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 v = glm::cross(a, b);
  const double c = glm::dot(a, b);
  if (!(c > -1 + 1e-12)) return glm::dmat3(1.0);
  const glm::dmat3 k(0, v.z, -v.y, -v.z, 0, v.x, v.y, -v.x, 0);  // columns of [v]x
  return glm::dmat3(1.0) + k + (k * k) * (1.0 / (1.0 + c));
}

struct Bent {
  std::vector<glm::dvec3> p;  // centre line samples, follicle to tip
  std::vector<glm::dmat3> r;  // frame rotation at each sample (identity at the root)
  double localLength = 0;     // chain length in feather-local x units
};

Bent bend(const FeatherPlacement& pl, const ShaftBend& b) {
  Bent out;
  const int n = static_cast<int>(b.offset.size());
  const int m = kSamplesPerSegment * n;
  const double scale = glm::length(pl.x);
  const glm::dvec3 axis = unitOr(pl.x, glm::dvec3(1, 0, 0));
  out.localLength = scale > 0 ? b.length / scale : 0.0;
  const double step = b.length / m;
  // Joint displacements with the ends extended: an even reflection at the root (zero slope: the root
  // segment leaves along the follicle frame), a linear extension past the tip.
  std::vector<glm::dvec3> d(static_cast<size_t>(n) + 3);
  d[1] = glm::dvec3(0.0);
  for (int k = 1; k <= n; ++k) d[static_cast<size_t>(k) + 1] = b.offset[static_cast<size_t>(k) - 1];
  d[0] = d[2];
  d[static_cast<size_t>(n) + 2] = 2.0 * d[static_cast<size_t>(n) + 1] - d[static_cast<size_t>(n)];
  out.p.resize(static_cast<size_t>(m) + 1);
  out.p[0] = pl.origin;
  glm::dvec3 dir = axis;
  for (int i = 1; i <= m; ++i) {
    const int seg = std::min(i / kSamplesPerSegment, n - 1);
    const double u = static_cast<double>(i) / kSamplesPerSegment - seg;
    const size_t s = static_cast<size_t>(seg);
    const glm::dvec3 target = pl.origin + axis * (step * i) + catmullRom(d[s], d[s + 1], d[s + 2], d[s + 3], u);
    // Follow the leader: keep the rest spacing, so the shaft does not stretch.
    dir = unitOr(target - out.p[static_cast<size_t>(i) - 1], dir);
    out.p[static_cast<size_t>(i)] = out.p[static_cast<size_t>(i) - 1] + step * dir;
  }
  out.r.resize(out.p.size());
  out.r[0] = glm::dmat3(1.0);
  glm::dvec3 prev = axis;
  for (int i = 1; i <= m; ++i) {
    const size_t k = static_cast<size_t>(i);
    const glm::dvec3 t = i < m ? unitOr(out.p[k + 1] - out.p[k - 1], prev) : unitOr(out.p[k] - out.p[k - 1], prev);
    out.r[k] = minimalRotation(prev, t) * out.r[k - 1];
    prev = t;
  }
  return out;
}

}  // namespace

bool ShaftBend::rigid() const {
  if (!(length > 0)) return true;
  for (const glm::dvec3& o : offset)
    if (o != glm::dvec3(0.0)) return false;
  return true;
}

std::vector<glm::dvec3> bentShaft(const FeatherPlacement& placement, const ShaftBend& b) {
  if (b.rigid()) {
    const int n = std::max<int>(1, static_cast<int>(b.offset.size()));
    std::vector<glm::dvec3> p;
    const glm::dvec3 axis = unitOr(placement.x, glm::dvec3(1, 0, 0));
    for (int i = 0; i <= kSamplesPerSegment * n; ++i)
      p.push_back(placement.origin + axis * (b.length * i / (kSamplesPerSegment * n)));
    return p;
  }
  return bend(placement, b).p;
}

void placeBentFeatherVertices(const FeatherPlacement& placement, const ShaftBend& b, const glm::vec3* positions,
                              const PackedDir* normals, const PackedDir* tangents, size_t count,
                              glm::vec3* outPositions, PackedDir* outNormals, PackedDir* outTangents) {
  if (b.rigid()) {
    placeFeatherVertices(placement, positions, normals, tangents, count, outPositions, outNormals, outTangents);
    return;
  }
  const Bent s = bend(placement, b);
  const meshing::Xform xf(placement);
  const size_t m = s.p.size() - 1;
  const double perSample = s.localLength / static_cast<double>(m);
  for (size_t v = 0; v < count; ++v) {
    const glm::dvec3 q(positions[v]);
    const double a = std::clamp(q.x, 0.0, s.localLength);
    const double at = perSample > 0 ? a / perSample : 0.0;
    const size_t j = std::min(static_cast<size_t>(at), m - 1);
    const double w = at - static_cast<double>(j);
    const glm::dvec3 centre = s.p[j] + w * (s.p[j + 1] - s.p[j]);
    const glm::dmat3 r = (1.0 - w) * s.r[j] + w * s.r[j + 1];
    const glm::dvec3 local = placement.x * (q.x - a) + placement.y * q.y + placement.z * q.z;
    outPositions[v] = glm::vec3(centre + r * local);
    const glm::mat3 rf(r);
    const glm::vec3 n = normals[v], t = tangents[v];
    outNormals[v] = meshing::safeUnit(rf * xf.placeNormal(n), n);
    outTangents[v] = meshing::safeUnit(rf * xf.placeTangent(t), t);
  }
}

}  // namespace pteryla::feather
