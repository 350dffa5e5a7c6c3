// Handles with the orbit tool (docs/viewer.md, "Handles"; handles.hpp): the control, brush, styling vector,
// key feather or pinned follicle nearest the mouse (within 8 pixels) is ringed with a readout; a press on
// it selects it and a drag moves it over the skin (one edit on release); Delete removes the selected one.
#include <imgui.h>

#include <glm/geometric.hpp>

#include "app.hpp"
#include "picking.hpp"

namespace pteryla::viewer {

bool App::handleHandles(const glm::vec2& mouse, bool overUi, bool leftPressed) {
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
      guarded(*panels_, [&] { moveHandle(doc_, h, glm::dvec3(view_.handlePreview)); });
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
    view_.handlePreview = handles[size_t(k)].at;
    view_.handleDragging = true;
    handleDrag_ = true;
    handleMoved_ = handleOnSkin_ = false;
    handleStart_ = mouse;
  }
  return true;
}

void App::deleteSelectedHandle() {
  if (!view_.selectedHandle) return;
  const Handle h = *view_.selectedHandle;
  view_.selectedHandle.reset();
  view_.hoveredHandle.reset();
  guarded(*panels_, [&] { removeHandle(doc_, h); });
}

}  // namespace pteryla::viewer
