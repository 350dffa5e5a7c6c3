#pragma once
// The viewer application: a GLFW window with an OpenGL 3.3 context, Dear ImGui panels, the 3D view
// drawn by render::SceneView, and the Document evaluating the scene in the background.
//   app.cpp         main loop, GL view sync, screenshots, the orbit benchmark
//   app_ui.cpp      menu bar, the panel column, dialogs (open, save as, overwrite, unsaved changes, errors)
//   app_input.cpp   camera navigation and the viewport tools (picking on the skin)
//   app_script.cpp  --script sessions
//   app_timeline.cpp playback at the frame rate (frames dropped, not lagging), the flipbook of drawn frames
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "camera_controller.hpp"
#include "document.hpp"
#include "file_browser.hpp"
#include "gizmo.hpp"
#include "navigation.hpp"
#include "panels.hpp"
#include "playback.hpp"
#include "recovery.hpp"
#include "script.hpp"

struct GLFWwindow;
struct ImDrawList;

#include "pteryla/render/image.hpp"
#include "pteryla/render/image_texture.hpp"
#include "pteryla/render/renderer.hpp"

namespace pteryla::viewer {

class GlfwContext;

// Layout of the window: menu bar, panel column on the left, status bar, the 3D view in the rest.
inline constexpr float kStatusHeight = 30.0f;

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

 private:
  enum class Pending { None, Quit, Open };

