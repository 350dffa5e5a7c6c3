#pragma once
// The viewer application: a GLFW window with an OpenGL 3.3 context, Dear ImGui panels, the 3D view and
// the Document evaluating the scene in the background. App owns the window and the frame loop and
// composes the parts that own the rest of the viewer's state (docs/architecture.md, "Viewer"):
//   Viewport       viewport.hpp        uploads, the navigation coat, the 3D view's texture, framing, captures
//   ViewportInput  input.hpp           camera navigation, selection, tools, brushes, handles, gizmos
//   Timeline       timeline.hpp        playback at the frame rate, the flipbook, cache fill
//   Dialogs        dialogs.hpp         errors, open / save / replace / unsaved changes, autosave, recovery
//   ScriptSession  script_session.hpp  --script: commands, scripted mouse and keys
//   OrbitBenchmark orbit_benchmark.hpp --benchmark-orbit
//   FrameRenderer  frame_render.hpp    Render frames (the timeline range to PNGs)
//   FramePacing    frame_pacing.hpp    redraw on demand, the frame rate
//   app.cpp     window, main loop, screenshots
//   app_ui.cpp  menu bar, the panel column, keyboard shortcuts, the JSON, help and scratchboard windows
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "camera_controller.hpp"
#include "dialogs.hpp"
#include "document.hpp"
#include "frame_pacing.hpp"
#include "frame_render.hpp"
#include "input.hpp"
#include "orbit_benchmark.hpp"
#include "panels.hpp"
#include "pteryla/render/image_texture.hpp"
#include "script_session.hpp"
#include "timeline.hpp"
#include "viewport.hpp"

struct GLFWwindow;

namespace pteryla::viewer {

class GlfwContext;

struct ViewerOptions {
  std::string scene;       // scene file or bare mesh to open ("" = none)
  std::string script;      // --script
  std::string screenshot;  // --screenshot: capture after `frames` frames and the evaluation, then quit
  int frames = 1;          // --frames
  int benchmarkOrbit = 0;  // --benchmark-orbit N: N frames of a full orbit, prints fps, quits
  int width = 1280, height = 800;
  std::optional<double> lod;
  bool vsync = true;
  double autosaveSeconds = 60.0;  // --autosave-seconds: recovery file interval (0 = off), recovery.hpp
  bool recover = false;           // --recover: restore the recovery file without asking
  double quitAfter = 0;           // --quit-after S: an interactive run that ends after S seconds and prints
                                  // its frame counts as JSON (the idle check, docs/viewer.md)
};

// Runs the viewer; returns the process exit code (0 ok, 1 internal/window error, 2 bad input or a
// failed script).
int runViewer(const ViewerOptions& options);

class App {
 public:
  explicit App(const ViewerOptions& o);
  ~App();
  int run();

  // Called by GLFW callbacks.
  void onCloseRequested();
  void noteInput() { pacing_.noteInput(); }

 private:
  // app.cpp
  bool initWindow();
  bool scripted() const;  // script, --screenshot or --benchmark-orbit: errors end the run
  void frame();
  bool cameraMoving() const;  // a drag, a wheel zoom, the orbit benchmark or the forced navigation view
  void renderView();
  void captureScreenshot(int fbw, int fbh, bool afterUi);
  void fail(const std::string& message, int code);
  void reportError(const std::string& message, int code);  // scripted: fail, else the error modal
  void endFrameAfterError();  // an exception left an ImGui frame open: close it so the next one starts cleanly
  // app_ui.cpp
  void buildUi();
  void menuBar();
  void panelColumn();
  // Runs one panel or window body; an exception from it unwinds what it left open on ImGui's stack
  // (windows, tables, trees, IDs, colours) and goes to the error modal, so the frame ends cleanly.
  void guardedUi(const char* what, const std::function<void()>& body);
  void sceneJsonWindow();
  void helpWindow();
  void scratchboardWindow();

  ViewerOptions options_;
  GLFWwindow* window_ = nullptr;
  std::unique_ptr<GlfwContext> context_;
  bool imguiReady_ = false;
  Document doc_;
  ViewState view_;
  CameraController camera_;
  AppRequests requests_;
  PanelContext panels_{doc_, view_, camera_, requests_};
  FeatherDesigner designer_;
  // The parts (constructed in this order: each takes those before it).
  Viewport viewport_{doc_, view_, camera_};
  ViewportInput input_{panels_, viewport_};
  Timeline timeline_{doc_, view_, viewport_};
  Dialogs dialogs_;
  ScriptSession script_;
  OrbitBenchmark bench_;
  FrameRenderer frames_{doc_, view_};
  float menuHeight_ = 19.0f;

  // Scratchboard preview (CPU renderer) as a GL texture.
  std::unique_ptr<render::ImageTexture> scratchTexture_;
  std::string scratchError_;

  bool quit_ = false;
  int exitCode_ = 0;
  double lastDrawnTime_ = -1e300;  // the timeline time on screen when the window was last drawn
  FramePacing pacing_{view_};      // redraw on demand, frame rate
};

}  // namespace pteryla::viewer
