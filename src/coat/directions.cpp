// Surface directions and the follicle coordinate frame. Streit 2003, 6.3.1: the direction comes from the
// body segment's medial axis projected onto the surface at the follicle, or from a few user-placed surface
// styling vectors whose interpolated object-space direction is projected onto the surface; the frame is
// (N, T, B = N x T). Storing T in the face's edge basis keeps it attached to the skin when the skin moves
// (Chapter 8: the coat follows an animated skin).
#include "pteryla/coat/directions.hpp"

#include <tbb/parallel_for.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

#include "pteryla/core/error.hpp"

namespace pteryla::coat {
namespace {

glm::dvec3 anyPerpendicular(const glm::dvec3& n) {
  const glm::dvec3 a = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  return glm::normalize(glm::cross(n, a));
}

glm::dvec3 projectTangent(const glm::dvec3& v, const glm::dvec3& n) { return v - glm::dot(v, n) * n; }

bool finite3(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Unit tangent from v, or from the fallbacks when v has (almost) no tangential part.
glm::dvec3 tangentOrFallback(const glm::dvec3& v, const glm::dvec3& n, const glm::dvec3& fallback,
                             const glm::dvec3& edge, bool& usedFallback) {
  usedFallback = false;
  const double lv = glm::length(v);
  glm::dvec3 t = projectTangent(v, n);
  if (lv > 0 && glm::length(t) > 1e-6 * lv) return glm::normalize(t);
  usedFallback = true;
  const double lf = glm::length(fallback);
  t = projectTangent(fallback, n);
  if (lf > 0 && glm::length(t) > 1e-6 * lf) return glm::normalize(t);
  t = projectTangent(edge, n);
  if (glm::length(t) > 1e-9 * glm::length(edge)) return glm::normalize(t);
  return anyPerpendicular(n);
}

double vectorsEps2(const DirectionSpec& s) {
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (const auto& v : s.vectors) lo = glm::min(lo, v.at), hi = glm::max(hi, v.at);
  const double ext = s.vectors.empty() ? 0.0 : glm::length(hi - lo);
  return std::max(1e-6 * ext * ext, 1e-300);
}

void validateSpec(const DirectionSpec& s, const std::string& where) {
  if (!s.axis.empty() && s.axis.size() < 2) throw Error("a body axis needs at least two points", {}, where + ".axis");
  for (size_t i = 0; i < s.axis.size(); ++i) {
    if (!finite3(s.axis[i])) throw Error("axis point is not finite", {}, where + ".axis[" + std::to_string(i) + "]");
    if (i > 0 && s.axis[i] == s.axis[i - 1])
      throw Error("consecutive axis points coincide", {}, where + ".axis[" + std::to_string(i) + "]");
  }
  for (size_t i = 0; i < s.vectors.size(); ++i)
    if (!finite3(s.vectors[i].at) || !finite3(s.vectors[i].direction) || glm::length(s.vectors[i].direction) == 0)
      throw Error("styling vector needs a finite position and a non-zero direction", {},
                  where + ".vectors[" + std::to_string(i) + "]");
  if (!(s.falloff >= 0) || !std::isfinite(s.falloff)) throw Error("falloff must be >= 0", {}, where + ".falloff");
  for (size_t i = 0; i < s.vectors.size(); ++i) {
    const std::string at = where + ".vectors[" + std::to_string(i) + "].radius";
    const double r = s.vectors[i].radius;
    if (!(r >= 0) || !std::isfinite(r)) throw Error("radius must be a finite number >= 0", {}, at);
    if (s.axis.empty() && r > 0)
      throw Error("a radius applies to styling vectors over a body axis (use falloff without one)", {}, at);
    if (!s.axis.empty() && r == 0 && s.falloff == 0)
      throw Error("a styling vector over a body axis needs a radius (or the field a falloff > 0)", {}, at);
  }
  if (!finite3(s.fallback)) throw Error("fallback must be finite", {}, where + ".fallback");
}

std::vector<glm::dvec3> readPoints(JsonReader& r, const std::string& key) {
  const Json& a = r.raw(key);
  const std::string base = r.pathOf(key);
  if (!a.is_array()) throw Error("expected an array of [x,y,z] points", r.file(), base);
  std::vector<glm::dvec3> pts;
  for (size_t i = 0; i < a.size(); ++i) {
    const std::string p = base + "[" + std::to_string(i) + "]";
    if (!a[i].is_array() || a[i].size() != 3) throw Error("expected [x,y,z]", r.file(), p);
    pts.emplace_back(jsonNumber(a[i][0], r.file(), p + "[0]"), jsonNumber(a[i][1], r.file(), p + "[1]"),
                     jsonNumber(a[i][2], r.file(), p + "[2]"));
  }
  return pts;
}

}  // namespace

namespace {
glm::dvec3 axisDirection(const DirectionSpec& s, const glm::dvec3& p) {
  double best = std::numeric_limits<double>::infinity();
  glm::dvec3 dir(0.0);
  for (size_t i = 0; i + 1 < s.axis.size(); ++i) {
    const glm::dvec3 a = s.axis[i], d = s.axis[i + 1] - a;
    const double len2 = glm::dot(d, d);
    if (!(len2 > 0)) continue;
    const double t = std::clamp(glm::dot(p - a, d) / len2, 0.0, 1.0);
    const glm::dvec3 q = a + t * d - p;
    const double d2 = glm::dot(q, q);
    if (d2 < best) best = d2, dir = d / std::sqrt(len2);
  }
  return dir;
}

// A combed axis: the axis blended toward the vectors by their coverage (directions.hpp).
glm::dvec3 combedDirection(const DirectionSpec& s, const glm::dvec3& p) {
  const glm::dvec3 a = axisDirection(s, p);
  glm::dvec3 v(0.0);
  double uncovered = 1.0;
  for (const auto& sv : s.vectors) {
    const double r = sv.radius > 0 ? sv.radius : s.falloff;
    const double g = std::exp(-glm::dot(sv.at - p, sv.at - p) / (2.0 * r * r));
    v += g * glm::normalize(sv.direction);
    uncovered *= 1.0 - g;
  }
  const double lv = glm::length(v);
  if (!(lv > 0)) return a;
  const double w = 1.0 - uncovered;
  return (1.0 - w) * a + w * (v / lv);
}
}  // namespace

glm::dvec3 fieldDirection(const DirectionSpec& s, const glm::dvec3& p) {
  if (s.axis.size() >= 2) return s.vectors.empty() ? axisDirection(s, p) : combedDirection(s, p);
  if (s.vectors.empty()) return glm::dvec3(0.0);
  glm::dvec3 sum(0.0);
  if (s.falloff > 0) {
    double d2min = std::numeric_limits<double>::infinity();
    for (const auto& v : s.vectors) d2min = std::min(d2min, glm::dot(v.at - p, v.at - p));
    const double inv = 1.0 / (2.0 * s.falloff * s.falloff);
    for (const auto& v : s.vectors)
      sum += std::exp(-(glm::dot(v.at - p, v.at - p) - d2min) * inv) * glm::normalize(v.direction);
  } else {
    const double eps2 = vectorsEps2(s);
    for (const auto& v : s.vectors) sum += glm::normalize(v.direction) / (glm::dot(v.at - p, v.at - p) + eps2);
  }
  return sum;
}

glm::dvec2 directionToFaceCoords(const SkinMesh& skin, uint32_t face, const glm::dvec3& bary, const glm::dvec3& t) {
  const auto& f = skin.faces[face];
  const glm::dvec3 p0 = skin.positions[f[0]];
  const glm::dvec3 e1 = skin.positions[f[1]] - p0, e2 = skin.positions[f[2]] - p0;
  glm::dvec3 n = normalAt(skin, face, bary);
  if (glm::dot(n, skin.faceNormals[face]) < 0.1) n = skin.faceNormals[face];
  // Solve [e1 e2 n] (a b c)^T = t by Cramer's rule.
  const glm::dvec3 e2n = glm::cross(e2, n);
  const double det = glm::dot(e1, e2n);
  PTERYLA_CHECK(std::abs(det) > 0, "degenerate face in directionToFaceCoords");
  return {glm::dot(t, e2n) / det, glm::dot(e1, glm::cross(t, n)) / det};
}

glm::dvec3 directionAt(const SkinMesh& skin, uint32_t face, const glm::dvec3& bary, const glm::dvec2& c) {
  const auto& f = skin.faces[face];
  const glm::dvec3 p0 = skin.positions[f[0]];
  const glm::dvec3 e1 = skin.positions[f[1]] - p0, e2 = skin.positions[f[2]] - p0;
  const glm::dvec3 n = normalAt(skin, face, bary);
  bool fb = false;
  const glm::dvec3 t = tangentOrFallback(c.x * e1 + c.y * e2, n, glm::dvec3(0.0), e1, fb);
  return glm::normalize(projectTangent(t, n));
}

FeatherFrame follicleFrame(const SkinMesh& skin, uint32_t face, const glm::dvec3& bary, const glm::dvec2& coords) {
  FeatherFrame fr;
  fr.origin = pointAt(skin, face, bary);
  fr.normal = normalAt(skin, face, bary);
  fr.tangent = directionAt(skin, face, bary, coords);
  fr.binormal = glm::cross(fr.normal, fr.tangent);
  return fr;
}

SurfaceDirections computeSurfaceDirections(const SkinMesh& rest, const std::vector<Tract>& tracts,
                                           const Follicles& follicles, const DirectionOptions& options) {
  validateSpec(options.field, "directions");
  std::vector<const DirectionSpec*> specOf(tracts.size(), &options.field);
  for (const auto& [name, spec] : options.tracts) {
    const std::string where = "directions.tracts." + name;
    validateSpec(spec, where);
    bool found = false;
    for (size_t t = 0; t < tracts.size(); ++t)
      if (tracts[t].name == name) specOf[t] = &spec, found = true;
    if (!found) throw Error("no tract named '" + name + "'", {}, where);
  }
  SurfaceDirections out;
  const size_t n = follicles.size();
  out.faceCoords.resize(n);
  out.usedFallback.assign(n, 0);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    const uint32_t t = follicles.tract[i];
    const DirectionSpec& spec = t < specOf.size() ? *specOf[t] : options.field;
    const uint32_t face = follicles.face[i];
    const glm::dvec3& bary = follicles.bary[i];
    const glm::dvec3 p = pointAt(rest, face, bary);
    const glm::dvec3 nrm = normalAt(rest, face, bary);
    const auto& f = rest.faces[face];
    bool fb = false;
    const glm::dvec3 dir =
        tangentOrFallback(fieldDirection(spec, p), nrm, spec.fallback, rest.positions[f[1]] - rest.positions[f[0]], fb);
    out.faceCoords[i] = directionToFaceCoords(rest, face, bary, dir);
    out.usedFallback[i] = fb;
  });
  for (uint8_t u : out.usedFallback) out.fallbacks += u;
  return out;
}