  // app.cpp
  bool initWindow();
  bool scripted() const;  // script, --screenshot or --benchmark-orbit: errors end the run
  void frame();
  void layoutViewport();  // view rectangle from the window size and the panel layout
  void syncView();
  void uploadResults();
  void buildNavigationCoat(const pipeline::CoatMesh& coat);
  // Colour-by modes (app_colour.cpp): the draw ranges of `ranges` with each feather's material replaced
  // by its colour entry when a mode is on; the palette as render materials.
  std::vector<render::FeatherDrawRange> drawRangesFor(const std::vector<pipeline::CoatDrawRange>& ranges) const;
  std::vector<render::FeatherMaterial> paletteMaterials() const;
  bool updateColouring();
  void legendWindow();  // the colour mode's legend, bottom left of the 3D view  // recomputes colouring_ when the mode,
                        // the result or the check changed
  bool cameraMoving() const;
  void renderView();
  std::vector<float> viewKey() const;
  void initCamera();
  void frameAll();
  void frameSelection();  // F: the selected feather, else everything
  void captureScreenshot(int fbw, int fbh, bool afterUi);
  void updateFps();
  void benchmarkStep();
  void fail(const std::string& message, int code);
  void endFrameAfterError();  // an exception left an ImGui frame open: close it so the next one starts cleanly
  // Autosave and recovery (recovery.hpp).
  void autosaveTick();
  void offerRecovery();
  void restoreOffered();
  // app_ui.cpp
  void buildUi();
  void menuBar();
  void panelColumn();
  void dialogs();
  void showError(const std::string& message);
  // Runs one panel or window body; an exception from it unwinds what it left open on ImGui's stack
  // (windows, tables, trees, IDs, colours) and goes to the error modal, so the frame ends cleanly.
  void guardedUi(const char* what, const std::function<void()>& body);
  void requestOpen(const std::string& path);
  void openNow(const std::string& path);
  void fitTimeRange();  // timeline range from the scene's keys and moult windows
  void requestSave();
  void requestSaveAs();
  void afterSave();
  // The Open and Save As dialogs (app_files.cpp): a file browser, recent files, Enter confirms.
  void openDialog();
  void saveAsDialog();
  void saveAsNow(const std::string& path);
  void remember(const std::string& path);  // adds to recent files (user actions only, not scripts)
  void sceneJsonWindow();
  void helpWindow();
  void scratchboardWindow();
  // app_input.cpp
  void handleInput();
  // Returns false when a press hit nothing the tool uses (the drag then orbits as usual).
  bool handleTool(bool pressed, bool down, bool released, const glm::vec2& mouse);
  // app_handles.cpp: hover, drag and select the scene's handles with the orbit tool (handles.hpp); true
  // when the mouse is on one (or dragging it), so the feather pick and the orbit leave it alone.
  bool handleHandles(const glm::vec2& mouse, bool overUi, bool leftPressed);
  // Delete: the boxed handles and the boxed feathers' follicles, else the selected handle, else the
  // selected feather's follicle (handles.hpp, removeHandles), one undo step.
  void deleteSelectedHandle();
  // Box selection (Ctrl + drag): fills view_.boxFeathers / boxFollicles from a rectangle in view pixels;
  // true when the mouse is boxing. frameBoxSelection frames the boxed feathers (false without any).
  bool handleBox(const glm::vec2& mouse, bool overUi, bool leftPressed);
  void boxSelect(const glm::vec2& a, const glm::vec2& b);
  bool frameBoxSelection();
  // app_gizmo.cpp: the selected control's offset gizmo and the skeleton's joints and rotation rings
  // (gizmo.hpp); true when the mouse is on one (or dragging it). keySelected is K: key the selected
  // joint's rotation, else the selected control, at the current time. gizmoDragPoints: where a scripted
  // `gizmo-drag` presses and releases (view pixels); false when there is no such gizmo.
  GizmoGeometry gizmoGeometry();
  glm::dvec3 ringPoint(const GizmoGeometry& g, int joint, int axis, int k) const;
  bool handleGizmo(const glm::vec2& mouse, bool overUi, bool leftPressed);
  void drawGizmos(ImDrawList* dl);
  void keySelected();
  bool gizmoDragPoints(bool ring, int axis, double amount, glm::vec2& from, glm::vec2& to);
  bool gizmoDrag_ = false, gizmoRing_ = false, gizmoMoved_ = false;
  int gizmoAxis_ = -1, gizmoJoint_ = -1, gizmoHover_ = -1;  // hover: 0-2 offset axes, 3-5 rings
  glm::dvec3 gizmoAxisWorld_{0.0}, gizmoStartTip_{0.0}, gizmoStartOffset_{0.0}, gizmoPreview_{0.0};
  glm::dvec3 gizmoPivot_{0.0}, gizmoStartVec_{0.0};
  double gizmoStartParam_ = 0, gizmoDegrees_ = 0;
  // app_frames.cpp: the timeline range rendered to PNGs on a pipeline of its own (evaluated on a worker
  // thread, drawn here), with progress and Cancel. Called once per frame.
  void frameRenderStep();
  struct FrameRender;
  std::shared_ptr<FrameRender> frames_;  // shared: FrameRender is complete only in app_frames.cpp
  // app_paint.cpp: the face and density brushes (Tool::PaintFaces, Tool::PaintDensity)
  bool handlePaint(bool pressed, bool down, bool released, const glm::vec2& mouse);
  void updateBrushHover(const glm::vec2& mouse, bool overUi);
  void paintDab(const glm::vec3& at);
  void commitStroke();
  // app_script.cpp
  void scriptStep();
  // app_timeline.cpp
  void advancePlayback();
  // The flipbook's key of the 3D view at a level of detail: what the image depends on besides the time.
  std::vector<float> flipbookKey(double lod) const;
  // Shows a flipbook frame instead of rendering (a time whose coat is not evaluated yet); false: none.
  bool showFlipbookFrame();
  void storeFlipbookFrame();  // the view just rendered, complete and at rest, for its time
  void finishPlayReport();    // `play S`: prints what the playback showed

