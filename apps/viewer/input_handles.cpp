// Handles with the orbit tool (docs/viewer.md, "Handles"; handles.hpp): the control, brush, styling vector,
// key feather or pinned follicle nearest the mouse (within 8 pixels) is ringed with a readout; a press on
// it selects it and a drag moves it over the skin (one edit on release); Delete removes the selected one,
// or the selected feather's follicle. Ctrl + drag boxes feathers (and shown follicles); Delete then removes
// the boxed handles and the boxed feathers' follicles.
#include <imgui.h>

#include <algorithm>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "input.hpp"
#include "picking.hpp"

namespace pteryla::viewer {

bool ViewportInput::handleHandles(const glm::vec2& mouse, bool overUi, bool leftPressed) {
  const render::Camera& cam = camera_.camera();
  if (handleDrag_) {
    if (glm::length(mouse - handleStart_) > 3.0f) handleMoved_ = true;
    if (handleMoved_) {
      const auto hit = raycast(doc_.snapshot().skin, pixelRay(cam, mouse, view_.viewSize));
      if (hit) {
        view_.handlePreview = hit->point;
        handleOnSkin_ = true;
      }
    }
    if (ImGui::IsMouseDown(ImGuiMouseButton_Left)) return true;
    handleDrag_ = false;
    view_.handleDragging = false;
    if (handleMoved_ && handleOnSkin_ && view_.selectedHandle) {
      const Handle h = *view_.selectedHandle;
      guarded(panels_, [&] { moveHandle(doc_, h, glm::dvec3(view_.handlePreview)); });
      doc_.endGesture();
    }
    return true;
  }
  view_.hoveredHandle.reset();
  if (overUi || dragging_) return false;
  const std::vector<Handle> handles = sceneHandles(doc_.scene());
  if (handles.empty()) return false;
  std::vector<glm::vec3> points;
  points.reserve(handles.size());
  for (const Handle& h : handles) points.push_back(h.at);
  const int k = pickPoint(points, {}, cam, view_.viewSize, mouse, 8.0f);
  if (k < 0) return false;
  view_.hoveredHandle = handles[size_t(k)];
  if (leftPressed) {
    view_.selectedHandle = handles[size_t(k)];
    view_.selectedFeather = -1;
    view_.boxHandles.clear();  // Delete now means this handle
    // A control shows its offset gizmo (input_gizmo.cpp); any other handle hides it.
    view_.selectedControl = handles[size_t(k)].kind == HandleKind::Control ? int(handles[size_t(k)].index) : -1;
    view_.selectedJoint = -1;
    view_.handlePreview = handles[size_t(k)].at;
    view_.handleDragging = true;
    handleDrag_ = true;
    handleMoved_ = handleOnSkin_ = false;
    handleStart_ = mouse;
  }
  return true;
}

void ViewportInput::deleteSelected() {
  // A box selection: every boxed handle, and the follicles of the boxed feathers and follicles (their
  // tracts' removed_follicles), as one undo step.
  if (!view_.boxHandles.empty() || !view_.boxFeathers.empty() || !view_.boxFollicles.empty()) {
    const std::vector<Handle> hs = view_.boxHandles;
    const std::vector<FollicleRef> fs = follicleRefs(doc_.snapshot(), view_.boxFeathers, view_.boxFollicles);
    view_.boxHandles.clear();
    view_.boxFeathers.clear();
    view_.boxFollicles.clear();
    view_.selectedHandle.reset();
    view_.hoveredHandle.reset();
    guarded(panels_, [&] { removeHandles(doc_, hs, fs); });
    return;
  }
  if (view_.selectedHandle) {
    const Handle h = *view_.selectedHandle;
    view_.selectedHandle.reset();
    view_.hoveredHandle.reset();
    guarded(panels_, [&] { removeHandle(doc_, h); });
    return;
  }
  if (view_.selectedFeather >= 0) {  // the clicked feather: its follicle goes, leaving a gap
    const std::vector<FollicleRef> fs = follicleRefs(doc_.snapshot(), {view_.selectedFeather}, {});
    view_.selectedFeather = view_.hoveredFeather = -1;
    guarded(panels_, [&] { removeHandles(doc_, {}, fs); });
  }
}

bool ViewportInput::handleBox(const glm::vec2& mouse, bool overUi, bool leftPressed) {
  if (view_.boxActive) {
    view_.boxTo = mouse;
    if (ImGui::IsMouseDown(ImGuiMouseButton_Left)) return true;
    view_.boxActive = false;
    boxSelect(view_.boxFrom, view_.boxTo);
    return true;
  }
  if (!leftPressed || overUi || !ImGui::GetIO().KeyCtrl) return false;
  view_.boxActive = true;
  view_.boxFrom = view_.boxTo = mouse;
  return true;
}

void ViewportInput::boxSelect(const glm::vec2& a, const glm::vec2& b) {
  const glm::vec2 lo = glm::min(a, b), hi = glm::max(a, b);
  const render::Camera& cam = camera_.camera();
  const Snapshot& s = doc_.snapshot();
  auto inside = [&](const glm::vec3& p, const glm::vec3* n) {
    if (n && glm::dot(*n, cam.eye - p) < 0.0f) return false;  // facing away
    glm::vec2 q;
    return projectToPixel(cam, p, view_.viewSize, q) && q.x >= lo.x && q.y >= lo.y && q.x <= hi.x && q.y <= hi.y;
  };
  view_.boxFeathers.clear();
  view_.boxFollicles.clear();
  view_.boxHandles.clear();
  {
    // The handles of the kinds the overlays show (controls, brushes, vectors; key feathers, pinned follicles).
    const ViewState& v = view_;
    for (const Handle& h : sceneHandles(doc_.scene())) {
      const bool shown = h.kind == HandleKind::Control  ? v.showControls
                         : h.kind == HandleKind::Brush  ? v.showBrushes
                         : h.kind == HandleKind::Vector ? v.showVectors
                                                        : v.showKeys;
      if (shown && inside(h.at, nullptr)) view_.boxHandles.push_back(h);
    }
  }
  for (size_t i = 0; i < s.featherOrigin.size(); ++i) {
    if (i < s.featherPresent.size() && !s.featherPresent[i]) continue;
    if (inside(s.featherOrigin[i], i < s.featherNormal.size() ? &s.featherNormal[i] : nullptr))
      view_.boxFeathers.push_back(int(i));
  }
  if (view_.showFollicles)
    for (size_t i = 0; i < s.follicle.size(); ++i)
      if (inside(s.follicle[i], i < s.follicleNormal.size() ? &s.follicleNormal[i] : nullptr))
        view_.boxFollicles.push_back(int(i));
  view_.selectedFeather = -1;
  view_.selectedHandle.reset();
}

bool ViewportInput::frameBoxSelection() {
  const Snapshot& s = doc_.snapshot();
  glm::vec3 lo(1e30f), hi(-1e30f);
  bool any = false;
  for (int f : view_.boxFeathers) {
    if (size_t(f) >= s.featherOrigin.size()) continue;
    const float r = size_t(f) < s.featherLength.size() ? std::max(s.featherLength[size_t(f)], 1e-4f) : 0.1f;
    lo = glm::min(lo, s.featherOrigin[size_t(f)] - glm::vec3(r));
    hi = glm::max(hi, s.featherOrigin[size_t(f)] + glm::vec3(r));
    any = true;
  }
  if (!any) return false;
  viewport_.frameBox(lo, hi);
  return true;
}

}  // namespace pteryla::viewer