void evaluateFrames(const SkinMesh& skin, const Follicles& follicles, const SurfaceDirections& directions,
                    CoatFeathers& coat) {
  PTERYLA_CHECK_EQ(directions.faceCoords.size(), follicles.size(), "directions were computed for other follicles");
  coat.frames.resize(coat.size());
  tbb::parallel_for(size_t(0), coat.size(), [&](size_t i) {
    const uint32_t f = coat.follicle[i];
    coat.frames[i] = follicleFrame(skin, follicles.face[f], follicles.bary[f], directions.faceCoords[f]);
  });
}

DirectionSpec parseDirectionSpec(JsonReader& r) {
  DirectionSpec s;
  if (r.has("axis")) {
    s.axis = readPoints(r, "axis");
    if (s.axis.size() < 2) r.fail("axis", "a body axis needs at least two points (head to tail)");
    for (size_t i = 1; i < s.axis.size(); ++i)
      if (s.axis[i] == s.axis[i - 1])
        r.fail("axis", "consecutive points " + std::to_string(i - 1) + " and " + std::to_string(i) + " coincide");
  }
  if (r.has("vectors")) {
    if (!r.json().at("vectors").is_array()) r.fail("vectors", "expected an array of {\"at\", \"direction\"} objects");
    for (auto& v : r.objects("vectors")) {
      StylingVector sv;
      sv.at = v.vec3("at");
      sv.direction = v.vec3("direction");
      if (glm::length(sv.direction) == 0) v.fail("direction", "must be non-zero");
      sv.radius = v.number("radius", 0.0, 0.0, std::numeric_limits<double>::max());
      v.finish();
      s.vectors.push_back(sv);
    }
    if (s.vectors.empty()) r.fail("vectors", "needs at least one styling vector");
  }
  s.falloff = r.number("falloff", 0.0, 0.0, std::numeric_limits<double>::max());
  s.fallback = r.vec3("fallback", s.fallback);
  if (glm::length(s.fallback) == 0) r.fail("fallback", "must be non-zero");
  for (size_t i = 0; i < s.vectors.size(); ++i)
    if (s.axis.empty() && s.vectors[i].radius > 0)
      r.fail("vectors", "vector " + std::to_string(i) +
                            " has a \"radius\", which applies only over a body axis (use \"falloff\" without one)");
  if (!s.axis.empty() && s.falloff == 0)
    for (size_t i = 0; i < s.vectors.size(); ++i)
      if (s.vectors[i].radius == 0)
        r.fail("vectors", "vector " + std::to_string(i) +
                              " lies over a body axis and needs a \"radius\" (or the field a \"falloff\" > 0)");
  r.finish();
  return s;
}

DirectionOptions parseDirections(JsonReader& r) {
  DirectionOptions o;
  if (r.has("tracts")) {
    JsonReader tr = r.object("tracts");
    for (auto it = tr.json().begin(); it != tr.json().end(); ++it) {
      JsonReader one = tr.object(it.key());
      o.tracts.emplace_back(it.key(), parseDirectionSpec(one));
    }
    tr.finish();
  }
  o.field = parseDirectionSpec(r);  // finishes r ("tracts" is already marked used)
  return o;
}

}  // namespace pteryla::coat
