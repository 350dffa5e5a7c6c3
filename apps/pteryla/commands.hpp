#pragma once
#include <cstdint>
#include <optional>
#include <string>

#include "cli_support.hpp"

namespace pteryla::cli {

struct SceneArgs {
  std::string scene;
  std::optional<double> time;
  std::optional<double> lod;
  std::string seed;       // empty = the scene's seed; else a non-negative integer (checked in load)
  std::string size;       // "WxH" or empty for the scene's render size
  bool fixedLod = false;  // --fixed-lod: render.lod_by_screen_size false (render, bench, frames, farm)
  std::optional<double> instanceTolerance;  // --instance-tolerance: render.instance_tolerance (same commands)
};

struct BenchArgs : SceneArgs {
  bool check = false;  // also time the checker (check_mesh, check)
};
struct RenderArgs : SceneArgs {
  std::string out;
  std::string style;  // empty = scene's style
};
struct ExportArgs : SceneArgs {
  std::string out;
  std::optional<double> from, to;  // a frame range (both or neither)
  double fps = 24;
  std::string as = "curves";  // USD coat representation: curves, cards or instances
  bool asGiven = false;       // --as was on the command line
  double metersPerUnit = 1.0;
};
struct FramesArgs : SceneArgs {
  double from = 0, to = 1, fps = 24;
  std::string out;
  std::string style;
  std::optional<int64_t> chunk;  // frames per task; with `task`, render only that chunk
  std::optional<int64_t> task;   // 0-based chunk index
  bool force = false;            // re-render frames even when their sidecar says they are complete
  bool assemble = false;         // render nothing: verify every frame, write the manifest and contact sheet
  std::string golden;            // compare each frame with GOLDEN/frame_NNNN.png (empty: no comparison)
  render::DiffTolerance goldenTolerance;
  // --export .glb|.gltf|.usda: each frame is exported (exchange::exportCoat at that time) to
  // DIR/frame_NNNN<ext> instead of rendered; empty = PNG frames.
  std::string exportExt;
  std::string as = "curves";  // USD coat representation (--as)
  bool asGiven = false;
  double metersPerUnit = 1.0;
  bool metersGiven = false;
};
struct FarmArgs : FramesArgs {
  int64_t farmChunk = 10;  // frames per array task
  std::string partition;
  std::string mem;  // Slurm --mem for each task (e.g. 2G); empty = the cluster default
  bool dryRun = false;
};
struct DiffArgs {
  std::string actual, expected, out;  // out: a picture of the difference (empty: none)
  render::DiffTolerance tolerance;
};
struct FeatherArgs {
  std::string file, out;
  double age = 1.0;
  double lod = 1.0;
  std::string size = "512x512";
  // --from-scan IMAGE: measure a feather from a flatbed scan and write it to `out` (.json) instead.
  std::string fromScan;
  std::optional<std::string> rachis;    // "x0,y0,x1,y1[,...]" pixels, base to tip; absent = detect
  std::optional<double> pixelsPerUnit;  // empty: the scan's resolution metadata, else 300 dpi (per cm)
  std::string texture;                  // texture file; empty = OUT's name + "_texture.png"
  bool noTexture = false;
};

// Each returns the process exit code; bad input throws pteryla::Error (main maps it to exit 2).
int cmdRender(const Common&, const RenderArgs&);
int cmdCheck(const Common&, const SceneArgs&);
int cmdBench(const Common&, const BenchArgs&);
int cmdExport(const Common&, const ExportArgs&);
// Builds a feather file's geometry or image, or with --from-scan measures a feather from a scan.
int cmdFeather(const Common&, const FeatherArgs&);
int cmdFrames(const Common&, const FramesArgs&);
int cmdFarmSlurm(const Common&, const FarmArgs&);
// Exit 0 when the images match within the tolerance, 1 when they differ (or differ in size).
int cmdDiff(const Common&, const DiffArgs&);

}  // namespace pteryla::cli
