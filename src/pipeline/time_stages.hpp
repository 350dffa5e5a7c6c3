#pragma once
// The time-dependent stages of the pipeline (thesis Ch.8 + AnimFur): skin pose, feather ages (moult)
// and expressive controls. Each is a pure function of (scene, t) and the rest-state results, so any
// time can be evaluated in any order. The work is done by src/moult; these hooks take the scene's typed
// settings (scene_settings.hpp) and keep what outlives a frame, keyed by what it was made from.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/packer.hpp"
#include "pteryla/coat/parameterize.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/feather/bend.hpp"
#include "pteryla/moult/chain.hpp"
#include "pteryla/moult/controls.hpp"
#include "pteryla/moult/schedule.hpp"
#include "pteryla/moult/skinning.hpp"
#include "scene_settings.hpp"

namespace pteryla::pipeline {

// A packer (coat::Packer: the pack, and the skin samples it keeps while the skin is unchanged) and the
// inputs its pack was computed from, so a later frame can repack incrementally (Packer::repack,
// bit-identical to a full pack) when only some feathers' packing inputs changed: same key (the rest state
// and the "packing" section), same posed skin; the frames, presence, opened/unopened class (the only way
// the packer reads a feather's age: PackOptions::openingAge) and fixed elevations are compared per
// feather. Which feathers changed is the memo's to say (it knows how the pipeline grew them); whether the
// pack and the samples still fit the skin and the options is the packer's.
struct PackMemo {
  InputKey key;                  // TimeState::packKey of the inputs (empty: nothing remembered)
  std::vector<glm::dvec3> skin;  // posed skin positions
  std::vector<coat::FeatherFrame> frames;
  std::vector<uint8_t> present, unopened;
  std::vector<double> fixed;  // per feather, NaN = free
  // Per feather, the age its packing parameters were grown to (1 = the rest parameters); empty = all 1.
  // Within a rest state a feather's packing parameters are a function of this age.
  std::vector<double> grownAge;
  coat::Packer packer;
  uint64_t version = 0;  // changes whenever the packer's result is replaced (remember)
  // The result is the full pack of its inputs (pack() or repack() from one), so it can seed a repack. A
  // posed frame's pack (packDeformed, or a repack seeded by one) is not: it is reused only for the very
  // same inputs, so that no frame's result depends on the frames evaluated before it.
  bool exact = true;

  const coat::PackResult& result() const { return packer.result(); }
  void clear() { *this = PackMemo{}; }
  // Feathers whose packing input differs from the memo's, or nullopt when the memo cannot seed a repack
  // (empty, another key, skin or feather count).
  // The options and the styling's constraints follow from the key (the "packing" section and the rest
  // state); fixed elevations are compared per feather.
  std::optional<std::vector<uint32_t>> changes(const coat::SkinMesh& skin, const coat::CoatFeathers& coat,
                                               const coat::PackOptions& options,
                                               const coat::PackConstraints& constraints, const InputKey& key,
                                               const std::vector<double>& grownAge = {}) const;
  // Records the inputs the packer's new result was packed from.
  void remember(const coat::SkinMesh& skin, const coat::CoatFeathers& coat, const coat::PackOptions& options,
                const coat::PackConstraints& constraints, const InputKey& key, const std::vector<double>& grownAge = {},
                bool exact = true);
};

// Posed frames (a skeleton moving the skin) pack with Packer::packDeformed from a reference pack: the same
// coat on the rest skin, with the frames it would have at rest (evaluated on the rest skin, styled as the
// scene styles them; expressive controls' turns are left out and so count as motion). Kept while its key
// (the rest state and the "packing" section) is unchanged.
struct PoseReference {
  InputKey key;                            // empty: not set up
  double tolerance = 0;                    // PackingSettings::poseTolerance (0: posed frames pack in full)
  std::vector<coat::FeatherFrame> frames;  // per feather, at rest
  coat::CoatFeathers coat;                 // scratch: the coat being packed, with `frames`
  PackMemo natural, frame;                 // the reference packs (exact) of the natural and the frame pack
};

// How the last frame's packs were made (diagnostics for tests and benchmarks).
struct PackReport {
  bool naturalIncremental = false, finalIncremental = false;
  size_t naturalChanged = 0, finalChanged = 0;  // feathers handed to repack as changed
  size_t naturalRecomputed = 0, finalRecomputed = 0;
  // Moult frames (packMoultFrame): the final* fields describe the mature coat's pack, these the lost and
  // growing feathers packed over it.
  bool moult = false;
  size_t moultChanged = 0, moultRecomputed = 0;
  // Posed frames: packs made by packDeformed this frame, with what they moved and repacked (summed).
  size_t deformedPacks = 0, poseMoved = 0, poseRepacked = 0;
};

// What the time stages keep across frames. Each cache is keyed by what it was made from (InputKey) and
// made again when that changes (scene edits, a new rest state), so a cache never changes a result.
struct TimeState {
  // The rest skin of the last poseSkin call (control bindings are made at rest).
  const coat::SkinMesh* rest = nullptr;

