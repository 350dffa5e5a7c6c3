// Styling by fixed feather angles and surface direction edits, Streit 2003, 8.3 ("Feather
// Rearrangement": a tool lifts a set of feathers to a fixed angle, or the surface direction vectors are
// modified; the rest of the coat is then packed against them).
#include "pteryla/coat/style.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"

namespace pteryla::coat {

namespace {

double segmentDistance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 ab = b - a;
  const double l2 = glm::dot(ab, ab);
  const double t = l2 > 0 ? std::clamp(glm::dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
  return glm::length(p - (a + t * ab));
}

}  // namespace

std::vector<uint32_t> selectFeathers(const CoatFeathers& coat, const StyleSelection& s, const std::string& where) {
  std::vector<uint32_t> out;
  const size_t n = coat.size();
  switch (s.kind) {
    case StyleKind::Ids:
      for (size_t k = 0; k < s.ids.size(); ++k) {
        if (s.ids[k] >= n)
          throw Error(
              "feather id " + std::to_string(s.ids[k]) + " out of range (coat has " + std::to_string(n) + " feathers)",
              {}, where.empty() ? "ids[" + std::to_string(k) + "]" : where + ".ids[" + std::to_string(k) + "]");
        out.push_back(s.ids[k]);
      }
      std::sort(out.begin(), out.end());
      out.erase(std::unique(out.begin(), out.end()), out.end());
      break;
    case StyleKind::Sphere:
      for (uint32_t i = 0; i < n; ++i)
        if (glm::length(coat.frames[i].origin - s.center) <= s.radius) out.push_back(i);
      break;
    case StyleKind::Comb:
      for (uint32_t i = 0; i < n; ++i)
        if (segmentDistance(coat.frames[i].origin, s.from, s.to) <= s.radius) out.push_back(i);
      break;
  }
  return out;
}

StyleApplied applyStyling(CoatFeathers& coat, const std::vector<StyleSelection>& selections,
                          const std::vector<double>& baseFixed) {
  const size_t n = coat.size();
  StyleApplied r;
  r.fixedElevation = baseFixed;
  if (r.fixedElevation.empty()) r.fixedElevation.assign(n, std::numeric_limits<double>::quiet_NaN());
  PTERYLA_CHECK_EQ(r.fixedElevation.size(), n, "baseFixed must be empty or one entry per feather");
  std::vector<uint8_t> changed(n, 0);
  for (size_t k = 0; k < selections.size(); ++k) {
    const StyleSelection& s = selections[k];
    const std::vector<uint32_t> sel = selectFeathers(coat, s, "styling[" + std::to_string(k) + "]");
    r.selectedCount.push_back(static_cast<uint32_t>(sel.size()));
    for (uint32_t i : sel) {
      if (s.elevation) {
        if (!(r.fixedElevation[i] == *s.elevation)) changed[i] = 1;
        r.fixedElevation[i] = *s.elevation;
      }
      if (s.direction) {
        FeatherFrame& f = coat.frames[i];
        glm::dvec3 t = *s.direction - glm::dot(*s.direction, f.normal) * f.normal;
        const double l = glm::length(t);
        if (!(l > 1e-12)) continue;  // direction along the normal: keep the old tangent
        t /= l;
        const glm::dvec3 b = glm::normalize(glm::cross(f.normal, t));
        if (t != f.tangent || b != f.binormal) changed[i] = 1;
        f.tangent = t;
        f.binormal = b;
      }
    }
  }
  for (uint32_t i = 0; i < n; ++i)
    if (changed[i]) r.changed.push_back(i);
  return r;
}

std::vector<double> resolveStyling(const CoatFeathers& coat, const std::vector<StyleSelection>& selections) {
  std::vector<double> fixed(coat.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t k = 0; k < selections.size(); ++k) {
    const StyleSelection& s = selections[k];
    if (!s.elevation) continue;
    for (uint32_t i : selectFeathers(coat, s, "styling[" + std::to_string(k) + "]")) fixed[i] = *s.elevation;
  }
  return fixed;
}

namespace {

// Per feather the value of one optional field of the selections (later ones win; NaN = none); empty when
// no selection sets it.
std::vector<double> resolvePerFeather(const CoatFeathers& coat, const std::vector<StyleSelection>& selections,
                                      std::optional<double> StyleSelection::*field) {
  std::vector<double> v;
  for (size_t k = 0; k < selections.size(); ++k) {
    const StyleSelection& s = selections[k];
    if (!(s.*field)) continue;
    if (v.empty()) v.assign(coat.size(), std::numeric_limits<double>::quiet_NaN());
    for (uint32_t i : selectFeathers(coat, s, "styling[" + std::to_string(k) + "]")) v[i] = *(s.*field);
  }
  return v;
}

}  // namespace

std::vector<double> resolveMinElevation(const CoatFeathers& coat, const std::vector<StyleSelection>& selections) {
  return resolvePerFeather(coat, selections, &StyleSelection::minElevation);
}

std::vector<double> resolveShaftBand(const CoatFeathers& coat, const std::vector<StyleSelection>& selections) {
  return resolvePerFeather(coat, selections, &StyleSelection::shaftBand);
}

StyleSelection parseStyleSelection(JsonReader& r) {
  StyleSelection s;
  const std::string kind = r.oneOf("select", "ids", {"ids", "sphere", "comb"});
  if (kind == "ids") {
    s.kind = StyleKind::Ids;
    const Json& ids = r.raw("ids");
    if (!ids.is_array()) r.fail("ids", "expected an array of feather indices");
    for (size_t k = 0; k < ids.size(); ++k) {
      const double v = jsonNumber(ids[k], r.file(), r.pathOf("ids") + "[" + std::to_string(k) + "]");
      if (v < 0 || v != std::floor(v) || v > 4294967295.0)
        throw Error("expected a non-negative integer feather index", r.file(),
                    r.pathOf("ids") + "[" + std::to_string(k) + "]");
      s.ids.push_back(static_cast<uint32_t>(v));
    }
  } else if (kind == "sphere") {
    s.kind = StyleKind::Sphere;
    s.center = r.vec3("center");
    s.radius = r.number("radius", 0.0, std::numeric_limits<double>::infinity());
  } else {
    s.kind = StyleKind::Comb;
    s.from = r.vec3("from");
    s.to = r.vec3("to");
    s.radius = r.number("radius", 0.0, std::numeric_limits<double>::infinity());
  }
  if (r.has("elevation_deg")) s.elevation = r.number("elevation_deg", -90.0, 180.0) * 3.14159265358979323846 / 180.0;
  if (r.has("direction")) {
    const glm::dvec3 d = r.vec3("direction");
    if (!(glm::length(d) > 0)) r.fail("direction", "direction must not be zero");
    s.direction = d;
  }
  if (r.has("min_elevation_deg"))
    s.minElevation = r.number("min_elevation_deg", -90.0, 180.0) * 3.14159265358979323846 / 180.0;
  if (r.has("shaft_band")) s.shaftBand = r.number("shaft_band", 0.0, 1.0);
  if (!s.elevation && !s.direction && !s.minElevation && !s.shaftBand)
    r.fail("elevation_deg", "a styling selection needs elevation_deg, min_elevation_deg, direction and/or shaft_band");
  r.finish();
  return s;
}

Json styleSelectionToJson(const StyleSelection& s) {
  Json j = Json::object();
  switch (s.kind) {
    case StyleKind::Ids:
      j["select"] = "ids";
      j["ids"] = s.ids;
      break;
    case StyleKind::Sphere:
      j["select"] = "sphere";
      j["center"] = {s.center.x, s.center.y, s.center.z};
      j["radius"] = s.radius;
      break;
    case StyleKind::Comb:
      j["select"] = "comb";
      j["from"] = {s.from.x, s.from.y, s.from.z};
      j["to"] = {s.to.x, s.to.y, s.to.z};
      j["radius"] = s.radius;
      break;
  }
  if (s.elevation) j["elevation_deg"] = *s.elevation * 180.0 / 3.14159265358979323846;
  if (s.minElevation) j["min_elevation_deg"] = *s.minElevation * 180.0 / 3.14159265358979323846;
  if (s.direction) j["direction"] = {s.direction->x, s.direction->y, s.direction->z};
  if (s.shaftBand) j["shaft_band"] = *s.shaftBand;
  return j;
}

}  // namespace pteryla::coat
