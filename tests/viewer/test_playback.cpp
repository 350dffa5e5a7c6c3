// Timeline playback's clock (frames dropped, not lagging) and the flipbook of drawn frames.
#include <gtest/gtest.h>

#include "playback.hpp"

using namespace pteryla;
using namespace pteryla::viewer;

namespace {
render::Image image(int w, int h, uint8_t v) {
  render::Image im;
  im.width = w;
  im.height = h;
  im.rgba.assign(size_t(w) * size_t(h) * 4, v);
  return im;
}
}  // namespace

TEST(Playback, FrameGridCoversTheRangeInSteps) {
  const FrameGrid g{2.0, 3.0, 0.25};
  EXPECT_EQ(g.last(), 4);  // 2, 2.25, 2.5, 2.75, 3
  EXPECT_EQ(g.nearest(2.6), 2);
  EXPECT_EQ(g.nearest(-5), 0);
  EXPECT_EQ(g.nearest(99), 4);
  EXPECT_DOUBLE_EQ(g.time(3), 2.75);
  const FrameGrid empty{1.0, 1.0, 0.1};
  EXPECT_EQ(empty.last(), 0);
}

// The frame due follows the wall clock: a slow frame makes the next one due be several frames on (the
// ones in between are dropped), never the one after the last shown.
TEST(Playback, TheClockDropsFramesInsteadOfLagging) {
  PlaybackClock c;
  EXPECT_FALSE(c.due(0, 24, true).has_value());  // not started
  const FrameGrid g{0.0, 10.0, 1.0 / 24.0};
  c.start(g, 1.0, 100.0);  // frame 24
  EXPECT_EQ(*c.due(100.0, 24, false), 24);
  EXPECT_EQ(*c.due(100.0 + 1.0 / 24.0 + 1e-6, 24, false), 25);
  // Half a second spent on one frame: the next one due is 12 frames on.
  EXPECT_EQ(*c.due(100.5, 24, false), 36);
  // Past the end: stop, or wrap when looping.
  const int64_t n = g.last() + 1;  // 241 frames
  EXPECT_FALSE(c.due(100.0 + double(n) / 24.0, 24, false).has_value());
  EXPECT_EQ(*c.due(100.0 + double(n - 24) / 24.0 + 1e-6, 24, true), 0);
  // A wall clock that went backwards shows the start frame.
  EXPECT_EQ(*c.due(50.0, 24, true), 24);
}

TEST(Playback, FlipbookFindsWhatItStoredByTimeAndView) {
  Flipbook f(1 << 20);
  const std::vector<float> a = {1, 2, 3}, b = {1, 2, 4};
  f.store(0.5, a, image(8, 8, 10));
  ASSERT_NE(f.find(0.5, a), nullptr);
  EXPECT_EQ(f.find(0.5, a)->rgba[0], 10);
  EXPECT_EQ(f.find(0.5, b), nullptr);         // another camera or look
  EXPECT_EQ(f.find(0.5 + 1e-3, a), nullptr);  // another time
  f.store(0.5, a, image(8, 8, 20));           // replaced, not added
  EXPECT_EQ(f.size(), 1u);
  EXPECT_EQ(f.find(0.5, a)->rgba[0], 20);
  EXPECT_EQ(f.bytes(), 8u * 8u * 4u);
  f.clear();
  EXPECT_EQ(f.size(), 0u);
  EXPECT_EQ(f.bytes(), 0u);
}

// Within its budget the flipbook drops the least recently used frames first; a look refreshes a frame.
TEST(Playback, FlipbookKeepsTheMostRecentlyUsedWithinItsBudget) {
  const size_t one = 16 * 16 * 4;
  Flipbook f(3 * one);
  const std::vector<float> k = {0};
  for (int i = 0; i < 3; ++i) f.store(i, k, image(16, 16, uint8_t(i)));
  ASSERT_NE(f.find(0, k), nullptr);  // frame 0 is now the most recent
  f.store(3, k, image(16, 16, 3));   // drops frame 1, the least recently used
  EXPECT_EQ(f.size(), 3u);
  EXPECT_LE(f.bytes(), 3 * one);
  EXPECT_NE(f.find(0, k), nullptr);
  EXPECT_EQ(f.find(1, k), nullptr);
  EXPECT_NE(f.find(2, k), nullptr);
  EXPECT_NE(f.find(3, k), nullptr);
  f.setBudget(one);
  EXPECT_EQ(f.size(), 1u);
  EXPECT_NE(f.find(3, k), nullptr) << "the most recently used survives a smaller budget";
  f.store(9, k, image(64, 64, 0));  // larger than the budget: not kept, nothing dropped
  EXPECT_EQ(f.size(), 1u);
  EXPECT_EQ(f.find(9, k), nullptr);
}
