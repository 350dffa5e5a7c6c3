#pragma once
// Synthesised feather colour patterns and alpha masks (thesis 7.1.1-7.1.2 map acquired or
// synthesised patterns onto feathers; pteryla ships no scans). Pure CPU code, no GL.
//
// Colour patterns live in feather (u, v) space (the uvGlobal parameterisation of 7.1.1): u runs
// across the vane from 0 (right edge) through 0.5 (rachis) to 1 (left edge), v from the base (0) to
// the tip (1). Image row 0 is v = 1 (tip at the top of the file), so the file looks like a feather
// standing upright. Texture alpha carries the vane outline (1 inside, 0 outside the feather shape).
//
// Barb alpha masks live in barb space (see renderer.hpp, uvBarb): s across one barb with its
// barbules (0..1, the barb at s = 0.5), t along the barb from the rachis (0) to the barb tip (1).
// The renderer repeats the mask barbCount times across a polygon.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "pteryla/render/image.hpp"

namespace pteryla::render {

enum class PatternKind { Plain, Barred, Scalloped, Spotted, Eyespot };

struct PatternParams {
  PatternKind kind = PatternKind::Plain;
  int width = 128;                             // pixels across (u)
  int height = 256;                            // pixels along (v)
  glm::vec3 baseColor{0.55f, 0.42f, 0.30f};    // linear [0,1]
  glm::vec3 markColor{0.18f, 0.12f, 0.08f};    // bars, scallop edges, spots, eye-spot ring
  glm::vec3 accentColor{0.85f, 0.70f, 0.25f};  // eye-spot centre and inner ring
  float frequency = 6.0f;                      // bars / scallop rows along v, spots per unit v
  float markWidth = 0.35f;                     // fraction of a period taken by the mark, in (0, 1)
  float softness = 0.04f;                      // edge blur in v units (or in spot radii for spots)
  float shaftDarken = 0.15f;  // darkening of the rachis stripe at u = 0.5, factor 1 - shaftDarken (< 0 lightens)
  float tipDarken = 0.10f;    // darkening toward the tip, in [0,1]
  float noise = 0.05f;        // amplitude of seeded value noise on the tone
  bool outline = true;        // alpha = feather outline (false: opaque everywhere)
  uint64_t seed = 1;
};

// Throws pteryla::Error for non-positive sizes or out-of-range fractions.
Image generatePattern(const PatternParams& params);

struct BarbAlphaParams {
  int width = 32;                // pixels across the barb (s)
  int height = 128;              // pixels along the barb (t)
  float barbWidth = 0.18f;       // opaque core (the barb ramus) as a fraction of s
  float barbuleOpacity = 0.75f;  // opacity of the barbule fringe next to the barb
  float tipFalloff = 0.25f;      // fraction of t over which alpha falls quadratically to 0 at the tip
  float edgeLead = 0.08f;        // the falloff starts this much earlier (in t) at the fringe edges (7.1.2)
  float fluff = 0.0f;            // 0 pennaceous, 1 plumulaceous (down): sparse, noisy barbules
  uint64_t seed = 1;
};

// Single-channel mask stored in all four channels (R = G = B = A), top row t = 1.
Image generateBarbAlpha(const BarbAlphaParams& params);

// The standard set committed under data/textures: colour patterns barred_brown, scalloped_grey,
// spotted, eyespot, plain_white, down_grey, flight_dark (128 x 256) and alpha masks barb_alpha,
// down_alpha (32 x 128). Returns (name, image) pairs; names have no extension.
struct NamedImage {
  std::string name;
  Image image;
};
std::vector<NamedImage> standardTextures(uint64_t seed = 1);
// Writes standardTextures(seed) as <dir>/<name>.png (the directory must exist) and returns the
// paths written. This is what `pteryla patterns --out DIR` calls.
std::vector<std::string> writeStandardTextures(const std::string& dir, uint64_t seed = 1);

}  // namespace pteryla::render
