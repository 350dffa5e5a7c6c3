// The evaluation pipeline: one StageGraph node per stage of the thesis' method (Streit 2003, Ch.6-8),
// each owning its cached result. See include/pteryla/pipeline/pipeline.hpp for the graph. This file
// holds the graph, the time stages (pose to mesh: Ch.7-8) and the public API; the rest stages (skin to
// directions: Ch.6) are in rest_stages.cpp, the mesher in coat_mesher.cpp.
#include "pteryla/pipeline/pipeline.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "pipeline_impl.hpp"
#include "pteryla/coat/check.hpp"
#include "pteryla/coat/metrics.hpp"
#include "pteryla/coat/style.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/feather/mesh.hpp"

namespace pteryla::pipeline {

const char* stageName(Stage s) {
  switch (s) {
    case Stage::Skin:
      return "skin";
    case Stage::Tracts:
      return "tracts";
    case Stage::Distribute:
      return "distribute";
    case Stage::Interpolate:
      return "interpolate";
    case Stage::Directions:
      return "directions";
    case Stage::Pose:
      return "pose";
    case Stage::Ages:
      return "ages";
    case Stage::Controls:
      return "controls";
    case Stage::Pack:
      return "pack";
    case Stage::Mesh:
      return "mesh";
  }
  return "?";
}

void Pipeline::Impl::build() {
  auto add = [&](Stage s, std::vector<Stage> in, void (Impl::*fn)()) {
    std::vector<StageGraph::Id> inputs;
    for (Stage i : in) inputs.push_back(id(i));
    const StageGraph::Id added = graph.add(stageName(s), inputs, [this, fn] { (this->*fn)(); });
    PTERYLA_CHECK(added == id(s), "stages are added in the order of pipeline::Stage");
  };
  add(Stage::Skin, {}, &Impl::computeSkin);
  add(Stage::Tracts, {Stage::Skin}, &Impl::computeTracts);
  add(Stage::Distribute, {Stage::Tracts}, &Impl::computeDistribute);
  add(Stage::Interpolate, {Stage::Distribute}, &Impl::computeInterpolate);
  add(Stage::Directions, {Stage::Interpolate}, &Impl::computeDirections);
  add(Stage::Pose, {Stage::Directions}, &Impl::computePose);
  add(Stage::Ages, {Stage::Pose}, &Impl::computeAges);
  add(Stage::Controls, {Stage::Ages}, &Impl::computeControls);
  add(Stage::Pack, {Stage::Controls}, &Impl::computePack);
  add(Stage::Mesh, {Stage::Pack}, &Impl::computeMesh);
}

void Pipeline::Impl::computePose() {
  timeState.generation = restGeneration();
  if (!skinPose.empty()) {
    // The caller's pose (setSkinPose) replaces the skeleton's. Checked against the rest skin again here:
    // a scene edit may have changed the mesh since it was set.
    if (skinPose.size() != rest.positions.size())
      throw Error("the skin pose has " + std::to_string(skinPose.size()) + " vertices, the skin " +
                      std::to_string(rest.positions.size()),
                  scene.file, "pose");
    posed = rest;
    posed.positions = skinPose;
    coat::recomputeGeometry(posed);
    timeState.rest = &rest;
    timeState.posedMoved = true;
    timeState.drivingRig = nullptr;
    timeState.drivingRigKey = InputKey{};
    posedKey = InputKey{};
  } else {
    const size_t vertices = rest.vertexCount();
    const moult::SkinRig* rig = settings.skeleton(scene, vertices);
    // poseSkin wants `posed` as a copy of `rest` and touches it only when the pose moves the skin.
    if (posedKey != restKey()) posed = rest;
    posedKey = InputKey{};
    poseSkin(rig, settings.skeletonKey(vertices), time, rest, posed, timeState);
    if (!timeState.posedMoved) posedKey = restKey();
  }
  posedFollicles = follicles;
  coat::updateFollicleGeometry(posed, posedFollicles);
  // Rest data (params, follicles, layer order) is copied once per rest state; the time stages rewrite
  // frames, ages and presence every frame.
  if (coatNowKey != restKey()) {
    coatNow = coatRest;
    coatNowKey = restKey();
  }
  coat::evaluateFrames(posed, posedFollicles, directions, coatNow);
}

void Pipeline::Impl::computeAges() {
  coatNow.age.assign(coatNow.size(), 1.0);
  coatNow.present.assign(coatNow.size(), 1);
  const auto& moult = settings.moult(scene);
  featherAges(moult, restKey().add(settings.moultKey()), time, params, posedFollicles, timeState, coatNow);
}

// Packing options (and their styling selections) are read here so a packing edit only repacks.
void Pipeline::Impl::computeControls() {
  const coat::PackingSettings& packing = settings.packing(scene);
  timeState.packKey = restKey().add(settings.packingKey());
  packOptions = packing.options;
  moultOver = packing.moultOver;
  carryPosedDrape = packing.carryPosedDrape;
  fixedElevation.assign(coatNow.size(), std::nan(""));
  constraints = coat::PackConstraints{};
  // Styling is resolved here, once per frame, into fixed elevations, frames and the packer's constraints.
  if (!packing.styling.empty()) {
    try {
      fixedElevation = coat::applyStyling(coatNow, packing.styling, fixedElevation).fixedElevation;
      constraints.minElevation = coat::resolveMinElevation(coatNow, packing.styling);
      constraints.shaftBand = coat::resolveShaftBand(coatNow, packing.styling);
    } catch (const Error& e) {
      if (!e.file().empty()) throw;
      throw Error(e.detail(), scene.file, "packing." + e.element());  // "styling[0].ids[3]" is under packing
    }
  }
  // The caller's fixed elevations win over styling; expressive controls still raise on top of them.
  if (!hostElevations.empty())
    for (size_t i = 0; i < coatNow.size(); ++i)
      if (auto it = hostElevations.find(follicles.id[coatNow.follicle[i]]); it != hostElevations.end())
        fixedElevation[i] = it->second;
  // Posed frames pack from the rest pose's pack (packDeformed): the frames the coat has at rest, styled.
  PoseReference& pr = timeState.poseRef;
  pr.tolerance = packing.poseTolerance;
  const bool carries = packing.carryPosedDrape && packing.options.method == coat::PackMethod::Drape;
  if (timeState.posedMoved && (pr.tolerance > 0 || carries) && pr.key != timeState.packKey) {
    coat::CoatFeathers c = coatRest;
    coat::evaluateFrames(rest, follicles, directions, c);
    if (!packing.styling.empty()) coat::applyStyling(c, packing.styling, {});
    pr.frames = std::move(c.frames);
    pr.coat = coat::CoatFeathers{};  // referenceCoat copies the new frames in
    pr.key = timeState.packKey;
    pr.natural.clear();
    pr.frame.clear();
  }
  const ControlSettings& controls = settings.controls(scene);
  applyControls(controls, settings.controlsKey(), packing, time, posed, posedFollicles, timeState, coatNow, constraints,
                fixedElevation);
  // A carried drape's reference turns with the controls as the frame does, at rest.
  restTurned.clear();
  if (carries && timeState.posedMoved && !controls.controls.empty() && pr.frames.size() == coatNow.size())
    restTurned = restTurnedFrames(controls, packing.options, time, rest, follicles, coatNow, pr.frames, constraints);
  constraints.fixedElevation = fixedElevation;
}

// A growing feather is packed with its barbs (age 1 for the packer) as it will be meshed: once its
// shaft is full grown, as grown at its age (the packer sees its barb lengths, angles and opening, and
// computeMesh meshes the packed grown parameters as they are); while its shaft still grows, as the
// mature feather, grown afterwards (a prefix of the packed shaft, barbs closed and short). Straight
// shafts of the mature feather (the packer's age < opening_age rule) let opening barbs reach into
// the skin, and a short grown shaft's thin footprint finds no skin to pack against.
const coat::CoatFeathers& Pipeline::Impl::grownPackInput() {
  bool anyGrowing = false;
  for (size_t i = 0; i < coatNow.size() && !anyGrowing; ++i) anyGrowing = coatNow.present[i] && coatNow.age[i] < 1.0;
  packGrownAge.clear();
  if (!anyGrowing) return coatNow;
  packGrownAge.assign(coatNow.size(), 1.0);
  packCoat = coatNow;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, packCoat.size(), 16), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i)
      if (packCoat.present[i] && packCoat.age[i] < 1.0) {
        const feather::GrowthSchedule& schedule = feather::growthScheduleOf(coatNow.params[i]);
        if (packedAsGrown(packCoat.age[i], schedule, coatNow.params[i])) {
          packCoat.params[i] = feather::featherAtAge(coatNow.params[i], coatNow.age[i], schedule);
          packGrownAge[i] = coatNow.age[i];
        }
        packCoat.age[i] = 1.0;
      }
  });
  return packCoat;
}

