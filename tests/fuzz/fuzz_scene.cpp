// Fuzz target: the scene reader. pipeline::loadScene on a .json scene (strict JSON, top-level keys,
// camera, lights, render), then every module section through the parser the pipeline uses for it
// (feathers, tracts on a small mesh, directions, ordering, packing, moult, controls, skeleton), and
// sceneToJson. No stage is evaluated (no follicles, no packing), so each input stays cheap.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz_common.hpp"
#include "pteryla/coat/directions.hpp"
#include "pteryla/coat/ordering.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/primitives.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/moult/controls.hpp"
#include "pteryla/moult/schedule.hpp"
#include "pteryla/moult/skinning.hpp"
#include "pteryla/pipeline/scene.hpp"

namespace {

using pteryla::Json;
using pteryla::JsonReader;

const pteryla::coat::SkinMesh& tractMesh() {
  static const pteryla::coat::SkinMesh mesh = pteryla::coat::makeIcosphere(1, 1.0, glm::dvec3(0));
  return mesh;
}

void readSections(const pteryla::pipeline::Scene& s) {
  for (auto it = s.feathers.begin(); it != s.feathers.end(); ++it) {
    if (it->is_string()) {
      (void)pteryla::feather::loadFeather(it->get<std::string>());
    } else {
      JsonReader r(*it, s.file, "feathers." + it.key());
      (void)pteryla::feather::readFeather(r);
    }
  }
  if (!s.directions.empty()) {
    JsonReader r(s.directions, s.file, "directions");
    (void)pteryla::coat::parseDirections(r);
  }
  if (!s.ordering.empty()) {
    JsonReader r(s.ordering, s.file, "ordering");
    (void)pteryla::coat::parseOrdering(r);
  }
  if (!s.packing.empty()) {
    JsonReader r(s.packing, s.file, "packing");
    (void)pteryla::coat::parsePackingSettings(r);
  }
  if (!s.moult.empty()) {
    JsonReader r(s.moult, s.file, "moult");
    (void)pteryla::moult::readMoultOptions(r);
  }
  (void)pteryla::moult::readControls(s.controls, s.file, "controls");
  if (!s.skeleton.empty()) {
    JsonReader r(s.skeleton, s.file, "skeleton");
    (void)pteryla::moult::readSkinRig(r, 4096);  // more vertices than the seeds' skeletons reference
  }
  // Last: the seeds' tracts name groups of their own meshes, which the small test mesh does not have.
  std::vector<pteryla::coat::Tract> earlier;
  for (size_t i = 0; i < s.tracts.size(); ++i) {
    JsonReader r(s.tracts[i], s.file, "tracts[" + std::to_string(i) + "]");
    earlier.push_back(pteryla::coat::readTract(r, tractMesh(), earlier));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string dir = pteryla::fuzz::dataLinkedDir("scenes");
  const std::string path = pteryla::fuzz::writeInput(data, size, "scenes/scene.json");
  (void)dir;
  try {
    const pteryla::pipeline::Scene s = pteryla::pipeline::loadScene(path);
    (void)pteryla::pipeline::sceneToJson(s, path);
    readSections(s);
  } catch (const pteryla::Error&) {
    // bad input, reported with file and key path: expected
  }
  return 0;
}
