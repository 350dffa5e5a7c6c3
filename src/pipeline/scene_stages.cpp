#include "pteryla/pipeline/scene_stages.hpp"

#include <cstring>

#include "scene_sections.hpp"

namespace pteryla::pipeline {

const std::vector<SectionStage>& sectionStages() {
  static const std::vector<SectionStage> table = {
      {"pteryla", "", std::nullopt},
      {"name", "", std::nullopt},
      {"time", "", std::nullopt},  // the starting time: Pipeline::setTime
      {"mesh", "", Stage::Skin},
      {"mesh_repair", "", Stage::Skin},
      {"feathers", "", Stage::Skin},  // the feather library is loaded with the skin
      {"tracts", "", Stage::Tracts},
      {"tracts", "moult", Stage::Ages},        // per-tract moult overrides: read by the ages stage
      {"growth", "", Stage::Tracts},           // the scene's growth schedule, read with the tracts
      {"seed", "", Stage::Distribute},         // scatter seeds (and the interpolation's jitter)
      {"density_map", "", Stage::Distribute},  // painted density factors (compared by value, not by file name)
      {"directions", "", Stage::Directions},
      {"ordering", "", Stage::Directions},  // layer order is computed with the directions
      {"skeleton", "", Stage::Pose},
      {"moult", "", Stage::Ages},
      {"controls", "", Stage::Controls},
      {"packing", "", Stage::Controls},  // styling and the controls' natural pack read it
      {"camera", "", std::nullopt},
      {"lights", "", std::nullopt},
      {"render", "", std::nullopt},                   // render.lod: the starting level of detail, Pipeline::setLod
      {"render", "instance_tolerance", Stage::Mesh},  // read by the mesh stage
  };
  return table;
}

Json sectionValue(const Json& scene, const SectionStage& row) {
  const auto it = scene.find(row.key);
  const Json section = it == scene.end() ? Json() : *it;
  if (!section.is_array() && !section.is_object()) return *row.subKey ? Json() : section;
  // An object section's sub-key is one of its members.
  if (section.is_object() && *row.subKey) return section.contains(row.subKey) ? section.at(row.subKey) : Json();
  if (section.is_object() && !*row.subKey) {
    Json out = section;
    for (const SectionStage& other : sectionStages())
      if (*other.subKey && std::strcmp(other.key, row.key) == 0) out.erase(other.subKey);
    return out;
  }
  if (*row.subKey) {
    Json out = Json::array();
    for (const Json& e : section) out.push_back(e.is_object() && e.contains(row.subKey) ? e.at(row.subKey) : Json());
    return out;
  }
  // The whole section less the sub-keys other rows compare.
  Json out = section;
  for (const SectionStage& other : sectionStages())
    if (*other.subKey && std::strcmp(other.key, row.key) == 0)
      for (Json& e : out)
        if (e.is_object()) e.erase(other.subKey);
  return out;
}

std::optional<Stage> earliestChangedStage(const Scene& before, const Scene& after) {
  if (before.fromBareMesh != after.fromBareMesh) return Stage::Skin;  // a bare mesh implies directions and scales
  const Json a = sceneToJson(before, ""), b = sceneToJson(after, "");
  std::optional<Stage> earliest;
  for (const SectionStage& row : sectionStages()) {
    if (!row.stage || (earliest && *earliest <= *row.stage)) continue;
    // The density map is its factors: the same factors from another file (saved elsewhere) change nothing.
    const bool changed = std::strcmp(row.key, "density_map") == 0 ? !sameDensityFactors(before, after)
                                                                  : sectionValue(a, row) != sectionValue(b, row);
    if (changed) earliest = row.stage;
  }
  return earliest;
}

}  // namespace pteryla::pipeline
