// The host API's typed inputs (include/pteryla/pteryla.hpp) turned into the pipeline's: skin arrays into a
// checked SkinMesh, a CoatSetup into the scene sections the pipeline already parses, so a typed set-up and
// the equivalent scene file evaluate to the same coat, bit for bit.
#include "session_setup.hpp"

#include <glm/vec3.hpp>

#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "pteryla/core/json.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/moult/controls.hpp"
#include "pteryla/moult/schedule.hpp"

namespace pteryla::host {
namespace {

void requireFinite(double v, const std::string& element, const char* what) {
  if (!std::isfinite(v)) throw Error(std::string(what) + " must be a finite number", "", element);
}

Json point(const std::array<double, 3>& p) { return Json::array({p[0], p[1], p[2]}); }

}  // namespace

std::string at(const char* array, size_t i) { return std::string(array) + "[" + std::to_string(i) + "]"; }

coat::SkinMesh skinFromArrays(const SkinArrays& in) {
  if (in.positions.empty()) throw Error("the skin has no vertices", "", "positions");
  if (in.positions.size() % 3 != 0)
    throw Error("expected 3 values (x, y, z) per vertex, got " + std::to_string(in.positions.size()) + " values", "",
                "positions");
  if (in.triangles.empty()) throw Error("the skin has no triangles", "", "triangles");
  if (in.triangles.size() % 3 != 0)
    throw Error("expected 3 vertex indices per triangle, got " + std::to_string(in.triangles.size()) + " indices", "",
                "triangles");
  const size_t nv = in.positions.size() / 3, nf = in.triangles.size() / 3;
  if (!in.faceGroups.empty() && in.faceGroups.size() != nf)
    throw Error("expected one group per face (" + std::to_string(nf) + "), got " + std::to_string(in.faceGroups.size()),
                "", "faceGroups");
  for (size_t f = 0; f < in.faceGroups.size(); ++f)
    if (in.faceGroups[f] < -1 || (in.faceGroups[f] >= 0 && size_t(in.faceGroups[f]) >= in.groupNames.size()))
      throw Error("group " + std::to_string(in.faceGroups[f]) + " is not -1 or an index into groupNames (" +
                      std::to_string(in.groupNames.size()) + " names)",
                  "", at("faceGroups", f));
  std::vector<glm::dvec3> positions(nv);
  for (size_t v = 0; v < nv; ++v)
    positions[v] = {in.positions[3 * v], in.positions[3 * v + 1], in.positions[3 * v + 2]};
  std::vector<std::array<uint32_t, 3>> faces(nf);
  for (size_t f = 0; f < nf; ++f) faces[f] = {in.triangles[3 * f], in.triangles[3 * f + 1], in.triangles[3 * f + 2]};
  coat::MeshLoadOptions o;
  o.repair = in.repair;
  // makeSkinMesh checks indices, finiteness, coordinate range, degeneracy, manifoldness and orientation,
  // naming "vertex v" and "face f" (triangle indices of this array).
  return coat::makeSkinMesh(std::move(positions), std::move(faces), in.groupNames, in.faceGroups, o);
}

pipeline::Scene sceneFromSetup(const CoatSetup& setup) {
  Json j = Json::object();
  j["pteryla"] = 1;
  j["name"] = "session";
  j["seed"] = setup.seed;
  j["mesh"] = "";  // the skin is in memory (Pipeline(Scene, SkinMesh))

  // Feathers: one entry per distinct file, named by its stem (the bundled contour feather is "contour",
  // as for a bare mesh).
  std::map<std::string, std::string> nameOfFile;
  std::set<std::string> names;
  Json feathers = Json::object();
  auto featherName = [&](const std::string& file, const std::string& element) {
    const std::string path = file.empty()
                                 ? (std::filesystem::path(dataDirectory()) / "feathers" / "contour.json").string()
                                 : std::filesystem::absolute(file).lexically_normal().string();
    if (!fileExists(path)) throw Error("feather file not found: " + path, "", element);
    if (auto it = nameOfFile.find(path); it != nameOfFile.end()) return it->second;
    const std::string stem = std::filesystem::path(path).stem().string();
    std::string name = stem;
    for (int k = 2; names.count(name); ++k) name = stem + "-" + std::to_string(k);
    names.insert(name);
    nameOfFile[path] = name;
    feathers[name] = path;
    return name;
  };

  Json tracts = Json::array();
  std::vector<TractSetup> list = setup.tracts;
  if (list.empty()) {
    list.emplace_back();
    list.back().name = "all";
  }
  for (size_t i = 0; i < list.size(); ++i) {
    const TractSetup& t = list[i];
    const std::string where = at("tracts", i);
    Json o = Json::object();
    o["name"] = t.name;
    if (!t.groups.empty()) o["groups"] = t.groups;
    if (!t.faces.empty()) o["faces"] = t.faces;
    requireFinite(t.density, where + ".density", "density");
    if (t.density < 0) throw Error("density must not be negative", "", where + ".density");
    if (t.count > uint64_t(std::numeric_limits<int64_t>::max()))
      throw Error("count is out of range", "", where + ".count");
    if (t.count > 0)
      o["count"] = uint64_t(t.count);
    else if (t.density > 0)
      o["density"] = t.density;
    o["feather"] = featherName(t.featherFile, where + ".featherFile");
    requireFinite(t.featherScale, where + ".feather_scale", "feather_scale");
    if (t.featherScale < 0)
      throw Error("feather_scale must be positive, or 0 for automatic", "", where + ".feather_scale");
    if (t.featherScale > 0)
      o["feather_scale"] = t.featherScale;
    else
      o["feather_scale"] = "auto";
    requireFinite(t.featherSpacings, where + ".feather_spacings", "feather_spacings");
    o["feather_spacings"] = t.featherSpacings;
    o["relax"] = {{"iterations", t.relaxIterations}};
    if (t.seed) o["seed"] = *t.seed;
    if (!t.moult) o["moult"] = false;
    // One feather per tract: nothing is interpolated, so the cheapest parameterization serves.
    o["parameterization"] = {{"method", "projection"}};
    tracts.push_back(std::move(o));
  }
  j["feathers"] = feathers;
  j["tracts"] = tracts;

  // The axis is checked here (the pipeline parses directions only when it evaluates them).
  Json axis = Json::array();
  for (size_t k = 0; k < setup.axis.size(); ++k) {
    for (int c = 0; c < 3; ++c) requireFinite(setup.axis[k][c], at("axis", k), "axis points");
    if (k > 0 && setup.axis[k] == setup.axis[k - 1])
      throw Error("coincides with the point before it", "", at("axis", k));
    axis.push_back(point(setup.axis[k]));
  }
  if (setup.axis.size() == 1) throw Error("a body axis needs at least two points (head to tail)", "", "axis");
  if (!axis.empty()) j["directions"] = {{"axis", axis}};
  switch (setup.ordering) {
    case CoatSetup::Ordering::Axis:
      if (!axis.empty()) j["ordering"] = {{"method", "axis"}, {"axis", axis}};
      break;  // no axis: the bounding-box axis, as for a bare mesh (Scene::fromBareMesh below)
    case CoatSetup::Ordering::Tracts:
      // Checked here: the pipeline resolves the names only when it orders the layers (evaluate).
      for (size_t k = 0; k < setup.tractOrder.size(); ++k) {
        bool known = false;
        for (const TractSetup& t : list) known = known || t.name == setup.tractOrder[k];
        if (!known) throw Error("unknown tract '" + setup.tractOrder[k] + "'", "", at("tractOrder", k));
      }
      j["ordering"] = {{"method", "tracts"}};
      if (!setup.tractOrder.empty()) j["ordering"]["tracts"] = setup.tractOrder;
      break;
    case CoatSetup::Ordering::Flow:
      j["ordering"] = {{"method", "flow"}};
      break;
  }
  j["packing"] = {{"method", setup.packing == CoatSetup::Packing::Drape ? "drape" : "height_field"}};
  if (setup.moult.enabled) {
    const MoultSetup& m = setup.moult;
    for (const auto& [v, key] : {std::pair{m.start, "start"},
                                 {m.duration, "duration"},
                                 {m.window, "window"},
                                 {m.gap, "gap"},
                                 {m.random, "random"}})
      requireFinite(v, std::string("moult.") + key, key);
    Json mj = {{"start", m.start}, {"duration", m.duration}, {"window", m.window}, {"sequence", m.sequence},
               {"gap", m.gap},     {"random", m.random},     {"seed", m.seed}};
    // Checked now, with the scene format's ranges and names (the time stages read it at evaluate()).
    JsonReader r(mj, "", "moult");
    moult::readMoultOptions(r);
    j["moult"] = std::move(mj);
  }
  if (!setup.controls.empty()) {
    Json controls = Json::array();
    for (size_t c = 0; c < setup.controls.size(); ++c) {
      const ControlSetup& in = setup.controls[c];
      const std::string where = at("controls", c);
      for (int k = 0; k < 3; ++k) requireFinite(in.at[k], where + ".at", "at");
      for (const auto& [v, key] : {std::pair{in.radius, "radius"},
                                   {in.falloff, "falloff"},
                                   {in.twistAngleDeg, "twist_angle"},
                                   {in.maxLiftDeg, "max_lift"}})
        requireFinite(v, where + "." + key, key);
      Json o = {{"name", in.name},
                {"at", point(in.at)},
                {"radius", in.radius},
                {"falloff", in.falloff},
                {"interpolation", in.interpolation},
                {"seed", in.seed},
                {"twist_angle", in.twistAngleDeg},
                {"max_lift", in.maxLiftDeg}};
      if (!in.tracts.empty()) o["tracts"] = in.tracts;
      if (in.keys.empty()) throw Error("a control needs at least one key", "", where + ".keys");
      Json keys = Json::array();
      for (size_t k = 0; k < in.keys.size(); ++k) {
        const ControlKey& key = in.keys[k];
        const std::string kw = where + ".keys[" + std::to_string(k) + "]";
        requireFinite(key.t, kw + ".t", "t");
        Json kj = {{"t", key.t}};
        for (const auto& [v, name] : {std::pair{key.lift, "lift"},
                                      {key.aim, "aim"},
                                      {key.direction, "direction"},
                                      {key.random, "random"},
                                      {key.dynamic, "dynamic"}})
          if (v) {
            requireFinite(*v, kw + "." + name, name);
            kj[name] = *v;
          }
        if (key.offset) {
          for (int i = 0; i < 3; ++i) requireFinite((*key.offset)[i], kw + ".offset", "offset");
          kj["offset"] = point(*key.offset);
        }
        keys.push_back(std::move(kj));
      }
      o["keys"] = std::move(keys);
      controls.push_back(std::move(o));
    }
    // Checked now, with the scene format's ranges and names (the controls stage reads them at evaluate()).
    moult::readControls(controls, "", "controls");
    for (size_t c = 0; c < setup.controls.size(); ++c)
      for (size_t k = 0; k < setup.controls[c].tracts.size(); ++k) {
        bool known = false;
        for (const TractSetup& t : list) known = known || t.name == setup.controls[c].tracts[k];
        if (!known)
          throw Error("unknown tract '" + setup.controls[c].tracts[k] + "'", "",
                      at("controls", c) + ".tracts[" + std::to_string(k) + "]");
      }
    j["controls"] = std::move(controls);
  }
  pipeline::Scene s = pipeline::sceneFromJson(j, "");
  // Without an axis, directions and axis ordering follow the skin's longest bounding-box axis.
  s.fromBareMesh = setup.axis.empty();
  return s;
}

}  // namespace pteryla::host
