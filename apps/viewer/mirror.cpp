#include "mirror.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "actions.hpp"
#include "pteryla/core/error.hpp"
#include "scene_edit.hpp"

namespace pteryla::viewer {

using pipeline::Scene;

namespace {

glm::dvec3 centroid(const coat::SkinMesh& m, size_t t) {
  const auto& f = m.faces[t];
  return (m.positions[f[0]] + m.positions[f[1]] + m.positions[f[2]]) / 3.0;
}

void reflectPoint(Json& j, const char* key, const MirrorPlane& p) {
  if (j.is_object() && j.contains(key) && j[key].is_array() && j[key].size() == 3)
    j[key] = actions::vec3Json(p.reflect(actions::jsonVec3(j[key])));
}
void reflectVector(Json& j, const char* key, const MirrorPlane& p) {
  if (j.is_object() && j.contains(key) && j[key].is_array() && j[key].size() == 3)
    j[key] = actions::vec3Json(p.reflectVector(actions::jsonVec3(j[key])));
}

// Points and directions of a brush, control or styling vector (and of a control's keys) reflected.
Json reflectElement(Json j, const MirrorPlane& p) {
  for (const char* k : {"at", "center", "from", "to"}) reflectPoint(j, k, p);
  for (const char* k : {"direction", "offset"}) reflectVector(j, k, p);
  if (j.is_object() && j.contains("keys") && j["keys"].is_array())
    for (Json& k : j["keys"]) reflectVector(k, "offset", p);
  return j;
}

// Equal up to `tol` in every number (names aside).
bool near(const Json& a, const Json& b, double tol) {
  if (a.is_number() && b.is_number()) return std::abs(a.get<double>() - b.get<double>()) <= tol;
  if (a.is_array() && b.is_array()) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
      if (!near(a[i], b[i], tol)) return false;
    return true;
  }
  if (a.is_object() && b.is_object()) {
    for (auto it = a.begin(); it != a.end(); ++it)
      if (it.key() != "name" && (!b.contains(it.key()) || !near(*it, b[it.key()], tol))) return false;
    for (auto it = b.begin(); it != b.end(); ++it)
      if (it.key() != "name" && !a.contains(it.key())) return false;
    return true;
  }
  return a == b;
}

// Appends reflected copies of `list`'s elements (those `take` accepts) that are neither on the plane nor
// already in the list; returns how many.
size_t mirrorList(Json& list, const MirrorPlane& p, double tol, const std::function<bool(const Json&)>& take,
                  const std::function<void(Json&)>& rename) {
  if (!list.is_array()) return 0;
  const size_t n = list.size();
  size_t added = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!take(list[i])) continue;
    // On the plane (its points are): its mirror image would sit on it, or point against it.
    bool onPlane = false;
    for (const char* k : {"at", "center", "from", "to"})
      if (list[i].contains(k)) {
        const glm::dvec3 at = actions::jsonVec3(list[i][k]);
        onPlane = std::abs(at[p.axis] - p.offset) <= tol;
        if (!onPlane) break;
      }
    if (onPlane) continue;
    Json m = reflectElement(list[i], p);
    rename(m);
    bool present = false;
    for (const Json& e : list) present = present || near(e, m, tol);
    if (present) continue;
    list.push_back(m);
    ++added;
  }
  return added;
}

}  // namespace

MirrorPlane symmetryPlane(const coat::SkinMesh& rest) {
  MirrorPlane best;
  if (rest.positions.empty()) return best;
  glm::dvec3 lo = rest.positions[0], hi = lo;
  for (const auto& p : rest.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const size_t n = rest.positions.size(), step = std::max<size_t>(1, n / 400);
  double bestError = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    MirrorPlane p{axis, 0.5 * (lo[axis] + hi[axis])};
    double error = 0;
    size_t samples = 0;
    for (size_t i = 0; i < n; i += step, ++samples) {
      const glm::dvec3 r = p.reflect(rest.positions[i]);
      double d2 = std::numeric_limits<double>::infinity();
      for (const auto& q : rest.positions) d2 = std::min(d2, glm::dot(q - r, q - r));
      error += std::sqrt(d2);
    }
    error /= double(std::max<size_t>(samples, 1));
    if (error < bestError - 1e-12) {
      bestError = error;
      best = p;
    }
  }
  return best;
}

std::string mirroredName(const std::string& name) {
  static const std::pair<const char*, const char*> words[] = {{"left", "right"}, {"Left", "Right"}, {"LEFT", "RIGHT"}};
  for (const auto& [a, b] : words) {
    for (const auto& [from, to] : {std::pair{a, b}, std::pair{b, a}}) {
      const size_t at = name.find(from);
      if (at != std::string::npos) return name.substr(0, at) + to + name.substr(at + std::string(from).size());
    }
  }
  auto ends = [&](const std::string& s) {
    return name.size() > s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0;
  };
  auto starts = [&](const std::string& s) { return name.size() > s.size() && name.compare(0, s.size(), s) == 0; };
  for (const auto& [a, b] : {std::pair<std::string, std::string>{"_l", "_r"}, {"_r", "_l"}, {"_L", "_R"}, {"_R", "_L"}})
    if (ends(a)) return name.substr(0, name.size() - a.size()) + b;
  for (const auto& [a, b] : {std::pair<std::string, std::string>{"l_", "r_"}, {"r_", "l_"}, {"L_", "R_"}, {"R_", "L_"}})
    if (starts(a)) return b + name.substr(a.size());
  return name + "_mirror";
}

