// Scene file reading and writing (docs/scene-format.md). The scene's own keys are checked here with the
// strict JsonReader so unknown keys and bad values fail at load with their key path; the module sections
// are checked for their types and their paths resolved (scene_sections.cpp), and read by their modules'
// parsers when the pipeline first needs them (scene_settings.cpp; tracts in the tracts stage).
#include "pteryla/pipeline/scene.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>

#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"
#include "scene_sections.hpp"

namespace pteryla::pipeline {
namespace {

bool isMeshPath(const std::string& p) {
  const std::string e = extensionOf(p);
  return e == ".obj" || e == ".ply" || e == ".off" || e == ".stl";
}

glm::dvec3 color(JsonReader& r, const std::string& key, const glm::dvec3& def) {
  const glm::dvec3 c = r.vec3(key, def);
  for (int i = 0; i < 3; ++i)
    if (c[i] < 0 || c[i] > 1) r.fail(key, "colour components must be in [0, 1]");
  return c;
}

CameraSpec readCamera(JsonReader r) {
  CameraSpec c;
  c.fovDeg = r.number("fov", c.fovDeg, 1.0, 170.0);
  c.up = r.vec3("up", c.up);
  c.viewDir = r.vec3("view_direction", c.viewDir);
  const bool hasEye = r.has("eye"), hasTarget = r.has("target");
  if (hasEye != hasTarget) r.fail(hasEye ? "target" : "eye", "eye and target must be given together");
  if (hasEye) {
    c.eye = r.vec3("eye");
    c.target = r.vec3("target");
    c.autoFrame = false;
    if (glm::dvec3 d = c.target - c.eye; d.x * d.x + d.y * d.y + d.z * d.z < 1e-18)
      r.fail("target", "must differ from eye");
  }
  c.autoFrame = r.boolean("auto_frame", c.autoFrame);
  r.finish();
  return c;
}

LightSpec readLight(JsonReader r) {
  LightSpec l;
  l.direction = r.vec3("direction", l.direction);
  l.color = color(r, "color", l.color);
  l.intensity = r.number("intensity", l.intensity, 0.0, 100.0);
  if (l.direction.x == 0 && l.direction.y == 0 && l.direction.z == 0) r.fail("direction", "must be non-zero");
  r.finish();
  return l;
}

RenderSpec readRender(JsonReader r) {
  RenderSpec s;
  if (r.has("size")) {
    const auto n = r.numbers("size");
    if (n.size() != 2 || n[0] < 16 || n[1] < 16 || n[0] > 16384 || n[1] > 16384 || n[0] != int(n[0]) ||
        n[1] != int(n[1]))
      r.fail("size", "expected [width, height] integers in [16, 16384]");
    s.width = int(n[0]);
    s.height = int(n[1]);
  } else {
    r.allow("size");
  }
  s.lod = r.number("lod", s.lod, 1e-3, 1.0);
  s.lodByScreenSize = r.boolean("lod_by_screen_size", s.lodByScreenSize);
  s.instanceTolerance = r.number("instance_tolerance", s.instanceTolerance, 0.0, 0.1);
  s.style = r.oneOf("style", s.style, {"shaded", "scratchboard"});
  s.background = color(r, "background", s.background);
  s.skinColor = color(r, "skin_color", s.skinColor);
  s.ambient = r.number("ambient", s.ambient, 0.0, 1.0);
  s.shadows = r.boolean("shadows", s.shadows);
  s.shadowStrength = r.number("shadow_strength", s.shadowStrength, 0.0, 1.0);
  const double msaa = r.number("msaa", s.msaa, 0.0, 8.0);
  if (msaa != 0 && msaa != 2 && msaa != 4 && msaa != 8) r.fail("msaa", "expected 0 (off), 2, 4 or 8 samples");
  s.msaa = int(msaa);
  s.exposure = r.number("exposure", s.exposure, -8.0, 8.0);
  s.tone = r.oneOf("tone", s.tone, {"linear", "filmic"});
  s.lightRig = r.oneOf("light_rig", s.lightRig, {"scene", "studio"});
  s.ground = r.boolean("ground", s.ground);
  s.groundColor = color(r, "ground_color", s.groundColor);
  if (r.has("brdf")) {
    JsonReader b = r.object("brdf");
    s.brdfD = b.number("d", s.brdfD, 1e-3, 20.0);
    s.brdfH = b.number("h", s.brdfH, 0.0, 0.999);
    b.finish();
  } else {
    r.allow("brdf");
  }
  r.finish();
  return s;
}

Json takeSection(JsonReader& r, const std::string& key, Json def) {
  if (!r.has(key)) {
    r.allow(key);
    return def;
  }
  return r.raw(key);
}

}  // namespace

Scene sceneFromJson(const Json& j, const std::string& file) {
  JsonReader r(j, file);
  Scene s;
  s.file = file;
  if (!r.has("pteryla")) r.fail("pteryla", "missing version field: a scene starts with \"pteryla\": 1");
  s.version = static_cast<int>(r.integer("pteryla", 1, 1));
  s.name = r.string("name", std::filesystem::path(file).stem().string());
  s.seed = r.seed("seed", s.seed);
  s.time = r.number("time", s.time, -1e9, 1e9);
  s.meshPath = resolveRelative(file, r.string("mesh"));
  s.meshRepair = r.boolean("mesh_repair", false);
  s.feathers = takeSection(r, "feathers", Json::object());
  s.tracts = takeSection(r, "tracts", Json::array());
  s.directions = takeSection(r, "directions", Json::object());
  s.moult = takeSection(r, "moult", Json::object());
  s.growth = takeSection(r, "growth", Json::object());
  s.skeleton = takeSection(r, "skeleton", Json::object());
  s.controls = takeSection(r, "controls", Json::array());
  s.packing = takeSection(r, "packing", Json::object());
  s.ordering = takeSection(r, "ordering", Json::object());
  if (r.has("camera"))
    s.camera = readCamera(r.object("camera"));
  else
    r.allow("camera");
  for (auto& l : r.objects("lights")) s.lights.push_back(readLight(l));
  if (r.has("render"))
    s.render = readRender(r.object("render"));
  else
    r.allow("render");
  if (r.has("density_map")) {
    s.densityMap = resolveRelative(file, r.string("density_map"));
    std::error_code ec;
    if (!std::filesystem::is_regular_file(s.densityMap, ec))
      r.fail("density_map", "density map file '" + s.densityMap + "' does not exist");
    s.densityFactor = std::make_shared<const std::vector<float>>(readDensityMap(s.densityMap));
  } else {
    r.allow("density_map");
  }
  r.finish();
  if (s.lights.empty()) {
    s.lights.push_back(LightSpec{});
    s.lights.push_back(LightSpec{{0.7, -0.3, 0.6}, {0.55, 0.6, 0.7}, 0.5});
  }
  // Module sections: validated (and relative paths resolved) by their own parsers.
  validateSections(s);
  return s;
}

Scene loadScene(const std::string& path) {
  if (path.empty()) throw Error("no scene given");
  const std::string abs = std::filesystem::absolute(path).lexically_normal().string();
  if (!fileExists(abs)) throw Error("file not found", path);
  if (isMeshPath(abs)) return bareMeshScene(abs);
  if (extensionOf(abs) != ".json")
    throw Error("unsupported scene type: expected a .json scene or a .obj/.ply/.off/.stl mesh", path);
  return sceneFromJson(readJsonFile(abs), abs);
}

Json sceneToJson(const Scene& s, const std::string& relativeTo) {
  auto rel = [&](const std::string& p) {
    if (relativeTo.empty()) return p;
    return std::filesystem::path(p).lexically_relative(std::filesystem::path(relativeTo).parent_path()).string();
  };
  auto vec = [](const glm::dvec3& v) { return Json::array({v.x, v.y, v.z}); };
  Json j;
  j["pteryla"] = 1;
  j["name"] = s.name;
  j["seed"] = s.seed;
  j["time"] = s.time;
  j["mesh"] = rel(s.meshPath);
  if (s.meshRepair) j["mesh_repair"] = true;
  j["feathers"] = sectionsRelativeTo(s, s.feathers, "feathers", relativeTo);
  j["tracts"] = sectionsRelativeTo(s, s.tracts, "tracts", relativeTo);
  if (!s.directions.empty()) j["directions"] = s.directions;
  if (!s.moult.empty()) j["moult"] = s.moult;
  if (!s.growth.empty()) j["growth"] = s.growth;
  if (!s.skeleton.empty()) j["skeleton"] = sectionsRelativeTo(s, s.skeleton, "skeleton", relativeTo);
  if (!s.controls.empty()) j["controls"] = s.controls;
  if (!s.packing.empty()) j["packing"] = s.packing;
  if (!s.ordering.empty()) j["ordering"] = s.ordering;
  if (s.densityFactor && !s.densityMap.empty()) j["density_map"] = rel(s.densityMap);
  Json cam;
  cam["fov"] = s.camera.fovDeg;
  cam["up"] = vec(s.camera.up);
  cam["view_direction"] = vec(s.camera.viewDir);
  if (!s.camera.autoFrame) {
    cam["eye"] = vec(s.camera.eye);
    cam["target"] = vec(s.camera.target);
  }
  j["camera"] = cam;
  j["lights"] = Json::array();
  for (const auto& l : s.lights)
    j["lights"].push_back({{"direction", vec(l.direction)}, {"color", vec(l.color)}, {"intensity", l.intensity}});
  const RenderSpec& rs = s.render;
  j["render"] = {{"size", {rs.width, rs.height}},
                 {"lod", rs.lod},
                 {"lod_by_screen_size", rs.lodByScreenSize},
                 {"instance_tolerance", rs.instanceTolerance},
                 {"style", rs.style},
                 {"background", vec(rs.background)},
                 {"skin_color", vec(rs.skinColor)},
                 {"ambient", rs.ambient},
                 {"shadows", rs.shadows},
                 {"shadow_strength", rs.shadowStrength},
                 {"msaa", rs.msaa},
                 {"exposure", rs.exposure},
                 {"tone", rs.tone},
                 {"light_rig", rs.lightRig},
                 {"ground", rs.ground},
                 {"ground_color", vec(rs.groundColor)},
                 {"brdf", {{"d", rs.brdfD}, {"h", rs.brdfH}}}};
  return j;
}

void saveScene(const std::string& path, const Scene& scene) {
  const std::string abs = std::filesystem::absolute(path).lexically_normal().string();
  if (!scene.densityFactor) {
    writeJsonFile(path, sceneToJson(scene, abs));
    return;
  }
  // The painted density goes next to the scene file (written first: the scene never names a missing map).
  Scene s = scene;
  s.densityMap = densityMapPathFor(abs);
  writeDensityMap(s.densityMap, *s.densityFactor);
  writeJsonFile(path, sceneToJson(s, abs));
}

bool sameDensityFactors(const Scene& a, const Scene& b) {
  if (a.densityFactor == b.densityFactor) return true;
  if (!a.densityFactor || !b.densityFactor) return false;
  return *a.densityFactor == *b.densityFactor;
}

std::string densityMapPathFor(const std::string& scenePath) {
  const std::filesystem::path p(scenePath);
  return (p.parent_path() / (p.stem().string() + ".density.json")).string();
}

std::vector<float> readDensityMap(const std::string& path) {
  const Json j = readJsonFile(path);
  JsonReader r(j, path);
  if (!r.has("pteryla_density")) r.fail("pteryla_density", "not a density map (missing \"pteryla_density\": 1)");
  r.integer("pteryla_density", 1, 1, 1);
  const int64_t n = r.integer("vertices", 0, 0, 100000000);
  if (!r.has("factor") || !j.at("factor").is_array()) r.fail("factor", "expected an array of factors, one per vertex");
  const Json& f = j.at("factor");
  if (int64_t(f.size()) != n)
    r.fail("factor", std::to_string(f.size()) + " factors for " + std::to_string(n) + " vertices");
  std::vector<float> out;
  out.reserve(f.size());
  for (size_t i = 0; i < f.size(); ++i) {
    const std::string where = "factor[" + std::to_string(i) + "]";
    if (!f[i].is_number()) throw Error("expected a number", path, where);
    const double v = f[i].get<double>();
    if (!std::isfinite(v) || v < 0 || v > 100) throw Error("a density factor must be in [0, 100]", path, where);
    out.push_back(static_cast<float>(v));
  }
  r.allow("factor");
  r.finish();
  return out;
}

void writeDensityMap(const std::string& path, const std::vector<float>& factor) {
  std::string text = "{\"pteryla_density\": 1, \"vertices\": " + std::to_string(factor.size()) + ", \"factor\": [";
  char buf[32];
  for (size_t i = 0; i < factor.size(); ++i) {
    const float v = factor[i];
    if (!std::isfinite(v) || v < 0 || v > 100)
      throw Error("a density factor must be in [0, 100]", path, "factor[" + std::to_string(i) + "]");
    const auto res = std::to_chars(buf, buf + sizeof buf, v);  // shortest form that reads back to v
    if (i) text += i % 16 ? ", " : ",\n ";
    text.append(buf, res.ptr);
  }
  text += "]}\n";
  writeFileAtomic(path, text);
}

}  // namespace pteryla::pipeline
