#pragma once
// Module sections of a scene (feathers, tracts, directions, moult, skeleton, controls, packing):
// validation at load time and path handling, shared by loadScene, saveScene and the Pipeline.
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/pipeline/scene_stages.hpp"

namespace pteryla::pipeline {

// Checks every module section with the module's own parser; resolves relative file paths in place
// (feather files, label files, skeleton files) against the scene file. Throws Error with key paths.
void validateSections(Scene& s);
// The scene for a bare mesh: whole mesh one tract, default feather and direction.
Scene bareMeshScene(const std::string& meshPath);
// Copy of a section with absolute paths rewritten relative to `relativeTo` (for saving).
Json sectionsRelativeTo(const Scene& s, const Json& section, const std::string& which, const std::string& relativeTo);
// What `row` of sectionStages() compares of a scene's JSON form (sceneToJson, or an object with some of
// its sections): the section, less the sub-keys other rows compare, or the sub-key of every element.
Json sectionValue(const Json& scene, const SectionStage& row);
// Directory holding the bundled data: pteryla::dataDirectory() (core/data_dir.hpp).
std::string dataDir();

}  // namespace pteryla::pipeline
