#pragma once
// The viewer's panels: thin ImGui views over the Document. Panels never touch the Pipeline while a job
// runs; they read the Snapshot and edit the scene through actions.hpp (one undo step per edit).
//
// Edits replace the scene: Document::edit (and undo, redo, open) move-assigns doc.scene(), so a
// `const Json&`, an iterator or a string_view into it dangles after the edit. A panel therefore reads a
// copy of the scene (`const Scene s = doc.scene();`, sections are small JSON) taken before it draws, and
// edits address elements by index or name, re-checked by the action (actions.hpp) against the scene it
// edits. Nothing a panel holds across an edit points into the document.
// Viewport tools (placing key feathers, styling vectors, brushes, controls, bias vectors) are modes
// set here and carried out by the app on mouse input (tool.hpp-like state in ViewState).
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "camera_controller.hpp"
#include "colour_by.hpp"
#include "document.hpp"
#include "gizmo.hpp"
#include "handles.hpp"

namespace pteryla::viewer {

enum class Tool {
  Orbit,         // left drag orbits (default)
  PlaceKey,      // click a follicle: key feather `toolFeather` there
  AddVector,     // press on the skin and drag: styling vector
  EditVectors,   // drag the tip of a styling vector
  AddBias,       // press on the skin and drag: relaxation bias vector of the selected tract
  Brush,         // click on the skin: fixed-angle packing brush
  AddControl,    // click on the skin: expressive control
  Pin,           // click on the skin: pinned follicle in the selected tract
  PaintFaces,    // drag on the skin: add / remove faces of the selected tract, or (de)select faces
  PaintDensity,  // drag on the skin: the follicle density map (input_paint.cpp)
};

// What the face brush does (Tool::PaintFaces).
enum class FacePaint { Add, Remove, Select, Deselect };

// A panel widget a script drives (`ui PANEL WIDGET [VALUE]`, script_session.cpp): the panel checks
// uiRequested() next to the ImGui widget and acts exactly as when the user uses it, so a scripted session
// runs the panel's own code (not only the action behind it).
struct UiRequest {
  std::string panel, widget, value;
  bool pending = false;
  int frames = 0;  // frames the script has waited for a panel to take the request
};

// View settings and selections shared by panels, overlays and the app.
struct ViewState {
  bool showCoat = true, showSkin = true, wireframe = false;
  bool showFollicles = false, showDirections = false, showTract = false, showKeys = true;
  bool showVectors = true, showBrushes = true, showControls = true;
  bool showProblems = true;
  ColourBy colourBy = ColourBy::Material;  // coat colours: materials, or a view mode with a legend  // after a check:
                                           // the feathers it found crossing another or under the skin
  int selectedTract = 0;
  int selectedFollicle = -1;
  int selectedControl = -1;
  int selectedVector = -1;
  // Skeleton joints (input_gizmo.cpp, panels_skeleton.cpp): drawn at their posed pivots; the selected one
  // shows rotation rings. The rig is the scene's skeleton section parsed (cached).
  bool showJoints = true;
  int selectedJoint = -1, hoveredJoint = -1;
  RigCache rig;
  int selectedFeather = -1;  // index into the coat's feathers (click in the view with the orbit tool)
  int hoveredFeather = -1;   // under the mouse (readout)
  Tool tool = Tool::Orbit;
  std::string toolFeather;   // PlaceKey
  float brushRadius = 0.1f;  // scene units (set from the skin size on load)
  float brushElevationDeg = 45.0f;
  bool brushLift = false;  // lift brush (at least the angle) instead of a fixed angle
  float controlRadius = 0.2f;
  float combRadius = 0.0f;  // reach of a new styling vector over a body axis, scene units (0 = a tenth of the axis)
  float biasSigma = 0.2f, biasStretch = 1.5f;
  // Painting (input_paint.cpp, panels_paint.cpp, overlays_paint.cpp). Brush radius in scene units (set
  // from the skin size on load). A stroke is previewed and committed as one edit on release.
  FacePaint facePaint = FacePaint::Add;
  float paintRadius = 0.1f;
  std::vector<uint32_t> faceSelection;  // source faces, sorted: the view's face selection (never saved)
  std::vector<uint32_t> strokeFaces;    // faces under the stroke being painted
  float densityValue = 2.0f, densityStrength = 0.5f;
  std::vector<float> strokeDensity;  // factors while a density stroke is painted (else empty)
  bool painting = false;             // a stroke is under way
  bool brushVisible = false;         // the paint brush is over the skin
  glm::vec3 brushAt{0};
  bool showDensity = true;  // painted density factors on the skin
  // Handles (input_handles.cpp): the point under the mouse, the one clicked (Delete removes it), and
  // where a dragged one would go.
  std::optional<Handle> hoveredHandle, selectedHandle;
  bool handleDragging = false;
  glm::vec3 handlePreview{0};
  // Box selection (Ctrl + left drag with the orbit tool): present feathers whose base, and follicles (when
  // shown) that project inside the box, facing the camera, and the handles inside it. F frames the
  // feathers; Delete removes the boxed handles (pinned follicles, key feathers, ...); Esc clears.
  std::vector<int> boxFeathers, boxFollicles;
  std::vector<Handle> boxHandles;  // handles inside the box (shown ones): Delete removes them as one edit
  int hoveredFollicle = -1;        // with follicles shown and no feather or handle under the mouse (readout)
  bool boxActive = false;
  glm::vec2 boxFrom{0.0f}, boxTo{0.0f};
  // Frame rendering (Scene panel, frame_render.cpp): a request the app picks up, its progress and outcome.
  struct FrameRequest {
    std::string dir;
    double from = 0, to = 1, fps = 24;
  };
  std::optional<FrameRequest> frameRequest;
  bool frameCancel = false;
  bool framesRunning = false;
  size_t framesDone = 0, framesTotal = 0;
  std::string framesStatus;  // what the last render did ("" before any)
  // Mirror left/right (panels_paint.cpp, mirror.hpp): what to mirror and about which plane.
  bool mirrorTract = true, mirrorBrushes = true, mirrorControls = true, mirrorVectors = true;
  int mirrorAxis = 0;  // 0 x, 1 y, 2 z, 3 the body's symmetry plane
  float mirrorOffset = 0.0f;
  // Timeline.
  bool playing = false;
  float timeStart = 0.0f, timeEnd = 10.0f, timeStep = 1.0f / 24.0f;
  bool loop = true;
  // Playback runs at playFps frames a second of wall time: a frame that is not ready when the next is
  // due is dropped (timeline.cpp). Frames drawn before are shown from the flipbook at once.
  float playFps = 24.0f;
  int flipbookMB = 512;  // memory for the flipbook of drawn frames
  // While playing with a flipbook, the coat is evaluated ahead of the clock: the time on screen.
  double shownTime = 0;
  // While the time slider is dragged the coat is evaluated at scrubLod (when lower than the preview
  // LOD), and at the preview LOD again on release.
  bool scrubLowLod = true;
  float scrubLod = 0.05f;
  double scrubSavedLod = 0;  // the preview LOD during a drag (0: not dragging)
  // What the timeline shows: flipbook frames and memory, and the last playback's rates.
  size_t flipbookFrames = 0, flipbookBytes = 0;
  bool cacheRangeRequested = false;  // fill the flipbook over the range (the app takes the request)
  bool caching = false;              // ... is being filled
  float cacheProgress = 0.0f;
  std::string playReadout;
  // Fast navigation: while the camera moves, draw every k-th feather so at most this many coat
  // triangles are drawn (navigation.hpp); the full coat as soon as it stops.
  bool fastNavigation = true;
  int navigationBudget = 90000;
  // While the camera moves the 3D view is also rendered at 1/navigationScale of its resolution (per
  // axis) and stretched; full resolution as soon as it stops. 1 = off.
  int navigationScale = 2;
  bool navigationChanged = false;
  // Fast playback: while the timeline plays, each new frame is drawn like a moving view (1/navigationScale
  // of the resolution, no multisampling, every feather): drawing, not evaluating, is most of a played
  // frame on llvmpipe. A paused frame is drawn again at full quality. Off: played frames at full quality.
  bool fastPlayback = true;
  bool forceNavigation = false;  // draw the navigation coat even at rest (script: show navigation on)
  // Adaptive navigation: while the camera moves, keep drawing every feather (at 1/navigationScale) as
  // long as such a frame renders within fullCoatBudgetMs; the navigation coat only when slower.
  bool adaptiveNavigation = true;
  float fullCoatBudgetMs = 85.0f;
  // Measured frame rate (frames per second over the last half second).
  float fps = 0.0f;      // frames drawn per second while the view is active
  float frameMs = 0.0f;  // work per drawn frame (without waiting for events), ms
  bool idle = false;     // nothing to draw: the loop waits for input
  // The 3D view's rectangle in window coordinates (right of the panel column, between the menu bar
  // and the status bar); overlays and picking work in it.
  glm::vec2 viewOrigin{0.0f};
  glm::ivec2 viewSize{1, 1};
  bool hidePanels = false;
  float panelWidth = 420.0f;  // the panel column, pixels (drag its right edge)
  // Panel headers to open (1) or close (0) on the next frame, by name ("*" = all): set by scripts.
  std::map<std::string, int> panelRequests;
  UiRequest ui;
  // Windows.
  bool showDesigner = false, showJsonInspector = false, showHelp = false;
  // A styling vector being dragged (preview until release).
  int dragVector = -1;
  glm::vec3 dragAt{0}, dragDirection{0};
  bool dragActive = false;
};

// What panels can ask of the app.
struct AppRequests {
  std::function<void()> frameAll;
  std::function<void(const std::string&)> screenshot;  // path
  std::function<void(const std::string&)> open;        // path (asks about unsaved changes)
  std::function<void()> save;                          // Save (Save As when the scene has no file)
  std::function<void()> saveAs;
  std::function<void(const std::string&)> error;  // shows the error modal
};

struct PanelContext {
  Document& doc;
  ViewState& view;
  CameraController& camera;
  AppRequests& app;
};

// A separator with a title (ImGui 1.86 has no SeparatorText).
void sectionTitle(const char* title);

// Runs `fn` and routes a pteryla::Error (or any std::exception) to the error modal.
void guarded(PanelContext& ctx, const std::function<void()>& fn);

// Scripted widgets (UiRequest): true once when the script asks for `widget` of `panel` (with `value`, for
// list items named or numbered by it); the request is then taken. The widget "throw" of a panel makes
// its first uiRequested() call throw (`ui PANEL throw`, a test of the panel guard in app_ui.cpp).
bool uiRequested(PanelContext& ctx, const char* panel, const char* widget);
bool uiRequested(PanelContext& ctx, const char* panel, const char* widget, const std::string& value);
// A slider or field: sets `v` to the script's number.
bool uiRequestedNumber(PanelContext& ctx, const char* panel, const char* widget, float& v);
// A text field or a button with an argument: sets `value` to the script's VALUE (possibly empty).
bool uiRequestedText(PanelContext& ctx, const char* panel, const char* widget, std::string& value);

// panels_scene.cpp: master seed, layer ordering, export
void drawScenePanel(PanelContext& ctx);
void drawFramesSection(PanelContext& ctx);  // panels_frames.cpp: render the timeline range to PNGs

// panels_view.cpp
void drawViewPanel(PanelContext& ctx);
void drawRenderPanel(PanelContext& ctx);
void drawStatusBar(PanelContext& ctx, float height);
// panels_coat.cpp
void drawTractsPanel(PanelContext& ctx);
void drawFolliclesPanel(PanelContext& ctx);
void drawKeyFeathersPanel(PanelContext& ctx);
void drawDirectionsPanel(PanelContext& ctx);
void drawPackingPanel(PanelContext& ctx);
// panels_paint.cpp: the face brush and "new tract from selection" (in Tracts), the density brush (in
// Follicles)
void drawFacePaintSection(PanelContext& ctx);
void drawDensityPaintSection(PanelContext& ctx);
void drawMirrorSection(PanelContext& ctx);  // in Tracts: mirror left/right
// panels_time.cpp
void drawTimelinePanel(PanelContext& ctx);
void drawControlsPanel(PanelContext& ctx);
// panels_gizmo.cpp: the selected control's offset and Key (in Expressive controls); the Skeleton panel
void drawControlOffsetSection(PanelContext& ctx, size_t control);
void drawSkeletonPanel(PanelContext& ctx);

// panel_feather.cpp: the feather designer window.
class FeatherDesigner {
 public:
  FeatherDesigner();
  ~FeatherDesigner();
  void draw(PanelContext& ctx, bool* open);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pteryla::viewer
