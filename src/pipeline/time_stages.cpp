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

std::string tractName(const Scene& scene, size_t i) {
  if (i < scene.tracts.size() && scene.tracts[i].is_object()) {
    const auto it = scene.tracts[i].find("name");
    if (it != scene.tracts[i].end() && it->is_string()) return it->get<std::string>();
  }
  return {};
}

void parseMoult(const Scene& scene, TimeState& state) {
  Json key = {{"file", scene.file}, {"moult", scene.moult}, {"tracts", Json::array()}};
  for (size_t i = 0; i < scene.tracts.size(); ++i) {
    const Json& t = scene.tracts[i];
    key["tracts"].push_back(t.is_object() && t.contains("moult") ? t.at("moult") : Json());
  }
  if (state.moultParsed && key == state.moultKey) return;
  state.moultParsed = false;
  state.moultPlan.reset();
  state.moultOptions.assign(scene.tracts.size(), std::nullopt);
  std::optional<moult::MoultOptions> defaults;
  if (!scene.moult.empty()) {
    JsonReader r(scene.moult, scene.file, "moult");
    defaults = moult::readMoultOptions(r);
  }
  for (size_t i = 0; i < scene.tracts.size(); ++i) {
    const Json& sec = key["tracts"][i];
    const std::string where = "tracts[" + std::to_string(i) + "].moult";
    if (sec.is_null()) {
      state.moultOptions[i] = defaults;
    } else if (sec.is_boolean()) {
      if (sec.get<bool>()) state.moultOptions[i] = defaults ? *defaults : moult::MoultOptions{};
    } else if (sec.is_object()) {
      JsonReader r(sec, scene.file, where);
      state.moultOptions[i] = moult::readMoultOptions(r, defaults ? *defaults : moult::MoultOptions{});
    } else {
      throw Error("expected a moult object (overrides of the scene's \"moult\") or true/false", scene.file, where);
    }
    if (state.moultOptions[i] && !state.moultOptions[i]->enabled) state.moultOptions[i].reset();
  }
  state.moultKey = std::move(key);
  state.moultParsed = true;
}

void parseRig(const Scene& scene, const coat::SkinMesh& rest, TimeState& state) {
  const Json key = {{"file", scene.file}, {"skeleton", scene.skeleton}, {"vertices", rest.vertexCount()}};
  if (key == state.rigKey) return;
  state.rig.reset();
  state.rigKey = Json();
  if (!scene.skeleton.empty()) {
    JsonReader r(scene.skeleton, scene.file, "skeleton");
    state.rig = moult::readSkinRig(r, rest.vertexCount());
  }
  state.rigKey = key;
}

void parseControls(const Scene& scene, TimeState& state) {
  Json names = Json::array();
  for (size_t i = 0; i < scene.tracts.size(); ++i) names.push_back(tractName(scene, i));
  Json key = {{"file", scene.file}, {"controls", scene.controls}, {"packing", scene.packing}, {"tracts", names}};
  if (state.controlsParsed && key == state.controlsKey) return;
  state.controlsParsed = false;
  state.controls = moult::readControls(scene.controls, scene.file, "controls");
  state.controlTracts.assign(state.controls.size(), {});
  for (size_t c = 0; c < state.controls.size(); ++c) {
    const auto& wanted = state.controls[c].tracts;
    for (size_t k = 0; k < wanted.size(); ++k) {
      bool found = false;
      for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == wanted[k]) {
          state.controlTracts[c].push_back(static_cast<uint32_t>(i));
          found = true;
        }
      if (!found)
        throw Error("unknown tract '" + wanted[k] + "'", scene.file,
                    "controls[" + std::to_string(c) + "].tracts[" + std::to_string(k) + "]");
    }
  }
  state.packing = coat::PackingSettings{};
  if (!scene.packing.empty()) {
    JsonReader r(scene.packing, scene.file, "packing");
    state.packing = coat::parsePackingSettings(r);
  }
  state.controlsKey = std::move(key);
  state.controlsParsed = true;
}

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
  if (!p || !p->rest || !p->ref || !p->ref->valid || !(p->ref->tolerance > 0) || p->ref->frames.size() != coat.size())
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
                                     const coat::PackConstraints& constraints, uint64_t generation, const Json& packing,
                                     bool& incremental, size_t& changedCount, size_t& recomputed,
                                     const std::vector<double>& grownAge = {}, const Posed* posed = nullptr) {
  std::optional<std::vector<uint32_t>> changed =
      memo.changes(skin, coat, options, constraints, generation, packing, grownAge);
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
    std::optional<std::vector<uint32_t>> alt =
        alternative->changes(skin, coat, options, constraints, generation, packing, grownAge);
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
        packWithMemo(*posed->refMemo, nullptr, *posed->rest, referenceCoat(coat, ref), options, constraints, generation,
                     packing, refIncremental, refChanged, refRecomputed, grownAge);
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
  memo.remember(skin, coat, options, constraints, generation, packing, grownAge, exact);
  return memo.result();
}

}  // namespace

