#pragma once
// Golden-image comparison for headless renders (OpenImageIO ImageBufAlgo::compare, the engine of
// idiff). A render fails when more than 0.1% of its pixels differ from the golden by more than
// 5/255 in any channel, or any pixel differs by more than 64/255. On failure actual.png and a
// scaled diff.png go to <build>/tests/render/golden_out/<name>/ and max/mean errors are reported.
// Goldens (tests/render/golden/<name>.png) are rewritten only when PTERYLA_UPDATE_GOLDEN=1.
#include <gtest/gtest.h>

#include <string>

#include "pteryla/render/image.hpp"

namespace pteryla::render::golden {

struct GoldenTolerance {
  double pixelThreshold = 5.0 / 255.0;  // a pixel "differs" above this
  double maxFailFraction = 0.001;       // fraction of differing pixels allowed
  double maxError = 64.0 / 255.0;       // no pixel may differ more
};

::testing::AssertionResult matchesGolden(const Image& actual, const std::string& name,
                                         const GoldenTolerance& tolerance = {});

std::string goldenPath(const std::string& name);
std::string outputDir(const std::string& name);

}  // namespace pteryla::render::golden
