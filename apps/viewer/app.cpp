// The viewer's main loop: events, background evaluation, GL view sync, UI, screenshots and the orbit
// benchmark. The Renderer (src/render) does the scene's GL into its off-screen target; the viewer keeps
// the last frame in a texture drawn behind the panels, re-rendering only when the camera, the uploaded
// results or the look change. It calls no GL itself: the texture is a render::ImageTexture, the wireframe
// a RenderSettings flag, the window's clear Renderer::clearWindow (only ImGui's GL backend draws).
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
#include "pteryla/render/image.hpp"
#include "pteryla/render/renderer.hpp"
#include "pteryla/render/scene_view.hpp"
#include "pteryla/render/scratchboard.hpp"

namespace pteryla::viewer {

namespace {

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

App::App(const ViewerOptions& o) : options_(o), autosave_(o.autosaveSeconds) {
  requests_.frameAll = [this] { frameAll(); };
  requests_.screenshot = [this](const std::string& p) {
    shotPath_ = p;
    shotWanted_ = true;
    shotWithUi_ = false;
  };
  requests_.open = [this](const std::string& p) { requestOpen(p); };
  requests_.save = [this] { requestSave(); };
  requests_.saveAs = [this] { requestSaveAs(); };
  requests_.error = [this](const std::string& m) { showError(m); };
  panels_ = std::make_unique<PanelContext>(PanelContext{doc_, view_, camera_, requests_});
}

App::~App() {
  if (window_) glfwMakeContextCurrent(window_);
  scratchTexture_.reset();  // each deletes its texture in the window's context
  viewTexture_.reset();
  renderer_.reset();
  navRenderer_.reset();
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
  renderer_ = std::make_unique<render::Renderer>(*context_);

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

int App::run() {
  try {
    if (!initWindow()) return 1;
    if (!options_.script.empty()) script_ = loadScript(options_.script);
    if (!options_.scene.empty()) {
      try {
        doc_.open(options_.scene);
        remember(options_.scene);
      } catch (const Error& e) {
        // Interactive: the window opens with the error, and File > Open starts at the file. A script,
        // screenshot or benchmark has nobody to read it: exit 2 below.
        if (scripted()) throw;
        openPath_ = options_.scene;
        showError(e.what());
      }
    }
    offerRecovery();
    fitTimeRange();
    if (options_.lod) doc_.setLod(*options_.lod);
    if (!options_.screenshot.empty()) {
      shotPath_ = options_.screenshot;
      shotWanted_ = true;
      view_.hidePanels = script_.empty();  // the capture is the 3D view: give it the window's width
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "pteryla-viewer: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pteryla-viewer: %s\n", e.what());
    return 1;
  }
  fpsStart_ = started_ = std::chrono::steady_clock::now();
  while (!quit_) {
    try {
      frame();
    } catch (const Error& e) {
      // Anything that escapes the panel guards or the view sync: report and keep running (scripts stop).
      endFrameAfterError();
      if (scripted())
        fail(e.what(), 2);
      else
        showError(e.what());
    } catch (const std::exception& e) {
      endFrameAfterError();
      if (scripted())
        fail(e.what(), 1);
      else
        showError(e.what());
    }
    if (glfwWindowShouldClose(window_)) quit_ = true;
  }
  if (options_.quitAfter > 0)
    std::printf("{\"frames_drawn\": %d, \"frames_skipped\": %ld, \"seconds\": %.3f}\n", framesDrawn_, framesSkipped_,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count());
  // Saved (or never changed): the recovery file is not needed any more. Unsaved work keeps it.
  autosave_.finish(doc_);
  return exitCode_;
}

void App::endFrameAfterError() {
  if (!imguiReady_) return;
  ImGuiContext& g = *ImGui::GetCurrentContext();
  if (!g.WithinFrameScope) return;
  ImGui::ErrorCheckEndFrameRecover(nullptr);
  ImGui::EndFrame();
}

void App::autosaveTick() {
  try {
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    if (autosave_.tick(doc_, now) && scripted())
      std::fprintf(stderr, "pteryla-viewer: autosaved %s\n", autosave_.written().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pteryla-viewer: autosave failed: %s\n", e.what());
    if (!autosaveErrorShown_) showError(std::string("autosave failed (retrying): ") + e.what());
    autosaveErrorShown_ = true;
  }
}

// At start: unsaved work of the scene given (or, with no scene, the newest) is offered for restoring;
// --recover restores it without asking (scripted sessions), other scripted runs leave it alone.
void App::offerRecovery() {
  const bool bareMesh = doc_.hasScene() && doc_.path().empty();
  std::optional<std::string> file;
  if (!bareMesh) file = findRecovery(doc_.hasScene() ? doc_.path() : "");
  if (!file) {
    if (options_.recover) throw Error("--recover: no unsaved work to recover", recoveryDir());
    return;
  }
  if (!options_.recover && scripted()) return;
  try {
    offered_ = readRecovery(*file);
  } catch (const Error& e) {
    if (options_.recover) throw;
    showError(std::string("a recovery file cannot be read (it is kept): ") + e.what());  // the viewer still starts
    return;
  }
  if (options_.recover)
    restoreOffered();
  else
    popupToOpen_ = "Recover unsaved work";
}

void App::restoreOffered() {
  if (!offered_) return;
  const Recovery r = std::move(*offered_);
  offered_.reset();
  restoreRecovery(doc_, r);
  autosave_.adopt(r.file, doc_);
  std::fprintf(stderr, "pteryla-viewer: restored unsaved work from %s\n", r.file.c_str());
}

void App::onCloseRequested() {
  if (doc_.modified() && !scripted()) {
    glfwSetWindowShouldClose(window_, GLFW_FALSE);
    pending_ = Pending::Quit;
    popupToOpen_ = "Unsaved changes";
  }
}

void App::frame() {
  // cameraMoving(): a wheel zoom is drawn at low cost for 300 ms, then once more in full.
  const bool active = doc_.busy() || view_.playing || scripted() || shotWanted_ || dragging_ || cameraMoving();
  if (active)
    glfwPollEvents();
  else
    glfwWaitEventsTimeout(settleFrames_ > 0 ? 0.02 : 0.5);  // 0.5 s: autosave and --quit-after still tick
  const auto workStart = std::chrono::steady_clock::now();
  if (options_.quitAfter > 0 && std::chrono::duration<double>(workStart - started_).count() >= options_.quitAfter)
    quit_ = true;

  doc_.update();
  if (auto e = doc_.takeError()) {
    if (scripted())
      fail("evaluation failed: " + *e, 2);
    else
      showError(*e);
  }
  autosaveTick();
  advancePlayback();
  if (!script_.empty()) scriptStep();
  if (quit_) return;
  // Nothing happened and the last frames settled: draw nothing (the window keeps its last image).
  if (active || inputSeen_ || doc_.busy() || !popupToOpen_.empty()) settleFrames_ = kSettleFrames;
  inputSeen_ = false;
  if (settleFrames_ == 0) {
    ++framesSkipped_;
    if (!view_.idle) {
      view_.idle = true;
      fpsFrames_ = 0;
      fpsWorkMs_ = 0;
    }
    return;
  }
  --settleFrames_;
  if (view_.idle) {
    view_.idle = false;
    fpsStart_ = workStart;
  }

  int w = 0, h = 0, fw = 0, fh = 0;
  glfwGetWindowSize(window_, &w, &h);
  glfwGetFramebufferSize(window_, &fw, &fh);
  windowSize_ = {w, h};
  fbSize_ = {fw, fh};
  layoutViewport();
  syncView();
  if (options_.benchmarkOrbit > 0) benchmarkStep();
  if (viewPixels_.x > 0 && viewPixels_.y > 0) renderView();

  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  if (fakeMouseNext_ < fakeMouse_.size()) {
    // Scripted mouse: overrides what the GLFW backend read from the (headless) pointer.
    const FakeMouse& m = fakeMouse_[fakeMouseNext_++];
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = ImVec2(view_.viewOrigin.x + m.pos.x, view_.viewOrigin.y + m.pos.y);
    for (int b = 0; b < 3; ++b) io.MouseDown[b] = m.down[b];
    if (fakeMouseNext_ == fakeMouse_.size()) {
      fakeMouse_.clear();
      fakeMouseNext_ = 0;
    }
  }
  if (fakeKeysNext_ < fakeKeys_.size()) {
    const auto [key, down] = fakeKeys_[fakeKeysNext_++];
    ImGui::GetIO().KeysDown[key] = down;
    if (fakeKeysNext_ == fakeKeys_.size()) {
      fakeKeys_.clear();
      fakeKeysNext_ = 0;
    }
  }
  ImGui::NewFrame();
  if (viewTexture_ && viewTexture_->id() && doc_.hasScene()) {
    const glm::vec2 o = view_.viewOrigin, e = o + glm::vec2(view_.viewSize);
    ImGui::GetBackgroundDrawList()->AddImage(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(viewTexture_->id())),
                                             ImVec2(o.x, o.y), ImVec2(e.x, e.y));
  }
  guardedUi("viewport", [&] { handleInput(); });
  buildUi();
  if (doc_.hasScene() && options_.benchmarkOrbit <= 0)
    guardedUi("overlays", [&] {
      drawOverlays(ImGui::GetBackgroundDrawList(), *panels_);
      drawGizmos(ImGui::GetBackgroundDrawList());
    });
  ImGui::Render();

  if (fw > 0 && fh > 0) {
    const glm::dvec3 bg = doc_.hasScene() ? doc_.scene().render.background : glm::dvec3(0.2, 0.22, 0.25);
    renderer_->clearWindow(fw, fh, glm::vec3(bg));
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    captureScreenshot(fw, fh, true);
    captureScreenshot(fw, fh, false);
  }
  glfwSwapBuffers(window_);
  ++framesDrawn_;
  fpsWorkMs_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - workStart).count();
  updateFps();
  // --screenshot: the capture above happened once the evaluation was complete; then quit.
  if (!options_.screenshot.empty() && !shotWanted_ && script_.empty()) quit_ = true;
}

void App::updateFps() {
  ++fpsFrames_;
  const auto now = std::chrono::steady_clock::now();
  const double s = std::chrono::duration<double>(now - fpsStart_).count();
  if (s >= 0.5) {
    view_.fps = static_cast<float>(fpsFrames_ / s);
    view_.frameMs = static_cast<float>(fpsWorkMs_ / fpsFrames_);
    fpsFrames_ = 0;
    fpsWorkMs_ = 0;
    fpsStart_ = now;
  }
}

void App::layoutViewport() {
  const float panel = view_.hidePanels ? 0.0f : std::clamp(view_.panelWidth, 260.0f, 0.7f * float(windowSize_.x));
  view_.viewOrigin = {panel, menuHeight_};
  view_.viewSize = {std::max(1, int(float(windowSize_.x) - panel)),
                    std::max(1, int(float(windowSize_.y) - menuHeight_ - kStatusHeight))};
  const float sx = windowSize_.x > 0 ? float(fbSize_.x) / float(windowSize_.x) : 1.0f;
  const float sy = windowSize_.y > 0 ? float(fbSize_.y) / float(windowSize_.y) : 1.0f;
  viewPixels_ = {int(std::lround(float(view_.viewSize.x) * sx)), int(std::lround(float(view_.viewSize.y) * sy))};
}

void App::initCamera() {
  const Snapshot& s = doc_.snapshot();
  const glm::ivec2 vs = view_.viewSize;
  const float aspect = float(vs.x) / float(vs.y);
  camera_.set(render::sceneCamera(doc_.scene(), s.skin, TriMesh{}, vs.x, vs.y));
  if (doc_.scene().camera.autoFrame) camera_.frame(s.skinLo, s.skinHi, aspect);
  const float diag = glm::length(s.skinHi - s.skinLo);
  if (diag > 0) {
    view_.brushRadius = diag * 0.05f;
    view_.paintRadius = diag * 0.05f;
    view_.controlRadius = diag * 0.1f;
    view_.biasSigma = diag * 0.1f;
  }
  cameraReady_ = true;
  cameraMoved_ = false;
}

void App::frameAll() {
  const Snapshot& s = doc_.snapshot();
  glm::vec3 lo = s.skinLo, hi = s.skinHi;
  if (s.haveCoat) {
    lo = glm::min(lo, s.coatLo);
    hi = glm::max(hi, s.coatHi);
  }
  camera_.frame(lo, hi, float(view_.viewSize.x) / float(view_.viewSize.y));
}

void App::frameSelection() {
  const Snapshot& s = doc_.snapshot();
  const int f = view_.selectedFeather;
  if (frameBoxSelection()) return;  // app_handles.cpp
  if (f < 0 || size_t(f) >= s.featherOrigin.size()) {
    frameAll();
    return;
  }
  const float r = size_t(f) < s.featherLength.size() ? std::max(s.featherLength[size_t(f)], 1e-4f) : 0.1f;
  const glm::vec3 c = s.featherOrigin[size_t(f)] + 0.5f * r * s.featherTangent[size_t(f)];
  camera_.frame(c - glm::vec3(r), c + glm::vec3(r), float(view_.viewSize.x) / float(view_.viewSize.y));
  cameraMoved_ = true;
}

// Results to the renderer: the skin as soon as a job publishes it (progressive display), the coat and
// its materials once the evaluation is complete.
void App::syncView() {
  if (!doc_.hasScene()) return;
  const Snapshot& s = doc_.snapshot();
  if (s.skinVersion != uploadedSkin_ && !s.skin.empty()) {
    context_->makeCurrent();
    renderer_->setSkin(s.skin);
    if (navRenderer_) navRenderer_->setSkin(s.skin);
    uploadedSkin_ = s.skinVersion;
    ++uploadVersion_;
  }
  if (!cameraReady_ && !s.skin.empty()) initCamera();
  uploadResults();
  if (cameraReady_ && !cameraFramedCoat_ && s.haveCoat) {
    if (!cameraMoved_ && doc_.scene().camera.autoFrame) frameAll();
    cameraFramedCoat_ = true;
  }
}

void App::uploadResults() {
  const pipeline::Scene& scene = doc_.scene();
  const Snapshot& snap = doc_.snapshot();
  pipeline::Pipeline* p = doc_.idlePipeline();
  if (p && doc_.upToDate() && doc_.resultVersion() != syncedResult_) {
    // The pipeline is idle and clean: reading its coat does not evaluate anything.
    const uint64_t meshEvals = p->evaluations(pipeline::Stage::Mesh);
    if (meshEvals != meshEvals_) {
      const pipeline::CoatMesh& coat = p->coatMesh();
      context_->makeCurrent();
      updateColouring();
      renderer_->setCoat(coat.mesh, drawRangesFor(coat.ranges));
      uploadedMaterials_ = coat.materials;  // the ranges index these: set together, never the snapshot's
      meshEvals_ = meshEvals;
      materialsStale_ = true;
      ++uploadVersion_;
      navNeeded_ = true;
    }
    syncedResult_ = doc_.resultVersion();
  }
  if (view_.navigationChanged) {
    view_.navigationChanged = false;
    navNeeded_ = true;
  }
  // A new colour mode (or a check finishing under "problems"): the same coat with other ranges.
  if (p && doc_.upToDate() && doc_.resultVersion() == syncedResult_ && updateColouring()) {
    context_->makeCurrent();
    renderer_->setCoat(p->coatMesh().mesh, drawRangesFor(p->coatMesh().ranges));
    uploadedMaterials_ = p->coatMesh().materials;
    materialsStale_ = true;
    navNeeded_ = true;
    ++uploadVersion_;
  }
  if (navNeeded_ && p && doc_.upToDate() && doc_.resultVersion() == syncedResult_) {
    navNeeded_ = false;
    buildNavigationCoat(p->coatMesh());
  }
  // The materials of the coat the renderer holds (its draw ranges index them): a snapshot published by
  // a later job can list other materials (a changed coat blends other key feathers) before that job's
  // coat is uploaded, and drawing the old ranges with them failed.
  if (snap.haveCoat && meshEvals_ != ~0ull &&
      (materialsStale_ || lastBrdfD_ != scene.render.brdfD || lastBrdfH_ != scene.render.brdfH ||
       lastMaterials_ != uploadedMaterials_)) {
    pipeline::CoatMesh materialsOnly;
    materialsOnly.materials = uploadedMaterials_;
    const auto materials =
        view_.colourBy == ColourBy::Material ? render::sceneMaterials(scene, materialsOnly) : paletteMaterials();
    renderer_->setMaterials(materials);
    if (navRenderer_) navRenderer_->setMaterials(materials);
    lastBrdfD_ = scene.render.brdfD;
    lastBrdfH_ = scene.render.brdfH;
    lastMaterials_ = uploadedMaterials_;
    materialsStale_ = false;
    ++uploadVersion_;
  }
}

void App::buildNavigationCoat(const pipeline::CoatMesh& coat) {
  navReady_ = false;
  navTriangles_ = 0;
  navStride_ = 1;
  if (!view_.fastNavigation) return;
  NavigationCoat nav = makeNavigationCoat(coat, size_t(std::max(view_.navigationBudget, 1)));
  if (nav.mesh.empty()) return;  // the whole coat fits the budget
  context_->makeCurrent();
  const bool fresh = !navRenderer_;
  if (fresh) navRenderer_ = std::make_unique<render::Renderer>(*context_);
  if (fresh || uploadedSkin_ != 0) navRenderer_->setSkin(doc_.snapshot().skin);
  navRenderer_->setCoat(nav.mesh, drawRangesFor(nav.ranges));
  materialsStale_ = true;  // both renderers get the materials on the next upload
  navTriangles_ = nav.mesh.triangleCount();
  navStride_ = nav.stride;
  navReady_ = true;
}

bool App::cameraMoving() const {
  if (benchFrame_ >= 0) return benchPass_ != 2;
  if (view_.forceNavigation) return true;
  return dragging_ || std::chrono::steady_clock::now() - lastWheel_ < std::chrono::milliseconds(300);
}

// Everything the 3D image depends on; the view is re-rendered when it changes.
std::vector<float> App::viewKey() const {
  const render::Camera& c = camera_.camera();
  const pipeline::Scene& s = doc_.scene();
  std::vector<float> k = {float(viewPixels_.x),
                          float(viewPixels_.y),
                          c.eye.x,
                          c.eye.y,
                          c.eye.z,
                          c.target.x,
                          c.target.y,
                          c.target.z,
                          c.up.x,
                          c.up.y,
                          c.up.z,
                          c.fovYDegrees,
                          c.zNear,
                          c.zFar,
                          float(uploadVersion_),
                          float(view_.showSkin),
                          float(view_.showCoat),
                          float(view_.wireframe),
                          float(s.render.ambient),
                          float(s.render.background.x),
                          float(s.render.background.y),
                          float(s.render.background.z),
                          float(s.render.skinColor.x),
                          float(s.render.skinColor.y),
                          float(s.render.skinColor.z),
                          float(s.render.shadows),
                          float(s.render.shadowStrength),
                          float(s.render.msaa),
                          float(s.render.exposure),
                          float(s.render.tone == "filmic"),
                          float(s.render.lightRig == "studio"),
                          float(s.render.ground),
                          float(s.render.groundColor.x),
                          float(s.render.groundColor.y),
                          float(s.render.groundColor.z)};
  for (const auto& l : s.lights)
    for (float v : {float(l.direction.x), float(l.direction.y), float(l.direction.z), float(l.color.x),
                    float(l.color.y), float(l.color.z), float(l.intensity)})
      k.push_back(v);
  return k;
}

void App::renderView() {
  if (!doc_.hasScene() || !cameraReady_) return;
  const bool moving = cameraMoving();
  // Levels of detail by screen size (render.lod_by_screen_size) follow the view at rest.
  if (!moving) doc_.setPreviewView(camera_.camera(), viewPixels_.x, viewPixels_.y);
  // A time drawn before whose coat is not evaluated yet: its flipbook frame (app_timeline.cpp).
  if (!moving && showFlipbookFrame()) return;
  flipbookShown_ = false;
  // A new coat or view size invalidates the measured full-coat time (adaptive navigation).
  const float fullKey[3] = {float(uploadVersion_), float(viewPixels_.x), float(viewPixels_.y)};
  if (!std::equal(fullKey, fullKey + 3, movingFullKey_)) {
    std::copy(fullKey, fullKey + 3, movingFullKey_);
    movingFullMs_ = -1.0;
  }
  const bool benchPass = benchFrame_ >= 0 && benchPass_ < 2;  // benchmark passes fix the coat drawn
  const bool navChoice = benchPass ? benchPass_ == 0
                                   : useNavigationCoat(view_.forceNavigation, view_.adaptiveNavigation, movingFullMs_,
                                                       view_.fullCoatBudgetMs);
  const bool nav = navReady_ && view_.fastNavigation && moving && navRenderer_ && navChoice;
  // While moving, fewer pixels as well: the coat's fragments cost as much as its triangles on llvmpipe.
  const int scale = moving && view_.fastNavigation ? std::clamp(view_.navigationScale, 1, 8) : 1;
  std::vector<float> key = viewKey();
  key.push_back(nav ? 1.0f : 0.0f);
  key.push_back(float(scale));
  if (key == lastViewKey_ && viewTexture_ && viewTexture_->id()) {
    drawnResult_ = syncedResult_;  // the view on screen shows the synced result
    return;
  }
  render::Renderer& renderer = nav ? *navRenderer_ : *renderer_;
  navUsed_ = nav;
  const pipeline::Scene& scene = doc_.scene();
  render::RenderSettings settings =
      render::sceneSettings(scene, std::max(1, viewPixels_.x / scale), std::max(1, viewPixels_.y / scale));
  settings.drawSkin = view_.showSkin;
  settings.drawCoat = view_.showCoat;
  settings.wireframe = view_.wireframe;  // also turns off shadows and sub-pixel culling
  if (moving) settings.msaaSamples = 0;  // multisampling costs most of a frame on llvmpipe: only at rest
  // The navigation coat shows every k-th feather: colour the skin like the coat looked (the mean of
  // the last full view) so the body reads as feathered rather than bare while the camera moves.
  if (nav && navSkinColor_.x >= 0.0f) settings.skinColor = navSkinColor_;
  const auto t0 = std::chrono::steady_clock::now();
  viewImage_ = renderer.renderImage(camera_.camera(), render::sceneLights(scene), settings);
  if (!viewTexture_) viewTexture_ = std::make_unique<render::ImageTexture>(*context_);
  viewTexture_->upload(viewImage_);
  lastRenderSeconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!nav && moving && view_.fastNavigation) movingFullMs_ = smoothFrameMs(movingFullMs_, 1000.0 * lastRenderSeconds_);
  if (!nav && scale == 1 && view_.showCoat) {
    const glm::vec4 bg = settings.background * 255.0f;
    glm::dvec3 sum(0.0);
    size_t count = 0;
    for (size_t i = 0; i + 3 < viewImage_.rgba.size(); i += 4 * 5) {
      const uint8_t* p = &viewImage_.rgba[i];
      if (std::abs(p[0] - bg.r) + std::abs(p[1] - bg.g) + std::abs(p[2] - bg.b) < 12.0f) continue;
      sum += glm::dvec3(p[0], p[1], p[2]);
      ++count;
    }
    if (count > 0) navSkinColor_ = glm::clamp(glm::vec3(sum / (255.0 * double(count))) * 1.15f, 0.0f, 1.0f);
  }
  if (!nav && !moving && scale == 1) storeFlipbookFrame();
  lastViewKey_ = std::move(key);
  drawnResult_ = syncedResult_;
}

void App::captureScreenshot(int fbw, int fbh, bool afterUi) {
  if (!shotWanted_ || afterUi != shotWithUi_) return;
  // Scripted and --screenshot captures wait for the evaluation (and its upload) to finish.
  if (doc_.hasScene() && (!doc_.upToDate() || doc_.resultVersion() != syncedResult_ || viewImage_.empty())) {
    if (doc_.failed() || doc_.halted()) {
      shotWanted_ = false;
      if (scripted())
        fail("screenshot: the scene did not evaluate", 2);
      else
        showError("screenshot skipped: the scene did not evaluate");
    }
    return;
  }
  if (framesDrawn_ + 1 < options_.frames && !options_.screenshot.empty() && script_.empty()) return;
  // A view drawn while the camera moved has a reduced resolution: wait for the full one (unless the
  // navigation view is forced on, which never stops "moving": capture what it shows).
  if (!afterUi && viewImage_.width != viewPixels_.x && doc_.scene().render.style != "scratchboard" &&
      !view_.forceNavigation)
    return;
  shotWanted_ = false;
  try {
    render::Image img;
    if (afterUi) {
      img = renderer_->readPixels(fbw, fbh);
    } else if (doc_.scene().render.style == "scratchboard" && doc_.idlePipeline()) {
      pipeline::Pipeline& p = *doc_.idlePipeline();
      render::ScratchboardSettings ss;
      ss.width = viewPixels_.x;
      ss.height = viewPixels_.y;
      img = render::renderScratchboard(p.coatMesh().mesh, p.skinTriMesh(), camera_.camera(),
                                       render::sceneLights(p.scene()), ss);
    } else {
      img = viewImage_;  // exactly the 3D view on screen, without the panels
    }
    render::saveImage(shotPath_, img);
    std::fprintf(stderr, "pteryla-viewer: wrote %s (%dx%d)\n", shotPath_.c_str(), img.width, img.height);
  } catch (const Error& e) {
    if (scripted())
      fail(e.what(), 2);
    else
      showError(e.what());
  }
}

// --benchmark-orbit N: once the scene is evaluated, uploaded and framed, one full turn in N frames
// (every frame re-renders the 3D view and draws the panels): first with the navigation coat (when the
// coat exceeds its budget), then every feather at the moving resolution, then the full coat at full
// resolution. `moving_coat` / `fps_moving` say what an interactive orbit draws (adaptive navigation).
void App::benchmarkStep() {
  const int n = options_.benchmarkOrbit;
  if (benchFrame_ < 0) {
    if (!doc_.hasScene() || !doc_.upToDate() || doc_.resultVersion() != syncedResult_ || !cameraReady_ ||
        viewImage_.empty() || navNeeded_) {
      if (doc_.failed() || doc_.halted()) fail("benchmark: the scene did not evaluate", 2);
      return;
    }
    benchFrame_ = 0;
    benchPass_ = navReady_ ? 0 : 1;
    benchNavFps_ = benchMovingFps_ = -1;
    benchStart_ = std::chrono::steady_clock::now();
    benchRenderSeconds_ = 0;
  } else {
    benchRenderSeconds_ += lastRenderSeconds_;
  }
  if (benchFrame_ == n) {
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - benchStart_).count();
    if (benchPass_ < 2) {
      (benchPass_ == 0 ? benchNavFps_ : benchMovingFps_) = double(n) / secs;
      (benchPass_ == 0 ? benchNavRenderMs_ : benchMovingRenderMs_) = 1000.0 * benchRenderSeconds_ / n;
      if (benchPass_ == 1 && benchNavFps_ < 0) {  // the whole coat is the navigation coat
        benchNavFps_ = benchMovingFps_;
        benchNavRenderMs_ = benchMovingRenderMs_;
      }
      ++benchPass_;
      benchFrame_ = 0;
      benchRenderSeconds_ = 0;
      benchStart_ = std::chrono::steady_clock::now();
    } else {
      const Snapshot& s = doc_.snapshot();
      const auto& st = renderer_->lastStats();
      // What an interactive orbit draws (adaptive navigation, judged on the measured full-coat pass).
      const bool movingNav = navReady_ && view_.fastNavigation &&
                             useNavigationCoat(view_.forceNavigation, view_.adaptiveNavigation, benchMovingRenderMs_,
                                               view_.fullCoatBudgetMs);
      std::printf(
          "{\"orbit_frames\": %d, \"seconds\": %.4f, \"fps\": %.2f, \"render_ms\": %.1f, \"fps_navigation\": %.2f, "
          "\"render_ms_navigation\": %.1f, \"fps_moving_full_coat\": %.2f, \"render_ms_moving_full_coat\": %.1f, "
          "\"navigation_scale\": %d, \"navigation_triangles\": %zu, \"navigation_stride\": %zu, \"width\": %d, "
          "\"height\": %d, \"lod\": %.3f, \"feathers\": %zu, \"coat_triangles\": %zu, \"drawn_triangles\": %zu, "
          "\"moving_coat\": \"%s\", \"fps_moving\": %.2f, \"gl\": \"%s\"}\n",
          n, secs, double(n) / secs, 1000.0 * benchRenderSeconds_ / n, benchNavFps_, benchNavRenderMs_, benchMovingFps_,
          benchMovingRenderMs_, std::clamp(view_.navigationScale, 1, 8), navReady_ ? navTriangles_ : s.coatTriangles,
          navStride_, viewPixels_.x, viewPixels_.y, doc_.lod(), s.coatFeathers, s.coatTriangles, st.triangles,
          movingNav ? "navigation" : "full", movingNav ? benchNavFps_ : benchMovingFps_,
          renderer_->glVersion().c_str());
      std::fflush(stdout);
      quit_ = true;
      return;
    }
  }
  camera_.orbit(2.0f * 3.14159265f / float(n), 0.0f);
  ++benchFrame_;
}

}  // namespace pteryla::viewer