std::optional<std::vector<uint32_t>> PackMemo::changes(const coat::SkinMesh& skinNow, const coat::CoatFeathers& coat,
                                                       const coat::PackOptions& options,
                                                       const coat::PackConstraints& constraints, uint64_t gen,
                                                       const Json& packingNow,
                                                       const std::vector<double>& grownAgeNow) const {
  const size_t n = coat.size();
  if (!valid || gen != generation || frames.size() != n || coat.frames.size() != n || packingNow != packing)
    return std::nullopt;
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
                        const coat::PackConstraints& constraints, uint64_t gen, const Json& packingNow,
                        const std::vector<double>& grownAgeNow, bool isExact) {
  const size_t n = coat.size();
  valid = true;
  exact = isExact;
  generation = gen;
  packing = packingNow;
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

void poseSkin(const Scene& scene, double t, const coat::SkinMesh& rest, coat::SkinMesh& posed, TimeState& state) {
  state.rest = &rest;
  state.posedMoved = false;
  parseRig(scene, rest, state);
  state.drivingRig = state.rig ? &*state.rig : nullptr;
  if (!state.rig) return;
  const moult::SkeletonPose pose = moult::poseAt(state.rig->animation, t);
  state.posedMoved = moult::poseSkinMesh(state.rig->skeleton, pose, rest, posed);
}

void featherAges(const Scene& scene, double t, const std::vector<coat::TractParameterization>& params,
                 const coat::Follicles& follicles, TimeState& state, coat::CoatFeathers& coat) {
  parseMoult(scene, state);
  state.moultStats = moult::MoultStats{};
  bool any = false;
  for (const auto& o : state.moultOptions) any = any || o.has_value();
  if (!any) {
    coat.age.assign(coat.size(), 1.0);
    coat.present.assign(coat.size(), 1);
    state.moultStats.old = coat.size();
    return;
  }
  // The plan depends only on rest data (parameterization, feather sizes, ids) and the moult sections:
  // planned once per rest state (generation) and section edit.
  if (!state.moultPlan || state.moultPlanGeneration != state.generation) {
    state.moultPlan = moult::planCoatMoult(params, follicles, coat, state.moultOptions);
    state.moultPlanGeneration = state.generation;
  }
  state.moultStats = moult::applyMoult(*state.moultPlan, t, coat);
}

void applyControls(const Scene& scene, double t, const coat::SkinMesh& posed, const coat::Follicles& follicles,
                   TimeState& state, coat::CoatFeathers& coat, const coat::PackConstraints& constraints,
                   std::vector<double>& fixedElevation) {
  state.controlResult = moult::ControlResult{};
  state.packReport = PackReport{};
  state.bends.clear();
  if (scene.controls.empty()) return;
  parseControls(scene, state);
  if (state.controls.empty()) return;
  const coat::SkinMesh& rest = state.rest ? *state.rest : posed;
  const moult::ControlBinding binding = moult::bindControls(rest, follicles, state.controls, state.controlTracts);
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
    const coat::CoatFeathers& input = state.packing.moultOver && moulting(c) ? matureCoat(c, state) : c;
    const Posed posed{state.rest, &state.poseRef, &state.poseRef.natural, &state.packReport};
    return packWithMemo(state.natural, {}, skin, input, o, k, state.generation, scene.packing,
                        state.packReport.naturalIncremental, state.packReport.naturalChanged,
                        state.packReport.naturalRecomputed, {}, &posed);
  };
  state.controlResult = moult::evaluateControls(state.controls, binding, posed, follicles, t, state.packing.options,
                                                constraints, coat, fixedElevation, natural);
  applyChains(scene, t, follicles, binding, state, coat);
}

