// Time stages of the pipeline: skin pose (Streit 2003, 8.3), moult (8.1-8.2) and expressive controls
// (AnimFur, Grier 2019) read from the scene and evaluated by src/moult.
#include "time_stages.hpp"

#include <cmath>

#include "pteryla/core/error.hpp"

namespace pteryla::pipeline {

namespace {

std::string tractName(const Scene& scene, size_t i) {
  if (i < scene.tracts.size() && scene.tracts[i].is_object()) {
    const auto it = scene.tracts[i].find("name");
    if (it != scene.tracts[i].end() && it->is_string()) return it->get<std::string>();
  }
  return {};
}

void parseMoult(const Scene& scene, TimeState& state) {
  Json key = {{"file", scene.file}, {"moult", scene.moult}, {"tracts", Json::array()}};
  for (size_t i = 0; i < scene.tracts.size(); ++i) {
    const Json& t = scene.tracts[i];
    key["tracts"].push_back(t.is_object() && t.contains("moult") ? t.at("moult") : Json());
  }
  if (state.moultParsed && key == state.moultKey) return;
  state.moultParsed = false;
  state.moultOptions.assign(scene.tracts.size(), std::nullopt);
  std::optional<moult::MoultOptions> defaults;
  if (!scene.moult.empty()) {
    JsonReader r(scene.moult, scene.file, "moult");
    defaults = moult::readMoultOptions(r);
  }
  for (size_t i = 0; i < scene.tracts.size(); ++i) {
    const Json& sec = key["tracts"][i];
    const std::string where = "tracts[" + std::to_string(i) + "].moult";
    if (sec.is_null()) {
      state.moultOptions[i] = defaults;
    } else if (sec.is_boolean()) {
      if (sec.get<bool>()) state.moultOptions[i] = defaults ? *defaults : moult::MoultOptions{};
    } else if (sec.is_object()) {
      JsonReader r(sec, scene.file, where);
      state.moultOptions[i] = moult::readMoultOptions(r, defaults ? *defaults : moult::MoultOptions{});
    } else {
      throw Error("expected a moult object (overrides of the scene's \"moult\") or true/false", scene.file, where);
    }
    if (state.moultOptions[i] && !state.moultOptions[i]->enabled) state.moultOptions[i].reset();
  }
  state.moultKey = std::move(key);
  state.moultParsed = true;
}

void parseRig(const Scene& scene, const coat::SkinMesh& rest, TimeState& state) {
  const Json key = {{"file", scene.file}, {"skeleton", scene.skeleton}, {"vertices", rest.vertexCount()}};
  if (key == state.rigKey) return;
  state.rig.reset();
  state.rigKey = Json();
  if (!scene.skeleton.empty()) {
    JsonReader r(scene.skeleton, scene.file, "skeleton");
    state.rig = moult::readSkinRig(r, rest.vertexCount());
  }
  state.rigKey = key;
}

void parseControls(const Scene& scene, TimeState& state) {
  Json names = Json::array();
  for (size_t i = 0; i < scene.tracts.size(); ++i) names.push_back(tractName(scene, i));
  Json key = {{"file", scene.file}, {"controls", scene.controls}, {"packing", scene.packing}, {"tracts", names}};
  if (state.controlsParsed && key == state.controlsKey) return;
  state.controlsParsed = false;
  state.controls = moult::readControls(scene.controls, scene.file, "controls");
  state.controlTracts.assign(state.controls.size(), {});
  for (size_t c = 0; c < state.controls.size(); ++c) {
    const auto& wanted = state.controls[c].tracts;
    for (size_t k = 0; k < wanted.size(); ++k) {
      bool found = false;
      for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == wanted[k]) {
          state.controlTracts[c].push_back(static_cast<uint32_t>(i));
          found = true;
        }
      if (!found)
        throw Error("unknown tract '" + wanted[k] + "'", scene.file,
                    "controls[" + std::to_string(c) + "].tracts[" + std::to_string(k) + "]");
    }
  }
  state.packOptions = coat::PackOptions{};
  if (!scene.packing.empty()) {
    JsonReader r(scene.packing, scene.file, "packing");
    state.packOptions = coat::parsePackOptions(r);
  }
  state.controlsKey = std::move(key);
  state.controlsParsed = true;
}

}  // namespace

void poseSkin(const Scene& scene, double t, const coat::SkinMesh& rest, coat::SkinMesh& posed, TimeState& state) {
  state.rest = &rest;
  state.posedMoved = false;
  parseRig(scene, rest, state);
  if (!state.rig) return;
  const moult::SkeletonPose pose = moult::poseAt(state.rig->animation, t);
  state.posedMoved = moult::poseSkinMesh(state.rig->skeleton, pose, rest, posed);
}

void featherAges(const Scene& scene, double t, const std::vector<coat::TractParameterization>& params,
                 const coat::Follicles& follicles, TimeState& state, coat::CoatFeathers& coat) {
  parseMoult(scene, state);
  state.moultStats = moult::MoultStats{};
  bool any = false;
  for (const auto& o : state.moultOptions) any = any || o.has_value();
  if (!any) {
    coat.age.assign(coat.size(), 1.0);
    coat.present.assign(coat.size(), 1);
    state.moultStats.old = coat.size();
    return;
  }
  // The plan depends only on rest data (parameterization, feather sizes, ids); it is cheap next to
  // packing, so it is rebuilt per evaluation rather than cached against upstream edits.
  const moult::CoatMoultPlan plan = moult::planCoatMoult(params, follicles, coat, state.moultOptions);
  state.moultStats = moult::applyMoult(plan, t, coat);
}

void applyControls(const Scene& scene, double t, const coat::SkinMesh& posed, const coat::Follicles& follicles,
                   TimeState& state, coat::CoatFeathers& coat, std::vector<double>& fixedElevation) {
  state.controlResult = moult::ControlResult{};
  if (scene.controls.empty()) return;
  parseControls(scene, state);
  if (state.controls.empty()) return;
  const coat::SkinMesh& rest = state.rest ? *state.rest : posed;
  const moult::ControlBinding binding = moult::bindControls(rest, follicles, state.controls, state.controlTracts);
  state.controlResult = moult::evaluateControls(state.controls, binding, posed, follicles, t, state.packOptions, coat,
                                                fixedElevation);
}

coat::PackResult packFrame(const coat::SkinMesh& posed, const coat::CoatFeathers& coat, const coat::PackOptions& options,
                           TimeState& state) {
  moult::ControlResult& cr = state.controlResult;
  if (!cr.naturalPacked) return coat::pack(posed, coat, options);
  cr.naturalPacked = false;
  coat::PackResult natural = std::move(cr.natural);
  cr.natural = coat::PackResult{};
  // The natural pack must have used the same options (it did unless the packing section was edited
  // without re-running the tracts stage, where the pipeline parses its own copy).
  if (coat::packOptionsToJson(options) != coat::packOptionsToJson(state.packOptions))
    return coat::pack(posed, coat, options);
  return coat::repack(posed, coat, natural, cr.changed, options);
}

}  // namespace pteryla::pipeline
