#include "scene_edit.hpp"

#include <algorithm>

#include <glm/common.hpp>

#include "pteryla/coat/skin.hpp"
#include "pteryla/core/error.hpp"

namespace pteryla::viewer {

using pipeline::Scene;

Json sceneJson(const Scene& s) { return pipeline::sceneToJson(s, ""); }

Json parseLooseValue(const std::string& text) {
  Json v = Json::parse(text, nullptr, false);
  if (v.is_discarded()) return Json(text);
  return v;
}

void setScenePointer(Scene& s, const std::string& pointer, const Json& value) {
  Json j = sceneJson(s);
  try {
    const Json::json_pointer p(pointer);
    if (p.empty()) throw Error("cannot replace the whole scene", s.file, pointer);
    // Walk to the parent, creating missing objects (arrays before "-" or an index): sections are
    // omitted from the JSON form when empty. Misspelt keys are still caught by the strict readers.
    std::vector<std::string> tokens;
    for (Json::json_pointer q = p; !q.empty(); q = q.parent_pointer()) tokens.insert(tokens.begin(), q.back());
    auto isIndex = [](const std::string& t) {
      return t == "-" || (!t.empty() && std::all_of(t.begin(), t.end(), [](char c) { return c >= '0' && c <= '9'; }));
    };
    Json* node = &j;
    std::string at;
    for (size_t i = 0; i + 1 < tokens.size(); ++i) {
      const std::string& t = tokens[i];
      at += "/" + t;
      if (node->is_object()) {
        if (!node->contains(t)) (*node)[t] = isIndex(tokens[i + 1]) ? Json::array() : Json::object();
        node = &(*node)[t];
      } else if (node->is_array()) {
        if (!isIndex(t) || t == "-" || std::stoul(t) >= node->size())
          throw Error("no such array element (size " + std::to_string(node->size()) + ")", s.file, at);
        node = &(*node)[std::stoul(t)];
      } else {
        throw Error("cannot descend into a " + std::string(node->type_name()), s.file, at);
      }
    }
    const std::string& leaf = tokens.back();
    if (node->is_array()) {
      if (leaf == "-") {
        node->push_back(value);
      } else {
        if (!isIndex(leaf)) throw Error("expected an array index", s.file, pointer);
        const size_t idx = std::stoul(leaf);
        if (idx >= node->size())
          throw Error("array index out of range (size " + std::to_string(node->size()) + ")", s.file, pointer);
        (*node)[idx] = value;
      }
    } else if (node->is_object()) {
      (*node)[leaf] = value;
    } else {
      throw Error("parent is neither an object nor an array", s.file, pointer);
    }
  } catch (const Json::exception& e) {
    throw Error(std::string("bad JSON pointer: ") + e.what(), s.file, pointer);
  }
  Scene next = pipeline::sceneFromJson(j, s.file);
  next.fromBareMesh = s.fromBareMesh;
  keepPaintedDensity(s, next);
  s = std::move(next);
}

void keepPaintedDensity(const Scene& from, Scene& next) {
  if (next.densityMap == from.densityMap) next.densityFactor = from.densityFactor;
}

void makeBareMeshExplicit(Scene& s, const glm::dvec3& lo, const glm::dvec3& hi) {
  if (!s.fromBareMesh) return;
  // Same construction as the pipeline's bare-mesh defaults: the longest bounding-box axis through the
  // box centre, head at its low end.
  const glm::dvec3 ext = hi - lo;
  int axes[3] = {0, 1, 2};
  std::sort(axes, axes + 3, [&](int x, int y) { return ext[x] > ext[y]; });
  glm::dvec3 a = 0.5 * (lo + hi), b = a;
  a[axes[0]] = lo[axes[0]];
  b[axes[0]] = hi[axes[0]];
  const Json axis = Json::array({Json::array({a.x, a.y, a.z}), Json::array({b.x, b.y, b.z})});
  if (s.tracts.empty()) s.tracts = Json::array({Json{{"name", "all"}}});
  for (auto& t : s.tracts)
    if (t.is_object() && !t.contains("feather_scale")) t["feather_scale"] = "auto";
  if (s.directions.empty()) s.directions = Json{{"axis", axis}};
  if (s.ordering.empty()) s.ordering = Json{{"method", "axis"}, {"axis", axis}};
  s.fromBareMesh = false;
}

void makeBareMeshExplicit(Scene& s) {
  if (!s.fromBareMesh) return;
  coat::MeshLoadOptions o;
  o.repair = s.meshRepair;
  const coat::SkinMesh m = coat::loadSkinMesh(s.meshPath, o);
  glm::dvec3 lo(0), hi(0);
  if (!m.positions.empty()) lo = hi = m.positions[0];
  for (const auto& p : m.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  makeBareMeshExplicit(s, lo, hi);
}

namespace {
void collectKeyTimes(const Json& j, bool inKeys, std::vector<double>& out) {
  if (j.is_object()) {
    if (inKeys && j.contains("t") && j["t"].is_number()) out.push_back(j["t"].get<double>());
    for (auto it = j.begin(); it != j.end(); ++it) collectKeyTimes(*it, it.key() == "keys", out);
  } else if (j.is_array()) {
    for (const auto& e : j) collectKeyTimes(e, inKeys, out);
  }
}
void moultSpan(const Json& m, std::vector<double>& out) {
  if (!m.is_object() || m.value("enabled", true) == false) return;
  const double start = m.contains("start") && m["start"].is_number() ? m["start"].get<double>() : 0.0;
  const double duration = m.contains("duration") && m["duration"].is_number() ? m["duration"].get<double>() : 1.0;
  out.push_back(start);
  out.push_back(start + duration);
}
}  // namespace

std::optional<std::pair<double, double>> sceneTimeSpan(const Scene& s) {
  std::vector<double> t;
  collectKeyTimes(s.controls, false, t);
  collectKeyTimes(s.skeleton, false, t);
  if (!s.moult.empty()) moultSpan(s.moult, t);  // an empty scene-level object: no scene moult
  for (const auto& tr : s.tracts) {
    if (!tr.is_object() || !tr.contains("moult")) continue;
    const Json& m = tr["moult"];
    if (m.is_boolean() && m.get<bool>())
      moultSpan(s.moult.empty() ? Json::object() : s.moult, t);
    else
      moultSpan(m, t);
  }
  if (t.empty()) return std::nullopt;
  const auto [lo, hi] = std::minmax_element(t.begin(), t.end());
  return std::make_pair(*lo, *hi);
}

std::string tractName(const Scene& s, size_t i) {
  if (i < s.tracts.size() && s.tracts[i].is_object() && s.tracts[i].contains("name") && s.tracts[i]["name"].is_string())
    return s.tracts[i]["name"].get<std::string>();
  return "tract " + std::to_string(i);
}

std::vector<size_t> resolveTracts(const Scene& s, const std::string& ref, const std::string& where) {
  std::vector<size_t> out;
  if (ref == "*") {
    for (size_t i = 0; i < s.tracts.size(); ++i) out.push_back(i);
    if (out.empty()) throw Error("the scene has no tracts", s.file, where);
    return out;
  }
  if (!ref.empty() && std::all_of(ref.begin(), ref.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    const size_t i = std::stoul(ref);
    if (i >= s.tracts.size())
      throw Error("tract index " + ref + " out of range (" + std::to_string(s.tracts.size()) + " tracts)", s.file,
                  where);
    return {i};
  }
  for (size_t i = 0; i < s.tracts.size(); ++i)
    if (tractName(s, i) == ref) return {i};
  throw Error("no tract named '" + ref + "'", s.file, where);
}

}  // namespace pteryla::viewer