void Pipeline::Impl::computePack() {
  report(progress, "pack", 0);
  const coat::PackOptions& o = packOptions;
  // A draped coat is laid by the mesh stage from the frame's own feathers, so nothing is grown for a
  // packer here (timeFullPack grows them when it times a pack).
  packGrownAge.clear();
  const coat::CoatFeathers* packInput = o.method == coat::PackMethod::Drape ? &coatNow : &grownPackInput();
  if (o.method == coat::PackMethod::Drape) {
    // Laid by the mesh stage (computeMesh drapes the flat coat): every feather meshed flat, unpacked.
    flatPack = coat::PackResult{};
    flatPack.order = coatNow.layerOrder;
    flatPack.elevation.assign(coatNow.size(), 0.0);
    flatPack.stats.packed = coatNow.layerOrder.size();
    packed = &flatPack;
    packedCoat = &coatNow;
  } else if (moultOver && moulting(coatNow)) {
    // A moult frame: the mature coat is packed as a frame without a moult would be, and the lost and
    // growing feathers are packed over it (docs/moult.md). With "moult_pack": "full" the frame is
    // repacked like any other (below).
    packed =
        &packMoultFrame(posed, matureCoat(coatNow, timeState), *packInput, o, constraints, timeState, packGrownAge);
    packedCoat = packInput;
  } else {
    // Repacks incrementally from the last frame's pack or this frame's natural pack when it can.
    packed = &packFrame(posed, *packInput, o, constraints, timeState, packGrownAge);
    packedCoat = packInput;
  }
  report(progress, "pack", 1);
}

