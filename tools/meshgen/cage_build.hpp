#pragma once
// Building blocks for hand-made quad cages: lofted rings, tubes extruded from a loop of existing
// vertices, pole caps, and bone-chain skin weights. Internal to pteryla_meshgen.
#include "meshgen.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <utility>

namespace pteryla::meshgen {

constexpr double kPi = 3.14159265358979323846;
// Edge flips may not bend the surface more than this (degrees).
constexpr double kFlipDihedralDeg = 15.0;

// Cross-section of a loft: an 8-vertex ring around `center` in the plane spanned by `up` and
// `side`, going from `up` towards `side`; the upper half uses rTop, the lower half rBottom, the
// sides rSide.
struct Ring {
  glm::dvec3 center{0.0};
  glm::dvec3 up{0, 1, 0};
  glm::dvec3 side{0, 0, 1};
  double rTop = 0, rBottom = 0, rSide = 0;
  // Vertex k: k even sits on an axis (0 top, 2 +side, 4 bottom, 6 -side); k odd halves the arc
  // length of its elliptic quadrant, so flat rings still get even edges.
  glm::dvec3 vertex(int k) const {
    const int quadrant = k / 2;
    const double rv = quadrant == 0 || quadrant == 3 ? rTop : rBottom;
    double th = quadrant * kPi / 2.0;
    if (k % 2) th += arcMidAngle(quadrant % 2 == 0 ? rv : rSide, quadrant % 2 == 0 ? rSide : rv);
    const double c = std::cos(th), s = std::sin(th);
    return center + up * (c * rv) + side * (s * rSide);
  }
  // Angle t in [0, pi/2] halving the arc of (a cos t, b sin t) from t = 0.
  static double arcMidAngle(double a, double b) {
    constexpr int kSteps = 256;
    double len[kSteps + 1] = {0};
    for (int i = 1; i <= kSteps; ++i) {
      const double t = (i - 0.5) * (kPi / 2) / kSteps;
      len[i] = len[i - 1] + std::hypot(a * std::sin(t), b * std::cos(t)) * (kPi / 2) / kSteps;
    }
    int i = 0;
    while (i < kSteps && len[i + 1] < len[kSteps] / 2) ++i;
    const double f = (len[kSteps] / 2 - len[i]) / (len[i + 1] - len[i]);
    return (i + f) * (kPi / 2) / kSteps;
  }
};

// A spine key: position and radii; lofts orient each ring perpendicular to the spine tangent,
// with `side` fixed to +Z (the spine stays in the XY plane).
struct SpineKey {
  double x, y, rTop, rBottom, rSide;
};

inline std::vector<Ring> ringsAlongSpine(const std::vector<SpineKey>& keys, double tangentBlend = 1.0) {
  std::vector<Ring> rings(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    const size_t a = i == 0 ? 0 : i - 1, b = i + 1 < keys.size() ? i + 1 : i;
    glm::dvec3 t(keys[b].x - keys[a].x, keys[b].y - keys[a].y, 0.0);
    t = glm::normalize(glm::mix(glm::dvec3(1, 0, 0), glm::normalize(t), tangentBlend));
    Ring& r = rings[i];
    r.center = {keys[i].x, keys[i].y, 0.0};
    r.side = {0, 0, 1};
    r.up = glm::normalize(glm::cross(r.side, t));
    r.rTop = keys[i].rTop;
    r.rBottom = keys[i].rBottom;
    r.rSide = keys[i].rSide;
  }
  return rings;
}

// Adds ring vertices and the quads between consecutive rings, except faces listed in `skip`
// as (ring, k) = the face between rings (ring, ring+1) and angles (k, k+1). Face params are
// (s, a) = (ring index + sOffset, angle index). Returns vertex ids [ring][k].
inline std::vector<std::array<uint32_t, 8>> loft(QuadCage& cage, const std::vector<Ring>& rings, int part,
                                                 const std::set<std::pair<int, int>>& skip, double sOffset = 0) {
  std::vector<std::array<uint32_t, 8>> ids(rings.size());
  for (size_t r = 0; r < rings.size(); ++r)
    for (int k = 0; k < 8; ++k) ids[r][k] = cage.addVertex(rings[r].vertex(k));
  for (int r = 0; r + 1 < static_cast<int>(rings.size()); ++r)
    for (int k = 0; k < 8; ++k) {
      if (skip.count({r, k})) continue;
      const double s0 = r + sOffset, s1 = s0 + 1;
      cage.addQuad({ids[r][k], ids[r][(k + 1) % 8], ids[r + 1][(k + 1) % 8], ids[r + 1][k]}, part,
                   {glm::dvec2(s0, k), glm::dvec2(s0, k + 1), glm::dvec2(s1, k + 1), glm::dvec2(s1, k)});
    }
  return ids;
}

// Closes a loop of 2m vertices (m = 3 or 4) with m quads around a new pole vertex. Params: loop
// vertex i gets (s, i), the pole (s + ds, centre of its quad).
inline uint32_t capPole(QuadCage& cage, const std::vector<uint32_t>& loop, const glm::dvec3& pole, int part, double s,
                        double ds) {
  const uint32_t c = cage.addVertex(pole);
  const int n = static_cast<int>(loop.size());
  for (int i = 0; i < n; i += 2) {
    const int i1 = i + 1, i2 = i + 2;
    cage.addQuad({loop[i], loop[i1 % n], loop[i2 % n], c}, part,
                 {glm::dvec2(s, i), glm::dvec2(s, i1), glm::dvec2(s, i2), glm::dvec2(s + ds, i1)});
  }
  return c;
}

// Extrudes a tube from `root` (a loop of existing vertices) through `sections` (same loop size).
// Face params are (w, l): w = section index (root = 0), l = loop index (the closing edge uses
// l = n so params stay continuous). Returns the vertex ids of every section including the root.
inline std::vector<std::vector<uint32_t>> tube(QuadCage& cage, const std::vector<uint32_t>& root,
                                               const std::vector<std::vector<glm::dvec3>>& sections, int part) {
  std::vector<std::vector<uint32_t>> ids{root};
  const int n = static_cast<int>(root.size());
  for (const auto& sec : sections) {
    std::vector<uint32_t> cur;
    for (const auto& p : sec) cur.push_back(cage.addVertex(p));
    const auto& prev = ids.back();
    const double w0 = static_cast<double>(ids.size() - 1), w1 = w0 + 1;
    for (int l = 0; l < n; ++l)
      cage.addQuad({prev[l], prev[(l + 1) % n], cur[(l + 1) % n], cur[l]}, part,
                   {glm::dvec2(w0, l), glm::dvec2(w0, l + 1), glm::dvec2(w1, l + 1), glm::dvec2(w1, l)});
    ids.push_back(std::move(cur));
  }
  return ids;
}

// Drops vertices no quad uses (e.g. the interior of a patch a tube replaced) and renumbers.
inline void compactCage(QuadCage& cage) {
  std::vector<int64_t> remap(cage.positions.size(), -1);
  std::vector<glm::dvec3> kept;
  for (auto& q : cage.quads)
    for (auto& v : q) {
      if (remap[v] < 0) {
        remap[v] = static_cast<int64_t>(kept.size());
        kept.push_back(cage.positions[v]);
      }
      v = static_cast<uint32_t>(remap[v]);
    }
  for (auto& chain : cage.chains)
    for (auto& v : chain) v = static_cast<uint32_t>(remap[v]);
  cage.positions = std::move(kept);
}

inline QuadCage subdivide(QuadCage cage, int levels) {
  compactCage(cage);
  orientOutward(cage);
  for (int i = 0; i < levels; ++i) cage = subdivideCatmullClark(cage);
  projectToLimit(cage);
  return cage;
}

// Final clean-up of a triangulated cage: flips, relaxation on the cage's limit surface (sampled by
// one more subdivision level), flips again.
inline void finishSurface(GroupedMesh& mesh, const QuadCage& cage) {
  const QuadCage reference = subdivide(cage, 3);
  improveByFlips(mesh, kFlipDihedralDeg);
  relaxOnSurface(mesh, reference, 25, 0.5);
  improveByFlips(mesh, kFlipDihedralDeg);
}

// Per-vertex (s, a) / (w, l) coordinates of `part`, read off the faces' corner params; NaN for
// vertices not on that part.
inline std::vector<glm::dvec2> vertexParams(const QuadCage& cage, int part) {
  std::vector<glm::dvec2> out(cage.positions.size(), glm::dvec2(std::nan("")));
  for (size_t f = 0; f < cage.quads.size(); ++f)
    if (cage.tags[f].part == part)
      for (int j = 0; j < 4; ++j) out[cage.quads[f][j]] = cage.tags[f].param[j];
  return out;
}

inline double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// Skin weights of one vertex along a bone chain joints[0] (root) .. joints[3] (wrist), with
// joints[4] the tip. beta0 in [0,1] is how far the vertex has left the root (0 on the body);
// elbow and wrist blend across their bisector planes over +-width.
inline std::vector<SkinWeight> chainWeights(uint32_t vertex, const glm::dvec3& p, double beta0,
                                            const std::array<uint32_t, 5>& chain, const Skeleton& sk, double width) {
  const glm::dvec3 s = sk.joints[chain[1]].position, e = sk.joints[chain[2]].position, w = sk.joints[chain[3]].position,
                   t = sk.joints[chain[4]].position;
  const glm::dvec3 d0 = glm::normalize(e - s), d1 = glm::normalize(w - e), d2 = glm::normalize(t - w);
  const double b1 = smoothstep(-width, width, glm::dot(p - e, glm::normalize(d0 + d1)));
  const double b2 = smoothstep(-width, width, glm::dot(p - w, glm::normalize(d1 + d2)));
  const double raw[4] = {1 - beta0, beta0 * (1 - b1), beta0 * b1 * (1 - b2), beta0 * b1 * b2};
  // Drop negligible weights, round to 1e-5 and give the rounding residue to the largest.
  std::vector<SkinWeight> out;
  double sum = 0;
  for (int k = 0; k < 4; ++k)
    if (raw[k] >= 1e-3) {
      out.push_back({vertex, chain[k], raw[k]});
      sum += raw[k];
    }
  double rounded = 0;
  size_t big = 0;
  for (size_t k = 0; k < out.size(); ++k) {
    out[k].weight = std::round(out[k].weight / sum * 1e5) / 1e5;
    rounded += out[k].weight;
    if (out[k].weight > out[big].weight) big = k;
  }
  out[big].weight = std::round((out[big].weight + 1.0 - rounded) * 1e5) / 1e5;
  return out;
}

}  // namespace pteryla::meshgen
