// Feather meshing throughput (Streit 2003, 5.3 and 9.1: 3,148 feathers, 2.2 million triangles at full
// detail, 276,000 at 20%). Targets on 2 cores: a coat of 3,150 feathers (~2.2 M triangles) meshed at
// full detail in < 0.5 s (BM_CoatMesh/100) and at 20% detail in < 0.1 s (BM_CoatMesh/20).
// Curves and collapse orders are computed once (they belong to the feather definitions); the timed part
// is tessellation + attributes + placement into one coat TriMesh whose storage is reused (re-meshing a
// coat every frame; the first build also pays the page faults of ~140 MB of attributes).
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "pteryla/core/trimesh_reuse.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/feather/lod.hpp"
#include "pteryla/feather/mesh.hpp"

using namespace pteryla;
using namespace pteryla::feather;

namespace {

struct Coat {
  std::vector<FeatherCurves> curves;
  std::vector<LodOrder> orders;
  std::vector<FeatherPlacement> placements;
};

// 3,150 contour feathers of varying size (rachis 40%..100% of data/feathers/contour.json, barbs every
// 0.1 units: 10..25 barbs per vane), placed on a unit-radius body.
const Coat& coat() {
  static const Coat c = [] {
    Coat out;
    FeatherParams base = loadFeather(std::string(PTERYLA_DATA_DIR) + "/feathers/contour.json");
    base.afterfeather.reset();
    base.spacingBase = base.spacingTip = 0.1;
    const int n = 3150;
    out.curves.resize(n);
    out.orders.resize(n);
    out.placements.resize(n);
    for (int i = 0; i < n; ++i) {
      FeatherParams p = base;
      const double s = 0.4 + 0.6 * ((i * 37) % 101) / 100.0;
      p.rachisLength *= s;
      p.barbLength *= s;
      p.seed = 100 + static_cast<uint64_t>(i);
      generateBarbs(p, out.curves[i]);
      computeLodOrder(out.curves[i], out.orders[i]);
      const double th = 2.399963 * i, z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1 - z * z);
      const glm::dvec3 N(r * std::cos(th), r * std::sin(th), z);
      glm::dvec3 T = glm::cross(N, glm::dvec3(0, 0, 1));
      if (glm::length(T) < 1e-6) T = {1, 0, 0};
      T = glm::normalize(T);
      out.placements[i] = FeatherPlacement::fromFollicle(N, T, N, 0.2, 0.05);
    }
    return out;
  }();
  return c;
}

std::vector<FeatherMeshInput> inputs(double lod) {
  const Coat& c = coat();
  std::vector<FeatherMeshInput> in(c.curves.size());
  for (size_t i = 0; i < in.size(); ++i) {
    in[i].curves = &c.curves[i];
    in[i].order = &c.orders[i];
    in[i].placement = c.placements[i];
    in[i].featherId = static_cast<uint32_t>(i);
    in[i].lod = lod;
  }
  return in;
}

// Whole coat, parallel (TBB): range(0) = level of detail in percent.
void BM_CoatMesh(benchmark::State& state) {
  const std::vector<FeatherMeshInput> in = inputs(state.range(0) / 100.0);
  TriMesh mesh;
  std::vector<FeatherMeshRanges> ranges;
  appendFeatherMeshes(in.data(), in.size(), MeshOptions{}, mesh, &ranges);  // warm: steady-state re-meshing
  size_t tris = 0;
  for (auto _ : state) {
    clearKeepingCapacity(mesh);
    appendFeatherMeshes(in.data(), in.size(), MeshOptions{}, mesh, &ranges);
    tris = mesh.triangleCount();
    benchmark::DoNotOptimize(mesh.positions.data());
  }
  state.counters["feathers"] = static_cast<double>(in.size());
  state.counters["triangles"] = static_cast<double>(tris);
  state.counters["vertices"] = static_cast<double>(mesh.vertexCount());
  state.counters["tri/s"] =
      benchmark::Counter(static_cast<double>(tris) * state.iterations(), benchmark::Counter::kIsRate);
}
// Real time is the target; the CPU column is the whole process (all TBB threads), useful on a busy machine.
BENCHMARK(BM_CoatMesh)
    ->Arg(100)
    ->Arg(60)
    ->Arg(20)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// Same coat, one feather after the other on one thread (appendFeatherMesh).
void BM_CoatMeshSerial(benchmark::State& state) {
  const std::vector<FeatherMeshInput> in = inputs(state.range(0) / 100.0);
  TriMesh mesh;
  for (const auto& f : in) appendFeatherMesh(f, MeshOptions{}, mesh);  // warm
  for (auto _ : state) {
    clearKeepingCapacity(mesh);
    for (const auto& f : in) appendFeatherMesh(f, MeshOptions{}, mesh);
    benchmark::DoNotOptimize(mesh.positions.data());
  }
  state.counters["triangles"] = static_cast<double>(mesh.triangleCount());
  state.counters["tri/s"] =
      benchmark::Counter(static_cast<double>(mesh.triangleCount()) * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_CoatMeshSerial)->Arg(100)->Arg(20)->Unit(benchmark::kMillisecond)->UseRealTime();

// One large contour feather (the ~3,000-triangle feather of Fig. 5.8) from params, growth included.
void BM_BuildFeatherMesh(benchmark::State& state) {
  const FeatherParams p = loadFeather(std::string(PTERYLA_DATA_DIR) + "/feathers/contour.json");
  const double age = state.range(0) / 100.0;
  size_t tris = 0;
  for (auto _ : state) {
    const TriMesh m = buildFeatherMesh(p, age, 1.0);
    tris = m.triangleCount();
    benchmark::DoNotOptimize(m.positions.data());
  }
  state.counters["triangles"] = static_cast<double>(tris);
}
BENCHMARK(BM_BuildFeatherMesh)->Arg(100)->Arg(65)->Unit(benchmark::kMicrosecond);

}  // namespace
