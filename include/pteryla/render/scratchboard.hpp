#pragma once
// Scratchboard rendering (Streit 2003, 7.3): white scratches on a black canvas placed along the barbs
// of the feathers, their density and width chosen so that the local fraction of white matches the
// tone of the shaded surface. Pure CPU code (no GL), deterministic for a given seed.
//
// Method: the coat and skin are rasterised with a z-buffer into a tone / direction buffer (tone =
// albedo x (ambient + sum of two-sided Lambert terms) x per-vertex alpha; direction = the screen
// projection of the TriMesh tangent, i.e. the barb). Stroke seeds lie on a jittered grid of spacing
// `strokeSpacing`; a stroke follows the barb direction field both ways for `strokeLength`, stopping
// at another feather or a depth jump. Its width is tone x spacing (white fraction = tone); where that
// is thinner than `minWidth`, strokes keep `minWidth` and are thinned out with probability
// tone x spacing / minWidth; where wider than `maxWidth`, extra strokes are added in between.
// Skin pixels get strokes along a fixed screen direction.
#include <cstdint>
#include <vector>

#include "pteryla/core/trimesh.hpp"
#include "pteryla/render/camera.hpp"
#include "pteryla/render/image.hpp"

namespace pteryla::render {

struct ScratchboardSettings {
  int width = 512;  // pixels
  int height = 512;
  float strokeSpacing = 4.0f;    // pixels between neighbouring strokes at full density
  float strokeLength = 16.0f;    // pixels, total length of one stroke
  float minWidth = 0.7f;         // pixels
  float maxWidth = 3.0f;         // pixels
  float coatAlbedo = 0.85f;      // [0,1]
  float skinAlbedo = 0.45f;      // [0,1]
  float ambient = 0.08f;         // added to the Lambert term
  float skinStrokeAngle = 0.6f;  // radians, screen direction of skin strokes
  bool drawSkin = true;
  uint64_t seed = 1;
};

Image renderScratchboard(const TriMesh& coat, const TriMesh& skin, const Camera& camera,
                         const std::vector<Light>& lights, const ScratchboardSettings& settings);

// The tone the strokes reproduce, as a grey image (R = G = B = round(255 tone), black background):
// for inspection and tests of tone preservation.
Image scratchboardTone(const TriMesh& coat, const TriMesh& skin, const Camera& camera, const std::vector<Light>& lights,
                       const ScratchboardSettings& settings);

}  // namespace pteryla::render
