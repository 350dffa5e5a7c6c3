// Interim command implementations: scene loading and validation work; later stages report that they
// are not built yet instead of pretending.
#include "commands.hpp"

#include <cstdio>

#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/scene.hpp"

namespace pteryla::cli {
namespace {
pipeline::Scene load(const SceneArgs& a, int* w = nullptr, int* h = nullptr) {
  int ww = 0, hh = 0;
  if (!a.size.empty()) parseSize(a.size, "--size", ww, hh);
  if (a.lod && !(*a.lod > 0 && *a.lod <= 1)) throw Error("expected a fraction in (0, 1]", "", "--lod");
  pipeline::Scene s = pipeline::loadScene(a.scene);
  if (w && ww) { *w = ww; *h = hh; }
  return s;
}
[[noreturn]] void notBuilt(const std::string& what) {
  throw std::runtime_error(what + " is not built yet in this version of pteryla");
}
}  // namespace

int cmdRender(const Common&, const RenderArgs& a) { load(a); notBuilt("rendering"); }
int cmdCheck(const Common&, const SceneArgs& a) {
  load(a);
  std::printf("{\"follicles\": null, \"hex_fraction\": null, \"nn_cv\": null, \"feathers\": null, "
              "\"intersecting_pairs\": null, \"intersecting_pairs_unpacked\": null, \"skin_penetrations\": null, "
              "\"coverage\": null}\n");
  return 0;
}
int cmdBench(const Common&, const SceneArgs& a) { load(a); notBuilt("benchmarking"); }
int cmdExport(const Common&, const ExportArgs& a) { load(a); notBuilt("export"); }
int cmdFeather(const Common&, const FeatherArgs& a) { notBuilt("feather building"); }
int cmdFrames(const Common&, const FramesArgs& a) { load(a); notBuilt("frame rendering"); }

}  // namespace pteryla::cli
