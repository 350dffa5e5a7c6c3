// The viewer's main loop: events, background evaluation, the 3D view (Viewport), the UI, screenshots;
// redraw on demand and the frame rate. The viewer calls no GL itself: the Viewport's Renderer draws the
// scene and clears the window, only ImGui's GL backend draws the panels.
#include "app.hpp"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_internal.h>
#include <imgui_impl_opengl3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>
#if defined(__SANITIZE_ADDRESS__)
#include <dlfcn.h>
#include <link.h>
#endif

#include "glfw_context.hpp"
#include "overlays.hpp"
#include "pteryla/core/error.hpp"

namespace pteryla::viewer {

namespace {

// While the loop only waits for an evaluation or the play clock: how long it sleeps at most between
// looks (input wakes it at once), and how often it redraws when nothing new is shown (the progress).
constexpr double kBackgroundTick = 0.004;
constexpr double kReadoutInterval = 0.1;

void closeCallback(GLFWwindow* w) {
  if (auto* app = static_cast<App*>(glfwGetWindowUserPointer(w))) app->onCloseRequested();
}

// Input wakes the redraw (App::frame). Installed before ImGui's GLFW backend, which chains to them.
void noteInput(GLFWwindow* w) {
  if (auto* app = static_cast<App*>(glfwGetWindowUserPointer(w))) app->noteInput();
}
void cursorCallback(GLFWwindow* w, double, double) { noteInput(w); }
void buttonCallback(GLFWwindow* w, int, int, int) { noteInput(w); }
void scrollCallback(GLFWwindow* w, double, double) { noteInput(w); }
void keyCallback(GLFWwindow* w, int, int, int, int) { noteInput(w); }
void charCallback(GLFWwindow* w, unsigned int) { noteInput(w); }
void sizeCallback(GLFWwindow* w, int, int) { noteInput(w); }
void focusCallback(GLFWwindow* w, int) { noteInput(w); }
void enterCallback(GLFWwindow* w, int) { noteInput(w); }
void refreshCallback(GLFWwindow* w) { noteInput(w); }

void glfwErrorCallback(int code, const char* what) {
  std::fprintf(stderr, "pteryla-viewer: GLFW error %d: %s\n", code, what);
}

// AddressSanitizer builds only (tools/test.sh). LeakSanitizer checks at exit, after glfwTerminate made
// libGL unload what it loaded for the context: Mesa's DRI driver (swrast_dri.so under Xvfb, Debian 12)
// and the libraries it pulled in (libGLX_mesa, libglapi, libLLVM ...). Blocks the driver still held in
// its globals (a u_mmInit heap: two 56-byte blocks) then lost their root and were reported as leaks at
// an unmapped address that no suppression can name. Worse, a thread's dynamic-TLS slot of an unloaded
// library still points into freed memory, and LeakSanitizer's stop-the-world tracer crashes reading it
// ("Tracer caught signal 11", "DTLS 42 at 0x2f2c"; the process then exits 1 instead of its own status:
// about half of the runs of a script that fails early). Keeping every library loaded at this point
// mapped until the process ends (RTLD_NODELETE) keeps both the roots and the TLS blocks: called once
// the context exists and again before glfwTerminate, for whatever was loaded in between.
void pinLoadedLibrariesForLeakSanitizer() {
#if defined(__SANITIZE_ADDRESS__)
  std::vector<std::string> libraries;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* out) {
        const std::string name = info->dlpi_name ? info->dlpi_name : "";
        if (name.find(".so") != std::string::npos) static_cast<std::vector<std::string>*>(out)->push_back(name);
        return 0;
      },
      &libraries);
  for (const std::string& l : libraries) dlopen(l.c_str(), RTLD_LAZY | RTLD_NOLOAD | RTLD_NODELETE);
#endif
}

}  // namespace

int runViewer(const ViewerOptions& options) {
  App app(options);
  return app.run();
}

