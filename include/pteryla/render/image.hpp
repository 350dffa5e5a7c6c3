#pragma once
// Image: an RGBA8 picture, top row first (the order image files use). Reading and writing go through
// OpenImageIO, so any format it knows works; PNG, JPEG, TIFF and EXR are the ones pteryla promises.
// Pure CPU code: no GL.
#include <cstdint>
#include <string>
#include <vector>

#include "pteryla/export.hpp"

namespace pteryla::render {

struct PTERYLA_API Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba;  // width * height * 4, row-major, top row first

  Image() = default;
  Image(int w, int h, uint8_t r = 0, uint8_t g = 0, uint8_t b = 0, uint8_t a = 255);
  bool empty() const { return width <= 0 || height <= 0; }
  uint8_t* pixel(int x, int y) { return rgba.data() + (static_cast<size_t>(y) * width + x) * 4; }
  const uint8_t* pixel(int x, int y) const { return rgba.data() + (static_cast<size_t>(y) * width + x) * 4; }
};

// Writes `image`; the format follows the extension (.png .jpg/.jpeg .tif/.tiff .exr). JPEG drops
// alpha. Creates no directories. Atomic: encoded in memory, written to a temporary file and renamed, so a
// failed write throws pteryla::Error naming the file and leaves any previous file unchanged.
PTERYLA_API void saveImage(const std::string& path, const Image& image);
// Reads any OpenImageIO format into RGBA8; the size in the file's header is checked against the memory
// ceiling (core/limits.hpp) before anything is decoded (grey -> RGB, missing alpha -> 255, float images are
// clamped to [0,1]). Throws pteryla::Error naming the file when it is missing or unreadable.
PTERYLA_API Image loadImage(const std::string& path);

// `image` scaled down (box filter) so neither side exceeds maxSide; unchanged when it already fits.
// Used for textures wider or taller than the GL implementation's GL_MAX_TEXTURE_SIZE.
PTERYLA_API Image fitImage(const Image& image, int maxSide);

// Mean absolute difference over all pixels and the R, G, B channels, in [0,1] (1 = white vs black).
// Alpha is ignored. Throws pteryla::Error when the sizes differ.
PTERYLA_API double meanAbsoluteError(const Image& a, const Image& b);

// Fraction of pixels whose RGB differs from `background` by more than `tolerance` (0..255) in any
// channel: the covered-pixel fraction used by analytic coverage checks.
PTERYLA_API double coveredFraction(const Image& image, const uint8_t background[3], int tolerance = 2);

}  // namespace pteryla::render
