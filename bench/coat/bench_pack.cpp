// Packing speed (Streit 2003, 6.3.2-6.3.4; 9.1.2 reports 20 s / 66 s / 151 s for 426 feathers at three
// feather scales and ~9 min for 3,500 feathers on a PIII 800; 8.3 repacks every animation frame).
// Targets on 2 cores: ~3,150 feathers in < 0.35 s (BM_Pack3150/2), 426 feathers at three scales in < 0.1 s
// each (BM_Pack426), and close-to-linear growth from 1k to 50k feathers (BM_PackScaling: the counter
// us_per_feather should stay flat). Feather size follows the follicle spacing, so every feather overlaps
// about the same number of neighbours at every coat size.
// The machine is shared: besides wall time, `cpu_ms` reports the process CPU time per pack.
#include <benchmark/benchmark.h>

#include <cmath>
#include <ctime>
#include <tuple>
#include <map>
#include <memory>

#include "../../tests/coat/pack_fixtures.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/primitives.hpp"
#include "pteryla/coat/style.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

using namespace pteryla;
using namespace pteryla::coat;

namespace {

double cpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

struct Scene {
  SkinMesh skin;
  CoatFeathers coat;
};

// `feathers` feathers in the band |z| < 0.8 of a unit icosphere; `scale` 1 is the test scene's overlap
// (400 follicles, 320 feathers of length 0.42): the feather scale shrinks with the spacing.
const Scene& scene(size_t feathers, double scale, int subdivisions = 3) {
  static std::map<std::tuple<size_t, double, int>, std::unique_ptr<Scene>> cache;
  auto& s = cache[{feathers, scale, subdivisions}];
  if (!s) {
    s = std::make_unique<Scene>();
    s->skin = makeIcosphere(subdivisions);
    const size_t count = static_cast<size_t>(feathers / 0.8 + 0.5);
    s->coat = packtest::sphereCoat(s->skin, count, scale * std::sqrt(320.0 / feathers));
  }
  return *s;
}

void run(benchmark::State& state, const Scene& s, const PackOptions& o) {
  double cpu = 0;
  PackResult r;
  for (auto _ : state) {
    const double c0 = cpuSeconds();
    r = pack(s.skin, s.coat, o);
    cpu += cpuSeconds() - c0;
    benchmark::DoNotOptimize(r.elevation.data());
  }
  state.counters["feathers"] = static_cast<double>(s.coat.size());
  state.counters["cpu_ms"] = 1e3 * cpu / state.iterations();
  state.counters["candidates_per_feather"] = static_cast<double>(r.stats.candidatePoints) / s.coat.size();
  state.counters["unresolved_barbs"] = static_cast<double>(r.stats.barbsUnresolved);
}

// ~3,150 feathers (the thesis' bird has 3,148); threads = range(0).
void BM_Pack3150(benchmark::State& state) {
  PackOptions o;
  o.threads = static_cast<int>(state.range(0));
  run(state, scene(3150, 1.0, 4), o);
}
BENCHMARK(BM_Pack3150)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The bundled bird (data/scenes/bird.json, ~3,150 feathers): the scene is evaluated through the pipeline up
// to the posed skin and the styled, framed coat (once), then coat::pack alone is timed with the scene's
// packing options, as the pipeline's pack stage calls it. threads = range(0).
struct BirdScene {
  SkinMesh skin;
  CoatFeathers coat;
  PackOptions options;
  PackConstraints constraints;  // the styling, resolved
};

const BirdScene& birdScene() {
  static std::unique_ptr<BirdScene> s;
  if (!s) {
    s = std::make_unique<BirdScene>();
    const std::string path = std::string(PTERYLA_DATA_DIR) + "/scenes/bird.json";
    pipeline::Pipeline p(pipeline::loadScene(path));
    s->skin = p.posedSkin();
    s->coat = p.feathers();
    PackingSettings settings;
    if (!p.scene().packing.empty()) {
      JsonReader r(p.scene().packing, path, "packing");
      settings = parsePackingSettings(r);
    }
    s->options = settings.options;
    s->constraints.fixedElevation = resolveStyling(s->coat, settings.styling);
    s->constraints.minElevation = resolveMinElevation(s->coat, settings.styling);
    s->constraints.shaftBand = resolveShaftBand(s->coat, settings.styling);
  }
  return *s;
}

void runBird(benchmark::State& state, const PackOptions& o) {
  const BirdScene& b = birdScene();
  double cpu = 0;
  PackResult r;
  for (auto _ : state) {
    const double c0 = cpuSeconds();
    r = pack(b.skin, b.coat, o, b.constraints);
    cpu += cpuSeconds() - c0;
    benchmark::DoNotOptimize(r.elevation.data());
  }
  state.counters["feathers"] = static_cast<double>(r.stats.packed);
  state.counters["cpu_ms"] = 1e3 * cpu / state.iterations();
  state.counters["candidates_per_feather"] = static_cast<double>(r.stats.candidatePoints) / r.stats.packed;
  state.counters["deps_per_feather"] = static_cast<double>(r.stats.dependencies) / r.stats.packed;
  state.counters["skin_samples"] = static_cast<double>(r.stats.skinSamples);
}

void BM_PackBird(benchmark::State& state) {
  PackOptions o = birdScene().options;
  o.threads = static_cast<int>(state.range(0));
  runBird(state, o);
}
BENCHMARK(BM_PackBird)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The bird with the packer's default sampling (key barbs, barb/shaft samples, field bins, skin sample
// spacing) and the scene's styling: what the scene's denser sampling costs.
void BM_PackBirdDefaultSampling(benchmark::State& state) {
  PackOptions o = withDefaultSampling(birdScene().options);
  o.threads = static_cast<int>(state.range(0));
  runBird(state, o);
}
BENCHMARK(BM_PackBirdDefaultSampling)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// 426 feathers at three feather scales (thesis Figure 9.12: the largest feathers are twice as long as the
// smallest); range(0) = scale in percent of the middle one.
void BM_Pack426(benchmark::State& state) {
  PackOptions o;
  o.threads = 2;
  run(state, scene(426, state.range(0) / 100.0, 3), o);
}
BENCHMARK(BM_Pack426)->Arg(67)->Arg(100)->Arg(133)->Unit(benchmark::kMillisecond)->UseRealTime();

// Growth with coat size at constant overlap, 2 threads.
void BM_PackScaling(benchmark::State& state) {
  PackOptions o;
  o.threads = 2;
  const size_t n = static_cast<size_t>(state.range(0));
  const Scene& s = scene(n, 1.0, 3);
  run(state, s, o);
  state.counters["us_per_feather"] =
      benchmark::Counter(static_cast<double>(s.coat.size()) * state.iterations(),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert, benchmark::Counter::kIs1000);
}
BENCHMARK(BM_PackScaling)->Arg(1000)->Arg(5000)->Arg(20000)->Arg(50000)->Unit(benchmark::kMillisecond)->UseRealTime();

// Restyling: a few feathers get a new surface direction, then an incremental repack (8.3).
void BM_Repack3150(benchmark::State& state) {
  const Scene& s = scene(3150, 1.0, 4);
  PackOptions o;
  o.threads = 2;
  const PackResult before = pack(s.skin, s.coat, o);
  CoatFeathers edited = s.coat;
  StyleSelection dir;
  dir.kind = StyleKind::Ids;
  for (int k = 0; k < 5; ++k) dir.ids.push_back(edited.layerOrder[600 * k + 100]);
  dir.direction = glm::dvec3(0.3, 0.2, -1.0);
  const StyleApplied ap = applyStyling(edited, {dir});
  double cpu = 0;
  PackResult r;
  for (auto _ : state) {
    const double c0 = cpuSeconds();
    r = repack(s.skin, edited, before, ap.changed, o);
    cpu += cpuSeconds() - c0;
    benchmark::DoNotOptimize(r.elevation.data());
  }
  state.counters["recomputed"] = static_cast<double>(r.stats.recomputed);
  state.counters["cpu_ms"] = 1e3 * cpu / state.iterations();
}
BENCHMARK(BM_Repack3150)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