  ViewerOptions options_;
  GLFWwindow* window_ = nullptr;
  std::unique_ptr<GlfwContext> context_;
  std::unique_ptr<render::Renderer> renderer_;
  std::unique_ptr<render::Renderer> navRenderer_;  // the navigation coat (navigation.hpp)
  bool navReady_ = false, navNeeded_ = false, navUsed_ = false;
  size_t navTriangles_ = 0, navStride_ = 1;
  glm::vec3 navSkinColor_{-1.0f};  // mean colour of the last full view, for the skin while navigating
  std::chrono::steady_clock::time_point lastWheel_;
  Document doc_;
  ViewState view_;
  CameraController camera_;
  AppRequests requests_;
  std::unique_ptr<PanelContext> panels_;
  FeatherDesigner designer_;
  bool imguiReady_ = false;

  // View sync: results uploaded to the renderer, and the 3D view cached in a texture (re-rendered only
  // when the camera, the uploads or the look change, so panels stay fast over a heavy coat).
  uint64_t syncedResult_ = ~0ull, uploadedSkin_ = 0, meshEvals_ = ~0ull, uploadVersion_ = 0;
  std::vector<float> lastViewKey_;
  render::Image viewImage_;
  std::unique_ptr<render::ImageTexture> viewTexture_;
  double lastRenderSeconds_ = 0;
  // Adaptive navigation: smoothed full-coat render time while moving (< 0: not measured since the
  // last upload or view resize) and what it was measured for.
  double movingFullMs_ = -1.0;
  float movingFullKey_[3] = {-1.0f, -1.0f, -1.0f};  // upload version, view width, height
  bool cameraReady_ = false, cameraFramedCoat_ = false, cameraMoved_ = false;
  bool materialsStale_ = true;
  FeatherColouring colouring_;  // of view_.colourBy, for the uploaded coat
  std::vector<uint64_t> colourKey_;
  double lastBrdfD_ = -1, lastBrdfH_ = -1;
  std::vector<pipeline::CoatMaterial> lastMaterials_;      // the materials last set (blends follow the rest coat)
  std::vector<pipeline::CoatMaterial> uploadedMaterials_;  // those of the coat last given to the renderer
  glm::ivec2 windowSize_{0}, fbSize_{0};
  glm::ivec2 viewPixels_{0};  // the 3D view in framebuffer pixels
  float menuHeight_ = 19.0f;

  // Autosave: the recovery file written while the scene has unsaved changes, and the one offered at start.
  Autosaver autosave_;
  std::optional<Recovery> offered_;
  bool autosaveErrorShown_ = false;

  // Dialogs.
  std::vector<std::string> errors_;
  std::string popupToOpen_;
  Pending pending_ = Pending::None;
  std::string pendingPath_;
  std::string openPath_, saveAsPath_;
  FileBrowser openBrowser_{{".json", ".obj", ".ply", ".off", ".stl"}}, saveBrowser_{{".json"}};
  std::string openName_, saveName_;  // the dialogs' file-name fields
  bool focusName_ = false;           // put the keyboard in the file-name field when a dialog opens
  RecentFiles recent_{RecentFiles::defaultFile()};
  bool quit_ = false;

  // Screenshots and scripted runs.
  std::string shotPath_;
  bool shotWanted_ = false, shotWithUi_ = false;
  int framesDrawn_ = 0;
  std::vector<ScriptCommand> script_;
  size_t scriptNext_ = 0;
  int scriptWaitFrames_ = 0;
  // Playback (app_timeline.cpp): the clock, what it showed, and the flipbook.
  PlaybackClock playClock_;
  Flipbook flipbook_;
  double displayTime_ = 0;      // the time on screen while playing (a flipbook frame may run ahead)
  bool flipbookShown_ = false;  // the view texture holds a flipbook frame (of flipbookShownTime_)
  double flipbookShownTime_ = 0;
  uint64_t flipbookChanges_ = 0;  // the document's change count the flipbook's frames belong to
  uint64_t drawnResult_ = ~0ull;  // the result version (syncedResult_) the 3D view last showed
  // Filling the flipbook over the timeline range (Timeline panel "Cache range", script `cache-range`):
  // the next frame to draw, and the time to return to.
  struct CacheFill {
    bool active = false;
    int64_t next = 0;
    double returnTo = 0;
    size_t drawn = 0;
  } fill_;
  void advanceCacheFill();
  struct PlayStats {
    double startWall = 0, until = 0;  // until > 0: a scripted `play S` ends then
    double seconds = 0;               // `play S`: S (until is set when the clock starts)
    int64_t lastDue = -1, firstDue = -1;
    size_t due = 0, shown = 0, fromCache = 0, evaluated = 0;
    bool awaitingResult = false;
  } play_;
  std::chrono::steady_clock::time_point scriptSleepUntil_{};  // `sleep S`: keep drawing until then
  bool awaitingMetrics_ = false;
  bool awaitingFrames_ = false;  // render-frames: print what was written when the frames end
  int cancelFramesAfter_ = -1;   // render-frames ... cancel-after N: Cancel once N frames are written
  int exitCode_ = 0;