MirrorResult mirrorScene(Document& d, const coat::SkinMesh& rest, const MirrorRequest& q) {
  MirrorResult res;
  const MirrorPlane& p = q.plane;
  if (p.axis < 0 || p.axis > 2 || !std::isfinite(p.offset)) throw Error("bad mirror plane", "", "mirror");
  Scene next = d.scene();
  glm::dvec3 lo(0), hi(0);
  if (!rest.positions.empty()) {
    lo = hi = rest.positions[0];
    for (const auto& v : rest.positions) {
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
  }
  const double tol = 1e-6 * std::max(glm::length(hi - lo), 1e-9);
  if (!q.tracts.empty() && next.tracts.empty()) next.tracts = Json::array({Json{{"name", "all"}}});

  // Tracts: the faces nearest the reflections of the tract's triangles.
  if (!q.tracts.empty()) {
    std::vector<glm::dvec3> centre(rest.faces.size());
    for (size_t t = 0; t < rest.faces.size(); ++t) centre[t] = centroid(rest, t);
    const Scene original = next;
    for (size_t t : q.tracts) {
      if (t >= original.tracts.size())
        throw Error("tract index " + std::to_string(t) + " out of range", original.file, "tracts");
      const std::vector<uint32_t> faces = actions::tractSourceFaces(original, rest, t);
      std::vector<uint32_t> mirrored;
      for (size_t tri = 0; tri < rest.faces.size(); ++tri) {
        if (!std::binary_search(faces.begin(), faces.end(), rest.sourceFace[tri])) continue;
        const glm::dvec3 r = p.reflect(centre[tri]);
        size_t bestTri = 0;
        double bestD = std::numeric_limits<double>::infinity();
        for (size_t u = 0; u < centre.size(); ++u) {
          const double dd = glm::dot(centre[u] - r, centre[u] - r);
          if (dd < bestD) {
            bestD = dd;
            bestTri = u;
          }
        }
        mirrored.push_back(rest.sourceFace[bestTri]);
      }
      std::sort(mirrored.begin(), mirrored.end());
      mirrored.erase(std::unique(mirrored.begin(), mirrored.end()), mirrored.end());
      const std::string name = tractName(original, t), to = mirroredName(name);
      for (size_t i = 0; i < next.tracts.size(); ++i)
        if (tractName(next, i) == to)
          throw Error("a tract named '" + to + "' exists already (rename it to mirror '" + name + "' again)",
                      original.file, "tracts");
      Json copy = original.tracts[t];
      for (const char* k : {"all", "groups", "faces", "labels_file", "label", "union", "intersect", "subtract"})
        copy.erase(k);
      copy["name"] = to;
      copy["faces"] = mirrored;
      if (copy.contains("pinned") && copy["pinned"].is_array())
        for (Json& pin : copy["pinned"]) reflectPoint(pin, "at", p);
      if (copy.contains("key_feathers") && copy["key_feathers"].is_array()) {
        Json keys = Json::array();
        for (Json k : copy["key_feathers"])
          if (k.contains("at")) {  // a follicle id has no mirror image
            reflectPoint(k, "at", p);
            keys.push_back(k);
          }
        if (keys.empty())
          copy.erase("key_feathers");
        else
          copy["key_feathers"] = keys;
      }
      if (copy.contains("relax") && copy["relax"].contains("bias") && copy["relax"]["bias"].is_array())
        for (Json& b : copy["relax"]["bias"]) {
          reflectPoint(b, "at", p);
          reflectVector(b, "direction", p);
        }
      if (copy.contains("parameterization"))
        for (const char* k : {"view_direction", "up"}) reflectVector(copy["parameterization"], k, p);
      copy.erase("seed");  // its own scatter (a tract's seed is per tract)
      next.tracts.push_back(copy);
      ++res.tracts;
    }
  }
  auto none = [](Json&) {};
  if (q.brushes && next.packing.contains("styling")) {
    res.brushes = mirrorList(
        next.packing["styling"], p, tol,
        [](const Json& j) { return j.value("select", "") == "sphere" || j.value("select", "") == "comb"; }, none);
  }
  if (q.controls) {
    res.controls = mirrorList(
        next.controls, p, tol, [](const Json& j) { return j.is_object(); },
        [&](Json& c) {
          if (c.contains("name") && c["name"].is_string()) c["name"] = mirroredName(c["name"].get<std::string>());
          // A tract it names becomes its mirrored tract when the scene has one.
          if (c.contains("tracts") && c["tracts"].is_array())
            for (Json& t : c["tracts"])
              if (t.is_string()) {
                const std::string to = mirroredName(t.get<std::string>());
                for (size_t i = 0; i < next.tracts.size(); ++i)
                  if (tractName(next, i) == to) t = to;
              }
        });
  }
  if (q.vectors && next.directions.contains("vectors")) {
    res.vectors = mirrorList(
        next.directions["vectors"], p, tol, [](const Json& j) { return j.is_object(); }, none);
  }
  if (res.tracts + res.brushes + res.controls + res.vectors == 0) return res;
  d.edit("mirror", [&](Scene& s) { s = next; });
  return res;
}

}  // namespace pteryla::viewer
