// bench_moult: one frame of a moulting coat through the Pipeline (skin pose, ages, controls, pack and
// mesh at 20% LOD), as a timeline scrub re-evaluates it. Target: < 0.15 s per frame for ~3,000 feathers.
//   bird:       data/scenes/bird.json with a moult added (skipped if the scene is missing), optionally
//               bent wings and lift controls (a crest and a chest)
//   synthetic:  bird.obj, one tract of 3,000 contour feathers, moult + bent wings
// Also the moult schedule, skinning and controls on their own, and the coat checker on the bird at full
// detail (CheckBird: part 0 the checker on the coat mesh, part 1 the unpacked proxy coat's pair count,
// part 2 all of Pipeline::check on a freshly evaluated scene: the full-detail mesh with the drape, the
// checker and what runs beside it).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pteryla/coat/check.hpp"
#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/moult/schedule.hpp"
#include "pteryla/moult/skinning.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

using namespace pteryla;

namespace {

const std::string kData = PTERYLA_DATA_DIR;

Json moultSection() {
  return Json::parse(R"({"start": 0, "duration": 10, "window": 0.2, "sequence": "centre_out", "gap": 0.05,
                        "random": 0.15, "seed": 3, "size_exponent": 0.5})");
}

Json birdWings() {
  return Json::parse(R"({"file": "../meshes/bird.skeleton.json", "interpolation": "smooth", "keys": [
      {"joint": "elbow_left", "t": 0, "rotation": [1, 0, 0, 0]},
      {"joint": "elbow_left", "t": 10, "rotation": [1, 0, 0, 30]},
      {"joint": "elbow_right", "t": 0, "rotation": [1, 0, 0, 0]},
      {"joint": "elbow_right", "t": 10, "rotation": [1, 0, 0, -30]}]})");
}