App::App(const ViewerOptions& o)
    : options_(o),
      dialogs_(doc_, view_, viewport_, Dialogs::Options{scripted(), o.recover, o.autosaveSeconds}),
      script_(o.script,
              ScriptHost{doc_, view_, camera_, viewport_, timeline_, dialogs_, input_,
                         [this](const std::string& m, int code) { fail(m, code); }, [this] { quit_ = true; }}),
      bench_(o.benchmarkOrbit, doc_, view_, camera_, viewport_) {
  requests_.frameAll = [this] { viewport_.frameAll(); };
  requests_.screenshot = [this](const std::string& p) { viewport_.requestScreenshot(p, false); };
  requests_.open = [this](const std::string& p) { dialogs_.requestOpen(p); };
  requests_.save = [this] { dialogs_.requestSave(); };
  requests_.saveAs = [this] { dialogs_.requestSaveAs(); };
  requests_.error = [this](const std::string& m) { dialogs_.showError(m); };
}

App::~App() {
  if (window_) glfwMakeContextCurrent(window_);
  scratchTexture_.reset();  // each deletes its texture in the window's context
  viewport_.releaseGl();
  if (imguiReady_) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  if (window_) glfwDestroyWindow(window_);
  pinLoadedLibrariesForLeakSanitizer();
  glfwTerminate();
}

bool App::scripted() const {
  return !options_.script.empty() || !options_.screenshot.empty() || options_.benchmarkOrbit > 0;
}