const coat::PackResult& packFrame(const Scene& scene, const coat::SkinMesh& posed, const coat::CoatFeathers& coat,
                                  const coat::PackOptions& options, const coat::PackConstraints& constraints,
                                  TimeState& state, const std::vector<double>& grownAge) {
  PackReport& r = state.packReport;
  // Controls that ran a natural pack this frame make it a candidate seed: it differs from this frame's
  // pack in the raised feathers only.
  const PackMemo* alternative = state.controlResult.naturalPacked ? &state.natural : nullptr;
  const Posed p{state.rest, &state.poseRef, &state.poseRef.frame, &r};
  return packWithMemo(state.frame, alternative, posed, coat, options, constraints, state.generation, scene.packing,
                      r.finalIncremental, r.finalChanged, r.finalRecomputed, grownAge, &p);
}

bool moulting(const coat::CoatFeathers& coat) {
  for (size_t i = 0; i < coat.size(); ++i)
    if (presentAt(coat, i) == 0 || (!coat.age.empty() && coat.age[i] < kMature)) return true;
  return false;
}

const coat::CoatFeathers& matureCoat(const coat::CoatFeathers& coat, TimeState& state) {
  if (state.matureGeneration != state.generation || state.mature.size() != coat.size()) {
    state.mature = coat;
    state.mature.age.assign(coat.size(), kMature);
    state.mature.present.assign(coat.size(), 1);
    state.matureGeneration = state.generation;
  }
  state.mature.frames = coat.frames;
  return state.mature;
}

const coat::PackResult& packMoultFrame(const Scene& scene, const coat::SkinMesh& posed,
                                       const coat::CoatFeathers& mature, const coat::CoatFeathers& coat,
                                       const coat::PackOptions& options, const coat::PackConstraints& constraints,
                                       TimeState& state, const std::vector<double>& grownAge) {
  PackReport& r = state.packReport;
  r.moult = true;
  const PackMemo* alternative = state.controlResult.naturalPacked ? &state.natural : nullptr;
  const Posed p{state.rest, &state.poseRef, &state.poseRef.frame, &r};
  const coat::PackResult& base =
      packWithMemo(state.frame, alternative, posed, mature, options, constraints, state.generation, scene.packing,
                   r.finalIncremental, r.finalChanged, r.finalRecomputed, {}, &p);
  // What differs from the mature coat: lost feathers, and growing ones (grown packing parameters, or the
  // packer's unopened class).
  std::vector<uint32_t> changed;
  for (uint32_t i = 0; i < coat.size(); ++i) {
    const bool grown = !grownAge.empty() && !sameBits(&grownAge[i], &kMature, sizeof(double));
    if (!presentAt(coat, i) || grown || unopenedAt(coat, i, options)) changed.push_back(i);
  }
  r.moultChanged = changed.size();
  const std::optional<std::vector<uint32_t>> diff =
      state.moultFrame.changes(posed, coat, options, constraints, state.generation, scene.packing, grownAge);
  if (diff && diff->empty() && state.moultBaseVersion == state.frame.version) {
    r.moultRecomputed = 0;
    return state.moultFrame.result();
  }
  coat::Packer& packer = state.moultFrame.packer;
  packer.use(posed, options);
  r.moultRecomputed = packer.packOver(base, coat, changed, constraints).stats.recomputed;
  state.moultBaseVersion = state.frame.version;
  state.moultFrame.remember(posed, coat, options, constraints, state.generation, scene.packing, grownAge);
  return state.moultFrame.result();
}

}  // namespace pteryla::pipeline
