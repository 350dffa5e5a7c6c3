#include "actions.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/feather/io.hpp"
#include "paint.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/moult/controls.hpp"
#include "scene_edit.hpp"

namespace pteryla::viewer::actions {

using pipeline::Scene;

Json vec3Json(const glm::dvec3& v) { return Json::array({v.x, v.y, v.z}); }

glm::dvec3 jsonVec3(const Json& j, const glm::dvec3& def) {
  if (!j.is_array() || j.size() != 3) return def;
  for (const auto& x : j)
    if (!x.is_number()) return def;
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

namespace {

void needTract(const Scene& s, size_t t) {
  if (t >= s.tracts.size())
    throw Error("tract index " + std::to_string(t) + " out of range (" + std::to_string(s.tracts.size()) + " tracts)",
                s.file, "tracts");
}
void needControl(const Scene& s, size_t c) {
  if (c >= s.controls.size())
    throw Error(
        "control index " + std::to_string(c) + " out of range (" + std::to_string(s.controls.size()) + " controls)",
        s.file, "controls");
}
void fixTracts(Scene& s) {
  if (s.tracts.empty()) s.tracts = Json::array({Json{{"name", "all"}}});
}
Json& tractOf(Scene& s, size_t t) {
  fixTracts(s);
  needTract(s, t);
  return s.tracts[t];
}
std::string ti(size_t t) { return std::to_string(t); }

}  // namespace

void ensureTracts(Document& d) {
  if (d.scene().tracts.empty()) d.edit("tracts", fixTracts);
}

void setTractCount(Document& d, size_t t, size_t count) {
  d.edit("count " + ti(t), [&](Scene& s) {
    Json& j = tractOf(s, t);
    j.erase("density");
    j["count"] = count;
  });
}

void setTractDensity(Document& d, size_t t, double density) {
  if (!(density > 0) || !std::isfinite(density)) throw Error("density must be a positive number", "", "density");
  d.edit("density " + ti(t), [&](Scene& s) {
    Json& j = tractOf(s, t);
    j.erase("count");
    j["density"] = density;
  });
}

void setRelaxIterations(Document& d, size_t t, int iterations) {
  if (iterations < 0) throw Error("iterations must be >= 0", "", "relax");
  d.edit("relax " + ti(t), [&](Scene& s) { tractOf(s, t)["relax"]["iterations"] = iterations; });
}

void setRelaxNumber(Document& d, size_t t, const std::string& key, const Json& value) {
  d.edit("relax." + key + " " + ti(t), [&](Scene& s) { tractOf(s, t)["relax"][key] = value; });
}

void addBias(Document& d, size_t t, const glm::dvec3& at, const glm::dvec3& dir, double sigma, double stretch,
             double gain) {
  d.edit("add bias", [&](Scene& s) {
    Json b = {{"at", vec3Json(at)}, {"direction", vec3Json(dir)}, {"sigma", sigma}, {"stretch", stretch}};
    if (gain > 0) b["density_gain"] = gain;
    tractOf(s, t)["relax"]["bias"].push_back(b);
  });
}

void addPinned(Document& d, size_t t, const glm::dvec3& at) {
  d.edit("pin follicle", [&](Scene& s) { tractOf(s, t)["pinned"].push_back({{"at", vec3Json(at)}}); });
}

void addTract(Document& d, const std::string& name, const std::vector<std::string>& groups) {
  if (name.empty()) throw Error("a tract needs a name", "", "name");
  d.edit("add tract", [&](Scene& s) {
    fixTracts(s);
    for (size_t i = 0; i < s.tracts.size(); ++i)
      if (tractName(s, i) == name) throw Error("a tract named '" + name + "' exists already", s.file, "tracts");
    Json t = {{"name", name}};
    if (groups.empty())
      t["all"] = true;
    else
      t["groups"] = groups;
    s.tracts.push_back(t);
  });
}

void removeTract(Document& d, size_t t) {
  d.edit("remove tract", [&](Scene& s) {
    needTract(s, t);
    s.tracts.erase(s.tracts.begin() + static_cast<long>(t));
  });
}

std::vector<uint32_t> tractSourceFaces(const Scene& s, const coat::SkinMesh& rest, size_t t) {
  needTract(s, t);
  std::vector<coat::Tract> earlier;
  for (size_t i = 0; i <= t; ++i) {
    JsonReader r(s.tracts[i], s.file, "tracts[" + std::to_string(i) + "]");
    earlier.push_back(coat::readTract(r, rest, earlier));
  }
  std::vector<uint32_t> out;
  for (uint32_t tri : earlier.back().faces) out.push_back(tri < rest.sourceFace.size() ? rest.sourceFace[tri] : tri);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

bool paintTractFaces(Document& d, const coat::SkinMesh& rest, size_t t, const std::vector<uint32_t>& faces, bool add) {
  std::vector<uint32_t> painted = faces;
  std::sort(painted.begin(), painted.end());
  painted.erase(std::unique(painted.begin(), painted.end()), painted.end());
  {
    Scene probe = d.scene();
    fixTracts(probe);
    const std::vector<uint32_t> current = tractSourceFaces(probe, rest, t);
    const std::vector<uint32_t> next = add ? faceUnion(current, painted) : faceDifference(current, painted);
    if (next == current) return false;
  }
  d.edit(add ? "paint tract faces" : "erase tract faces", [&](Scene& s) {
    fixTracts(s);
    const std::vector<uint32_t> current = tractSourceFaces(s, rest, t);
    const std::vector<uint32_t> next = add ? faceUnion(current, painted) : faceDifference(current, painted);
    Json& j = tractOf(s, t);
    if (next.empty())
      throw Error("the brush would leave tract '" + tractName(s, t) + "' without faces", s.file,
                  "tracts[" + std::to_string(t) + "]");
    const bool additiveOnly =
        !j.contains("intersect") && !j.contains("subtract") && !j.contains("all") &&
        (j.contains("groups") || j.contains("faces") || j.contains("labels_file") || j.contains("union"));
    if (add && additiveOnly) {
      // Keep the groups (or labels) and list the painted faces they do not select.
      Json list =
          j.contains("faces") ? (j["faces"].is_array() ? j["faces"] : Json::array({j["faces"]})) : Json::array();
      for (uint32_t f : faceDifference(painted, current)) list.push_back(f);
      j["faces"] = list;
      return;
    }
    for (const char* k : {"all", "groups", "faces", "labels_file", "label", "union", "intersect", "subtract"})
      j.erase(k);
    j["faces"] = next;
  });
  return true;
}

void addTractFromFaces(Document& d, const std::string& name, const std::vector<uint32_t>& faces) {
  if (name.empty()) throw Error("a tract needs a name", "", "name");
  if (faces.empty()) throw Error("no faces are selected (paint a face selection first)", "", "faces");
  std::vector<uint32_t> sorted = faces;
  std::sort(sorted.begin(), sorted.end());
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  d.edit("tract from faces", [&](Scene& s) {
    fixTracts(s);
    for (size_t i = 0; i < s.tracts.size(); ++i)
      if (tractName(s, i) == name) throw Error("a tract named '" + name + "' exists already", s.file, "tracts");
    Json t = {{"name", name}, {"faces", sorted}};
    // With several feathers a tract must say which it carries: the first of the library (the Key
    // feathers panel changes it).
    if (s.feathers.size() > 1) t["feather"] = s.feathers.begin().key();
    s.tracts.push_back(t);
  });
}

void setDensityFactors(Document& d, std::vector<float> factors) {
  if (factors.empty()) throw Error("a density map needs one factor per mesh vertex", "", "density_map");
  quantizeDensity(factors);
  if (d.scene().densityFactor && *d.scene().densityFactor == factors) return;
  auto shared = std::make_shared<const std::vector<float>>(std::move(factors));
  d.edit("paint density", [&](Scene& s) { s.densityFactor = shared; });
}

void clearDensityMap(Document& d) {
  if (!d.scene().densityFactor) throw Error("the scene has no density map", d.scene().file, "density_map");
  d.edit("clear density map", [&](Scene& s) {
    s.densityFactor.reset();
    s.densityMap.clear();
  });
}

void setFeatherFile(Document& d, const std::string& name, const std::string& path) {
  if (name.empty()) throw Error("a feather needs a name", "", "feathers");
  const std::string abs = std::filesystem::absolute(path).lexically_normal().string();
  if (!fileExists(abs)) throw Error("feather file not found", path);
  feather::loadFeather(abs);  // reject bad files now, with their own error
  d.edit("feather " + name, [&](Scene& s) { s.feathers[name] = abs; });
}

void setFeatherInline(Document& d, const std::string& name, const feather::FeatherParams& p) {
  if (name.empty()) throw Error("a feather needs a name", "", "feathers");
  feather::validateFeather(p);
  d.edit("design " + name, [&](Scene& s) { s.feathers[name] = feather::featherToJson(p, false); });
}

void setTractFeather(Document& d, size_t t, const std::string& f) {
  d.edit("tract feather " + ti(t), [&](Scene& s) {
    if (!s.feathers.contains(f)) throw Error("no feather named '" + f + "'", s.file, "feathers");
    tractOf(s, t)["feather"] = f;
  });
}

void addKeyFeather(Document& d, size_t t, const std::string& f, uint64_t follicleId) {
  d.edit("key feather", [&](Scene& s) {
    if (!s.feathers.contains(f)) throw Error("no feather named '" + f + "'", s.file, "feathers");
    Json& keys = tractOf(s, t)["key_feathers"];
    if (keys.is_array())
      keys.erase(std::remove_if(keys.begin(), keys.end(),
                                [&](const Json& k) {
                                  return k.contains("follicle") && k["follicle"].is_number() &&
                                         k["follicle"].get<uint64_t>() == follicleId;
                                }),
                 keys.end());
    keys.push_back({{"feather", f}, {"follicle", follicleId}});
  });
}

void addKeyFeatherAt(Document& d, size_t t, const std::string& f, const glm::dvec3& at) {
  d.edit("key feather", [&](Scene& s) {
    if (!s.feathers.contains(f)) throw Error("no feather named '" + f + "'", s.file, "feathers");
    tractOf(s, t)["key_feathers"].push_back({{"feather", f}, {"at", vec3Json(at)}});
  });
}

void removeKeyFeather(Document& d, size_t t, size_t k) {
  d.edit("remove key feather", [&](Scene& s) {
    Json& keys = tractOf(s, t)["key_feathers"];
    if (!keys.is_array() || k >= keys.size())
      throw Error("no key feather " + std::to_string(k), s.file, "key_feathers");
    keys.erase(keys.begin() + static_cast<long>(k));
    if (keys.empty()) tractOf(s, t).erase("key_feathers");
  });
}

void setRenderLod(Document& d, double f) {
  if (!(f > 0 && f <= 1)) throw Error("render level of detail must be in (0, 1]", "", "render.lod");
  d.edit("render LOD", [&](Scene& s) { s.render.lod = f; });
}

void setInstanceTolerance(Document& d, double f) {
  if (!(f >= 0 && f <= 0.1)) throw Error("instance tolerance must be in [0, 0.1]", "", "render.instance_tolerance");
  d.edit("instancing", [&](Scene& s) { s.render.instanceTolerance = f; });
}

double combRadius(const Scene& s) {
  if (!s.directions.is_object() || !s.directions.contains("axis") || !s.directions["axis"].is_array()) return 0;
  const Json& a = s.directions["axis"];
  double length = 0;
  for (size_t i = 1; i < a.size(); ++i) length += glm::length(jsonVec3(a[i]) - jsonVec3(a[i - 1]));
  return 0.1 * length;
}

void addStylingVector(Document& d, const glm::dvec3& at, const glm::dvec3& dir, double radius) {
  if (!(glm::dvec3(dir) != glm::dvec3(0))) throw Error("a styling vector needs a non-zero direction", "", "direction");
  if (!(radius >= 0) || !std::isfinite(radius))
    throw Error("a styling vector's radius must be a finite number >= 0", "", "radius");
  d.edit("add styling vector", [&](Scene& s) {
    Json v = {{"at", vec3Json(at)}, {"direction", vec3Json(dir)}};
    if (s.directions.contains("axis")) {
      // Over the axis: a comb stroke with its own reach, unless the field's falloff gives one.
      const double falloff = s.directions.value("falloff", 0.0);
      const double r = radius > 0 ? radius : falloff > 0 ? 0.0 : combRadius(s);
      if (r > 0) v["radius"] = r;
    }
    s.directions["vectors"].push_back(v);
  });
}

void setStylingVector(Document& d, size_t k, const glm::dvec3& at, const glm::dvec3& dir) {
  d.edit("styling vector " + std::to_string(k), [&](Scene& s) {
    Json& v = s.directions["vectors"];
    if (!v.is_array() || k >= v.size())
      throw Error("no styling vector " + std::to_string(k), s.file, "directions.vectors");
    v[k]["at"] = vec3Json(at);
    v[k]["direction"] = vec3Json(dir);
  });
}

void removeStylingVector(Document& d, size_t k) {
  d.edit("remove styling vector", [&](Scene& s) {
    Json& v = s.directions["vectors"];
    if (!v.is_array() || k >= v.size())
      throw Error("no styling vector " + std::to_string(k), s.file, "directions.vectors");
    v.erase(v.begin() + static_cast<long>(k));
    if (v.empty()) s.directions.erase("vectors");
  });
}

void setBodyAxis(Document& d, const std::vector<glm::dvec3>& pts) {
  if (pts.size() < 2) throw Error("a body axis needs at least two points", "", "directions.axis");
  d.edit("body axis", [&](Scene& s) {
    // Comb strokes (vectors over the old axis) stay on the new one; a vectors-only field is replaced.
    if (!s.directions.contains("axis")) s.directions.erase("vectors");
    Json a = Json::array();
    for (const auto& p : pts) a.push_back(vec3Json(p));
    s.directions["axis"] = a;
  });
}

void addBrush(Document& d, const glm::dvec3& c, double radius, double elevationDeg, bool lift) {
  if (!(radius > 0)) throw Error("a brush needs a positive radius", "", "radius");
  if (!std::isfinite(elevationDeg)) throw Error("a brush needs a finite elevation", "", "elevation_deg");
  d.edit(lift ? "lift brush" : "brush", [&](Scene& s) {
    s.packing["styling"].push_back({{"select", "sphere"},
                                    {"center", vec3Json(c)},
                                    {"radius", radius},
                                    {lift ? "min_elevation_deg" : "elevation_deg", elevationDeg}});
  });
}

void removeBrush(Document& d, size_t k) {
  d.edit("remove brush", [&](Scene& s) {
    Json& v = s.packing["styling"];
    if (!v.is_array() || k >= v.size())
      throw Error("no styling selection " + std::to_string(k), s.file, "packing.styling");
    v.erase(v.begin() + static_cast<long>(k));
    if (v.empty()) s.packing.erase("styling");
  });
}

void setPackingValue(Document& d, const std::string& key, const Json& value) {
  d.edit("packing." + key, [&](Scene& s) {
    if (value.is_null())
      s.packing.erase(key);
    else
      s.packing[key] = value;
  });
}

size_t addControl(Document& d, const glm::dvec3& at, double radius) {
  if (!(radius > 0)) throw Error("a control needs a positive radius", "", "radius");
  size_t index = 0;
  d.edit("add control", [&](Scene& s) {
    index = s.controls.size();
    s.controls.push_back({{"name", "control" + std::to_string(index)}, {"at", vec3Json(at)}, {"radius", radius}});
  });
  return index;
}

namespace {
int behaviourIndex(const std::string& b) {
  for (int i = 0; i < 5; ++i)
    if (b == kControlBehaviours[i]) return i;
  return -1;
}
}  // namespace

bool controlKeyedIn(const Json& ctl, const std::string& attribute) {
  if (!ctl.contains("keys") || !ctl["keys"].is_array()) return false;
  for (const auto& k : ctl["keys"])
    if (k.is_object() && k.contains(attribute)) return true;
  return false;
}

Json& controlKeyAt(Json& ctl, double time) {
  Json& keys = ctl["keys"];
  if (!keys.is_array()) keys = Json::array();
  for (auto& k : keys)
    if (k.is_object() && k.contains("t") && k["t"].is_number() && k["t"].get<double>() == time) return k;
  keys.push_back({{"t", time}});
  std::stable_sort(keys.begin(), keys.end(),
                   [](const Json& x, const Json& y) { return x.value("t", 0.0) < y.value("t", 0.0); });
  for (auto& k : keys)
    if (k.value("t", 0.0) == time) return k;
  return keys.back();
}

ControlNow controlAt(const Scene& s, size_t c, double time) {
  ControlNow out;
  if (c >= s.controls.size() || !s.controls[c].is_object()) return out;
  const Json& ctl = s.controls[c];
  for (int i = 0; i < 5; ++i) out.keyed[i] = controlKeyedIn(ctl, kControlBehaviours[i]);
  try {
    JsonReader r(ctl, s.file, "controls[" + std::to_string(c) + "]");
    const moult::ControlValues v = moult::controlValuesAt(moult::readControl(r), time);
    const double vals[5] = {v.lift, v.aim, v.direction, v.random, v.dynamic};
    for (int i = 0; i < 5; ++i) out.value[i] = vals[i];
  } catch (const std::exception&) {
    for (int i = 0; i < 5; ++i)
      out.value[i] = ctl.contains(kControlBehaviours[i]) && ctl[kControlBehaviours[i]].is_number()
                         ? ctl[kControlBehaviours[i]].get<double>()
                         : 0.0;
  }
  return out;
}

void setControlValue(Document& d, size_t c, const std::string& behaviour, double value, double time) {
  if (behaviourIndex(behaviour) < 0)
    throw Error("unknown control behaviour '" + behaviour + "' (lift, aim, direction, random, dynamic)");
  if (!(value >= 0 && value <= 1)) throw Error("behaviour weights are in [0, 1]", "", behaviour);
  d.edit(behaviour + " " + std::to_string(c), [&](Scene& s) {
    needControl(s, c);
    Json& ctl = s.controls[c];
    if (controlKeyedIn(ctl, behaviour))
      controlKeyAt(ctl, time)[behaviour] = value;
    else
      ctl[behaviour] = value;
  });
}

void setControlPoint(Document& d, size_t c, const glm::dvec3& at, double radius) {
  d.edit("move control " + std::to_string(c), [&](Scene& s) {
    needControl(s, c);
    s.controls[c]["at"] = vec3Json(at);
    s.controls[c]["radius"] = radius;
  });
}

void addControlKeyframe(Document& d, size_t c, double time) {
  const ControlNow now = controlAt(d.scene(), c, time);
  d.edit("keyframe", [&](Scene& s) {
    needControl(s, c);
    Json& ctl = s.controls[c];
    Json& k = controlKeyAt(ctl, time);
    for (int i = 0; i < 5; ++i) {
      ctl.erase(kControlBehaviours[i]);  // a keyed behaviour has no constant
      k[kControlBehaviours[i]] = now.value[i];
    }
  });
}

void removeControlKeyframe(Document& d, size_t c, size_t key) {
  d.edit("remove keyframe", [&](Scene& s) {
    needControl(s, c);
    Json& keys = s.controls[c]["keys"];
    if (!keys.is_array() || key >= keys.size()) throw Error("no key " + std::to_string(key), s.file, "controls.keys");
    keys.erase(keys.begin() + static_cast<long>(key));
    if (keys.empty()) s.controls[c].erase("keys");
  });
}

void removeControl(Document& d, size_t c) {
  d.edit("remove control", [&](Scene& s) {
    needControl(s, c);
    s.controls.erase(s.controls.begin() + static_cast<long>(c));
  });
}

void setStyle(Document& d, const std::string& style) {
  if (style != "shaded" && style != "scratchboard") throw Error("style must be shaded or scratchboard", "", "style");
  d.edit("style", [&](Scene& s) { s.render.style = style; });
}

void setBrdf(Document& d, double dSpacing, double hFloor) {
  if (!(dSpacing >= 1e-3 && dSpacing <= 20)) throw Error("BRDF d must be in [0.001, 20]", "", "brdf.d");
  if (!(hFloor >= 0 && hFloor <= 0.999)) throw Error("BRDF h must be in [0, 0.999]", "", "brdf.h");
  d.edit("brdf", [&](Scene& s) {
    s.render.brdfD = dSpacing;
    s.render.brdfH = hFloor;
  });
}

}  // namespace pteryla::viewer::actions