bool App::initWindow() {
  glfwSetErrorCallback(glfwErrorCallback);
  if (!glfwInit()) {
    std::fprintf(stderr, "pteryla-viewer: cannot initialise GLFW (no display? run under xvfb-run -a)\n");
    return false;
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  window_ = glfwCreateWindow(options_.width, options_.height, "pteryla viewer", nullptr, nullptr);
  if (!window_) {
    std::fprintf(stderr, "pteryla-viewer: cannot create an OpenGL 3.3 core window\n");
    return false;
  }
  glfwSetWindowUserPointer(window_, this);
  glfwSetWindowCloseCallback(window_, closeCallback);
  glfwSetCursorPosCallback(window_, cursorCallback);
  glfwSetMouseButtonCallback(window_, buttonCallback);
  glfwSetScrollCallback(window_, scrollCallback);
  glfwSetKeyCallback(window_, keyCallback);
  glfwSetCharCallback(window_, charCallback);
  glfwSetFramebufferSizeCallback(window_, sizeCallback);
  glfwSetWindowFocusCallback(window_, focusCallback);
  glfwSetCursorEnterCallback(window_, enterCallback);
  glfwSetWindowRefreshCallback(window_, refreshCallback);
  glfwMakeContextCurrent(window_);
  pinLoadedLibrariesForLeakSanitizer();
  glfwSwapInterval(options_.vsync && !scripted() ? 1 : 0);
  context_ = std::make_unique<GlfwContext>(window_);
  viewport_.attach(*context_);

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini next to the user's files
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 330 core");
  imguiReady_ = true;
  return true;
}

void App::fail(const std::string& message, int code) {
  std::fprintf(stderr, "pteryla-viewer: %s\n", message.c_str());
  if (exitCode_ == 0) exitCode_ = code;
  quit_ = true;
}

void App::reportError(const std::string& message, int code) {
  if (scripted())
    fail(message, code);
  else
    dialogs_.showError(message);
}

int App::run() {
  try {
    if (!initWindow()) return 1;
    script_.load();
    if (!options_.scene.empty()) {
      try {
        doc_.open(options_.scene);
        dialogs_.remember(options_.scene);
      } catch (const Error& e) {
        // Interactive: the window opens with the error, and File > Open starts at the file. A script,
        // screenshot or benchmark has nobody to read it: exit 2 below.
        if (scripted()) throw;
        dialogs_.setOpenPath(options_.scene);
        dialogs_.showError(e.what());
      }
    }
    dialogs_.offerRecovery();
    fitTimeRange(doc_, view_);
    if (options_.lod) doc_.setLod(*options_.lod);
    if (!options_.screenshot.empty()) {
      viewport_.requestScreenshot(options_.screenshot, false);
      view_.hidePanels = !script_.active();  // the capture is the 3D view: give it the window's width
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "pteryla-viewer: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pteryla-viewer: %s\n", e.what());
    return 1;
  }
  pacing_.start(std::chrono::steady_clock::now());
  while (!quit_) {
    try {
      frame();
    } catch (const Error& e) {
      // Anything that escapes the panel guards or the view sync: report and keep running (scripts stop).
      endFrameAfterError();
      reportError(e.what(), 2);
    } catch (const std::exception& e) {
      endFrameAfterError();
      reportError(e.what(), 1);
    }
    if (dialogs_.quitRequested()) quit_ = true;  // saved or discarded after Quit
    if (glfwWindowShouldClose(window_)) quit_ = true;
  }
  if (options_.quitAfter > 0)
    std::printf("{\"frames_drawn\": %d, \"frames_skipped\": %ld, \"seconds\": %.3f}\n", pacing_.framesDrawn(),
                pacing_.framesSkipped(), pacing_.seconds(std::chrono::steady_clock::now()));
  // Saved (or never changed): the recovery file is not needed any more. Unsaved work keeps it.
  dialogs_.finish();
  return exitCode_;
}

void App::endFrameAfterError() {
  if (!imguiReady_) return;
  ImGuiContext& g = *ImGui::GetCurrentContext();
  if (!g.WithinFrameScope) return;
  ImGui::ErrorCheckEndFrameRecover(nullptr);
  ImGui::EndFrame();
}

void App::onCloseRequested() {
  if (doc_.modified() && !scripted()) {
    glfwSetWindowShouldClose(window_, GLFW_FALSE);
    dialogs_.confirmQuit();
  }
}

void App::frame() {
  // cameraMoving(): a wheel zoom is drawn at low cost for 300 ms, then once more in full.
  const bool interacting =
      viewport_.screenshotPending() || input_.dragging() || cameraMoving() || script_.feedingInput();
  // Only an evaluation or the play clock is running: the loop waits for them (or input) instead of
  // spinning, and draws only what changed (below). On llvmpipe each redraw of an unchanged window took
  // cores from the evaluation it waited for: half the CPU of a played wing.
  const bool background = (doc_.busy() || view_.playing) && !interacting;
  const bool active = background || scripted() || interacting;
  if (background)
    glfwWaitEventsTimeout(kBackgroundTick);
  else if (active)
    glfwPollEvents();
  else
    glfwWaitEventsTimeout(pacing_.settling() ? 0.02 : 0.5);  // 0.5 s: autosave and --quit-after still tick
  const auto workStart = std::chrono::steady_clock::now();
  if (options_.quitAfter > 0 && pacing_.seconds(workStart) >= options_.quitAfter) quit_ = true;

  doc_.update();
  if (auto e = doc_.takeError()) {
    if (scripted())
      fail("evaluation failed: " + *e, 2);
    else
      dialogs_.showError(*e);
  }
  dialogs_.autosaveTick();
  timeline_.advance();
  if (script_.active() && !quit_) script_.step();
  if (quit_) return;
  if (background && !pacing_.inputPending() && !dialogs_.wantsToShow()) {
    // Draw when there is something new to show: a finished evaluation, another time on screen (a
    // flipbook frame), or, a few times a second, the progress readouts.
    const bool newResult = doc_.upToDate() && doc_.resultVersion() != viewport_.drawnResult();
    const bool newTime = timeline_.shownTime() != lastDrawnTime_;
    if (!newResult && !newTime && pacing_.sinceDrawn(workStart) < kReadoutInterval) return;
  }
  // Nothing happened and the last frames settled: draw nothing (the window keeps its last image).
  if (!pacing_.shouldDraw(active || doc_.busy() || dialogs_.wantsToShow(), workStart)) return;

  int w = 0, h = 0, fw = 0, fh = 0;
  glfwGetWindowSize(window_, &w, &h);
  glfwGetFramebufferSize(window_, &fw, &fh);
  viewport_.layout({w, h}, {fw, fh}, menuHeight_);
  viewport_.sync();
  if (bench_.enabled()) {
    const OrbitBenchmark::Step step = bench_.step();
    if (step == OrbitBenchmark::Step::Failed) fail("benchmark: the scene did not evaluate", 2);
    if (step == OrbitBenchmark::Step::Done) quit_ = true;
  }
  if (viewport_.pixels().x > 0 && viewport_.pixels().y > 0) renderView();

  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  script_.feedInput();
  ImGui::NewFrame();
  const render::ImageTexture* viewTexture = viewport_.texture();
  if (viewTexture && viewTexture->id() && doc_.hasScene()) {
    const glm::vec2 o = view_.viewOrigin, e = o + glm::vec2(view_.viewSize);
    ImGui::GetBackgroundDrawList()->AddImage(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(viewTexture->id())),
                                             ImVec2(o.x, o.y), ImVec2(e.x, e.y));
  }
  guardedUi("viewport", [&] { input_.handle(); });
  buildUi();
  if (doc_.hasScene() && !bench_.enabled())
    guardedUi("overlays", [&] {
      drawOverlays(ImGui::GetBackgroundDrawList(), panels_);
      input_.drawGizmos(ImGui::GetBackgroundDrawList());
    });
  ImGui::Render();

  if (fw > 0 && fh > 0) {
    const glm::dvec3 bg = doc_.hasScene() ? doc_.scene().render.background : glm::dvec3(0.2, 0.22, 0.25);
    viewport_.clearWindow(fw, fh, glm::vec3(bg));
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    captureScreenshot(fw, fh, true);
    captureScreenshot(fw, fh, false);
  }
  glfwSwapBuffers(window_);
  lastDrawnTime_ = timeline_.shownTime();
  pacing_.frameDrawn(workStart, std::chrono::steady_clock::now());
  // --screenshot: the capture above happened once the evaluation was complete; then quit.
  if (!options_.screenshot.empty() && !viewport_.screenshotPending() && !script_.active()) quit_ = true;
}