  // Measurement.
  std::chrono::steady_clock::time_point fpsStart_;
  int fpsFrames_ = 0;
  double fpsWorkMs_ = 0;  // work (not waiting) of the frames counted since fpsStart_
  // Redraw on demand: a frame is drawn while something happens (input, evaluation, playback, scripts,
  // a dialog to show) and for kSettleFrames after it; otherwise the loop waits for events and draws
  // nothing.
 public:
  void noteInput() { inputSeen_ = true; }

 private:
  static constexpr int kSettleFrames = 3;
  bool inputSeen_ = true;
  int settleFrames_ = kSettleFrames;
  long framesSkipped_ = 0;
  std::chrono::steady_clock::time_point started_;
  // Orbit benchmark passes: 0 what moving the camera draws (navigation coat when used, reduced
  // resolution), 1 the full coat at the reduced resolution, 2 the full coat at rest (full resolution).
  int benchFrame_ = -1, benchPass_ = 0;
  double benchNavFps_ = -1, benchNavRenderMs_ = 0, benchMovingFps_ = -1, benchMovingRenderMs_ = 0;
  std::chrono::steady_clock::time_point benchStart_;
  double benchRenderSeconds_ = 0;

  // Scripted mouse input (click / drag commands): one state per frame, in view pixels.
  struct FakeMouse {
    glm::vec2 pos{0};
    bool down[3] = {false, false, false};
  };
  std::vector<FakeMouse> fakeMouse_;
  size_t fakeMouseNext_ = 0;
  // Scripted keys (`key` command): (ImGui key index, down) per frame.
  std::vector<std::pair<int, bool>> fakeKeys_;
  size_t fakeKeysNext_ = 0;
  glm::vec2 scriptPoint(const ScriptCommand& c, size_t arg) const;

  // Drag state of the viewport.
  bool dragging_ = false, toolDrag_ = false;
  glm::vec2 clickStart_{0.0f};
  bool clickPending_ = false;  // a left press that may still become a click (selection)
  glm::vec2 hoverAt_{-1.0f};   // where the hovered feather was last picked
  uint64_t hoverResult_ = 0;
  glm::vec3 dragNormal_{0, 0, 1};
  // A handle being dragged: where the press was, whether it moved, whether the skin was under the mouse.
  bool handleDrag_ = false, handleMoved_ = false, handleOnSkin_ = false;
  glm::vec2 handleStart_{0.0f};
  // The stroke being painted: the skin it started on and where it last dabbed.
  std::shared_ptr<const coat::SkinMesh> strokeSkin_;
  std::vector<glm::vec3> strokePosed_;
  glm::vec3 lastDab_{0};
  bool dabbed_ = false;

  // Scratchboard preview (CPU renderer) as a GL texture.
  std::unique_ptr<render::ImageTexture> scratchTexture_;
  bool showScratch_ = false;
  std::string scratchError_;
};

}  // namespace pteryla::viewer