  // Skeleton (SceneSettings::skeleton).
  bool posedMoved = false;                     // the last pose moved the skin
  const moult::SkinRig* drivingRig = nullptr;  // the skeleton posing the skin this frame (null: none)
  InputKey drivingRigKey;                      // its SceneSettings::skeletonKey (empty: none)

  // Moult (SceneSettings::moult).
  moult::MoultStats moultStats;  // of the last evaluation
  // The plan depends only on rest data and the moult sections: kept while its key (the rest state and
  // SceneSettings::moultKey) is unchanged.
  std::optional<moult::CoatMoultPlan> moultPlan;
  InputKey moultPlanKey;

  // Controls (SceneSettings::controls).
  moult::ControlResult controlResult;  // of the last evaluation (its natural pack lives in `natural`)

  // Dynamic chains (moult/chain.hpp): one simulator per control with a dynamic behaviour, over the
  // follicles bound to it, kept with its checkpoints while `chainsKey` (controls, tract names, the driving
  // skeleton, the rest state, the follicle count) is unchanged. Their lags at the frame's time bend the
  // bound feathers (`bends`, per feather; empty: rigid), which the mesh stage applies.
  InputKey chainsKey;
  std::vector<std::unique_ptr<moult::ChainSim>> chains;  // per control (null: not dynamic)
  std::vector<std::vector<uint32_t>> chainFollicles;     // per control: the simulated follicles
  std::vector<feather::ShaftBend> bends;
  size_t chainSteps = 0, chainCount = 0;  // of the last evaluation: grid steps integrated, chains simulated