bool App::cameraMoving() const {
  if (bench_.running()) return bench_.moving();
  if (view_.forceNavigation) return true;
  return input_.cameraMoving();
}

void App::renderView() {
  if (!doc_.hasScene() || !viewport_.cameraReady()) return;
  const bool moving = cameraMoving();
  // Levels of detail by screen size (render.lod_by_screen_size) follow the view at rest.
  if (!moving) doc_.setPreviewView(camera_.camera(), viewport_.pixels().x, viewport_.pixels().y);
  // Playing ahead of the clock: a frame evaluated ahead is drawn into the flipbook when ready, and the
  // frame due is shown from it (timeline.cpp).
  if (!moving && timeline_.playingAhead()) {
    if (timeline_.evaluatedFrameToDraw()) {
      timeline_.liveViewShown();
      const Viewport::Drawn drawn = viewport_.render(false, bench_.fixedPass(), true);
      // Nothing: the view kept from before is this frame's already (same coat, view and quality).
      if (drawn != Viewport::Drawn::Reduced)
        timeline_.storeFlipbookFrame(
            drawn == Viewport::Drawn::Playback || (drawn == Viewport::Drawn::Nothing && view_.fastPlayback),
            drawn != Viewport::Drawn::Nothing);
    }
    timeline_.showShownFrame();
    return;
  }
  // A time drawn before whose coat is not evaluated yet: its flipbook frame (timeline.cpp).
  if (!moving && timeline_.showFlipbookFrame()) return;
  // Playing, with the frame shown not evaluated yet: keep the image on screen (drawing the last coat again
  // would show a stale frame and cost a frame's drawing).
  if (!moving && timeline_.awaitingPlayedFrame()) return;
  timeline_.liveViewShown();
  const Viewport::Drawn drawn = viewport_.render(moving, bench_.fixedPass(), view_.playing);
  if (drawn == Viewport::Drawn::Full || drawn == Viewport::Drawn::Playback)
    timeline_.storeFlipbookFrame(drawn == Viewport::Drawn::Playback);
}

void App::captureScreenshot(int fbw, int fbh, bool afterUi) {
  // --screenshot waits for its frame count (--frames).
  const bool waitFrames =
      pacing_.framesDrawn() + 1 < options_.frames && !options_.screenshot.empty() && !script_.active();
  const Viewport::Capture c = viewport_.capture(fbw, fbh, afterUi, waitFrames);
  if (c.status == Viewport::Capture::NotEvaluated) {
    if (scripted())
      fail("screenshot: the scene did not evaluate", 2);
    else
      dialogs_.showError("screenshot skipped: the scene did not evaluate");
  } else if (c.status == Viewport::Capture::Failed) {
    reportError(c.message, 2);
  }
}

}  // namespace pteryla::viewer
