// Coat II speed: the thesis' full bird (Streit 2003, 9.2.1: 18 tracts, 80 key feathers, 3148 feathers) on the
// bundled bird skin: parameterize every tract, interpolate every feather from the key feathers, compute
// directions and frames, order the layers. Target: interpolation of all feathers < 0.1 s.
#include <benchmark/benchmark.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <ctime>
#include <filesystem>
#include <limits>

#include "pteryla/coat/directions.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/key_feathers.hpp"
#include "pteryla/coat/ordering.hpp"
#include "pteryla/coat/parameterize.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/feather/io.hpp"

using namespace pteryla;
using namespace pteryla::coat;

namespace {

constexpr size_t kFollicles = 3150;

double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}
constexpr size_t kKeys = 80;

struct Bird {
  SkinMesh skin;
  std::vector<Tract> tracts;
  Follicles follicles;
  std::vector<TractParameterization> params;
  FeatherLibrary library;
  std::vector<TractKeys> keys;
  DirectionOptions directions;
  SurfaceDirections dirs;
  size_t keyCount = 0;
};

// k well-spread follicles of a tract: farthest-point sampling in (u,v) from the first follicle.
std::vector<uint32_t> spreadFollicles(const TractParameterization& p, size_t k) {
  std::vector<uint32_t> chosen{0};
  std::vector<double> d(p.follicles.size(), std::numeric_limits<double>::infinity());
  while (chosen.size() < std::min(k, p.follicles.size())) {
    const glm::dvec2 last = p.follicleUv[chosen.back()];
    size_t best = 0;
    for (size_t i = 0; i < d.size(); ++i) {
      d[i] = std::min(d[i], glm::length(p.follicleUv[i] - last));
      if (d[i] > d[best]) best = i;
    }
    chosen.push_back(static_cast<uint32_t>(best));
  }
  return chosen;
}

Bird makeBird() {
  Bird b;
  const std::string data = PTERYLA_DATA_DIR;
  b.skin = loadSkinMesh(data + "/meshes/bird.obj");
  for (const auto& g : b.skin.groupNames)
    if (g.rfind("apteria", 0) != 0) b.tracts.push_back(tractFromGroups(b.skin, g, {g}));
  double total = 0;
  for (const auto& t : b.tracts) total += tractArea(b.skin, t);
  for (uint32_t t = 0; t < b.tracts.size(); ++t) {
    ScatterOptions o;
    o.seed = 5;
    o.tractIndex = t;
    o.count =
        std::max<size_t>(8, static_cast<size_t>(std::lround(kFollicles * tractArea(b.skin, b.tracts[t]) / total)));
    o.density.uniform = 1.0;
    b.follicles.append(scatterFollicles(b.skin, b.tracts[t], o));
  }
  for (uint32_t t = 0; t < b.tracts.size(); ++t)
    b.params.push_back(parameterizeTract(b.skin, b.tracts[t], t, b.follicles));
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(data + "/feathers")) {
    if (!e.is_regular_file() || e.path().extension() != ".json") continue;
    feather::FeatherParams p = feather::loadFeather(e.path().string());
    if (p.generator != "streit") continue;
    names.push_back(e.path().stem().string());
    b.library[names.back()] = std::move(p);
  }
  std::sort(names.begin(), names.end());
  // 80 keys: 5 on the first (80 - 4 * 18) tracts, 4 on the others.
  const size_t nt = b.tracts.size();
  const size_t extra = kKeys > 4 * nt ? kKeys - 4 * nt : 0;
  size_t next = 0;
  b.keys.resize(nt);
  for (size_t t = 0; t < nt; ++t) {
    b.keys[t].param = &b.params[t];
    b.keys[t].scaleJitter = 0.1;
    for (uint32_t slot : spreadFollicles(b.params[t], t < extra ? 5 : 4))
      b.keys[t].keys.push_back({b.params[t].follicles[slot], names[next++ % names.size()]});
    b.keyCount += b.keys[t].keys.size();
  }
  b.directions.field.axis = {{0.97, 0.327, 0}, {0.74, 0.37, 0},  {0.44, 0.14, 0},
                             {-0.08, 0, 0},    {-0.56, 0.03, 0}, {-1.02, 0.07, 0}};
  b.dirs = computeSurfaceDirections(b.skin, b.tracts, b.follicles, b.directions);
  return b;
}

const Bird& bird() {
  static const Bird b = makeBird();
  return b;
}

void BM_InterpolateBird(benchmark::State& state) {
  const Bird& b = bird();
  CoatFeathers coat;
  InterpolateStats st;
  // Whole-process CPU (all threads): the build machine is shared, so wall time depends on its load.
  const double cpu0 = processCpuSeconds();
  for (auto _ : state) {
    st = interpolateCoatFeathers(b.follicles, b.keys, b.library, {}, coat);
    benchmark::DoNotOptimize(coat.params.data());
  }
  state.counters["process_cpu_ms"] = 1e3 * (processCpuSeconds() - cpu0) / static_cast<double>(state.iterations());
  state.counters["feathers"] = static_cast<double>(st.feathers);
  state.counters["keys"] = static_cast<double>(b.keyCount);
  state.counters["tracts"] = static_cast<double>(b.tracts.size());
  state.counters["blended"] = static_cast<double>(st.blended);
}
BENCHMARK(BM_InterpolateBird)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ParameterizeBird(benchmark::State& state) {
  const Bird& b = bird();
  size_t lscm = 0;
  for (auto _ : state) {
    lscm = 0;
    for (uint32_t t = 0; t < b.tracts.size(); ++t)
      lscm += parameterizeTract(b.skin, b.tracts[t], t, b.follicles).method == ParamMethod::Lscm;
  }
  state.counters["lscm_tracts"] = static_cast<double>(lscm);
  state.counters["tracts"] = static_cast<double>(b.tracts.size());
}
BENCHMARK(BM_ParameterizeBird)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_DirectionsAndFramesBird(benchmark::State& state) {
  const Bird& b = bird();
  CoatFeathers coat;
  interpolateCoatFeathers(b.follicles, b.keys, b.library, {}, coat);
  for (auto _ : state) {
    const SurfaceDirections d = computeSurfaceDirections(b.skin, b.tracts, b.follicles, b.directions);
    evaluateFrames(b.skin, b.follicles, d, coat);
    benchmark::DoNotOptimize(coat.frames.data());
  }
}
BENCHMARK(BM_DirectionsAndFramesBird)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_FramesOnPosedSkinBird(benchmark::State& state) {
  const Bird& b = bird();
  CoatFeathers coat;
  interpolateCoatFeathers(b.follicles, b.keys, b.library, {}, coat);
  for (auto _ : state) {
    evaluateFrames(b.skin, b.follicles, b.dirs, coat);
    benchmark::DoNotOptimize(coat.frames.data());
  }
}
BENCHMARK(BM_FramesOnPosedSkinBird)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_OrderBird(benchmark::State& state) {
  const Bird& b = bird();
  CoatFeathers coat;
  interpolateCoatFeathers(b.follicles, b.keys, b.library, {}, coat);
  for (auto _ : state) {
    orderLayers(b.skin, b.tracts, b.params, b.follicles, b.dirs, OrderOptions{}, coat);
    benchmark::DoNotOptimize(coat.layerOrder.data());
  }
}
BENCHMARK(BM_OrderBird)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
