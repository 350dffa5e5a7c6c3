// Redraw on demand and the frame rate (apps/viewer/frame_pacing.hpp): what the viewer's loop draws when
// nothing happens, and what the status bar's fps and ms a frame count.
#include <gtest/gtest.h>

#include "frame_pacing.hpp"

using namespace pteryla::viewer;
using Clock = FramePacing::Clock;
using std::chrono::milliseconds;

namespace {

// Calls shouldDraw `n` times (not busy), a millisecond apart from `t`; returns how many were drawn.
int drawnOf(FramePacing& p, int n, Clock::time_point t) {
  int drawn = 0;
  for (int i = 0; i < n; ++i) drawn += p.shouldDraw(false, t + milliseconds(i)) ? 1 : 0;
  return drawn;
}

// A loop that starts at t0.
class FramePacingTest : public ::testing::Test {
 protected:
  FramePacingTest() { p.start(t0); }
  ViewState view;
  FramePacing p{view};
  const Clock::time_point t0 = Clock::now();
};

}  // namespace

TEST_F(FramePacingTest, AfterActivityItDrawsTheSettleFramesThenNothing) {
  EXPECT_TRUE(p.settling());
  // The first frames are drawn (start-up counts as input), then kSettleFrames in all, then none.
  EXPECT_EQ(drawnOf(p, 10, t0), FramePacing::kSettleFrames);
  EXPECT_EQ(p.framesSkipped(), 10 - FramePacing::kSettleFrames);
  EXPECT_TRUE(view.idle);
  EXPECT_FALSE(p.settling());  // the loop may now wait long for events
}

TEST_F(FramePacingTest, ABusyLoopDrawsEveryFrameAndNeverIdles) {
  for (int i = 0; i < 50; ++i) EXPECT_TRUE(p.shouldDraw(true, t0 + milliseconds(i)));
  EXPECT_FALSE(view.idle);
  EXPECT_EQ(p.framesSkipped(), 0);
  // When the activity ends, the frames settle again: kSettleFrames counting the last busy one.
  EXPECT_EQ(drawnOf(p, 10, t0 + milliseconds(100)), FramePacing::kSettleFrames - 1);
  EXPECT_TRUE(view.idle);
}

TEST_F(FramePacingTest, InputWakesAnIdleLoopForTheSettleFrames) {
  drawnOf(p, 10, t0);
  ASSERT_TRUE(view.idle);
  p.noteInput();
  EXPECT_TRUE(p.shouldDraw(false, t0 + milliseconds(500)));
  EXPECT_FALSE(view.idle);
  EXPECT_EQ(drawnOf(p, 10, t0 + milliseconds(501)), FramePacing::kSettleFrames - 1);
  EXPECT_TRUE(view.idle);
}

TEST_F(FramePacingTest, TheFrameRateCountsDrawnFramesAndTheirWorkOverHalfASecond) {
  // A frame every 60 ms, 10 ms of work each: the rate is published once half a second has passed.
  int k = 0;
  for (; view.fps == 0.0f && k < 100; ++k) {
    const Clock::time_point start = t0 + milliseconds(60 * k);
    ASSERT_TRUE(p.shouldDraw(true, start));
    p.frameDrawn(start, start + milliseconds(10));
  }
  ASSERT_EQ(k, 10);  // the ninth frame ends at 490 ms, the tenth at 550 ms
  EXPECT_EQ(p.framesDrawn(), 10);
  EXPECT_NEAR(view.fps, 10.0 / 0.550, 1e-3);
  EXPECT_NEAR(view.frameMs, 10.0, 1e-4);  // the work, not the 60 ms between frames
  EXPECT_NEAR(p.seconds(t0 + milliseconds(1500)), 1.5, 1e-9);
}

TEST_F(FramePacingTest, TimeSpentIdleIsNotCountedInTheFrameRate) {
  // Three frames, then the loop idles for ten seconds.
  for (int i = 0; i < 3; ++i) {
    const Clock::time_point start = t0 + milliseconds(i);
    ASSERT_TRUE(p.shouldDraw(false, start));
    p.frameDrawn(start, start + milliseconds(1));
  }
  ASSERT_FALSE(p.shouldDraw(false, t0 + milliseconds(10)));
  ASSERT_TRUE(view.idle);
  // Woken at 10 s: frames every 100 ms count from the wake-up (six frames in 0.505 s, 11.9 fps), not
  // from the start (under 1 fps) nor with the frames before the idle time.
  const Clock::time_point wake = t0 + milliseconds(10000);
  for (int i = 0; i < 7; ++i) {
    const Clock::time_point start = wake + milliseconds(100 * i);
    ASSERT_TRUE(p.shouldDraw(true, start));
    p.frameDrawn(start, start + milliseconds(5));
  }
  EXPECT_GT(view.fps, 9.0f);
  EXPECT_LT(view.fps, 12.0f);
}
