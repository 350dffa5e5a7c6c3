// Time stages of the pipeline: skin pose (Streit 2003, 8.3), moult (8.1-8.2) and expressive controls
// (AnimFur, Grier 2019) read from the scene and evaluated by src/moult.
#include "time_stages.hpp"

#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <utility>

#include "pteryla/core/error.hpp"

namespace pteryla::pipeline {

namespace {

constexpr double kMature = 1.0;
bool sameBits(const void* a, const void* b, size_t bytes) { return bytes == 0 || std::memcmp(a, b, bytes) == 0; }

bool sameFixed(double a, double b) { return (std::isnan(a) && std::isnan(b)) || sameBits(&a, &b, sizeof(double)); }

double fixedAt(const coat::PackConstraints& k, size_t i) {
  return k.fixedElevation.empty() ? std::numeric_limits<double>::quiet_NaN() : k.fixedElevation[i];
}

uint8_t unopenedAt(const coat::CoatFeathers& c, size_t i, const coat::PackOptions& o) {
  return !c.age.empty() && c.age[i] < o.openingAge ? 1 : 0;
}

uint8_t presentAt(const coat::CoatFeathers& c, size_t i) { return c.present.empty() ? 1 : c.present[i]; }

// A posed frame's skin: the rest skin moved by the pose (PoseReference).
struct Posed {
  const coat::SkinMesh* rest = nullptr;
  PoseReference* ref = nullptr;
  PackMemo* refMemo = nullptr;  // the reference pack's memo (ref->natural or ref->frame)
  PackReport* report = nullptr;
};

bool posedSkin(const Posed* p, const coat::SkinMesh& skin, const coat::CoatFeathers& coat) {
  if (!p || !p->rest || !p->ref || p->ref->key.empty() || !(p->ref->tolerance > 0) ||
      p->ref->frames.size() != coat.size())
    return false;
  const auto& a = skin.positions;
  const auto& b = p->rest->positions;
  return a.size() == b.size() && !sameBits(a.data(), b.data(), a.size() * sizeof(glm::dvec3));
}

// `coat` with the reference frames (into ref.coat, reusing its storage). The parameters change only with
// the rest state or a moult's grown feathers: they are compared first, not copied every posed frame.
const coat::CoatFeathers& referenceCoat(const coat::CoatFeathers& coat, PoseReference& ref) {
  coat::CoatFeathers& c = ref.coat;
  c.follicle = coat.follicle;
  c.tract = coat.tract;
  if (c.params != coat.params) c.params = coat.params;
  if (c.frames.size() != ref.frames.size()) c.frames = ref.frames;
  c.age = coat.age;
  c.present = coat.present;
  c.layerOrder = coat.layerOrder;
  return c;
}

// Packs `coat` through `memo`: reuses the memo's result when no feather's input changed, repacks
// incrementally from the memo (or from `alternative` when that differs in fewer feathers), else packs
// fully. The memo then holds this pack. On a posed skin (`posed`), the pack is packDeformed's from the
// reference pack (itself through the reference memo, on the rest skin), or a repack from `alternative`
// (this frame's natural pack); the memo seeds nothing then, so the result never depends on history.
const coat::PackResult& packWithMemo(PackMemo& memo, const PackMemo* alternative, const coat::SkinMesh& skin,
                                     const coat::CoatFeathers& coat, const coat::PackOptions& options,
                                     const coat::PackConstraints& constraints, const InputKey& key, bool& incremental,
                                     size_t& changedCount, size_t& recomputed, const std::vector<double>& grownAge = {},
                                     const Posed* posed = nullptr) {
  std::optional<std::vector<uint32_t>> changed = memo.changes(skin, coat, options, constraints, key, grownAge);
  if (changed && changed->empty()) {
    incremental = true;
    changedCount = 0;
    recomputed = 0;
    return memo.result();  // same inputs, same pack
  }
  const bool deformed = posedSkin(posed, skin, coat);
  if (!memo.exact || deformed) changed.reset();
  const PackMemo* seed = changed ? &memo : nullptr;
  if (alternative && alternative != &memo && (alternative->exact || deformed)) {
    std::optional<std::vector<uint32_t>> alt = alternative->changes(skin, coat, options, constraints, key, grownAge);
    if (alt && (!changed || alt->size() < changed->size())) {
      changed = std::move(alt);
      seed = alternative;
    }
  }
  incremental = seed != nullptr;
  changedCount = changed ? changed->size() : coat.size();
  coat::Packer& packer = memo.packer;
  packer.use(skin, options);
  bool exact = true;
  if (seed) {
    if (seed == &memo)
      packer.repack(coat, *changed, constraints);
    else if (changed->empty())
      packer.assign(seed->result());  // the same inputs as the seed's: its pack
    else
      packer.repackFrom(seed->result(), coat, *changed, constraints);
    exact = seed->exact;
  } else if (deformed) {
    PoseReference& ref = *posed->ref;
    bool refIncremental = false;
    size_t refChanged = 0, refRecomputed = 0;
    const coat::PackResult& base =
        packWithMemo(*posed->refMemo, nullptr, *posed->rest, referenceCoat(coat, ref), options, constraints, key,
                     refIncremental, refChanged, refRecomputed, grownAge);
    coat::DeformedPackStats ds;
    packer.packDeformed(coat, *posed->rest, ref.frames, base, ref.tolerance, constraints, &ds);
    exact = false;
    if (posed->report) {
      ++posed->report->deformedPacks;
      posed->report->poseMoved += ds.moved;
      posed->report->poseRepacked += ds.repacked;
    }
  } else {
    packer.pack(coat, constraints);
  }
  recomputed = packer.result().stats.recomputed;
  memo.remember(skin, coat, options, constraints, key, grownAge, exact);
  return memo.result();
}

}  // namespace

std::optional<std::vector<uint32_t>> PackMemo::changes(const coat::SkinMesh& skinNow, const coat::CoatFeathers& coat,
                                                       const coat::PackOptions& options,
                                                       const coat::PackConstraints& constraints, const InputKey& keyNow,
                                                       const std::vector<double>& grownAgeNow) const {
  const size_t n = coat.size();
  if (key.empty() || keyNow != key || frames.size() != n || coat.frames.size() != n) return std::nullopt;
  if (!constraints.fixedElevation.empty() && constraints.fixedElevation.size() != n) return std::nullopt;
  if (skinNow.positions.size() != skin.size() ||
      !sameBits(skinNow.positions.data(), skin.data(), skin.size() * sizeof(glm::dvec3)))
    return std::nullopt;
  std::vector<uint32_t> out;
  for (size_t i = 0; i < n; ++i) {
    const bool same = sameBits(&coat.frames[i], &frames[i], sizeof(coat::FeatherFrame)) &&
                      presentAt(coat, i) == present[i] && unopenedAt(coat, i, options) == unopened[i] &&
                      sameFixed(fixedAt(constraints, i), fixed[i]) &&
                      sameBits(&(grownAgeNow.empty() ? kMature : grownAgeNow[i]),
                               &(grownAge.empty() ? kMature : grownAge[i]), sizeof(double));
    if (!same) out.push_back(static_cast<uint32_t>(i));
  }
  return out;
}

void PackMemo::remember(const coat::SkinMesh& skinNow, const coat::CoatFeathers& coat, const coat::PackOptions& options,
                        const coat::PackConstraints& constraints, const InputKey& keyNow,
                        const std::vector<double>& grownAgeNow, bool isExact) {
  const size_t n = coat.size();
  exact = isExact;
  key = keyNow;
  skin = skinNow.positions;
  frames = coat.frames;
  present.resize(n);
  unopened.resize(n);
  fixed.resize(n);
  for (size_t i = 0; i < n; ++i) {
    present[i] = presentAt(coat, i);
    unopened[i] = unopenedAt(coat, i, options);
    fixed[i] = fixedAt(constraints, i);
  }
  grownAge = grownAgeNow;
  static std::atomic<uint64_t> versions{0};
  version = ++versions;
}

void poseSkin(const moult::SkinRig* rig, const InputKey& rigKey, double t, const coat::SkinMesh& rest,
              coat::SkinMesh& posed, TimeState& state) {
  state.rest = &rest;
  state.posedMoved = false;
  state.drivingRig = rig;
  state.drivingRigKey = rig ? rigKey : InputKey{};
  if (!rig) return;
  const moult::SkeletonPose pose = moult::poseAt(rig->animation, t);
  state.posedMoved = moult::poseSkinMesh(rig->skeleton, pose, rest, posed);
}

void featherAges(const std::vector<std::optional<moult::MoultOptions>>& options, const InputKey& planKey, double t,
                 const std::vector<coat::TractParameterization>& params, const coat::Follicles& follicles,
                 TimeState& state, coat::CoatFeathers& coat) {
  state.moultStats = moult::MoultStats{};
  bool any = false;
  for (const auto& o : options) any = any || o.has_value();
  if (!any) {
    coat.age.assign(coat.size(), 1.0);
    coat.present.assign(coat.size(), 1);
    state.moultStats.old = coat.size();
    return;
  }
  // The plan depends only on rest data (parameterization, feather sizes, ids) and the moult sections:
  // planned once per rest state and section edit.
  if (!state.moultPlan || state.moultPlanKey != planKey) {
    state.moultPlan.reset();
    state.moultPlan = moult::planCoatMoult(params, follicles, coat, options);
    state.moultPlanKey = planKey;
  }
  state.moultStats = moult::applyMoult(*state.moultPlan, t, coat);
}

void applyControls(const ControlSettings& controls, const InputKey& controlsKey, const coat::PackingSettings& packing,
                   double t, const coat::SkinMesh& posed, const coat::Follicles& follicles, TimeState& state,
                   coat::CoatFeathers& coat, const coat::PackConstraints& constraints,
                   std::vector<double>& fixedElevation) {
  state.controlResult = moult::ControlResult{};
  state.packReport = PackReport{};
  state.bends.clear();
  if (controls.controls.empty()) return;
  const coat::SkinMesh& rest = state.rest ? *state.rest : posed;
  const moult::ControlBinding binding = moult::bindControls(rest, follicles, controls.controls, controls.tracts);
  // The natural pack (the frame without its raises) repacks from the last natural pack when it can.
  // In a moult frame the natural pack is the mature coat's (every feather present and mature): the moult
  // packs its lost and growing feathers over the mature coat (packMoultFrame), so raises start from the
  // mature coat's elevations, and that pack changes only with the pose and the controls' turns.
  const moult::NaturalPackFn natural = [&](const coat::SkinMesh& skin, const coat::CoatFeathers& c,
                                           const coat::PackOptions& o,
                                           const coat::PackConstraints& k) -> const coat::PackResult& {
    // A draped coat lies along the skin whatever its elevations (the drape reads none): raises start
    // from 0, and no height-field pack is made for them.
    if (o.method == coat::PackMethod::Drape) {
      state.flatNatural.elevation.assign(c.size(), 0.0);
      return state.flatNatural;
    }
    const coat::CoatFeathers& input = packing.moultOver && moulting(c) ? matureCoat(c, state) : c;
    const Posed posed{state.rest, &state.poseRef, &state.poseRef.natural, &state.packReport};
    return packWithMemo(state.natural, {}, skin, input, o, k, state.packKey, state.packReport.naturalIncremental,
                        state.packReport.naturalChanged, state.packReport.naturalRecomputed, {}, &posed);
  };
  state.controlResult = moult::evaluateControls(controls.controls, binding, posed, follicles, t, packing.options,
                                                constraints, coat, fixedElevation, natural);
  applyChains(controls, controlsKey, t, follicles, binding, state, coat);
}

std::vector<coat::FeatherFrame> restTurnedFrames(const ControlSettings& controls, const coat::PackOptions& options,
                                                 double t, const coat::SkinMesh& rest, const coat::Follicles& follicles,
                                                 const coat::CoatFeathers& coat,
                                                 const std::vector<coat::FeatherFrame>& restFrames,
                                                 const coat::PackConstraints& constraints) {
  coat::CoatFeathers c;
  c.follicle = coat.follicle;
  c.tract = coat.tract;
  c.params = coat.params;
  c.frames = restFrames;
  c.age = coat.age;
  c.present = coat.present;
  c.layerOrder = coat.layerOrder;
  if (controls.controls.empty()) return std::move(c.frames);
  const moult::ControlBinding binding = moult::bindControls(rest, follicles, controls.controls, controls.tracts);
  std::vector<double> fixed(c.size(), std::nan(""));
  coat::PackResult flat;
  flat.order = c.layerOrder;
  flat.elevation.assign(c.size(), 0.0);
  moult::evaluateControls(controls.controls, binding, rest, follicles, t, options, constraints, c, fixed,
                          [&](const coat::SkinMesh&, const coat::CoatFeathers&, const coat::PackOptions&,
                              const coat::PackConstraints&) -> const coat::PackResult& { return flat; });
  return std::move(c.frames);
}

const coat::PackResult& packFrame(const coat::SkinMesh& posed, const coat::CoatFeathers& coat,
                                  const coat::PackOptions& options, const coat::PackConstraints& constraints,
                                  TimeState& state, const std::vector<double>& grownAge) {
  PackReport& r = state.packReport;
  // Controls that ran a natural pack this frame make it a candidate seed: it differs from this frame's
  // pack in the raised feathers only.
  const PackMemo* alternative = state.controlResult.naturalPacked ? &state.natural : nullptr;
  const Posed p{state.rest, &state.poseRef, &state.poseRef.frame, &r};
  return packWithMemo(state.frame, alternative, posed, coat, options, constraints, state.packKey, r.finalIncremental,
                      r.finalChanged, r.finalRecomputed, grownAge, &p);
}

bool moulting(const coat::CoatFeathers& coat) {
  for (size_t i = 0; i < coat.size(); ++i)
    if (presentAt(coat, i) == 0 || (!coat.age.empty() && coat.age[i] < kMature)) return true;
  return false;
}

const coat::CoatFeathers& matureCoat(const coat::CoatFeathers& coat, TimeState& state) {
  const InputKey key{state.generation};
  if (state.matureKey != key || state.mature.size() != coat.size()) {
    state.mature = coat;
    state.mature.age.assign(coat.size(), kMature);
    state.mature.present.assign(coat.size(), 1);
    state.matureKey = key;
  }
  state.mature.frames = coat.frames;
  return state.mature;
}

const coat::PackResult& packMoultFrame(const coat::SkinMesh& posed, const coat::CoatFeathers& mature,
                                       const coat::CoatFeathers& coat, const coat::PackOptions& options,
                                       const coat::PackConstraints& constraints, TimeState& state,
                                       const std::vector<double>& grownAge) {
  PackReport& r = state.packReport;
  r.moult = true;
  const PackMemo* alternative = state.controlResult.naturalPacked ? &state.natural : nullptr;
  const Posed p{state.rest, &state.poseRef, &state.poseRef.frame, &r};
  const coat::PackResult& base =
      packWithMemo(state.frame, alternative, posed, mature, options, constraints, state.packKey, r.finalIncremental,
                   r.finalChanged, r.finalRecomputed, {}, &p);
  // What differs from the mature coat: lost feathers, and growing ones (grown packing parameters, or the
  // packer's unopened class).
  std::vector<uint32_t> changed;
  for (uint32_t i = 0; i < coat.size(); ++i) {
    const bool grown = !grownAge.empty() && !sameBits(&grownAge[i], &kMature, sizeof(double));
    if (!presentAt(coat, i) || grown || unopenedAt(coat, i, options)) changed.push_back(i);
  }
  r.moultChanged = changed.size();
  const std::optional<std::vector<uint32_t>> diff =
      state.moultFrame.changes(posed, coat, options, constraints, state.packKey, grownAge);
  if (diff && diff->empty() && state.moultBaseVersion == state.frame.version) {
    r.moultRecomputed = 0;
    return state.moultFrame.result();
  }
  coat::Packer& packer = state.moultFrame.packer;
  packer.use(posed, options);
  r.moultRecomputed = packer.packOver(base, coat, changed, constraints).stats.recomputed;
  state.moultBaseVersion = state.frame.version;
  state.moultFrame.remember(posed, coat, options, constraints, state.packKey, grownAge);
  return state.moultFrame.result();
}

}  // namespace pteryla::pipeline
