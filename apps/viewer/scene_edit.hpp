#pragma once
// Scene edits as the viewer sees them: generic JSON-pointer edits (the `set` script command and the JSON
// inspectors), and turning a bare-mesh scene into an explicit one so that what the viewer saves reloads
// to the same coat. Which stage an edit re-runs is the pipeline's to say: pipeline::earliestChangedStage
// (pteryla/pipeline/scene_stages.hpp).
// Pure data: no GL, no ImGui (unit-tested in tests/viewer).
#include <optional>
#include <string>

#include <glm/vec3.hpp>

#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

namespace pteryla::viewer {

// The scene as JSON with absolute paths (in-memory form; saveScene writes relative ones).
Json sceneJson(const pipeline::Scene& s);
// Replaces the value at JSON pointer `pointer` (RFC 6901, e.g. "/packing/clearance",
// "/tracts/0/relax/iterations"; "-" appends to an array) of the scene's JSON form by `value` and
// re-reads the scene through the strict scene reader. Throws pteryla::Error naming the pointer for a
// bad pointer or a value the scene reader rejects; `s` is unchanged then.
void setScenePointer(pipeline::Scene& s, const std::string& pointer, const Json& value);
// The scene's JSON form names the density map by its file only: a scene re-read from it (`set`, the
// Scene JSON window) gets `from`'s factors back (painted since the last save) while it names the same
// file (or none).
void keepPaintedDensity(const pipeline::Scene& from, pipeline::Scene& next);
// Parses a script or text-field value: JSON when it parses, else a plain string.
Json parseLooseValue(const std::string& text);

// A bare-mesh scene (loadScene of an .obj/.ply/...) depends on Scene::fromBareMesh, which scene files
// cannot express. This writes its implicit defaults explicitly (feather_scale "auto" per tract, the
// bounding-box body axis as directions and layer ordering) and clears fromBareMesh, so that the scene
// evaluates to the same coat and survives saveScene/loadScene. `lo`/`hi`: bounds of the rest skin.
void makeBareMeshExplicit(pipeline::Scene& s, const glm::dvec3& lo, const glm::dvec3& hi);
// Same, loading the scene's mesh to find its bounds.
void makeBareMeshExplicit(pipeline::Scene& s);

// Time span the scene animates over: key times ("t" of any "keys" entry: controls, skeleton) and moult
// windows (start .. start + duration, scene and tracts). nullopt when nothing is animated.
std::optional<std::pair<double, double>> sceneTimeSpan(const pipeline::Scene& s);

// Tract reference used by panels and scripts: an index ("0"), a name ("spinal") or "*" (all tracts).
// Returns the indices it selects; throws Error(element = `where`) for an unknown tract.
std::vector<size_t> resolveTracts(const pipeline::Scene& s, const std::string& ref, const std::string& where);
std::string tractName(const pipeline::Scene& s, size_t i);

}  // namespace pteryla::viewer