bool Pipeline::Impl::MatureDrapeKey::operator==(const MatureDrapeKey& o) const {
  auto sameFrames = [](const std::vector<coat::FeatherFrame>& a, const std::vector<coat::FeatherFrame>& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](const auto& x, const auto& y) {
             return x.origin == y.origin && x.normal == y.normal && x.tangent == y.tangent && x.binormal == y.binormal;
           });
  };
  return rest == o.rest && lod == o.lod && instanceTolerance == o.instanceTolerance && gap == o.gap &&
         spacing == o.spacing && maxSlope == o.maxSlope && baseAllowance == o.baseAllowance &&
         featherLods == o.featherLods && sameFrames(frames, o.frames) && skin == o.skin;
}

const coat::DrapeSpacing& Pipeline::Impl::drapeReference(const coat::DrapeOptions& o) {
  const InputKey key = restKey();
  if (drapeRef && drapeRef->rest == key && drapeRef->lod == lod && drapeRef->gap == o.gap &&
      drapeRef->maxSlope == o.maxSlope && drapeRef->baseAllowance == o.baseAllowance &&
      drapeRef->featherLods == featherLods)
    return drapeRef->spacing;
  // The rest coat, every feather present and mature, meshed flat as the mesh stage meshes a frame.
  coat::CoatFeathers mature = coatRest;
  const size_t n = mature.size();
  mature.age.assign(n, 1.0);
  mature.present.assign(n, 1);
  coat::PackResult flat;
  flat.order = mature.layerOrder;
  flat.elevation.assign(n, 0.0);
  CoatMeshInput in;
  in.coat = &mature;
  in.packedCoat = &mature;
  in.packed = &flat;
  in.lod = lod;
  in.featherLods = &featherLods;
  CoatMesher mesher;
  TriMesh restMesh;
  mesher.update(in, restMesh);
  DrapeReference r;
  r.rest = key;
  r.lod = lod;
  r.gap = o.gap;
  r.maxSlope = o.maxSlope;
  r.baseAllowance = o.baseAllowance;
  r.featherLods = featherLods;
  r.spacing = coat::drapeSpacing(rest, mature, restMesh, o);
  drapeRef = std::move(r);
  return drapeRef->spacing;
}

coat::DrapeResult Pipeline::Impl::carryFromRest(const coat::CoatFeathers& c, const CoatMeshInput& in,
                                                const coat::CoatFeathers& frame, TriMesh& posedMesh,
                                                const coat::DrapeOptions& o) {
  // The coat at rest: this frame's feathers with the pose reference's frames, meshed and draped over the
  // rest skin (the mesher and the cache keep what did not change since the last frame).
  RestDrape& R = restDrape;
  coat::CoatFeathers& rc = R.coat;
  const std::vector<coat::FeatherFrame>& frames = restTurned.empty() ? timeState.poseRef.frames : restTurned;
  MatureDrapeKey key{InputKey{timeState.generation},
                     lod,
                     o.gap,
                     o.spacing,
                     o.maxSlope,
                     o.baseAllowance,
                     featherLods,
                     frames,
                     rest.positions};
  key.instanceTolerance = in.instanceTolerance;
  const ProgressFn whole = o.progress;
  // Unchanged (a pose scrub over a mature coat, or a coat that holds still): its last drape as it is.
  if (!R.key || !(*R.key == key) || rc.params != c.params || rc.age != c.age || rc.present != c.present ||
      rc.layerOrder != c.layerOrder || rc.follicle != c.follicle) {
    R.key.reset();
    rc.follicle = c.follicle;
    rc.tract = c.tract;
    if (rc.params != c.params) rc.params = c.params;
    rc.frames = frames;
    rc.age = c.age;
    rc.present = c.present;
    rc.layerOrder = c.layerOrder;
    CoatMeshInput rin = in;
    rin.coat = &rc;
    rin.packedCoat = &rc;
    R.mesher.update(rin, R.mesh);
    R.mesher.keepIndices(R.mesh);
    coat::DrapeOptions ro = o;
    ro.progress = [whole](const std::string& s, double f) { return !whole || whole(s, 0.8 * f); };
    coat::drapeCoatMesh(rest, rc, R.mesh, ro, R.cache);
    R.key = std::move(key);
  }
  coat::DrapeOptions po = o;
  po.progress = [whole](const std::string& s, double f) { return !whole || whole(s, 0.8 + 0.2 * f); };
  coat::DrapeResult r = coat::drapeCarried(rest, posed, frame, posedMesh, R.cache, po);
  carried = r.stats.relaid;
  carriedRigid = r.stats.rigid;
  return r;
}

