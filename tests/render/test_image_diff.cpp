// Golden-frame comparison (issue #30 item 7): each figure of diffImages against a difference made by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "pteryla/core/error.hpp"
#include "pteryla/render/image_diff.hpp"

using namespace pteryla::render;

namespace {

Image grey(int w, int h, uint8_t v) { return Image(w, h, v, v, v, 255); }

}  // namespace

TEST(ImageDiff, IdenticalImagesMatchWithZeroError) {
  const Image a = grey(16, 8, 100);
  const ImageDiff d = diffImages(a, a);
  EXPECT_TRUE(d.sameSize);
  EXPECT_TRUE(d.matches);
  EXPECT_EQ(d.changedPixels, 0u);
  EXPECT_EQ(d.meanError, 0.0);
  EXPECT_EQ(d.maxError, 0.0);
  EXPECT_EQ(d.maxX, -1);
}

TEST(ImageDiff, OnePixelChangeIsLocatedAndMeasured) {
  const Image a = grey(10, 10, 100);
  Image b = a;
  b.pixel(7, 3)[1] = 110;  // green +10 at (7, 3)
  const ImageDiff d = diffImages(b, a);
  EXPECT_EQ(d.changedPixels, 1u);
  EXPECT_DOUBLE_EQ(d.changedFraction, 0.01);
  EXPECT_DOUBLE_EQ(d.maxError, 10.0 / 255.0);
  EXPECT_EQ(d.maxX, 7);
  EXPECT_EQ(d.maxY, 3);
  // Mean over 100 pixels x 4 channels.
  EXPECT_DOUBLE_EQ(d.meanError, 10.0 / (255.0 * 400.0));
  // 1% changed is over the default 0.1% bar; a 2% bar lets it pass; a 15/255 pixel tolerance ignores it.
  EXPECT_FALSE(d.matches);
  EXPECT_TRUE(diffImages(b, a, {5.0 / 255.0, 0.02, 64.0 / 255.0}).matches);
  const ImageDiff loose = diffImages(b, a, {15.0 / 255.0, 0.0, 64.0 / 255.0});
  EXPECT_EQ(loose.changedPixels, 0u);
  EXPECT_TRUE(loose.matches);
}

TEST(ImageDiff, ChangesAtTheToleranceDoNotCountAndOneLevelMoreDoes) {
  const Image a = grey(4, 4, 50);
  Image at = a, over = a;
  at.pixel(0, 0)[0] = 55;    // exactly 5/255
  over.pixel(0, 0)[0] = 56;  // 6/255
  EXPECT_EQ(diffImages(at, a).changedPixels, 0u);
  EXPECT_EQ(diffImages(over, a).changedPixels, 1u);
}

TEST(ImageDiff, OneFarPixelFailsTheMaxErrorBarEvenWhenFewChanged) {
  const Image a = grey(100, 100, 0);
  Image b = a;
  b.pixel(50, 50)[2] = 200;  // 1 pixel of 10,000 (0.01%) but 200/255 > 64/255
  const ImageDiff d = diffImages(b, a);
  EXPECT_LE(d.changedFraction, DiffTolerance{}.fraction);
  EXPECT_FALSE(d.matches);
  EXPECT_TRUE(diffImages(b, a, {5.0 / 255.0, 0.001, 1.0}).matches);
}

TEST(ImageDiff, AlphaCounts) {
  const Image a = grey(2, 2, 0);
  Image b = a;
  b.pixel(1, 1)[3] = 0;
  EXPECT_EQ(diffImages(b, a).changedPixels, 1u);
}

TEST(ImageDiff, DifferentSizesNeverMatch) {
  const ImageDiff d = diffImages(grey(4, 4, 0), grey(4, 5, 0));
  EXPECT_FALSE(d.sameSize);
  EXPECT_FALSE(d.matches);
  EXPECT_THROW(differenceImage(grey(4, 4, 0), grey(5, 4, 0)), pteryla::Error);
}

TEST(ImageDiff, ToleranceOutOfRangeOrNanIsRefused) {
  const Image a = grey(2, 2, 0);
  EXPECT_THROW(diffImages(a, a, {-0.1, 0.001, 0.25}), pteryla::Error);
  EXPECT_THROW(diffImages(a, a, {0.02, 1.5, 0.25}), pteryla::Error);
  EXPECT_THROW(diffImages(a, a, {0.02, 0.001, std::nan("")}), pteryla::Error);
}

TEST(ImageDiff, DifferencePictureShowsChangedPixelsAndNothingElse) {
  const Image a = grey(3, 1, 100);
  Image b = a;
  b.pixel(1, 0)[0] = 101;  // below tolerance: scaled, not tinted
  b.pixel(2, 0)[1] = 130;  // above: tinted red, green x8 clamps
  const Image p = differenceImage(b, a);
  EXPECT_EQ(p.pixel(0, 0)[0], 0);
  EXPECT_EQ(p.pixel(0, 0)[3], 255);
  EXPECT_EQ(p.pixel(1, 0)[0], 8);
  EXPECT_EQ(p.pixel(2, 0)[0], 160);
  EXPECT_EQ(p.pixel(2, 0)[1], 240);
}
