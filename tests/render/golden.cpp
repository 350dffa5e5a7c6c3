#include "golden.hpp"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "pteryla/core/error.hpp"

namespace pteryla::render::golden {
namespace {

OIIO::ImageBuf wrap(const Image& img) {
  OIIO::ImageSpec spec(img.width, img.height, 4, OIIO::TypeDesc::UINT8);
  OIIO::ImageBuf buf(spec);
  buf.set_pixels(OIIO::ROI::All(), OIIO::TypeDesc::UINT8, img.rgba.data());
  return buf;
}

bool updating() {
  const char* v = std::getenv("PTERYLA_UPDATE_GOLDEN");
  return v && std::string(v) == "1";
}

}  // namespace

std::string goldenPath(const std::string& name) { return std::string(PTERYLA_TEST_DIR) + "/golden/" + name + ".png"; }

std::string outputDir(const std::string& name) {
  return std::string(PTERYLA_BUILD_DIR) + "/tests/render/golden_out/" + name;
}

::testing::AssertionResult matchesGolden(const Image& actual, const std::string& name, const GoldenTolerance& tol) {
  const std::string golden = goldenPath(name);
  if (updating()) {
    saveImage(golden, actual);
    return ::testing::AssertionSuccess() << "updated " << golden;
  }
  Image expected;
  try {
    expected = loadImage(golden);
  } catch (const Error& e) {
    return ::testing::AssertionFailure() << "no golden image " << golden << " (" << e.what()
                                         << "); run with PTERYLA_UPDATE_GOLDEN=1 to create it";
  }
  const std::string dir = outputDir(name);
  std::filesystem::create_directories(dir);
  if (expected.width != actual.width || expected.height != actual.height) {
    saveImage(dir + "/actual.png", actual);
    return ::testing::AssertionFailure() << "size " << actual.width << "x" << actual.height << " differs from golden "
                                         << expected.width << "x" << expected.height << "; wrote " << dir
                                         << "/actual.png";
  }
  const OIIO::ImageBuf a = wrap(actual), b = wrap(expected);
  const auto r =
      OIIO::ImageBufAlgo::compare(a, b, static_cast<float>(tol.pixelThreshold), static_cast<float>(tol.pixelThreshold));
  const double pixels = static_cast<double>(actual.width) * actual.height;
  const double failFraction = static_cast<double>(r.nfail) / pixels;
  std::ostringstream msg;
  msg << name << ": " << r.nfail << " pixels (" << 100.0 * failFraction << "%) differ by more than "
      << tol.pixelThreshold * 255.0 << "/255, max error " << r.maxerror * 255.0 << "/255 at (" << r.maxx << ","
      << r.maxy << "), mean error " << r.meanerror * 255.0 << "/255";
  // r.error is also raised by OpenImageIO when pixels fail the threshold; the counts decide here.
  if (failFraction > tol.maxFailFraction || r.maxerror > tol.maxError) {
    saveImage(dir + "/actual.png", actual);
    OIIO::ImageBuf diff = OIIO::ImageBufAlgo::absdiff(a, b);
    diff = OIIO::ImageBufAlgo::mul(diff, 8.0f);
    Image d(actual.width, actual.height);
    diff.get_pixels(OIIO::ROI::All(), OIIO::TypeDesc::UINT8, d.rgba.data());
    for (size_t i = 3; i < d.rgba.size(); i += 4) d.rgba[i] = 255;
    saveImage(dir + "/diff.png", d);
    return ::testing::AssertionFailure() << msg.str() << "; wrote " << dir << "/actual.png and diff.png (x8)";
  }
  return ::testing::AssertionSuccess() << msg.str();
}

}  // namespace pteryla::render::golden