void Pipeline::Impl::computeMesh() {
  report(progress, "mesh", 0);
  // The coat at the levels it is meshed at, against the memory ceiling: the interpolate stage assumed the
  // least a render by screen size meshes.
  requireCoatMemory(coatNow.params, &coatNow.present, lod, &featherLods, "the coat's mesh", scene.file);
  CoatMeshInput in;
  in.coat = &coatNow;
  in.packedCoat = packedCoat;
  in.packed = packed;
  in.lod = lod;
  in.featherLods = &featherLods;
  in.bends = &timeState.bends;
  in.instanceTolerance = scene.render.instanceTolerance;
  mesher.update(in, mesh.mesh);
  drape = coat::DrapeResult{};
  carried.reset();
  if (packOptions.method == coat::PackMethod::Drape) {
    mesher.keepIndices(mesh.mesh);
    coat::DrapeOptions dopt;
    dopt.gap = packOptions.clearance;
    dopt.maxSlope = std::tan(packOptions.drapeMaxSlopeDeg * feather::kPi / 180.0);
    dopt.threads = packOptions.threads;
    dopt.baseAllowance = packOptions.baseAllowance;
    // The drape is most of the mesh stage's time: its steps move the stage's progress.
    report(progress, "mesh", 0.1);
    dopt.progress = [this](const std::string&, double f) {
      report(progress, "mesh", 0.1 + 0.9 * f);
      return true;
    };
    if (timeMatters() || !skinPose.empty()) {
      const coat::DrapeSpacing& ref = drapeReference(dopt);
      dopt.gap = ref.gap;
      dopt.spacing = ref.spacing;
    }
    // A posed frame is carried from the rest pose's drape (docs/moult.md, "Posed frames"), turned by the
    // controls at rest as the frame is turned; a dynamic chain's bends are draped in full.
    const bool bent = std::any_of(timeState.bends.begin(), timeState.bends.end(),
                                  [](const feather::ShaftBend& b) { return !b.rigid(); });
    const bool carry =
        carryPosedDrape && timeState.posedMoved && !bent && timeState.poseRef.frames.size() == coatNow.size();
    // The mature coat of a moult frame meshed flat as the frame is (matureFlat: its layers, elevation 0).
    auto matureInput = [&](const coat::CoatFeathers& mature) {
      matureFlat = coat::PackResult{};
      matureFlat.order = mature.layerOrder;
      matureFlat.elevation.assign(mature.size(), 0.0);
      CoatMeshInput min = in;
      min.coat = &mature;
      min.packedCoat = &mature;
      min.packed = &matureFlat;
      return min;
    };
    if (moultOver && moulting(coatNow) && carry) {
      // A posed moult frame: the mature coat's rest drape carried, with the frame's lost feathers left out
      // and its growing ones placed on their carried mature charts, in one pass.
      const coat::CoatFeathers& mature = matureCoat(coatNow, timeState);
      drape = carryFromRest(mature, matureInput(mature), coatNow, mesh.mesh, dopt);
    } else if (moultOver && moulting(coatNow)) {
      // A moult frame over the mature coat (docs/moult.md): the mature coat (every feather present and
      // mature) is meshed and draped by a mesher and a drape cache of its own, which reuse everything
      // while the skin and the controls do not move; the frame's feathers are copied from it or placed
      // on their mature charts.
      const coat::CoatFeathers& mature = matureCoat(coatNow, timeState);
      MatureDrapeKey key{InputKey{timeState.generation},
                         lod,
                         dopt.gap,
                         dopt.spacing,
                         dopt.maxSlope,
                         dopt.baseAllowance,
                         featherLods,
                         mature.frames,
                         posed.positions};
      key.instanceTolerance = in.instanceTolerance;
      if (bent || !matureDrapeKey || !(*matureDrapeKey == key)) {
        matureDrapeKey.reset();
        matureMesher.update(matureInput(mature), matureMesh);
        matureMesher.keepIndices(matureMesh);
        coat::DrapeOptions mopt = dopt;
        mopt.progress = [this](const std::string&, double f) {
          report(progress, "mesh", 0.1 + 0.8 * f);
          return true;
        };
        coat::drapeCoatMesh(posed, mature, matureMesh, mopt, matureDrapeCache);
        if (!bent) matureDrapeKey = std::move(key);
      }
      dopt.progress = [this](const std::string&, double f) {
        report(progress, "mesh", 0.9 + 0.1 * f);
        return true;
      };
      drape = coat::drapeOverMature(posed, coatNow, mesh.mesh, matureDrapeCache, dopt);
    } else if (carry) {
      drape = carryFromRest(coatNow, in, coatNow, mesh.mesh, dopt);
    } else {
      drape = coat::drapeCoatMesh(posed, coatNow, mesh.mesh, dopt, drapeCache);
    }
  }
  const std::vector<uint32_t>& which = mesher.feathers();
  const std::vector<feather::FeatherMeshRanges>& ranges = mesher.ranges();
  mesh.ranges.clear();
  mesh.ranges.reserve(ranges.size());
  const std::vector<uint32_t>& featherMaterial = restMaterials.featherMaterial;
  for (size_t k = 0; k < ranges.size(); ++k) {
    const uint32_t i = which[k];
    const auto& r = ranges[k];
    CoatDrawRange d;
    d.feather = i;
    d.firstIndex = r.shaftFirst;
    d.indexCount = indexEnd(r) - r.shaftFirst;
    d.partCount[0] = r.shaftCount;
    d.partCount[1] = r.leftCount;
    d.partCount[2] = r.rightCount;
    d.partCount[3] = r.afterCount;
    d.material = i < featherMaterial.size() ? featherMaterial[i] : 0;
    const coat::FeatherFrame& fr = coatNow.frames[i];
    const auto pl = feather::FeatherPlacement::fromFollicle(fr.origin, fr.tangent, fr.normal, packed->elevation[i]);
    d.origin = glm::vec3(fr.origin);
    d.axisX = glm::vec3(pl.x);
    d.axisY = glm::vec3(pl.y);
    mesh.ranges.push_back(d);
  }
  // Materials depend on the rest coat only: a timeline keeps one list (renderers set it once).
  if (mesh.materials != restMaterials.materials) mesh.materials = restMaterials.materials;
  report(progress, "mesh", 1);
}

