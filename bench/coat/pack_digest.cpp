// Bit-identity check for packer optimisations: packs the bundled bird (scene sampling and the packer's
// default sampling) and the synthetic 3,150-feather sphere at 1 and 2 threads, and prints one FNV-1a
// digest per run over every output bit (elevations, packed key barbs, points, bounds, group bounds,
// barbsChanged, recomputed, stats without seconds; with --fields also the captured barb height fields).
// Run it before and after a change: the lines must be equal.
//   pack_digest [--fields]
//   pack_digest --time N THREADS [default]: packs the bird N times, prints wall and CPU ms per pack (for
//   `perf stat` of the packer alone: subtract a run with N = 0).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <string>

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

struct Fnv {
  uint64_t h = 1469598103934665603ull;
  void bytes(const void* p, size_t n) {
    const auto* c = static_cast<const unsigned char*>(p);
    for (size_t k = 0; k < n; ++k) {
      h ^= c[k];
      h *= 1099511628211ull;
    }
  }
  template <class T>
  void pod(const T& v) {
    bytes(&v, sizeof(T));
  }
  template <class T, class A>
  void vec(const std::vector<T, A>& v) {
    pod(v.size());
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
};

void digest(const char* name, const CoatFeathers& coat, const PackResult& r, bool fields) {
  Fnv all, elev, params, pts;
  elev.vec(r.elevation);
  for (const auto& p : allPackedParams(coat, r))
    for (const auto* v : {&p.left, &p.right}) {
      params.pod(v->keyBarbs.size());
      for (const auto& kb : v->keyBarbs) {
        params.pod(kb.rp);
        params.vec(kb.cvs);
      }
    }
  pts.vec(r.points);
  pts.vec(r.bounds);
  pts.vec(r.groupBounds);
  all.pod(elev.h);
  all.pod(params.h);
  all.pod(pts.h);
  all.vec(r.order);
  all.vec(r.barbsChanged);
  all.vec(r.recomputed);
  all.vec(r.pointOffset);
  all.vec(r.groupOffset);
  all.vec(r.groupPoint);
  const PackStats& s = r.stats;
  for (size_t v : {s.packed, s.recomputed, s.fixed, s.unopened, s.free, s.shaftClamped, s.conflicts, s.barbsElevated,
                   s.barbsLifted, s.barbsUnresolved, s.candidatePoints, s.dependencies, s.skinSamples})
    all.pod(v);
  if (fields) {
    Fnv f;
    for (const BarbField& b : r.barbFields) {
      f.pod(b.feather);
      f.pod(b.vane);
      f.pod(b.key);
      f.pod(b.root);
      f.pod(b.along);
      f.pod(b.up);
      f.pod(b.length);
      f.pod(b.field.origin);
      f.pod(b.field.cell);
      f.vec(b.field.h);
    }
    all.pod(f.h);
    std::printf("%-22s fields %zu %016llx\n", name, r.barbFields.size(), static_cast<unsigned long long>(f.h));
  }
  std::printf(
      "%-22s all %016llx elev %016llx params %016llx points %016llx | free %zu elevated %zu lifted %zu "
      "unresolved %zu cand %zu deps %zu skin %zu\n",
      name, static_cast<unsigned long long>(all.h), static_cast<unsigned long long>(elev.h),
      static_cast<unsigned long long>(params.h), static_cast<unsigned long long>(pts.h), s.free, s.barbsElevated,
      s.barbsLifted, s.barbsUnresolved, s.candidatePoints, s.dependencies, s.skinSamples);
}

}  // namespace

double cpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double wallSeconds() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

int main(int argc, char** argv) {
  const bool fields = argc > 1 && std::string(argv[1]) == "--fields";
  const bool timing = argc > 3 && std::string(argv[1]) == "--time";
  const std::string path = std::string(PTERYLA_DATA_DIR) + "/scenes/bird.json";
  pipeline::Pipeline p(pipeline::loadScene(path));
  const SkinMesh skin = p.posedSkin();
  const CoatFeathers coat = p.feathers();
  PackingSettings settings;
  if (!p.scene().packing.empty()) {
    JsonReader r(p.scene().packing, path, "packing");
    settings = parsePackingSettings(r);
  }
  PackOptions o = settings.options;
  // The styling resolved as the pipeline resolves it (the bird's coat: no direction edits).
  PackConstraints styled;
  styled.fixedElevation = resolveStyling(coat, settings.styling);
  styled.minElevation = resolveMinElevation(coat, settings.styling);
  styled.shaftBand = resolveShaftBand(coat, settings.styling);
  o.captureFields = fields;
  PackOptions d = withDefaultSampling(o);
  if (timing) {
    const int reps = std::stoi(argv[2]);
    PackOptions& to = argc > 4 && std::string(argv[4]) == "default" ? d : o;
    to.threads = std::stoi(argv[3]);
    for (int k = 0; k < reps; ++k) {
      const double w0 = wallSeconds(), c0 = cpuSeconds();
      const PackResult r = pack(skin, coat, to, styled);
      const double w1 = wallSeconds(), c1 = cpuSeconds();
      std::printf("pack %d: wall %.1f ms cpu %.1f ms (stats.seconds %.1f ms)\n", k, 1e3 * (w1 - w0), 1e3 * (c1 - c0),
                  1e3 * r.stats.seconds);
    }
    return 0;
  }
  for (int t : {1, 2}) {
    o.threads = d.threads = t;
    digest(("bird/" + std::to_string(t)).c_str(), coat, pack(skin, coat, o, styled), fields);
    digest(("bird-default/" + std::to_string(t)).c_str(), coat, pack(skin, coat, d, styled), fields);
  }
  const SkinMesh sphere = makeIcosphere(4);
  const CoatFeathers sc = packtest::sphereCoat(sphere, static_cast<size_t>(3150 / 0.8 + 0.5), std::sqrt(320.0 / 3150));
  PackOptions so;
  so.captureFields = fields;
  for (int t : {1, 2}) {
    so.threads = t;
    digest(("sphere3150/" + std::to_string(t)).c_str(), sc, pack(sphere, sc, so), fields);
  }
  return 0;
}
