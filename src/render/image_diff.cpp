#include "pteryla/render/image_diff.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "pteryla/core/error.hpp"

namespace pteryla::render {
namespace {

void checkTolerance(double v, const char* element) {
  if (!(v >= 0.0 && v <= 1.0))
    throw Error(
        "expected a tolerance in [0, 1] (a fraction of the 0..255 range or of the pixels), got " + std::to_string(v),
        {}, element);
}

}  // namespace

ImageDiff diffImages(const Image& actual, const Image& expected, const DiffTolerance& tol) {
  checkTolerance(tol.pixel, "pixel tolerance");
  checkTolerance(tol.fraction, "changed fraction");
  checkTolerance(tol.maxError, "max error");
  ImageDiff d;
  d.width = actual.width;
  d.height = actual.height;
  d.sameSize =
      actual.width == expected.width && actual.height == expected.height && actual.rgba.size() == expected.rgba.size();
  if (!d.sameSize) return d;
  const size_t pixels = static_cast<size_t>(actual.width) * static_cast<size_t>(actual.height);
  // Integer thresholds: a channel changed when its difference exceeds tol.pixel * 255.
  const int threshold = static_cast<int>(std::floor(tol.pixel * 255.0 + 1e-9));
  uint64_t sum = 0;
  int worst = 0;
  size_t worstAt = 0;
  for (size_t p = 0; p < pixels; ++p) {
    const uint8_t* a = actual.rgba.data() + 4 * p;
    const uint8_t* b = expected.rgba.data() + 4 * p;
    int pixelMax = 0;
    for (int c = 0; c < 4; ++c) {
      const int e = std::abs(int(a[c]) - int(b[c]));
      sum += static_cast<uint64_t>(e);
      pixelMax = std::max(pixelMax, e);
    }
    if (pixelMax > threshold) ++d.changedPixels;
    if (pixelMax > worst) {
      worst = pixelMax;
      worstAt = p;
    }
  }
  d.meanError = pixels ? double(sum) / (255.0 * 4.0 * double(pixels)) : 0.0;
  d.maxError = worst / 255.0;
  if (worst > 0) {
    d.maxX = static_cast<int>(worstAt % static_cast<size_t>(actual.width));
    d.maxY = static_cast<int>(worstAt / static_cast<size_t>(actual.width));
  }
  d.changedFraction = pixels ? double(d.changedPixels) / double(pixels) : 0.0;
  d.matches = d.changedFraction <= tol.fraction && d.maxError <= tol.maxError + 1e-12;
  return d;
}

Image differenceImage(const Image& actual, const Image& expected, const DiffTolerance& tol, double gain) {
  if (actual.width != expected.width || actual.height != expected.height || actual.rgba.size() != expected.rgba.size())
    throw Error("cannot picture the difference of images of different sizes (" + std::to_string(actual.width) + "x" +
                std::to_string(actual.height) + " and " + std::to_string(expected.width) + "x" +
                std::to_string(expected.height) + ")");
  const int threshold = static_cast<int>(std::floor(tol.pixel * 255.0 + 1e-9));
  Image out(actual.width, actual.height);
  const size_t pixels = static_cast<size_t>(actual.width) * static_cast<size_t>(actual.height);
  for (size_t p = 0; p < pixels; ++p) {
    const uint8_t* a = actual.rgba.data() + 4 * p;
    const uint8_t* b = expected.rgba.data() + 4 * p;
    uint8_t* o = out.rgba.data() + 4 * p;
    int pixelMax = 0;
    for (int c = 0; c < 4; ++c) pixelMax = std::max(pixelMax, std::abs(int(a[c]) - int(b[c])));
    for (int c = 0; c < 3; ++c) o[c] = static_cast<uint8_t>(std::min(255.0, gain * std::abs(int(a[c]) - int(b[c]))));
    if (pixelMax > threshold) o[0] = std::max<uint8_t>(o[0], 160);  // changed: at least a visible red
    o[3] = 255;
  }
  return out;
}

}  // namespace pteryla::render
