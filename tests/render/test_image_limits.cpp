// Image limits (issue #21): textures are refused from their header before decoding when too large, and
// scaled down when wider than the GL implementation allows; saving is atomic.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "pteryla/core/error.hpp"
#include "pteryla/render/image.hpp"

using namespace pteryla;
using namespace pteryla::render;

TEST(ImageLimits, FitImageAveragesIntoTheLimit) {
  Image wide(20000, 1);
  for (int x = 0; x < wide.width; ++x) wide.pixel(x, 0)[0] = static_cast<uint8_t>(x < 10000 ? 0 : 200);
  const Image f = fitImage(wide, 16384);
  EXPECT_EQ(f.width, 16384);
  EXPECT_EQ(f.height, 1);
  EXPECT_EQ(f.pixel(0, 0)[0], 0);
  EXPECT_EQ(f.pixel(16383, 0)[0], 200);
  EXPECT_EQ(f.pixel(0, 0)[3], 255);
  Image small(8, 4, 1, 2, 3, 4);
  const Image same = fitImage(small, 16);
  EXPECT_EQ(same.rgba, small.rgba);
  const Image tall = fitImage(Image(3, 100, 9, 9, 9, 9), 10);
  EXPECT_EQ(tall.width, 3);
  EXPECT_EQ(tall.height, 10);
  EXPECT_EQ(tall.pixel(2, 9)[1], 9);
}

TEST(ImageLimits, SaveThenLoadRoundTripsThroughTheAtomicWriter) {
  const std::string d = std::string(PTERYLA_BUILD_DIR) + "/image_limits";
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  Image img(33, 17, 10, 20, 30, 255);
  img.pixel(5, 6)[0] = 250;
  for (const char* ext : {".png", ".tif"}) {
    const std::string p = d + "/a" + ext;
    saveImage(p, img);
    const Image back = loadImage(p);
    EXPECT_EQ(back.rgba, img.rgba) << ext;
  }
  size_t n = 0;
  for (auto it = std::filesystem::directory_iterator(d); it != std::filesystem::directory_iterator(); ++it) ++n;
  EXPECT_EQ(n, 2u) << "temporary files left behind";
}