// Builds and fully evaluates a pipeline once (rest stages cached), then times frames at new times:
// jumps across the timeline (scrub = 0: little to reuse between frames) or consecutive frames at
// 24 per time unit (scrub = 1: dragging the timeline; feathers whose inputs did not change are reused).
void runFrames(benchmark::State& state, pipeline::Scene scene, bool consecutive) {
  std::unique_ptr<pipeline::Pipeline> p;
  try {
    p = std::make_unique<pipeline::Pipeline>(std::move(scene));
    p->setLod(0.2);
    p->setTime(4.0);
    p->coatMesh();
  } catch (const Error& e) {
    state.SkipWithError(e.what());
    return;
  }
  const double times[] = {3.0, 5.5, 4.25, 6.0, 2.5, 7.75, 5.0, 3.5};
  size_t k = 0;
  double packChanged = 0, packRecomputed = 0, naturalRecomputed = 0, meshRegenerated = 0, meshReused = 0,
         incremental = 0, moultChanged = 0, moultRecomputed = 0, poseMoved = 0, poseRepacked = 0, drapeRelaid = 0,
         drapeReused = 0, drapeCarriedMoved = 0, drapeCarriedRigid = 0;
  p->resetTimings();
  for (auto _ : state) {
    p->setTime(consecutive ? 4.0 + double(++k) / 24.0 : times[k++ % 8]);
    benchmark::DoNotOptimize(p->coatMesh().mesh.vertexCount());
    const pipeline::FrameReuse r = p->frameReuse();
    packChanged += double(r.packChanged);
    packRecomputed += double(r.packRecomputed);
    naturalRecomputed += double(r.naturalRecomputed);
    meshRegenerated += double(r.meshRegenerated);
    meshReused += double(r.meshReused);
    incremental += r.packIncremental ? 1 : 0;
    moultChanged += double(r.moultChanged);
    moultRecomputed += double(r.moultRecomputed);
    poseMoved += double(r.poseMoved);
    poseRepacked += double(r.poseRepacked);
    drapeRelaid += double(r.drapeRelaid);
    drapeReused += double(r.drapeReused);
    drapeCarriedMoved += double(r.drapeCarriedMoved);
    drapeCarriedRigid += double(r.drapeCarriedRigid);
  }
  const auto& c = p->feathers();
  size_t absent = 0, growing = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    absent += c.present[i] ? 0 : 1;
    growing += c.present[i] && c.age[i] < 1 ? 1 : 0;
  }
  const double n = double(state.iterations());
  state.counters["feathers"] = double(c.size());
  state.counters["growing"] = double(growing);
  state.counters["absent"] = double(absent);
  state.counters["triangles"] = double(p->coatMesh().mesh.triangleCount());
  using pipeline::Stage;
  state.counters["pose_ms"] = 1e3 * p->stageSeconds(Stage::Pose) / n;
  state.counters["ages_ms"] = 1e3 * p->stageSeconds(Stage::Ages) / n;
  state.counters["controls_ms"] = 1e3 * p->stageSeconds(Stage::Controls) / n;
  state.counters["pack_ms"] = 1e3 * p->stageSeconds(Stage::Pack) / n;
  state.counters["mesh_ms"] = 1e3 * p->stageSeconds(Stage::Mesh) / n;
  // Reuse per frame: feathers changed / packed by the frame's pack (and the controls' natural pack),
  // fraction of frames repacked incrementally, feathers whose barb curves were regenerated and whose
  // triangles were copied from the last frame.
  state.counters["pack_changed"] = packChanged / n;
  state.counters["pack_recomputed"] = packRecomputed / n;
  state.counters["natural_recomputed"] = naturalRecomputed / n;
  state.counters["incremental"] = incremental / n;
  state.counters["mesh_regen"] = meshRegenerated / n;
  state.counters["mesh_reused"] = meshReused / n;
  // Moult frames: lost and growing feathers, and those packed over the mature coat's pack.
  state.counters["moult_changed"] = moultChanged / n;
  state.counters["moult_recomputed"] = moultRecomputed / n;
  // Posed frames: feathers whose surroundings moved beyond the pose tolerance, and those packed again.
  state.counters["pose_moved"] = poseMoved / n;
  state.counters["pose_repacked"] = poseRepacked / n;
  // Draped coats: feathers the drape laid again, and those whose draped vertices it copied.
  state.counters["drape_relaid"] = drapeRelaid / n;
  state.counters["drape_reused"] = drapeReused / n;
  // Posed frames of a draped coat carried from the rest pose's drape: feathers the pose moved.
  state.counters["drape_carried_moved"] = drapeCarriedMoved / n;
  state.counters["drape_carried_rigid"] = drapeCarriedRigid / n;
}

// The bundled bird with the bench's moult (and its wings bending), or nothing when it is not found.
std::optional<pipeline::Scene> moultingBird(benchmark::State& state, bool wings) {
  const std::string path = kData + "/scenes/bird.json";
  if (!fileExists(path)) {
    state.SkipWithError("data/scenes/bird.json not found");
    return std::nullopt;
  }
  pipeline::Scene s = pipeline::loadScene(path);
  if (s.moult.empty()) s.moult = moultSection();
  if (wings && s.skeleton.empty()) s.skeleton = birdWings();
  return s;
}

