#include "scene_sections.hpp"

#include <filesystem>

#include "pteryla/core/data_dir.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"

namespace pteryla::pipeline {
namespace {

std::string relPath(const std::string& p, const std::string& relativeTo) {
  if (relativeTo.empty()) return p;
  return std::filesystem::path(p).lexically_relative(std::filesystem::path(relativeTo).parent_path()).string();
}

void validateFeathers(Scene& s) {
  if (!s.feathers.is_object())
    throw Error("expected an object mapping feather names to files or definitions", s.file, "feathers");
  for (auto it = s.feathers.begin(); it != s.feathers.end(); ++it) {
    const std::string where = "feathers." + it.key();
    if (it->is_string()) {
      const std::string p = resolveRelative(s.file, it->get<std::string>());
      if (!fileExists(p)) throw Error("feather file not found: " + p, s.file, where);
      *it = p;
    } else if (!it->is_object()) {
      throw Error("expected a feather file path or an inline feather definition", s.file, where);
    }
  }
}

}  // namespace

std::string dataDir() { return dataDirectory(); }

void validateSections(Scene& s) {
  validateFeathers(s);
  if (!s.tracts.is_array()) throw Error("expected an array of tracts", s.file, "tracts");
  if (!s.controls.is_array()) throw Error("expected an array of controls", s.file, "controls");
  for (const char* key : {"directions", "moult", "growth", "skeleton", "packing", "ordering"}) {
    const Json& sec = key == std::string("directions") ? s.directions
                      : key == std::string("moult")    ? s.moult
                      : key == std::string("growth")   ? s.growth
                      : key == std::string("skeleton") ? s.skeleton
                      : key == std::string("ordering") ? s.ordering
                                                       : s.packing;
    if (!sec.is_object()) throw Error("expected an object", s.file, key);
  }
  // The skeleton side file, absolute like every Scene path (read by the time stages, docs/moult.md).
  if (s.skeleton.contains("file") && s.skeleton["file"].is_string())
    s.skeleton["file"] = resolveRelative(s.file, s.skeleton["file"].get<std::string>());
}

Scene bareMeshScene(const std::string& meshPath) {
  Scene s;
  s.file = "";
  s.name = std::filesystem::path(meshPath).stem().string();
  s.meshPath = meshPath;
  s.fromBareMesh = true;
  s.feathers = Json::object();
  s.feathers["contour"] = (std::filesystem::path(dataDir()) / "feathers" / "contour.json").string();
  s.tracts = Json::array({Json{{"name", "all"}, {"parameterization", {{"method", "projection"}}}}});
  s.lights.push_back(LightSpec{});
  s.lights.push_back(LightSpec{{0.7, -0.3, 0.6}, {0.55, 0.6, 0.7}, 0.5});
  return s;
}

Json sectionsRelativeTo(const Scene& s, const Json& section, const std::string& which, const std::string& relativeTo) {
  Json out = section;
  if (which == "feathers") {
    for (auto it = out.begin(); it != out.end(); ++it)
      if (it->is_string()) *it = relPath(it->get<std::string>(), relativeTo);
  }
  if (which == "skeleton" && out.contains("file") && out["file"].is_string())
    out["file"] = relPath(out["file"].get<std::string>(), relativeTo);
  return out;
}

}  // namespace pteryla::pipeline
