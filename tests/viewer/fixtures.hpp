#pragma once
// Shared helpers for the viewer tests: scratch directories and small, fast scenes.
#include <filesystem>
#include <string>

#include "pteryla/pipeline/scene.hpp"

namespace viewer_test {

inline std::string dataPath(const std::string& rel) { return std::string(PTERYLA_DATA_DIR) + "/" + rel; }

// A fresh directory under the build tree for one test.
inline std::string scratchDir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::path(PTERYLA_BUILD_DIR) / "viewer_test" / name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d.string();
}

// The patch scene with few follicles and relaxation steps, so an evaluation takes well under a second.
inline pteryla::pipeline::Scene smallPatch() {
  pteryla::pipeline::Scene s = pteryla::pipeline::loadScene(dataPath("scenes/patch.json"));
  s.tracts[0]["count"] = 24;
  s.tracts[0]["relax"]["iterations"] = 3;
  s.render.lod = 0.2;
  return s;
}

}  // namespace viewer_test
