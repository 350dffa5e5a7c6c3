// Redraw on demand and the frame rate (frame_pacing.hpp).
#include "frame_pacing.hpp"

namespace pteryla::viewer {

void FramePacing::start(Clock::time_point now) { fpsStart_ = started_ = now; }

bool FramePacing::shouldDraw(bool busy, Clock::time_point workStart) {
  // Nothing happened and the last frames settled: draw nothing (the window keeps its last image).
  if (busy || inputSeen_) settleFrames_ = kSettleFrames;
  inputSeen_ = false;
  if (settleFrames_ == 0) {
    ++framesSkipped_;
    if (!view_.idle) {
      view_.idle = true;
      fpsFrames_ = 0;
      fpsWorkMs_ = 0;
    }
    return false;
  }
  --settleFrames_;
  if (view_.idle) {
    view_.idle = false;
    fpsStart_ = workStart;
  }
  return true;
}

void FramePacing::frameDrawn(Clock::time_point workStart, Clock::time_point now) {
  ++framesDrawn_;
  lastDrawn_ = now;
  fpsWorkMs_ += std::chrono::duration<double, std::milli>(now - workStart).count();
  ++fpsFrames_;
  const double s = std::chrono::duration<double>(now - fpsStart_).count();
  if (s >= 0.5) {
    view_.fps = static_cast<float>(fpsFrames_ / s);
    view_.frameMs = static_cast<float>(fpsWorkMs_ / fpsFrames_);
    fpsFrames_ = 0;
    fpsWorkMs_ = 0;
    fpsStart_ = now;
  }
}

}  // namespace pteryla::viewer
