#pragma once
// Golden-frame comparison (issue #30): how far a rendered image is from a reference, by the measures a CI
// job can set a bar on. Pure CPU code: no GL. Used by `pteryla diff` and `pteryla frames --golden`.
#include <cstddef>

#include "pteryla/render/image.hpp"

#include "pteryla/export.hpp"

namespace pteryla::render {

// A pixel "changed" when any of its R, G, B, A channels differs by more than `pixel` (in [0,1], 1 = the
// whole 0..255 range). Two images match when they have the same size, at most `fraction` of their pixels
// changed and no channel anywhere differs by more than `maxError`. The defaults forgive the last-bit noise
// of a software rasterizer and nothing a viewer would see.
struct DiffTolerance {
  double pixel = 5.0 / 255.0;
  double fraction = 0.001;
  double maxError = 64.0 / 255.0;
};

struct ImageDiff {
  bool sameSize = false;
  int width = 0, height = 0;   // of the first image
  double meanError = 0;        // mean absolute difference over every pixel and channel, in [0,1]
  double maxError = 0;         // largest channel difference, in [0,1]
  int maxX = -1, maxY = -1;    // where it is (-1 when the images are equal or differ in size)
  size_t changedPixels = 0;    // pixels with a channel difference above the tolerance
  double changedFraction = 0;  // changedPixels / pixels
  bool matches = false;        // within every bar of the tolerance
};

// Compares `actual` with `expected`. Images of different sizes never match (sameSize = false, no other
// figure is computed). Throws pteryla::Error when a tolerance is not a number in [0, 1].
PTERYLA_API ImageDiff diffImages(const Image& actual, const Image& expected, const DiffTolerance& tolerance = {});

// A picture of the difference for a person: |actual - expected| per RGB channel times `gain`, opaque, with
// changed pixels (above tolerance.pixel) tinted so even a one-level change is visible. Sizes must match.
PTERYLA_API Image differenceImage(const Image& actual, const Image& expected, const DiffTolerance& tolerance = {},
                                  double gain = 8.0);

}  // namespace pteryla::render