  // Packs remembered across frames (see PackMemo): the controls' natural pack and the frame's pack.
  uint64_t generation = 0;  // set by the pipeline: the rest state's revision (changes with it)
  InputKey packKey;         // set by the pipeline: the rest state and the "packing" section of this frame
  PackMemo natural, frame;
  // Moult frames: the lost and growing feathers packed over `frame` (which then holds the mature coat's
  // pack) and the version of `frame` it was packed over.
  PackMemo moultFrame;
  uint64_t moultBaseVersion = 0;
  // The coat as it would be without the moult (matureCoat): what a moult frame's pack and the controls'
  // natural pack in a moult frame pack. Its rest parameters are copied once per rest state.
  coat::CoatFeathers mature;
  InputKey matureKey;
  bool naturalThisFrame = false;  // `natural` holds the pack of the current frame without raises
  PoseReference poseRef;          // set up by the pipeline for posed frames
  coat::PackResult flatNatural;   // a draped coat's "natural pack": every elevation 0 (no pack is made)
  PackReport packReport;
};

// posed = rest deformed by the skeleton `rig` (SceneSettings::skeleton, its key `rigKey`) at time t
// (identity without one). `posed` comes in as a copy of `rest`; it is only touched (skinned, geometry
// recomputed) when the pose moves it.
void poseSkin(const moult::SkinRig* rig, const InputKey& rigKey, double t, const coat::SkinMesh& rest,
              coat::SkinMesh& posed, TimeState& state);
// Sets coat.age / coat.present from the per-tract moult options (SceneSettings::moult) at time t (all
// mature without). `planKey`: what the moult plan is made from (the rest state and the moult sections).
void featherAges(const std::vector<std::optional<moult::MoultOptions>>& options, const InputKey& planKey, double t,
                 const std::vector<coat::TractParameterization>& params, const coat::Follicles& follicles,
                 TimeState& state, coat::CoatFeathers& coat);
// Expressive controls (SceneSettings::controls, their key `controlsKey`) at time t: lifted feathers get
// fixed elevations (NaN = free) and directions; feathers under a dynamic control get state.bends.
// `packing`: the scene's packing settings (the natural pack's options and moult rule).
// `constraints`: the styling's (its fixedElevation is ignored: `fixedElevation` stands for it).
void applyControls(const ControlSettings& controls, const InputKey& controlsKey, const coat::PackingSettings& packing,
                   double t, const coat::SkinMesh& posed, const coat::Follicles& follicles, TimeState& state,
                   coat::CoatFeathers& coat, const coat::PackConstraints& constraints,
                   std::vector<double>& fixedElevation);

// The frames a carried drape's reference has (coat::drapeCarried): `restFrames` (the coat's frames on the
// rest skin) turned by the controls at time t as applyControls turns the posed frames, evaluated on the
// rest skin and rest follicles. Raises are left out: a drape reads no elevation.
std::vector<coat::FeatherFrame> restTurnedFrames(const ControlSettings& controls, const coat::PackOptions& options,
                                                 double t, const coat::SkinMesh& rest, const coat::Follicles& follicles,
                                                 const coat::CoatFeathers& coat,
                                                 const std::vector<coat::FeatherFrame>& restFrames,
                                                 const coat::PackConstraints& constraints);

// The dynamic controls' chains at time t (called by applyControls with its binding): state.bends, per
// feather of `coat`, the shaft bend of every present feather bound to a dynamic control (scaled by the
// control's dynamic value times the binding weight); empty elsewhere.
void applyChains(const ControlSettings& controls, const InputKey& controlsKey, double t,
                 const coat::Follicles& follicles, const moult::ControlBinding& binding, TimeState& state,
                 const coat::CoatFeathers& coat);

// The frame's pack (state.frame.result()): an incremental repack (bit-identical to a full pack,
// coat/pack.hpp) from whichever remembered pack differs in fewer feathers, the previous frame's pack or
// this frame's natural pack (which differs in the raised feathers only); a full pack when neither fits.
// grownAge: per feather, the age `coat`'s parameters were grown to (PackMemo::grownAge; empty = all 1).
const coat::PackResult& packFrame(const coat::SkinMesh& posed, const coat::CoatFeathers& coat,
                                  const coat::PackOptions& options, const coat::PackConstraints& constraints,
                                  TimeState& state, const std::vector<double>& grownAge = {});

// True when some feather of `coat` is lost or growing at this time.
bool moulting(const coat::CoatFeathers& coat);
// `coat` with every feather present and mature (age 1), in its current frames: state.mature, its rest
// parameters copied from `coat` once per rest state (coat's parameters must be the rest ones).
const coat::CoatFeathers& matureCoat(const coat::CoatFeathers& coat, TimeState& state);

// A moult frame's pack (state.moultFrame.result()): the mature coat (every feather present, with its rest
// parameters, same frames and fixed elevations) is packed as packFrame packs a frame without a moult
// (into state.frame), then the lost and growing feathers of `coat` are packed over it (Packer::packOver):
// mature feathers keep their pose, so a lost feather leaves a gap and a growing one fills in under the
// feathers over it. Reused when neither the mature pack nor this frame's lost/growing feathers changed.
const coat::PackResult& packMoultFrame(const coat::SkinMesh& posed, const coat::CoatFeathers& mature,
                                       const coat::CoatFeathers& coat, const coat::PackOptions& options,
                                       const coat::PackConstraints& constraints, TimeState& state,
                                       const std::vector<double>& grownAge);

}  // namespace pteryla::pipeline
