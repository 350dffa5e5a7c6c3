#pragma once
// The stages of the Pipeline (pipeline.hpp), in evaluation order: each reads the one before it, so
// dirtying a stage dirties every later one. Clients address stages by this enum; stageName() is for
// printing only.
#include <cstddef>

namespace pteryla::pipeline {

enum class Stage { Skin, Tracts, Distribute, Interpolate, Directions, Pose, Ages, Controls, Pack, Mesh };
inline constexpr size_t kStageCount = 10;

// "skin", "tracts", "distribute", "interpolate", "directions", "pose", "ages", "controls", "pack", "mesh".
const char* stageName(Stage s);

}  // namespace pteryla::pipeline
