#pragma once
// Which pipeline stage reads each section of a scene file (docs/scene-format.md). Editing a section
// re-runs its stage and everything after it, never anything before it: an edit of "packing" repacks
// without re-relaxing follicles. This table is the one place that says so; the stages read their
// sections accordingly, the viewer re-runs what earliestChangedStage() returns, and
// tests/pipeline/test_scene_stages.cpp checks every row against fresh evaluations.
#include <optional>
#include <vector>

#include "pteryla/pipeline/scene.hpp"
#include "pteryla/pipeline/stage.hpp"

namespace pteryla::pipeline {

struct SectionStage {
  const char* key;             // top-level key of the scene file
  const char* subKey;          // "": the whole section (less the sub-keys of other rows); else this
                               // key of each element of the section ("moult" of every tract)
  std::optional<Stage> stage;  // the earliest stage that reads it; nullopt: no stage (view settings,
                               // or the starting value of Pipeline::setTime / setLod)
};

// Every key a scene file may have, once each (and the sub-keys that are read by a later stage than
// their section).
const std::vector<SectionStage>& sectionStages();

// The earliest stage whose input differs between `before` and `after` (by sectionStages(); a scene made
// from a bare mesh counts as a different mesh); nullopt when only sections read by no stage differ.
// The scene's file name is not compared.
std::optional<Stage> earliestChangedStage(const Scene& before, const Scene& after);

}  // namespace pteryla::pipeline
