#pragma once
// Scene: everything needed to evaluate a feather coat, as read from a scene file (docs/scene-format.md).
// Pure data; the Pipeline turns it into results. Paths are absolute (resolved against the scene file).
#include <glm/vec3.hpp>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pteryla/core/json.hpp"

namespace pteryla::pipeline {

struct CameraSpec {
  bool autoFrame = true;  // frame the skin's bounds when eye/target are not given
  glm::dvec3 eye{0, 0, 5}, target{0, 0, 0}, up{0, 1, 0};
  double fovDeg = 35;                     // vertical field of view, degrees
  glm::dvec3 viewDir{-0.4, -0.35, -1.0};  // used by autoFrame: direction the camera looks along
};

struct LightSpec {
  glm::dvec3 direction{-0.5, -1.0, -0.6};  // direction the light travels (world)
  glm::dvec3 color{1, 1, 1};
  double intensity = 1.0;
};

struct RenderSpec {
  int width = 960, height = 720;
  double lod = 1.0;             // fraction of feather geometry in (0,1]
  bool lodByScreenSize = true;  // pick per-feather LOD from screen size (7.1.3); lod is then the cap
  // Instancing (pipeline::CoatMesher, feather/instancing.hpp): mature feathers within this fraction of
  // their extent of an earlier feather are meshed from its curves, and identical meshes stored once; 0 = off.
  double instanceTolerance = 0.0;
  std::string style = "shaded";  // shaded | scratchboard
  glm::dvec3 background{0.82, 0.86, 0.9};
  glm::dvec3 skinColor{0.78, 0.62, 0.52};
  double brdfD = 1.0, brdfH = 0.0;  // Poulin-Fournier barbule spacing and floor height
  double ambient = 0.35;
  bool shadows = true;             // the first light casts coat and skin shadows (render::RenderSettings::shadows)
  double shadowStrength = 0.8;     // [0,1]: share of the key light removed in full shadow
  int msaa = 4;                    // multisampling of rendered images: 0 (off), 2, 4 or 8 samples
  double exposure = 0.0;           // stops, [-8, 8]: colours are scaled by 2^exposure before the tone curve
  std::string tone = "linear";     // linear (clamp) | filmic (a smooth shoulder instead of clipping)
  std::string lightRig = "scene";  // scene: `lights` | studio: key, fill and rim set from the camera
  bool ground = false;             // a ground plane under the model that receives its shadow
  glm::dvec3 groundColor{0.72, 0.72, 0.70};
};

struct Scene {
  int version = 1;
  std::string file;  // absolute path of the scene file ("" for in-memory scenes)
  std::string name;
  uint64_t seed = 1;
  double time = 0.0;     // default evaluation time
  std::string meshPath;  // absolute
  bool meshRepair = false;
  bool fromBareMesh = false;
  // Module sections, kept as validated JSON so each module owns its schema (see docs/scene-format.md).
  Json feathers = Json::object();  // name -> file path (absolute after load) or inline feather object
  Json tracts = Json::array();
  Json directions = Json::object();
  Json moult = Json::object();
  Json growth = Json::object();  // growth and wear schedule of every feather (docs/growth.md); {} = default
  Json skeleton = Json::object();
  Json controls = Json::array();
  Json packing = Json::object();
  Json ordering = Json::object();
  CameraSpec camera;
  std::vector<LightSpec> lights;
  RenderSpec render;
  // Painted follicle density (docs/scene-format.md, "Density map"): a factor >= 0 per mesh vertex
  // (linear across faces) multiplying the tracts' density. `densityMap` is the side file it was read
  // from (absolute; "" when painted and not saved yet); `densityFactor` the factors (null: no map).
  // saveScene writes the factors next to the scene file. Shared, so copies of a scene (undo) are cheap;
  // never modified in place: an edit stores a new vector.
  std::string densityMap;
  std::shared_ptr<const std::vector<float>> densityFactor;
};

// True when both scenes have no density map or the same factors.
bool sameDensityFactors(const Scene& a, const Scene& b);
// The side file saveScene writes for a scene file: "DIR/STEM.density.json".
std::string densityMapPathFor(const std::string& scenePath);
// Density map files: {"pteryla_density": 1, "vertices": N, "factor": [f0, f1, ...]} with N = the number of
// factors (one per mesh vertex, finite, in [0, 100]). Throws pteryla::Error naming the file and the
// element ("factor[17]"). The writer is atomic (core/atomic_file.hpp) and writes each factor in its
// shortest form that reads back to the same float.
std::vector<float> readDensityMap(const std::string& path);
void writeDensityMap(const std::string& path, const std::vector<float>& factor);

// Loads a scene file, or a bare mesh (.obj/.ply/.off/.stl) as a one-tract scene with default feathers.
// Throws pteryla::Error with file and key path for anything malformed or unknown.
Scene loadScene(const std::string& path);
// Serialises a scene so that loadScene(saveScene(s)) evaluates to the same coat. Paths are written
// relative to `path`'s directory. A scene with a density map also gets its side file
// (densityMapPathFor(path)), written before the scene file.
void saveScene(const std::string& path, const Scene& scene);
Json sceneToJson(const Scene& scene, const std::string& relativeTo);
Scene sceneFromJson(const Json& j, const std::string& file);

}  // namespace pteryla::pipeline
