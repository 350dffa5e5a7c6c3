// Fuzz target: the skeleton reader (moult::readSkinRig: a skeleton file's "joints"/"weights", or a scene's
// "skeleton" object with inline joints and keyframes, docs/skeleton-format.md). A rig that loads is posed
// at a few times and skins a small point set, the cheap evaluation every frame does.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_common.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/moult/skinning.hpp"

namespace {
constexpr size_t kVertices = 64;  // the seeds' weights reference vertices below this
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = pteryla::fuzz::writeInput(data, size, "skeleton.json");
  try {
    const pteryla::Json j = pteryla::readJsonFile(path);
    pteryla::JsonReader r(j, path, "skeleton");
    const pteryla::moult::SkinRig rig = pteryla::moult::readSkinRig(r, kVertices);
    std::vector<glm::dvec3> rest(kVertices), out;
    for (size_t v = 0; v < kVertices; ++v) rest[v] = glm::dvec3(double(v) * 0.1, double(v % 7) * 0.05, 0.0);
    for (double t : {-1.0, 0.0, 0.37, 1.0, 5.0}) {
      const pteryla::moult::SkeletonPose pose = pteryla::moult::poseAt(rig.animation, t);
      const auto joints = pteryla::moult::jointTransforms(rig.skeleton, pose);
      pteryla::moult::skinPoints(rig.skeleton, joints, rest, out);
    }
  } catch (const pteryla::Error&) {
    // bad input: expected
  }
  return 0;
}