namespace {
// A scene without tracts feathers the whole skin as one tract named "all" (docs/tracts.md). Filled in
// once where a scene enters the pipeline (construction and every edit), so every stage, rest or time,
// sees the same tracts whatever stage re-runs.
void defaultTracts(Scene& scene) {
  if (scene.tracts.empty()) scene.tracts = Json::array({Json{{"name", "all"}}});
}
}  // namespace

Pipeline::Pipeline(Scene scene, ProgressFn progress) : impl_(std::make_unique<Impl>()) {
  impl_->scene = std::move(scene);
  defaultTracts(impl_->scene);
  impl_->progress = std::move(progress);
  impl_->time = impl_->scene.time;
  impl_->lod = impl_->scene.render.lod;
  impl_->settings.update(impl_->scene);
  impl_->build();
}

Pipeline::Pipeline(Scene scene, coat::SkinMesh skin, ProgressFn progress)
    : Pipeline(std::move(scene), std::move(progress)) {
  impl_->memorySkin = std::move(skin);
}

Pipeline::~Pipeline() = default;

const Scene& Pipeline::scene() const { return impl_->scene; }
const coat::PackingSettings& Pipeline::packingSettings() { return impl_->settings.packing(impl_->scene); }
void Pipeline::editScene(Stage from, const std::function<void(Scene&)>& edit) {
  edit(impl_->scene);
  defaultTracts(impl_->scene);
  impl_->settings.update(impl_->scene);
  invalidate(from);
}
void Pipeline::invalidate(Stage from) { impl_->graph.invalidate(impl_->id(from)); }
void Pipeline::setProgress(ProgressFn progress) { impl_->progress = std::move(progress); }

// Whether the time stages read the time (SceneSettings::readsTime: a skeleton, a moult or controls).
bool Pipeline::Impl::timeMatters() const { return settings.readsTime(); }

void Pipeline::setTime(double t) {
  if (!std::isfinite(t)) throw Error("time must be a finite number", "", "--time");
  if (t == impl_->time) return;
  impl_->time = t;
  // Only stages that depend on time: the skin pose and everything after it, and only when something in
  // the scene reads the time. A scene with no skeleton, moult or controls is the same coat at every
  // time, so scrubbing its timeline (a host's frame change) costs nothing.
  if (impl_->settings.readsTime()) impl_->graph.invalidate(impl_->id(Stage::Pose));
}
double Pipeline::time() const { return impl_->time; }