void BM_FrameBirdScene(benchmark::State& state) {
  std::optional<pipeline::Scene> bird = moultingBird(state, state.range(0) != 0);
  if (!bird) return;
  pipeline::Scene& s = *bird;
  if (state.range(1) && s.controls.empty()) {
    // A raised crest and a puffed chest, rising over the scrubbed range.
    s.controls = Json::parse(R"([
      {"name": "crest", "at": [0.78, 0.47, 0.0], "radius": 0.15, "falloff": 0.3,
       "keys": [{"t": 2, "lift": 0.2}, {"t": 8, "lift": 1}]},
      {"name": "chest", "at": [0.62, -0.05, 0.0], "radius": 0.3, "seed": 7, "random": 0.5,
       "keys": [{"t": 2, "lift": 0.1}, {"t": 8, "lift": 0.5}]}])");
  }
  runFrames(state, std::move(s), state.range(2) != 0);
}
BENCHMARK(BM_FrameBirdScene)
    ->ArgsProduct({{0, 1}, {0, 1}, {0, 1}})
    ->ArgNames({"skeleton", "controls", "scrub"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// The draped bird moulting with its wings bending, scrubbed: posed frames carried from the rest pose's drape
// (packing.posed_drape "carry", the default) against a full drape of every posed frame ("full"), in one
// run (issue #26).
void BM_FrameBirdPosedDrape(benchmark::State& state) {
  std::optional<pipeline::Scene> bird = moultingBird(state, true);
  if (!bird) return;
  pipeline::Scene& s = *bird;
  if (!s.packing.is_object()) s.packing = Json::object();
  s.packing["posed_drape"] = state.range(0) ? "carry" : "full";
  runFrames(state, std::move(s), true);
}
BENCHMARK(BM_FrameBirdPosedDrape)
    ->Arg(0)
    ->Arg(1)
    ->ArgName("carry")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// The bird packed with height fields (the thesis' packing) with its wings bending, without a moult:
// posed frames from the rest pose's pack (packing.pose_tolerance 0.25) against a full pack of every
// posed frame (0), in one run.
void BM_FrameBirdPacked(benchmark::State& state) {
  const std::string path = kData + "/scenes/bird.json";
  if (!fileExists(path)) {
    state.SkipWithError("data/scenes/bird.json not found");
    return;
  }
  pipeline::Scene s = pipeline::loadScene(path);
  s.skeleton = birdWings();
  if (!s.packing.is_object()) s.packing = Json::object();
  s.packing["method"] = "height_field";
  s.packing["pose_tolerance"] = state.range(0) ? 0.25 : 0.0;
  runFrames(state, std::move(s), true);
}
BENCHMARK(BM_FrameBirdPacked)
    ->Arg(0)
    ->Arg(1)
    ->ArgName("reuse")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

void BM_FrameSynthetic(benchmark::State& state) {
  Json j = Json::parse(R"({"pteryla": 1, "seed": 4, "mesh": "../meshes/bird.obj",
      "feathers": {"contour": "../feathers/contour.json"},
      "tracts": [{"name": "body", "groups": ["spinal", "ventral", "caudal", "femoral_left", "femoral_right",
                                               "alar_left", "alar_right", "humeral_left", "humeral_right"],
                  "count": 3000, "feather_scale": "auto", "feather_spacings": 2.5,
                  "relax": {"iterations": 10}, "parameterization": {"method": "projection"}}],
      "directions": {"axis": [[0.97, 0.327, 0], [-0.95, 0.1, 0]]}})");
  j["moult"] = moultSection();
  if (state.range(0)) j["skeleton"] = birdWings();
  runFrames(state, pipeline::sceneFromJson(j, kData + "/scenes/bench_synthetic.json"), state.range(1) != 0);
}
BENCHMARK(BM_FrameSynthetic)
    ->ArgsProduct({{0, 1}, {0, 1}})
    ->ArgNames({"skeleton", "scrub"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// The schedule alone: plan + ages for 3,000 feathers.
void BM_MoultSchedule(benchmark::State& state) {
  std::vector<glm::dvec2> uv;
  std::vector<double> size;
  std::vector<uint64_t> id;
  for (uint64_t i = 0; i < 3000; ++i) {
    uv.push_back({hashUniform(1, i), hashUniform(2, i)});
    size.push_back(0.5 + hashUniform(3, i));
    id.push_back(i);
  }
  moult::MoultOptions o;
  o.random = 0.2;
  o.sizeExponent = 1;
  double t = 0;
  for (auto _ : state) {
    const moult::MoultPlan p = moult::planMoult(uv, size, id, o);
    double sum = 0;
    for (size_t i = 0; i < p.size(); ++i) sum += moult::moultStateAt(p, i, t).age;
    t += 0.01;
    benchmark::DoNotOptimize(sum);
  }
}
BENCHMARK(BM_MoultSchedule)->Unit(benchmark::kMicrosecond);

// Linear blend skinning of the bird (4,000 vertices) plus normals.
void BM_SkinBird(benchmark::State& state) {
  const coat::SkinMesh rest = coat::loadSkinMesh(kData + "/meshes/bird.obj");
  const moult::Skeleton s = moult::loadSkeleton(kData + "/meshes/bird.skeleton.json", rest.vertexCount());
  moult::SkeletonPose pose = moult::restPose(s);
  coat::SkinMesh posed = rest;
  double a = 1;
  for (auto _ : state) {
    pose.rotation[2] = moult::rotationFromAxisAngle({1, 0, 0}, a);
    pose.rotation[6] = moult::rotationFromAxisAngle({1, 0, 0}, -a);
    a += 0.1;
    benchmark::DoNotOptimize(moult::poseSkinMesh(s, pose, rest, posed));
  }
  state.counters["vertices"] = double(rest.vertexCount());
}
BENCHMARK(BM_SkinBird)->Unit(benchmark::kMicrosecond);

// The checker on the bundled bird at full detail (what `pteryla check` runs after meshing at LOD 1; the
// pipeline is evaluated once for both parts): part 0 coat::check (intersecting pairs, skin penetrations,
// coverage) on the coat mesh, part 1 the unpacked proxy coat built and its pairs counted, part 2
// Pipeline::check on a new pipeline evaluated up to the pack (untimed): what `pteryla check` spends after
// distributing and packing.
void BM_CheckBird(benchmark::State& state) {
  const std::string path = kData + "/scenes/bird.json";
  if (state.range(0) == 2) {
    if (!fileExists(path)) {
      state.SkipWithError("data/scenes/bird.json not found");
      return;
    }
    size_t pairs = 0;
    for (auto _ : state) {
      state.PauseTiming();
      auto fresh = std::make_unique<pipeline::Pipeline>(pipeline::loadScene(path));
      fresh->feathers();
      state.ResumeTiming();
      const pipeline::QualityMetrics m = fresh->check();
      pairs = m.intersectingPairsUnpacked.value_or(0);
      benchmark::DoNotOptimize(pairs);
      state.PauseTiming();
      fresh.reset();
      state.ResumeTiming();
    }
    state.counters["unpacked_pairs"] = double(pairs);
    return;
  }
  static std::unique_ptr<pipeline::Pipeline> p;
  if (!fileExists(path)) {
    state.SkipWithError("data/scenes/bird.json not found");
    return;
  }
  if (!p) {
    p = std::make_unique<pipeline::Pipeline>(pipeline::loadScene(path));
    p->setLod(1.0);
    p->coatMesh();
  }
  const coat::CoatFeathers& c = p->feathers();
  const TriMesh& mesh = p->coatMesh().mesh;
  std::vector<uint32_t> tractFaces;
  for (const auto& t : p->tracts()) tractFaces.insert(tractFaces.end(), t.faces.begin(), t.faces.end());
  std::sort(tractFaces.begin(), tractFaces.end());
  tractFaces.erase(std::unique(tractFaces.begin(), tractFaces.end()), tractFaces.end());
  coat::CheckOptions o;
  o.seed = p->scene().seed;
  o.attribute = true;  // as Pipeline::check
  coat::setFeatherBases(o, c, coat::PackOptions{}.baseAllowance);
  const std::vector<double> flat(c.size(), pipeline::kUnpackedElevationDeg * 3.14159265358979323846 / 180.0);
  size_t pairs = 0, triangles = 0;
  for (auto _ : state) {
    if (state.range(0) == 0) {
      const coat::CheckResult r = coat::check(p->posedSkin(), tractFaces, mesh, o);
      pairs = r.intersectingPairs;
      triangles = mesh.triangleCount();
      state.counters["coverage"] = r.coverage;
    } else {
      const TriMesh unpacked = coat::proxyCoatMesh(c, flat, c.params);
      pairs = coat::countIntersectingPairs(unpacked);
      triangles = unpacked.triangleCount();
    }
    benchmark::DoNotOptimize(pairs);
  }
  state.counters["triangles"] = double(triangles);
  state.counters["pairs"] = double(pairs);
}
BENCHMARK(BM_CheckBird)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("part")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Iterations(3);

}  // namespace
