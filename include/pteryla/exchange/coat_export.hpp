#pragma once
// Coat export for other tools: glTF 2.0 (.glb, .gltf), USD (.usda), Wavefront OBJ and PLY.
// docs/export.md maps every pteryla attribute to its glTF and USD name.
//
// glTF (through tinygltf): the skin and the coat as vane cards (the coat mesh, one primitive per feather
// material), the colour pattern as baseColorTexture (alpha BLEND; the pattern's alpha is the vane
// outline, COLOR_0.a the per-vertex barb-tip alpha), the barb direction as TANGENT with
// KHR_materials_anisotropy, and per-vertex _FEATHER_ID, _TRACT, _LAYER, _AGE (FLOAT scalars). A frame
// range is a node-animated sequence: one node per frame, shown (scale 1) over [t_k, t_k+1) and hidden
// (scale 0) otherwise by STEP scale channels.
//
// USD (own writer, .usda text, specified by the UsdGeom schemas): upAxis "Y", metersPerUnit, the skin as
// a Mesh and the coat under /Coat as
//   Curves    (default) one linear, non-periodic BasisCurves prim for the rachises and one for the
//             barbs, widths as diameters (vertex), primvars st (vertex), feather_id, tract, layer, age
//             (uniform: one per curve);
//   Cards     the vane cards as a Mesh with st and displayOpacity (vertex) and the same uniform
//             per-face primvars;
//   Instances a PointInstancer over a few prototype feathers (bucketed by material and length), one
//             instance per feather, moulted ones listed in invisibleIds.
// A frame range writes every varying attribute as timeSamples (time code = scene time x fps).
//
// Every file is written through AtomicFile (temporary + rename; a failed export keeps the old file) and
// is checked for NaN and infinity before anything is written. Output is deterministic: the same scene,
// times and options give the same bytes.
#include <cstddef>
#include <string>
#include <vector>

namespace pteryla::pipeline {
class Pipeline;
}

namespace pteryla::exchange {

enum class Format { Glb, Gltf, Usda, Obj, Ply };
enum class CoatAs { Curves, Cards, Instances };

// The format named by the extension of `path` (case-insensitive); throws pteryla::Error naming `path`
// (element "--out") for any other extension.
Format formatOf(const std::string& path);
// "curves", "cards", "instances"; throws pteryla::Error (element "--as") for anything else.
CoatAs coatAsOf(const std::string& name);

// Frame k of [from, to] at `fps` is at from + k / fps (the same times as `pteryla frames`). Throws
// pteryla::Error naming --from / --to / --fps for non-finite values, to < from, fps <= 0 or more than
// 100000 frames.
std::vector<double> frameTimes(double from, double to, double fps);

struct ExportOptions {
  CoatAs as = CoatAs::Curves;  // USD only: glTF, OBJ and PLY always carry cards
  std::vector<double> times;   // empty: one frame at the pipeline's current time
  double fps = 24;             // frames per unit of scene time (animation timing of `times`)
  double metersPerUnit = 1.0;  // scene units in metres (USD metersPerUnit; glTF is always metres)
  int instancePrototypes = 4;  // Instances: length buckets per feather material, >= 1
};

struct ExportResult {
  size_t bytes = 0;         // size of the file written
  double seconds = 0;       // wall time of evaluating every frame and writing
  double writeSeconds = 0;  // of that, building and writing the file
  size_t frames = 0;
  size_t feathers = 0;   // present feathers in the first frame
  size_t triangles = 0;  // cards: triangles written over all frames (skin included)
  size_t curves = 0;     // curves written over all frames
  size_t instances = 0;  // instances written (first frame) and prototypes
  size_t prototypes = 0;
};

// Evaluates `p` at each of opt.times (restoring its time afterwards) and writes `path` in the format of
// its extension. OBJ and PLY take one frame only (Error naming "--from" otherwise). Throws
// pteryla::Error naming the file for unwritable paths; nothing is left behind on failure.
ExportResult exportCoat(pipeline::Pipeline& p, const std::string& path, const ExportOptions& opt = {});

}  // namespace pteryla::exchange