void checkSkinPose(const coat::SkinMesh& rest, const std::vector<glm::dvec3>& positions) {
  const size_t n = rest.positions.size();
  if (positions.size() != n)
    throw Error("the pose has " + std::to_string(positions.size()) + " vertices; the skin has " + std::to_string(n) +
                    " (a pose keeps the skin's topology)",
                "", "pose");
  for (size_t v = 0; v < n; ++v)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(positions[v][c]) || std::abs(positions[v][c]) > coat::kMaxMeshCoordinate)
        throw Error("coordinate " + std::to_string(c) + " is " + std::to_string(positions[v][c]) +
                        ": pose coordinates must be finite and at most " + std::to_string(coat::kMaxMeshCoordinate) +
                        " in magnitude",
                    "", "vertex " + std::to_string(v));
}

void Pipeline::setSkinPose(std::vector<glm::dvec3> positions) {
  if (!positions.empty()) checkSkinPose(restSkin(), positions);
  if (positions == impl_->skinPose) return;
  impl_->skinPose = std::move(positions);
  impl_->graph.invalidate(impl_->id(Stage::Pose));
}
const std::vector<glm::dvec3>& Pipeline::skinPose() const { return impl_->skinPose; }

void Pipeline::setFixedElevations(std::map<uint64_t, double> elevations) {
  for (const auto& [id, e] : elevations)
    if (!std::isfinite(e) || e < 0 || e > feather::kPi / 2)
      throw Error("elevation " + std::to_string(e) + " is not in [0, pi/2] radians", "",
                  "follicle " + std::to_string(id));
  if (elevations == impl_->hostElevations) return;
  impl_->hostElevations = std::move(elevations);
  impl_->graph.invalidate(impl_->id(Stage::Controls));
}
const std::map<uint64_t, double>& Pipeline::fixedElevations() const { return impl_->hostElevations; }

void Pipeline::setLod(double f) {
  if (!(f > 0 && f <= 1)) throw Error("level of detail must be in (0, 1]", "", "lod");
  if (f == impl_->lod) return;
  impl_->lod = f;
  impl_->graph.invalidate(impl_->id(Stage::Mesh));
}
double Pipeline::lod() const { return impl_->lod; }

void Pipeline::setFeatherLods(std::vector<double> fractions) {
  for (size_t i = 0; i < fractions.size(); ++i)
    if (!(fractions[i] > 0 && fractions[i] <= 1))
      throw Error("per-feather level of detail must be in (0, 1], got " + std::to_string(fractions[i]), "",
                  "feather " + std::to_string(i));
  if (fractions == impl_->featherLods) return;
  impl_->featherLods = std::move(fractions);
  impl_->graph.invalidate(impl_->id(Stage::Mesh));
}
const std::vector<double>& Pipeline::featherLods() const { return impl_->featherLods; }

const coat::SkinMesh& Pipeline::restSkin() {
  impl_->graph.pull(impl_->id(Stage::Skin));
  return impl_->rest;
}
const coat::SkinMesh& Pipeline::posedSkin() {
  impl_->graph.pull(impl_->id(Stage::Pose));
  return impl_->posed;
}
const std::vector<coat::Tract>& Pipeline::tracts() {
  impl_->graph.pull(impl_->id(Stage::Tracts));
  return impl_->tracts;
}
const coat::Follicles& Pipeline::follicles() {
  impl_->graph.pull(impl_->id(Stage::Distribute));
  return impl_->follicles;
}
const coat::CoatFeathers& Pipeline::feathers() {
  impl_->graph.pull(impl_->id(Stage::Pack));
  return impl_->coatNow;
}
const std::vector<double>& Pipeline::elevations() {
  impl_->graph.pull(impl_->id(Stage::Pack));
  return impl_->packed->elevation;
}
const CoatMesh& Pipeline::coatMesh() {
  impl_->graph.pull(impl_->id(Stage::Mesh));
  return impl_->mesh;
}
TriMesh Pipeline::skinTriMesh() { return coat::toTriMesh(posedSkin()); }

