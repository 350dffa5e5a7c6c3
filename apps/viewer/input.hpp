#pragma once
// Mouse and keyboard in the 3D view (ViewportInput): the turntable camera (left drag orbits, right/middle
// or shift+left drag pans, the wheel zooms), hover readouts and click selection of feathers, and the
// viewport tools, which pick on the posed skin (raycast) or on follicles (nearest projection):
//   input.cpp          camera navigation, feather hover and selection, the panels' placing tools
//   input_paint.cpp    the face and density brushes (Tool::PaintFaces, Tool::PaintDensity)
//   input_handles.cpp  handles (hover, drag, select, Delete) and box selection (Ctrl + drag)
//   input_gizmo.cpp    the selected control's offset gizmo, the skeleton's joints and rotation rings, K
// Each drag keeps its state here; what it selects or previews goes to ViewState (drawn by the overlays),
// what it edits goes to the Document as one undo step. Errors of an edit go to the error modal.
#include <chrono>
#include <memory>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "camera_controller.hpp"
#include "document.hpp"
#include "gizmo.hpp"
#include "panels.hpp"
#include "viewport.hpp"

struct ImDrawList;

namespace pteryla::viewer {

class ViewportInput {
 public:
  // `panels` routes the errors of edits to the error modal (guarded); the camera and the view's
  // rectangle are those of `viewport`.
  ViewportInput(PanelContext& panels, Viewport& viewport)
      : doc_(panels.doc), view_(panels.view), camera_(panels.camera), panels_(panels), viewport_(viewport) {}

  // Once per frame inside the ImGui frame, before the panels: reads the mouse and acts on it.
  void handle();
  // A mouse button is held over the view (the camera may move), or the wheel zoomed in the last 300 ms.
  bool dragging() const { return dragging_; }
  bool cameraMoving() const;

  // The gizmos over the 3D view (after the overlays).
  void drawGizmos(ImDrawList* dl);
  // K: key the selected joint's rotation, else the selected control, at the current time.
  void keySelected();
  // Delete: the boxed handles and the boxed feathers' follicles, else the selected handle, else the
  // selected feather's follicle (handles.hpp, removeHandles), one undo step.
  void deleteSelected();
  // Box selection: fills view.boxFeathers / boxFollicles / boxHandles from a rectangle in view pixels
  // (Ctrl + drag, script `box-select`). frameBoxSelection frames the boxed feathers (false without any).
  void boxSelect(const glm::vec2& a, const glm::vec2& b);
  bool frameBoxSelection();
  // Where a scripted `gizmo-drag` presses and releases (view pixels); false when there is no such gizmo.
  bool gizmoDragPoints(bool ring, int axis, double amount, glm::vec2& from, glm::vec2& to);

 private:
  // Returns false when a press hit nothing the tool uses (the drag then orbits as usual).
  bool handleTool(bool pressed, bool down, bool released, const glm::vec2& mouse);
  // Handles with the orbit tool (handles.hpp): true when the mouse is on one (or dragging it), so the
  // feather pick and the orbit leave it alone.
  bool handleHandles(const glm::vec2& mouse, bool overUi, bool leftPressed);
  bool handleBox(const glm::vec2& mouse, bool overUi, bool leftPressed);
  // The gizmos (gizmo.hpp): true when the mouse is on one (or dragging it).
  GizmoGeometry gizmoGeometry();
  glm::dvec3 ringPoint(const GizmoGeometry& g, int joint, int axis, int k) const;
  bool handleGizmo(const glm::vec2& mouse, bool overUi, bool leftPressed);
  // The brushes (input_paint.cpp).
  bool handlePaint(bool pressed, bool down, bool released, const glm::vec2& mouse);
  void updateBrushHover(const glm::vec2& mouse, bool overUi);
  void paintDab(const glm::vec3& at);
  void commitStroke();

  Document& doc_;
  ViewState& view_;
  CameraController& camera_;
  PanelContext& panels_;
  Viewport& viewport_;

  // Drag state of the viewport.
  std::chrono::steady_clock::time_point lastWheel_;
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
  // A gizmo being dragged: an offset axis or a joint's ring.
  bool gizmoDrag_ = false, gizmoRing_ = false, gizmoMoved_ = false;
  int gizmoAxis_ = -1, gizmoJoint_ = -1, gizmoHover_ = -1;  // hover: 0-2 offset axes, 3-5 rings
  glm::dvec3 gizmoAxisWorld_{0.0}, gizmoStartTip_{0.0}, gizmoStartOffset_{0.0}, gizmoPreview_{0.0};
  glm::dvec3 gizmoPivot_{0.0}, gizmoStartVec_{0.0};
  double gizmoStartParam_ = 0, gizmoDegrees_ = 0;
};

}  // namespace pteryla::viewer
