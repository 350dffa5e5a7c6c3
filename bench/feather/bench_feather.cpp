// Barb generation throughput (Streit 2003, 5.2.2). Target: all barb curves of 3,150 contour feathers
// (~150 barbs each) in under 50 ms on 2 cores -> BM_CoatOfContourFeathers.
#include <benchmark/benchmark.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/interpolate.hpp"
#include "pteryla/feather/io.hpp"

using namespace pteryla::feather;

namespace {

const FeatherParams& contour() {
  static const FeatherParams p = loadFeather(std::string(PTERYLA_DATA_DIR) + "/feathers/contour.json");
  return p;
}

// 3,150 distinct contour feathers: blends of the contour and covert key feathers with varying seeds.
const std::vector<FeatherParams>& coat() {
  static const std::vector<FeatherParams> feathers = [] {
    const FeatherParams covert = loadFeather(std::string(PTERYLA_DATA_DIR) + "/feathers/covert.json");
    FeatherParams a = contour(), b = covert;
    a.afterfeather.reset();
    b.rachisLength = a.rachisLength;  // same size class: ~150 barbs each
    b.spacingBase = a.spacingBase;
    b.spacingTip = a.spacingTip;
    std::vector<FeatherParams> out;
    out.reserve(3150);
    for (int i = 0; i < 3150; ++i) {
      out.push_back(interpolateFeathers(a, b, (i % 97) / 96.0));
      out.back().seed = 1000 + i;
    }
    return out;
  }();
  return feathers;
}

void BM_GenerateContourFeather(benchmark::State& state) {
  FeatherParams p = contour();
  p.afterfeather.reset();
  FeatherCurves curves;
  generateBarbs(p, curves);
  for (auto _ : state) {
    generateBarbs(p, curves);
    benchmark::DoNotOptimize(curves.cvs.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(curves.barbs.size()));
  state.counters["barbs"] = static_cast<double>(curves.barbs.size());
}
BENCHMARK(BM_GenerateContourFeather);

void BM_CoatOfContourFeathers(benchmark::State& state) {
  const auto& feathers = coat();
  tbb::enumerable_thread_specific<FeatherCurves> scratch;
  std::vector<size_t> barbs(feathers.size());
  const bool parallel = state.range(0) != 0;
  for (auto _ : state) {
    auto body = [&](size_t i) {
      FeatherCurves& c = scratch.local();
      generateBarbs(feathers[i], c);
      barbs[i] = c.barbs.size();
    };
    if (parallel)
      tbb::parallel_for(size_t(0), feathers.size(), body);
    else
      for (size_t i = 0; i < feathers.size(); ++i) body(i);
  }
  size_t total = 0;
  for (size_t n : barbs) total += n;
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(total));
  state.counters["feathers"] = static_cast<double>(feathers.size());
  state.counters["barbs_per_feather"] = static_cast<double>(total) / feathers.size();
}
BENCHMARK(BM_CoatOfContourFeathers)->Arg(0)->Arg(1)->ArgName("parallel")->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_InterpolateFeathers(benchmark::State& state) {
  const FeatherParams a = contour();
  const FeatherParams b = loadFeather(std::string(PTERYLA_DATA_DIR) + "/feathers/covert.json");
  double t = 0.1;
  for (auto _ : state) {
    FeatherParams m = interpolateFeathers(a, b, t);
    benchmark::DoNotOptimize(m.rachisLength);
    t = t > 0.8 ? 0.1 : t + 0.05;
  }
}
BENCHMARK(BM_InterpolateFeathers);

}  // namespace
