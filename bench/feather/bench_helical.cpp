// Helical feather generator (Zhang & Kanai): cost of growing, unfurling and converting the example
// feathers, i.e. what loading a "helical" feather file costs on top of an ordinary one.
#include <benchmark/benchmark.h>

#include "pteryla/feather/helical.hpp"
#include "pteryla/feather/io.hpp"

using namespace pteryla;
using namespace pteryla::feather;

namespace {

const std::string kFlight = std::string(PTERYLA_DATA_DIR) + "/feathers/helical-flight.json";

const HelicalParams& flight() {
  static const HelicalParams p = [] {
    const Json j = readJsonFile(kFlight);
    JsonReader r(j.at("helical"), kFlight, "helical");
    return readHelical(r);
  }();
  return p;
}

// Spawn schedule and travel-time tables (500 completed barbs).
void BM_HelicalGrowth(benchmark::State& state) {
  for (auto _ : state) {
    HelicalGrowth g(flight());
    benchmark::DoNotOptimize(g.endTime());
  }
}
BENCHMARK(BM_HelicalGrowth)->Unit(benchmark::kMillisecond);

// Trails of every completed barb, unfurled into the feather frame (~70k points).
void BM_HelicalUnfurl(benchmark::State& state) {
  const HelicalGrowth g(flight());
  for (auto _ : state) {
    HelicalFeather f = helicalFeather(g);
    benchmark::DoNotOptimize(f.points.data());
  }
}
BENCHMARK(BM_HelicalUnfurl)->Unit(benchmark::kMillisecond);

// Key barb selection and Bezier fits.
void BM_HelicalConvert(benchmark::State& state) {
  const HelicalGrowth g(flight());
  const HelicalFeather f = helicalFeather(g);
  for (auto _ : state) {
    HelicalConversion c = convertHelical(g, f, 14.0);
    benchmark::DoNotOptimize(c.feather.left.keyBarbs.data());
  }
}
BENCHMARK(BM_HelicalConvert)->Unit(benchmark::kMillisecond);

// Animation: stepping the whole growth at 60 fps frame steps of the paper's dt = 0.05.
void BM_HelicalAnimate(benchmark::State& state) {
  const HelicalGrowth g(flight());
  for (auto _ : state) {
    HelicalState s(g);
    while (!s.finished()) s.step(0.05);
    benchmark::DoNotOptimize(s.spawnedCount());
  }
}
BENCHMARK(BM_HelicalAnimate)->Unit(benchmark::kMillisecond);

// loadFeather of the example file, end to end.
void BM_HelicalLoadFeather(benchmark::State& state) {
  for (auto _ : state) {
    FeatherParams p = loadFeather(kFlight);
    benchmark::DoNotOptimize(p.rachisLength);
  }
}
BENCHMARK(BM_HelicalLoadFeather)->Unit(benchmark::kMillisecond);

}  // namespace
