#pragma once
// The time-dependent stages of the pipeline (thesis Ch.8 + AnimFur): skin pose, feather ages (moult)
// and expressive controls. Each is a pure function of (scene, t) and the rest-state results, so any
// time can be evaluated in any order. The work is done by src/moult; these hooks parse the scene's
// sections (strictly: unknown keys are errors with their key path) and cache what they parsed.
#include <optional>
#include <string>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/parameterize.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/moult/controls.hpp"
#include "pteryla/moult/schedule.hpp"
#include "pteryla/moult/skinning.hpp"
#include "pteryla/pipeline/scene.hpp"

namespace pteryla::pipeline {

// Parsed time settings, cached across frames. Each cache remembers the JSON it was parsed from and is
// re-parsed when that changes (scene edits), so the cache never changes a result.
struct TimeState {
  // The rest skin of the last poseSkin call (control bindings are made at rest).
  const coat::SkinMesh* rest = nullptr;

  // Skeleton ("skeleton" section).
  Json rigKey;                            // {file, section, vertex count} the rig was read for
  std::optional<moult::SkinRig> rig;      // empty: no skeleton
  bool posedMoved = false;                // the last pose moved the skin

  // Moult ("moult" section and per-tract "moult" overrides).
  Json moultKey;
  bool moultParsed = false;
  std::vector<std::optional<moult::MoultOptions>> moultOptions;  // per tract
  moult::MoultStats moultStats;           // of the last evaluation

  // Controls ("controls" array) and the packing options they need for natural elevations.
  Json controlsKey;
  bool controlsParsed = false;
  std::vector<moult::ControlSpec> controls;
  std::vector<std::vector<uint32_t>> controlTracts;  // per control: tract indices (empty = any)
  coat::PackOptions packOptions;
  moult::ControlResult controlResult;     // of the last evaluation; its natural pack is consumed by packFrame
};

// posed = rest deformed by the scene's skeleton at time t (identity without a skeleton). `posed` comes
// in as a copy of `rest`; it is only touched (skinned, geometry recomputed) when the pose moves it.
void poseSkin(const Scene& scene, double t, const coat::SkinMesh& rest, coat::SkinMesh& posed, TimeState& state);
// Sets coat.age / coat.present from the scene's moult settings at time t (all mature without).
void featherAges(const Scene& scene, double t, const std::vector<coat::TractParameterization>& params,
                 const coat::Follicles& follicles, TimeState& state, coat::CoatFeathers& coat);
// Expressive controls at time t: lifted feathers get fixed elevations (NaN = free) and directions.
void applyControls(const Scene& scene, double t, const coat::SkinMesh& posed, const coat::Follicles& follicles,
                   TimeState& state, coat::CoatFeathers& coat, std::vector<double>& fixedElevation);

// The frame's pack: when applyControls had to pack the frame without its raises (to find natural
// elevations), an incremental repack from that pack over the raised feathers (bit-identical to a full
// pack, coat/pack.hpp); else a full pack. The natural pack is used once, so a later re-pack of the same
// frame (e.g. after editing packing options) packs fully.
coat::PackResult packFrame(const coat::SkinMesh& posed, const coat::CoatFeathers& coat, const coat::PackOptions& options,
                           TimeState& state);

}  // namespace pteryla::pipeline
