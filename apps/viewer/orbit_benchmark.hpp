#pragma once
// --benchmark-orbit N (docs/viewer.md, "Benchmark"; orbit_benchmark.cpp): once the scene is evaluated,
// uploaded and framed, one full turn of the camera in N frames, in three passes: 0 what moving the camera
// draws (the navigation coat when used, reduced resolution), 1 the full coat at the reduced resolution,
// 2 the full coat at rest (full resolution). Prints one JSON object of frame rates, then the run ends.
#include <chrono>
#include <string>

#include "camera_controller.hpp"
#include "document.hpp"
#include "panels.hpp"
#include "viewport.hpp"

namespace pteryla::viewer {

class OrbitBenchmark {
 public:
  OrbitBenchmark(int frames, const Document& doc, const ViewState& view, CameraController& camera,
                 const Viewport& viewport)
      : frames_(frames), doc_(doc), view_(view), camera_(camera), viewport_(viewport) {}
  bool enabled() const { return frames_ > 0; }
  // The camera turns (passes 0 and 1 draw as while moving).
  bool running() const { return frame_ >= 0; }
  bool moving() const { return pass_ != 2; }
  // The coat a pass draws (0 navigation, 1 full), or -1: the usual choice (Viewport::render).
  int fixedPass() const { return running() && pass_ < 2 ? pass_ : -1; }
  // Once per frame before the view is drawn: waits for the scene, turns the camera, measures. Returns
  // Done once the JSON is printed, Failed when the scene did not evaluate.
  enum class Step { Running, Done, Failed };
  Step step();

 private:
  int frames_;
  const Document& doc_;
  const ViewState& view_;
  CameraController& camera_;
  const Viewport& viewport_;
  int frame_ = -1, pass_ = 0;
  double navFps_ = -1, navRenderMs_ = 0, movingFps_ = -1, movingRenderMs_ = 0;
  std::chrono::steady_clock::time_point start_;
  double renderSeconds_ = 0;
};

}  // namespace pteryla::viewer
