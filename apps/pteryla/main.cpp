// pteryla: headless batch tool. Every subcommand evaluates scenes through the pipeline.
// Exit codes: 0 success, 2 bad input (scene, mesh, feather file, option), 1 internal failure.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include "commands.hpp"
#include "pteryla/pteryla.hpp"

using namespace pteryla::cli;

namespace {

void addSceneOptions(CLI::App* sub, SceneArgs& a, bool withSize) {
  sub->add_option("scene", a.scene, "Scene file (.json) or a bare mesh (.obj/.ply/.off/.stl) to feather with defaults")
      ->required();
  sub->add_option("--time,-t", a.time, "Time on the scene's timeline (moult, skinning, controls); default: scene time");
  sub->add_option("--lod", a.lod,
                  withSize ? "Fraction of feather geometry in (0,1]; default: the scene's render.lod. Rendering "
                             "by screen size (render.lod_by_screen_size, default on) it is the cap: the level of a "
                             "feather long enough on screen to show its barbs 2 pixels apart; smaller feathers "
                             "get less (docs/render.md)"
                           : "Fraction of feather geometry in (0,1]; default: the scene's render.lod");
  sub->add_option("--seed", a.seed, "Override the scene's master seed (an integer in [0, 2^64-1])");
  if (withSize) {
    sub->add_option("--size", a.size, "Image size WxH; default: the scene's render.size");
    sub->add_flag("--fixed-lod", a.fixedLod,
                  "Mesh every feather at --lod (a fixed level) instead of by its size on screen: as if the scene "
                  "had render.lod_by_screen_size false");
    sub->add_option("--instance-tolerance", a.instanceTolerance,
                    "Instancing: feathers within this fraction of their length of an earlier feather are "
                    "meshed from its curves and share one unplaced mesh, in [0, 0.1]; 0 = off; default: the "
                    "scene's render.instance_tolerance (docs/limits.md)");
  }
}

void addToleranceOptions(CLI::App* sub, pteryla::render::DiffTolerance& t, const std::string& prefix) {
  sub->add_option("--" + prefix + "tolerance", t.pixel,
                  "A pixel changed when a channel differs by more than this, in [0,1] of the 0..255 range "
                  "(default 5/255 = 0.0196)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--" + prefix + "fraction", t.fraction,
                  "Largest fraction of changed pixels that still matches (default 0.001)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--" + prefix + "max-error", t.maxError,
                  "Largest channel difference anywhere that still matches, in [0,1] (default 64/255 = 0.251)")
      ->check(CLI::Range(0.0, 1.0));
}

void addGoldenOptions(CLI::App* sub, FramesArgs& a) {
  sub->add_option("--golden", a.golden,
                  "Compare each frame with GOLDEN/frame_NNNN.png as it is rendered (or found complete); a missing "
                  "or differing golden makes the exit code 1, the manifest lists them and DIR/golden_diff/ "
                  "pictures each difference (docs/ci.md). Exported frames (--export) must equal their golden "
                  "byte for byte");
  addToleranceOptions(sub, a.goldenTolerance, "golden-");
}

// --export, --as, --meters-per-unit of `frames` and `farm slurm`.
void addFrameExportOptions(CLI::App* sub, FramesArgs& a) {
  sub->add_option("--export", a.exportExt,
                  "Export each frame instead of rendering it: .glb, .gltf or .usda, written to DIR/frame_NNNN.glb "
                  "... (the same file as `pteryla export --time T`; docs/export.md)");
  sub->add_option_function<std::string>(
      "--as", [&a](const std::string& v) { a.as = v, a.asGiven = true; },
      "With --export .usda: the coat as curves (default), cards or instances");
  sub->add_option_function<double>(
      "--meters-per-unit", [&a](double v) { a.metersPerUnit = v, a.metersGiven = true; },
      "With --export: scene units in metres (USD metersPerUnit; default 1)");
}

}  // namespace

