// bench_host: a host's frame change through the host API (include/pteryla/pteryla.hpp), as a DCC plug-in
// makes it: a new posed skin, evaluate(), frame(). The bundled bird (data/scenes/bird.json, 3,392
// feathers) at 20% LOD, with its outer parts bent up by a smooth angle that changes every frame.
//   Follow: PoseMode::Follow, the laid coat carried by the pose (issue #24: a frame change under 1 s).
//   Repack: PoseMode::Repack, every pose laid again.
//   TimeOnly: a new time and no new pose on a coat that reads no time (nothing to recompute).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "pteryla/pteryla.hpp"

namespace {

const std::string kBird = std::string(PTERYLA_DATA_DIR) + "/scenes/bird.json";

// The rest skin's positions, as a host holds them: the bird's OBJ vertices in file order (the scene's skin
// keeps that order).
std::vector<double> restPositions() {
  std::vector<double> p;
  FILE* f = std::fopen((std::string(PTERYLA_DATA_DIR) + "/meshes/bird.obj").c_str(), "r");
  if (!f) return p;
  char line[512];
  while (std::fgets(line, sizeof line, f)) {
    double x, y, z;
    if (line[0] == 'v' && line[1] == ' ' && std::sscanf(line + 2, "%lf %lf %lf", &x, &y, &z) == 3) {
      p.push_back(x);
      p.push_back(y);
      p.push_back(z);
    }
  }
  std::fclose(f);
  return p;
}

// Everything farther than 30% of the half width from the middle (in x) rotates about the x axis by up to
// `angle`, smoothly (the wings lift).
std::vector<double> bent(const std::vector<double>& rest, double angle) {
  double lo = 1e300, hi = -1e300;
  for (size_t v = 0; v < rest.size() / 3; ++v) {
    lo = std::min(lo, rest[3 * v]);
    hi = std::max(hi, rest[3 * v]);
  }
  std::vector<double> p = rest;
  for (size_t v = 0; v < rest.size() / 3; ++v) {
    const double x = std::abs(rest[3 * v] - 0.5 * (lo + hi)) / (0.5 * (hi - lo));
    double w = std::clamp((x - 0.3) / 0.4, 0.0, 1.0);
    w = w * w * (3 - 2 * w);
    const double a = angle * w, c = std::cos(a), s = std::sin(a), y = rest[3 * v + 1], z = rest[3 * v + 2];
    p[3 * v + 1] = c * y - s * z;
    p[3 * v + 2] = s * y + c * z;
  }
  return p;
}

void poseFrames(benchmark::State& state, pteryla::PoseMode mode) {
  const std::vector<double> rest = restPositions();
  pteryla::Session s = pteryla::Session::fromSceneFile(kBird);
  if (rest.size() != 3 * s.vertexCount()) {
    state.SkipWithError("data/meshes/bird.obj does not match the bird scene's skin");
    return;
  }
  s.setLod(0.2);
  s.setPoseMode(mode);
  if (!s.evaluate()) return;
  int k = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const std::vector<double> pose = bent(rest, 0.05 + 0.01 * (k++ % 20));
    state.ResumeTiming();
    s.setPose(pose);
    if (!s.evaluate()) state.SkipWithError("cancelled");
    benchmark::DoNotOptimize(s.frame().positions.data);
  }
  state.counters["vertices"] = double(s.frame().positions.size / 3);
  state.counters["feathers"] = double(s.frame().featherCount);
}

void BM_BirdPoseFollow(benchmark::State& state) { poseFrames(state, pteryla::PoseMode::Follow); }
void BM_BirdPoseRepack(benchmark::State& state) { poseFrames(state, pteryla::PoseMode::Repack); }

void BM_BirdTimeOnly(benchmark::State& state) {
  pteryla::Session s = pteryla::Session::fromSceneFile(kBird);
  s.setLod(0.2);
  if (!s.evaluate()) return;
  int k = 0;
  for (auto _ : state) {
    s.setTime(0.04 * (++k));
    if (!s.evaluate()) state.SkipWithError("cancelled");
    benchmark::DoNotOptimize(s.frame().positions.data);
  }
}

}  // namespace

BENCHMARK(BM_BirdPoseFollow)->Unit(benchmark::kMillisecond)->MinTime(2.0);
BENCHMARK(BM_BirdPoseRepack)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_BirdTimeOnly)->Unit(benchmark::kMillisecond)->MinTime(1.0);