QualityMetrics Pipeline::check() {
  QualityMetrics m;
  // Progress "check" over its parts, reported on the calling thread: the coat at full detail to 50%
  // (the mesh stage reports its own progress meanwhile), the checker (pairs, skin, coverage) to 85%,
  // and to 100% what runs beside them (below). A callback returning false stops it: the metrics not
  // computed yet stay empty.
  bool stopped = false;
  // What depends on neither the full-detail mesh nor the checker runs beside them as one TBB task, on
  // whichever core the mesh and the checker leave idle (the drape's layering and the tracts' metrics
  // have serial steps): the tracts' distribution metrics and the proxy coats' pair counts. It reports
  // through `aside` (its share done) and stops when `quit` is set.
  std::atomic<double> aside{0};
  std::atomic<bool> quit{false};
  auto part = [&](double lo, double hi) -> ProgressFn {
    return [this, lo, hi, &stopped, &aside](const std::string&, double x) {
      const double fore = lo + (hi - lo) * std::clamp(x, 0.0, 1.0);
      if (!report(impl_->progress, "check", 0.85 * fore + 0.15 * aside.load())) stopped = true;
      return !stopped;
    };
  };
  const auto& f = follicles();
  m.follicles = f.size();
  const ProgressFn start = part(0, 0);
  if (!start("check", 0)) return m;
  const auto& coat = feathers();
  size_t present = 0;
  for (auto p : coat.present) present += p ? 1 : 0;
  m.feathers = present;
  const bool draped = impl_->packOptions.method == coat::PackMethod::Drape;
  Impl& im = *impl_;

  // Beside: per tract its distribution, the packed proxy coat's pairs (height-field packing), and the
  // unpacked coat's pairs, from the input alone: every feather at kUnpackedElevationDeg with its own key
  // barbs (remembered with the coat it was counted on).
  std::vector<coat::DistributionMetrics> tractMetrics(im.tracts.size());
  std::optional<size_t> proxyPairs, unpackedPairs;
  TriMesh unpacked;
  bool unpackedReused = false;
  auto besideProgress = [&](double lo, double hi) -> ProgressFn {
    return [&aside, &quit, lo, hi](const std::string&, double x) {
      aside.store(lo + (hi - lo) * std::clamp(x, 0.0, 1.0));
      return !quit.load();
    };
  };
  auto beside = [&] {
    for (size_t i = 0; i < im.tracts.size() && !quit.load(); ++i) {
      tractMetrics[i] = coat::measureDistribution(im.rest, im.tracts[i], f);
      aside.store(0.1 * double(i + 1) / double(im.tracts.size()));
    }
    if (quit.load()) return;
    if (!draped) {
      const TriMesh packedProxy =
          coat::proxyCoatMesh(im.coatNow, im.packed->elevation, coat::allPackedParams(*im.packedCoat, *im.packed));
      proxyPairs = coat::countIntersectingPairs(packedProxy, besideProgress(0.1, 0.4));
      if (!proxyPairs) return;
    }
    const std::vector<double> flat(im.coatNow.size(), kUnpackedElevationDeg * feather::kPi / 180.0);
    unpacked = coat::proxyCoatMesh(im.coatNow, flat, im.coatNow.params);
    if (im.lastUnpackedPairs && unpacked.positions == im.lastUnpacked.positions &&
        unpacked.indices == im.lastUnpacked.indices && unpacked.featherId == im.lastUnpacked.featherId) {
      unpackedPairs = im.lastUnpackedPairs;
      unpackedReused = true;
    } else {
      unpackedPairs = coat::countIntersectingPairs(unpacked, besideProgress(draped ? 0.1 : 0.4, 1));
    }
    aside.store(1);
  };
  tbb::task_group group;
  // Waits for the task however check() leaves (a cancel may throw out of the mesh stage).
  struct Join {
    tbb::task_group& group;
    std::atomic<bool>& quit;
    bool done = false;
    void wait() {
      if (!done) group.wait();
      done = true;
    }
    ~Join() {
      quit.store(true);
      try {
        wait();
      } catch (...) {
      }
    }
  } join{group, quit};
  group.run(beside);

  // The independent checker (coat/check.hpp) on the coat at full geometry: every feather, also after a
  // render set levels by screen size (they are put back with the level when the check completes).
  const double savedLod = impl_->lod;
  const std::vector<double> savedLevels = impl_->featherLods;
  const auto restore = [&] {
    setLod(savedLod);
    setFeatherLods(savedLevels);
  };
  setLod(1.0);
  setFeatherLods({});
  const TriMesh& full = coatMesh().mesh;
  std::vector<uint32_t> tractFaces;
  for (const auto& t : impl_->tracts) tractFaces.insert(tractFaces.end(), t.faces.begin(), t.faces.end());
  std::sort(tractFaces.begin(), tractFaces.end());
  tractFaces.erase(std::unique(tractFaces.begin(), tractFaces.end()), tractFaces.end());
  coat::CheckOptions co;
  co.seed = impl_->scene.seed;
  co.attribute = true;  // which feathers intersect or penetrate (the counts are the same either way)
  co.progress = part(0.5, 1);
  if (!co.progress("check", 0)) {
    restore();
    return m;
  }
  coat::setFeatherBases(co, impl_->coatNow, impl_->packOptions.baseAllowance);
  const coat::CheckResult r = coat::check(impl_->posed, tractFaces, full, co);
  if (!r.complete) {
    restore();
    return m;
  }
  join.wait();
  const ProgressFn end = part(1, 1);
  // The tracts' distribution, weighted by their interior follicles.
  double hexSum = 0, cvSum = 0;
  size_t interior = 0;
  for (const coat::DistributionMetrics& d : tractMetrics) {
    hexSum += d.hexFraction * double(d.interior);
    cvSum += d.nnCv * double(d.interior);
    interior += d.interior;
  }
  if (interior > 0) {
    m.hexFraction = hexSum / double(interior);
    m.nnCv = cvSum / double(interior);
  }
  m.intersectingPairs = r.intersectingPairs;
  m.skinPenetrations = r.skinPenetrations;
  m.coverage = r.coverage;
  m.faceSamples = r.faceSamples;
  m.faceUncovered = r.faceUncovered;
  for (const coat::FeatherPairCount& p : r.featherPairs) {
    m.intersectingFeathers.push_back(p.a);
    m.intersectingFeathers.push_back(p.b);
  }
  std::sort(m.intersectingFeathers.begin(), m.intersectingFeathers.end());
  m.intersectingFeathers.erase(std::unique(m.intersectingFeathers.begin(), m.intersectingFeathers.end()),
                               m.intersectingFeathers.end());
  m.penetratingFeathers = r.penetratingFeathers;
  // How steeply feathers rise: the packed elevations, or for a draped coat its rise over the skin.
  const std::vector<double>& elevation = draped ? impl_->drape.elevation : impl_->packed->elevation;
  std::vector<double> el;
  for (size_t i = 0; i < impl_->coatNow.size(); ++i)
    if (impl_->coatNow.present[i] && i < elevation.size()) el.push_back(elevation[i] * 180.0 / feather::kPi);
  if (!el.empty()) {
    std::sort(el.begin(), el.end());
    m.elevationP50 = el[el.size() / 2];
    m.elevationP90 = el[std::min(el.size() - 1, el.size() * 9 / 10)];
  }
  if (draped) {
    m.fixedFeathers = impl_->drape.stats.trimmedFeathers;
    m.hiddenFeathers = impl_->drape.stats.hiddenFeathers;
  }
  m.intersectingPairsProxy = proxyPairs;
  m.intersectingPairsUnpacked = unpackedPairs;
  if (unpackedPairs && !unpackedReused) {
    im.lastUnpackedPairs = unpackedPairs;
    im.lastUnpacked = std::move(unpacked);
  }
  end("check", 1);
  restore();
  return m;
}

