#pragma once
// The host API's typed inputs turned into the pipeline's: the skin arrays into a checked SkinMesh, and a
// CoatSetup into the scene sections the pipeline parses (session_setup.cpp). Private to src/host.
#include <cstddef>
#include <string>

#include "pteryla/coat/skin.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/pteryla.hpp"

namespace pteryla::host {

// "array[i]": how errors name an element of a host array.
std::string at(const char* array, size_t i);
// The skin, checked (Error naming "positions", "triangles", "vertex v", "face f", "faceGroups[i]").
coat::SkinMesh skinFromArrays(const SkinArrays& in);
// The scene a typed set-up stands for (docs/scene-format.md), checked by sceneFromJson and the
// pipeline's own parsers like any scene file.
pipeline::Scene sceneFromSetup(const CoatSetup& setup);

}  // namespace pteryla::host
