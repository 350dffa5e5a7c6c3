// The orbit benchmark (orbit_benchmark.hpp).
#include "orbit_benchmark.hpp"

#include <algorithm>
#include <cstdio>

#include "navigation.hpp"

namespace pteryla::viewer {

// --benchmark-orbit N: once the scene is evaluated, uploaded and framed, one full turn in N frames
// (every frame re-renders the 3D view and draws the panels): first with the navigation coat (when the
// coat exceeds its budget), then every feather at the moving resolution, then the full coat at full
// resolution. `moving_coat` / `fps_moving` say what an interactive orbit draws (adaptive navigation).
OrbitBenchmark::Step OrbitBenchmark::step() {
  const int n = frames_;
  if (frame_ < 0) {
    if (!doc_.hasScene() || !viewport_.resultOnScreen() || !viewport_.cameraReady() || viewport_.navigationPending())
      return doc_.failed() || doc_.halted() ? Step::Failed : Step::Running;
    frame_ = 0;
    pass_ = viewport_.navigationReady() ? 0 : 1;
    navFps_ = movingFps_ = -1;
    start_ = std::chrono::steady_clock::now();
    renderSeconds_ = 0;
  } else {
    renderSeconds_ += viewport_.lastRenderSeconds();
  }
  if (frame_ == n) {
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    if (pass_ < 2) {
      (pass_ == 0 ? navFps_ : movingFps_) = double(n) / secs;
      (pass_ == 0 ? navRenderMs_ : movingRenderMs_) = 1000.0 * renderSeconds_ / n;
      if (pass_ == 1 && navFps_ < 0) {  // the whole coat is the navigation coat
        navFps_ = movingFps_;
        navRenderMs_ = movingRenderMs_;
      }
      ++pass_;
      frame_ = 0;
      renderSeconds_ = 0;
      start_ = std::chrono::steady_clock::now();
    } else {
      const Snapshot& s = doc_.snapshot();
      const auto& st = viewport_.renderer().lastStats();
      // What an interactive orbit draws (adaptive navigation, judged on the measured full-coat pass).
      const bool movingNav =
          viewport_.navigationReady() && view_.fastNavigation &&
          useNavigationCoat(view_.forceNavigation, view_.adaptiveNavigation, movingRenderMs_, view_.fullCoatBudgetMs);
      std::printf(
          "{\"orbit_frames\": %d, \"seconds\": %.4f, \"fps\": %.2f, \"render_ms\": %.1f, \"fps_navigation\": %.2f, "
          "\"render_ms_navigation\": %.1f, \"fps_moving_full_coat\": %.2f, \"render_ms_moving_full_coat\": %.1f, "
          "\"navigation_scale\": %d, \"navigation_triangles\": %zu, \"navigation_stride\": %zu, \"width\": %d, "
          "\"height\": %d, \"lod\": %.3f, \"feathers\": %zu, \"coat_triangles\": %zu, \"drawn_triangles\": %zu, "
          "\"moving_coat\": \"%s\", \"fps_moving\": %.2f, \"gl\": \"%s\"}\n",
          n, secs, double(n) / secs, 1000.0 * renderSeconds_ / n, navFps_, navRenderMs_, movingFps_, movingRenderMs_,
          std::clamp(view_.navigationScale, 1, 8),
          viewport_.navigationReady() ? viewport_.navigationTriangles() : s.coatTriangles, viewport_.navigationStride(),
          viewport_.pixels().x, viewport_.pixels().y, doc_.lod(), s.coatFeathers, s.coatTriangles, st.triangles,
          movingNav ? "navigation" : "full", movingNav ? navFps_ : movingFps_,
          viewport_.renderer().glVersion().c_str());
      std::fflush(stdout);
      return Step::Done;
    }
  }
  camera_.orbit(2.0f * 3.14159265f / float(n), 0.0f);
  ++frame_;
  return Step::Running;
}

}  // namespace pteryla::viewer
