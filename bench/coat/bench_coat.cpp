// Coat I speed: follicle scattering, Lloyd relaxation (target: 10,000 follicles x 20 iterations < 1 s on
// 2 cores) and its scaling from 1k to 100k follicles, regularity metrics.
// Run: build/bench/coat/bench_coat --benchmark_filter=Relax
#include <benchmark/benchmark.h>

#include <ctime>

#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/metrics.hpp"
#include "pteryla/coat/primitives.hpp"
#include "pteryla/coat/relax.hpp"

using namespace pteryla::coat;

namespace {

struct Sphere {
  SkinMesh mesh = makeIcosphere(5);  // 20,480 faces
  Tract tract = wholeMeshTract(mesh);
};

const Sphere& sphere() {
  static const Sphere s;
  return s;
}

Follicles scattered(size_t n) {
  ScatterOptions o;
  o.count = n;
  o.seed = 1;
  return scatterFollicles(sphere().mesh, sphere().tract, o);
}

double cpuSeconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

// Relaxation from random positions, `iterations` Lloyd steps; reports wall ms per iteration and the
// whole-process CPU time (the build machine is shared, so CPU is the steadier number).
void relax(benchmark::State& state, size_t n, int iterations) {
  const Follicles start = scattered(n);
  RelaxOptions o;
  o.iterations = iterations;
  double cpu = 0, wall = 0;
  for (auto _ : state) {
    state.PauseTiming();
    Follicles f = start;
    state.ResumeTiming();
    const double c0 = cpuSeconds();
    const RelaxResult r = relaxFollicles(sphere().mesh, sphere().tract, f, o);
    cpu += cpuSeconds() - c0;
    wall += r.seconds;
    benchmark::DoNotOptimize(r.energy.back());
  }
  const double runs = static_cast<double>(state.iterations());
  state.counters["ms_per_iter"] = 1000.0 * wall / runs / iterations;
  state.counters["us_per_follicle_iter"] = 1e6 * wall / runs / iterations / static_cast<double>(n);
  state.counters["cpu_s"] = cpu / runs;
}

void BM_Relax10kFollicles20Iterations(benchmark::State& state) { relax(state, 10000, 20); }
BENCHMARK(BM_Relax10kFollicles20Iterations)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

void BM_RelaxScaling(benchmark::State& state) { relax(state, static_cast<size_t>(state.range(0)), 5); }
BENCHMARK(BM_RelaxScaling)
    ->Arg(1000)
    ->Arg(3000)
    ->Arg(10000)
    ->Arg(30000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_RelaxBiased10k(benchmark::State& state) {
  const Follicles start = scattered(10000);
  RelaxOptions o;
  o.iterations = 20;
  o.bias.push_back({{0, 0, 1}, {1, 0, 0}, 0.6, 1.6, 0.0});
  for (auto _ : state) {
    state.PauseTiming();
    Follicles f = start;
    state.ResumeTiming();
    benchmark::DoNotOptimize(relaxFollicles(sphere().mesh, sphere().tract, f, o).energy.back());
  }
}
BENCHMARK(BM_RelaxBiased10k)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Scatter100k(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(scattered(100000).size());
}
BENCHMARK(BM_Scatter100k)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Metrics10k(benchmark::State& state) {
  Follicles f = scattered(10000);
  RelaxOptions o;
  o.iterations = 10;
  relaxFollicles(sphere().mesh, sphere().tract, f, o);
  for (auto _ : state) benchmark::DoNotOptimize(measureDistribution(sphere().mesh, sphere().tract, f).hexFraction);
}
BENCHMARK(BM_Metrics10k)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