int main(int argc, char** argv) {
  pteryla::keepFreedMemoryInProcess();
  CLI::App app{
      "pteryla: bird feather coats (Streit 2003) from the command line.\n"
      "Scenes are JSON files (docs/scene-format.md) or bare meshes.\n"
      "Exit codes: 0 success, 2 bad input (including requests above --max-memory and failed writes;\n"
      "every output is written to a temporary file and renamed, so a failed write keeps the old file),\n"
      "1 internal failure. Limits: docs/limits.md."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "pteryla 0.1.0");
  Common common;
  app.add_flag("--quiet,-q", common.quiet, "No progress or info on stderr")->configurable(false);
  const std::string memoryHelp =
      "Memory ceiling in GB (default " + std::to_string(int(pteryla::kDefaultMemoryLimitGb)) +
      "): requests estimated above it (follicles, barbs, triangles, image or texture pixels, declared mesh "
      "counts) are refused with exit 2 before allocating (docs/limits.md)";
  app.add_option("--max-memory", common.maxMemoryGb, memoryHelp)->configurable(false);

  RenderArgs render;
  auto* cRender = app.add_subcommand("render", "Render a scene to a PNG headlessly (OSMesa)");
  addSceneOptions(cRender, render, true);
  cRender->add_option("--out,-o", render.out, "Output image (.png, .jpg, .tif, .exr)")->required();
  cRender
      ->add_option("--style", render.style, "Render style: shaded or scratchboard; default: the scene's render.style")
      ->check(CLI::IsMember({"shaded", "scratchboard"}));

  SceneArgs check;
  auto* cCheck = app.add_subcommand(
      "check",
      "Print one JSON object of quality metrics on stdout: follicles, hex_fraction, nn_cv, feathers,\n"
      "intersecting_pairs, intersecting_pairs_unpacked (every feather at 10 degrees, unflattened),\n"
      "intersecting_pairs_proxy, skin_penetrations, coverage, elevation_p50, elevation_p90 (degrees),\n"
      "fixed_feathers, hidden_feathers (draped coats), intersecting_feathers and penetrating_feathers\n"
      "(the feathers, by index, with a triangle crossing another feather's or a vertex under the skin)\n"
      "(null = not computed)");
  addSceneOptions(cCheck, check, false);

  BenchArgs bench;
  auto* cBench = app.add_subcommand(
      "bench",
      "Print one JSON object of per-stage seconds of the first evaluation (load, distribute,\n"
      "interpolate, pack, mesh, render), pack_repeat (best of 3 more full packs, warm memory), frame\n"
      "(a timeline step from the rendered frame), triangles, the mesh stage's unplaced store\n"
      "(representatives, unplaced_meshes, unplaced_mb against unplaced_mb_unshared: instancing,\n"
      "--instance-tolerance) and peak_rss_mb on stdout; with --check\n"
      "also check_mesh (meshing at full detail) and check (`pteryla check`'s measurement of that mesh).\n"
      "The first evaluation is the first render's: the mesh at its levels of detail (by screen size\n"
      "unless --fixed-lod)");
  addSceneOptions(cBench, bench, true);
  cBench->add_flag("--check", bench.check, "Also time the checker: the mesh at full detail, then Pipeline::check");

  ExportArgs exportArgs;
  auto* cExport = app.add_subcommand(
      "export",
      "Write the skin and the coat for other tools (docs/export.md), by the extension of --out:\n"
      ".glb / .gltf  glTF 2.0: skin + vane cards with textures, KHR_materials_anisotropy, per-vertex\n"
      "              _FEATHER_ID _TRACT _LAYER _AGE; a frame range as a node-animated sequence\n"
      ".usda         USD: skin Mesh + the coat --as curves (BasisCurves), cards (Mesh) or instances\n"
      "              (PointInstancer); a frame range as time samples\n"
      ".obj / .ply   one frame of skin + cards\n"
      "The file is written to a temporary and renamed: a failed export keeps any previous file.");
  addSceneOptions(cExport, exportArgs, false);
  cExport->add_option("--out,-o", exportArgs.out, "Output file: .glb, .gltf, .usda, .obj or .ply")->required();
  auto* optFrom = cExport->add_option("--from", exportArgs.from,
                                      "Start time of a frame range (with --to; frame k at FROM + k/FPS)");
  auto* optTo = cExport->add_option("--to", exportArgs.to, "End time of the range (inclusive)");
  cExport->add_option("--fps", exportArgs.fps, "Frames per unit of time for a range (default 24)");
  auto* optAs = cExport->add_option("--as", exportArgs.as,
                                    "USD coat representation: curves (default; rachis + barbs as BasisCurves), cards "
                                    "(vane Mesh) or instances (PointInstancer over prototype feathers)");
  cExport->add_option("--meters-per-unit", exportArgs.metersPerUnit,
                      "Scene units in metres (USD metersPerUnit; default 1)");
  (void)optFrom;
  (void)optTo;

  FeatherArgs feather;
  auto* cFeather = app.add_subcommand(
      "feather",
      "Build one feather from a feather file: geometry (.obj/.ply) or an image (.png).\n"
      "With --from-scan IMAGE instead, measure a feather from a flatbed scan (tip up = left vane on the\n"
      "left, dorsal side shown) and write a feather file (.json): rachis length and lateral curvature,\n"
      "calamus, silhouette, barb spacing, barb angles and two key barbs per vane, and the scan resampled\n"
      "into the feather's texture space as its colour texture (docs/feather-format.md, \"Feathers from scans\")");
  auto* optFile = cFeather->add_option("file", feather.file, "Feather file (.json, docs/feather-format.md)");
  cFeather
      ->add_option("--out,-o", feather.out,
                   "Output: .obj/.ply mesh or .png image; with --from-scan a .json feather file")
      ->required();
  auto* optAge = cFeather->add_option("--age", feather.age, "Feather age in [0,1] (growth); values in (1,2] add wear")
                     ->check(CLI::Range(0.0, 2.0));
  auto* optLod =
      cFeather->add_option("--lod", feather.lod, "Fraction of geometry in (0,1]")->check(CLI::Range(0.0, 1.0));
  auto* optSize = cFeather->add_option("--size", feather.size, "Image size WxH for .png output");
  auto* optScan =
      cFeather->add_option("--from-scan", feather.fromScan,
                           "Scan image (any format OpenImageIO reads) to measure instead of a feather file");
  optFile->excludes(optScan);
  for (auto* o : {optAge, optLod, optSize}) o->excludes(optScan);
  cFeather
      ->add_option("--rachis", feather.rachis,
                   "With --from-scan: the rachis as pixel coordinates x0,y0,x1,y1 (x right, y down), from its base "
                   "(where the vanes begin) to its tip; more pairs mark a polyline. Default: found automatically, "
                   "which needs the bare calamus visible at the base and a shaft that contrasts with the vanes; "
                   "otherwise give it")
      ->needs(optScan);
  cFeather
      ->add_option("--pixels-per-unit", feather.pixelsPerUnit,
                   "With --from-scan: scan pixels per scene unit (default: the image's resolution metadata as pixels "
                   "per centimetre, else 300 dpi = 118.11)")
      ->needs(optScan);
  auto* optTexture = cFeather
                         ->add_option("--texture", feather.texture,
                                      "With --from-scan: where to write the colour texture (.png; default: OUT's "
                                      "name + _texture.png beside it); the feather file refers to it by a path "
                                      "relative to itself, so move the two together")
                         ->needs(optScan);
  cFeather
      ->add_flag("--no-texture", feather.noTexture,
                 "With --from-scan: write no texture (the feather keeps its default look)")
      ->needs(optScan)
      ->excludes(optTexture);

  FramesArgs frames;
  auto* cFrames = app.add_subcommand(
      "frames",
      "Render a time range to a PNG sequence DIR/frame_0000.png ... (frame k at time FROM + k/FPS; at\n"
      "most 100000 frames), or with --export .glb|.gltf|.usda export each frame to DIR/frame_0000.glb ...\n"
      "Each frame gets a sidecar frame_NNNN.png.json (SHA-256, seconds, host) written after it. Frames\n"
      "whose sidecar matches are skipped, so a rerun redoes only missing or corrupt ones.\n"
      "A whole-range run writes the manifest DIR/frames.json and removes frame_NNNN files of an\n"
      "earlier, longer run. --chunk K --task I makes only chunk I (0-based) of K frames and touches\n"
      "nothing else; --assemble then checks every frame and writes the manifest and (PNG frames)\n"
      "DIR/contact_sheet.png (docs/farm.md)");
  addSceneOptions(cFrames, frames, true);
  cFrames->add_option("--from", frames.from, "Start time")->required();
  cFrames->add_option("--to", frames.to, "End time (inclusive)")->required();
  cFrames->add_option("--fps", frames.fps, "Frames per unit of time")->check(CLI::Range(0.001, 10000.0));
  cFrames->add_option("--out,-o", frames.out, "Output directory")->required();
  cFrames->add_option("--style", frames.style, "shaded or scratchboard")
      ->check(CLI::IsMember({"shaded", "scratchboard"}));
  cFrames->add_option("--chunk", frames.chunk, "Frames per chunk (>= 1); with --task, render only that chunk");
  cFrames->add_option("--task", frames.task,
                      "0-based chunk index: renders frames [TASK*CHUNK, (TASK+1)*CHUNK) of the range (the last chunk "
                      "may be shorter)");
  cFrames->add_flag("--force", frames.force, "Render every frame again, even those whose sidecar says complete");
  cFrames->add_flag("--assemble", frames.assemble,
                    "Render nothing: check that every frame of the range exists with a matching checksum (exit 2 "
                    "naming the missing ones), then write DIR/frames.json and DIR/contact_sheet.png");
  addFrameExportOptions(cFrames, frames);
  addGoldenOptions(cFrames, frames);

  DiffArgs diff;
  auto* cDiff = app.add_subcommand(
      "diff",
      "Compare a rendered image with a golden one: print one JSON object (mean_error, max_error, max_at,\n"
      "changed_pixels, changed_fraction, match) on stdout; exit 0 when they match within the tolerance,\n"
      "1 when they differ or differ in size, 2 when an image cannot be read (docs/ci.md)");
  cDiff->add_option("actual", diff.actual, "The image to judge (any format OpenImageIO reads)")->required();
  cDiff->add_option("golden", diff.expected, "The reference image")->required();
  cDiff->add_option("--out,-o", diff.out, "Also write a picture of the difference (x8, changed pixels red)");
  addToleranceOptions(cDiff, diff.tolerance, "");

  FarmArgs farm;
  auto* cFarm = app.add_subcommand("farm", "Split a frame range over a cluster scheduler (docs/farm.md)");
  cFarm->require_subcommand(1);
  auto* cSlurm = cFarm->add_subcommand(
      "slurm",
      "Write DIR/slurm/frames.sbatch (a job array: task I runs `pteryla frames ... --chunk K --task I`)\n"
      "and DIR/slurm/assemble.sbatch (runs `pteryla frames ... --assemble` after every task succeeded),\n"
      "then submit both with sbatch (--dependency=afterok). Paths in the scripts are absolute.");
  addSceneOptions(cSlurm, farm, true);
  cSlurm->add_option("--from", farm.from, "Start time")->required();
  cSlurm->add_option("--to", farm.to, "End time (inclusive)")->required();
  cSlurm->add_option("--fps", farm.fps, "Frames per unit of time")->check(CLI::Range(0.001, 10000.0));
  cSlurm->add_option("--out,-o", farm.out, "Output directory (must be visible to every node)")->required();
  cSlurm->add_option("--style", farm.style, "shaded or scratchboard")->check(CLI::IsMember({"shaded", "scratchboard"}));
  cSlurm->add_option("--chunk", farm.farmChunk, "Frames per array task (default 10)");
  cSlurm->add_option("--partition", farm.partition, "Slurm partition (#SBATCH --partition)");
  cSlurm->add_option("--mem", farm.mem, "Memory per task (#SBATCH --mem, e.g. 2G); default: the cluster's");
  addFrameExportOptions(cSlurm, farm);
  addGoldenOptions(cSlurm, farm);
  cSlurm->add_flag("--dry-run", farm.dryRun, "Write and print the scripts and the sbatch commands; submit nothing");
  cSlurm->add_flag("--quiet,-q", common.quiet, "No progress or info on stderr");
  cSlurm->add_option("--max-memory", common.maxMemoryGb, memoryHelp);

  for (auto* sub : app.get_subcommands([](CLI::App*) { return true; }))
    sub->add_flag("--quiet,-q", common.quiet, "No progress or info on stderr");
  for (auto* sub : app.get_subcommands([](CLI::App*) { return true; }))
    sub->add_option("--max-memory", common.maxMemoryGb, memoryHelp);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "pteryla: error: %s\n", e.what());
    std::fprintf(stderr, "Run 'pteryla --help' or 'pteryla <command> --help'.\n");
    return 2;
  }

  pteryla::setQuiet(common.quiet);
  if (common.maxMemoryGb) {
    if (!(*common.maxMemoryGb > 0 && *common.maxMemoryGb <= 1e6)) {
      std::fprintf(stderr, "pteryla: error: --max-memory: expected a number of GB in (0, 1e6]\n");
      return 2;
    }
    pteryla::setMemoryLimitBytes(*common.maxMemoryGb * 1e9);
  }

  try {
    if (*cRender) return cmdRender(common, render);
    if (*cCheck) return cmdCheck(common, check);
    if (*cBench) return cmdBench(common, bench);
    if (*cExport) {
      exportArgs.asGiven = optAs->count() > 0;
      return cmdExport(common, exportArgs);
    }
    if (*cFeather) return cmdFeather(common, feather);
    if (*cFrames) return cmdFrames(common, frames);
    if (*cSlurm) return cmdFarmSlurm(common, farm);
    if (*cDiff) return cmdDiff(common, diff);
  } catch (const pteryla::Error& e) {
    endProgress(common);
    std::fprintf(stderr, "pteryla: error: %s\n", e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    endProgress(common);
    std::fprintf(stderr, "pteryla: internal error: out of memory\n");
    return 1;
  } catch (const std::exception& e) {
    endProgress(common);
    std::fprintf(stderr, "pteryla: internal error: %s\n", e.what());
    return 1;
  }
  return 1;
}
