#pragma once
// The time-dependent stages of the pipeline (thesis Ch.8 + AnimFur): skin pose, feather ages (moult)
// and expressive controls. Each is a pure function of (scene, t) and the rest-state results, so any
// time can be evaluated in any order.
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/parameterize.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/pipeline/scene.hpp"

namespace pteryla::pipeline {

// Parsed time settings, cached across frames (filled on first use from the scene).
struct TimeState {
  bool parsed = false;
};

// posed = rest deformed by the scene's skeleton at time t (identity without a skeleton).
void poseSkin(const Scene& scene, double t, const coat::SkinMesh& rest, coat::SkinMesh& posed, TimeState& state);
// Sets coat.age / coat.present from the scene's moult settings at time t (all mature without).
void featherAges(const Scene& scene, double t, const std::vector<coat::TractParameterization>& params,
                 const coat::Follicles& follicles, TimeState& state, coat::CoatFeathers& coat);
// Expressive controls at time t: lifted feathers get fixed elevations (NaN = free) and directions.
void applyControls(const Scene& scene, double t, const coat::SkinMesh& posed, const coat::Follicles& follicles,
                   TimeState& state, coat::CoatFeathers& coat, std::vector<double>& fixedElevation);

}  // namespace pteryla::pipeline
