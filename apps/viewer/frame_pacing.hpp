#pragma once
// Redraw on demand and the frame rate of the viewer's loop (App::frame), without GL or ImGui (unit-tested
// in tests/viewer): a frame is drawn while something happens (input, an evaluation, playback, a script,
// a dialog to show) and for kSettleFrames after it; otherwise the loop waits for events and draws
// nothing (ViewState::idle). The frame rate (ViewState::fps) counts drawn frames over half a second and
// the work per frame (ViewState::frameMs) leaves out the waiting.
#include <chrono>

#include "panels.hpp"

namespace pteryla::viewer {

class FramePacing {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr int kSettleFrames = 3;

  explicit FramePacing(ViewState& view) : view_(view) {}
  // The loop starts at `now` (the frame rate and seconds() count from here).
  void start(Clock::time_point now);
  // Input arrived (GLFW callbacks): the next frame is drawn.
  void noteInput() { inputSeen_ = true; }
  // Frames are still settling after the last activity: wait for events briefly, not for long.
  bool settling() const { return settleFrames_ > 0; }
  // After the events, at `workStart`: whether this frame is drawn. `busy`: something happens now.
  bool shouldDraw(bool busy, Clock::time_point workStart);
  // Input arrived since the last frame was drawn.
  bool inputPending() const { return inputSeen_; }
  // Seconds since the last frame was drawn (a large number before the first).
  double sinceDrawn(Clock::time_point now) const {
    return framesDrawn_ == 0 ? 1e9 : std::chrono::duration<double>(now - lastDrawn_).count();
  }
  // A frame was drawn: its work took from workStart to now.
  void frameDrawn(Clock::time_point workStart, Clock::time_point now);

  int framesDrawn() const { return framesDrawn_; }
  long framesSkipped() const { return framesSkipped_; }
  double seconds(Clock::time_point now) const { return std::chrono::duration<double>(now - started_).count(); }

 private:
  ViewState& view_;
  Clock::time_point started_, fpsStart_, lastDrawn_;
  int fpsFrames_ = 0;
  double fpsWorkMs_ = 0;  // work (not waiting) of the frames counted since fpsStart_
  bool inputSeen_ = true;
  int settleFrames_ = kSettleFrames;
  int framesDrawn_ = 0;
  long framesSkipped_ = 0;
};

}  // namespace pteryla::viewer