double Pipeline::timeFullPack(int repeats) {
  elevations();  // the pack stage has run: its inputs are this frame's
  Impl& m = *impl_;
  const coat::PackOptions& o = m.packOptions;
  // (A draped coat's pack stage grows nothing: its growing feathers are grown here, as a packer takes them.)
  if (o.method == coat::PackMethod::Drape && !m.timeState.packReport.moult) m.grownPackInput();
  const coat::CoatFeathers& c =
      m.timeState.packReport.moult ? m.timeState.mature : (m.packGrownAge.empty() ? m.coatNow : m.packCoat);
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < std::max(1, repeats); ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const coat::PackResult result = coat::pack(m.posed, c, o, m.constraints);
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

FrameReuse Pipeline::frameReuse() const {
  FrameReuse r;
  const PackReport& p = impl_->timeState.packReport;
  r.naturalPacked = impl_->timeState.controlResult.naturalPacked;
  r.naturalIncremental = p.naturalIncremental;
  r.naturalChanged = p.naturalChanged;
  r.naturalRecomputed = p.naturalRecomputed;
  r.packIncremental = p.finalIncremental;
  r.packChanged = p.finalChanged;
  r.packRecomputed = p.finalRecomputed;
  r.moult = p.moult;
  r.moultChanged = p.moultChanged;
  r.moultRecomputed = p.moultRecomputed;
  r.deformedPacks = p.deformedPacks;
  r.poseMoved = p.poseMoved;
  r.poseRepacked = p.poseRepacked;
  r.meshRegenerated = impl_->mesher.regenerated();
  r.meshReused = impl_->mesher.reused();
  const InstancingStats& inst = impl_->mesher.instancing();
  r.meshFeathers = inst.feathers;
  r.meshRepresentatives = inst.representatives;
  r.meshDistinct = inst.meshes;
  r.meshStoredVertices = inst.storedVertices;
  r.meshVertices = inst.vertices;
  r.drapeRelaid = impl_->drape.stats.relaid;
  r.drapeReused = impl_->drape.stats.reused;
  r.drapeCarried = impl_->carried.has_value();
  r.drapeCarriedMoved = impl_->carried ? *impl_->carried : 0;
  r.drapeCarriedRigid = impl_->carried ? impl_->carriedRigid : 0;
  return r;
}

uint64_t Pipeline::evaluations(Stage s) const { return impl_->graph.evaluations(Impl::id(s)); }
bool Pipeline::dirty(Stage s) const { return impl_->graph.dirty(Impl::id(s)); }
double Pipeline::lastSeconds(Stage s) const { return impl_->graph.lastSeconds(Impl::id(s)); }
double Pipeline::stageSeconds(Stage s) const { return impl_->graph.totalSeconds(impl_->id(s)); }
void Pipeline::resetTimings() { impl_->graph.resetTimings(); }

}  // namespace pteryla::pipeline
