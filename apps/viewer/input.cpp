// Viewport input: turntable camera (left drag orbits, right/middle or shift+left drag pans, wheel zooms)
// and the panel tools, which pick on the posed skin (raycast) or on follicles (nearest projection).
#include <imgui.h>

#include <cmath>

#include <glm/geometric.hpp>

#include "actions.hpp"
#include "input.hpp"
#include "overlays.hpp"
#include "picking.hpp"

namespace pteryla::viewer {

namespace {

// Intersection of a ray with the plane through `p` with normal `n`; false when parallel or behind.
bool rayPlane(const Ray& r, const glm::vec3& p, const glm::vec3& n, glm::vec3& out) {
  const float den = glm::dot(r.direction, n);
  if (std::abs(den) < 1e-9f) return false;
  const float t = glm::dot(p - r.origin, n) / den;
  if (t <= 0) return false;
  out = r.origin + t * r.direction;
  return true;
}

}  // namespace

bool ViewportInput::cameraMoving() const {
  return dragging_ || std::chrono::steady_clock::now() - lastWheel_ < std::chrono::milliseconds(300);
}

void ViewportInput::handle() {
  ImGuiIO& io = ImGui::GetIO();
  if (!doc_.hasScene() || !viewport_.cameraReady()) return;
  const glm::vec2 mouse = glm::vec2(io.MousePos.x, io.MousePos.y) - view_.viewOrigin;  // view pixels
  const float h = float(view_.viewSize.y);
  const bool inView =
      mouse.x >= 0 && mouse.y >= 0 && mouse.x < float(view_.viewSize.x) && mouse.y < float(view_.viewSize.y);
  const bool overUi = (io.WantCaptureMouse || !inView) && !dragging_ && !toolDrag_;
  if (!overUi && io.MouseWheel != 0.0f) {
    lastWheel_ = std::chrono::steady_clock::now();
    camera_.zoom(std::pow(0.88f, io.MouseWheel));
    viewport_.noteCameraMoved();
  }
  updateBrushHover(mouse, overUi);
  const bool leftPressed = ImGui::IsMouseClicked(ImGuiMouseButton_Left) && !overUi;
  const bool toolActive = view_.tool != Tool::Orbit && !io.KeyShift;
  if (toolActive && (leftPressed || toolDrag_)) {
    const bool used = handleTool(leftPressed, ImGui::IsMouseDown(ImGuiMouseButton_Left),
                                 ImGui::IsMouseReleased(ImGuiMouseButton_Left), mouse);
    if (used) return;
  }
  // Ctrl + drag: box selection of feathers and follicles.
  if (!toolActive && handleBox(mouse, overUi, leftPressed)) {
    view_.hoveredFeather = -1;
    return;
  }
  // Gizmos (the selected control's offset, skeleton joints and rings) come before handles and feathers.
  if (!toolActive && handleGizmo(mouse, overUi, leftPressed)) {
    view_.hoveredFeather = -1;
    return;
  }
  // Handles (controls, brushes, vectors, key feathers, pinned follicles) come before feathers.
  if (!toolActive && handleHandles(mouse, overUi, leftPressed)) {
    view_.hoveredFeather = -1;
    return;
  }
  // Hover readout and click selection of feathers (orbit tool): the feather whose follicle projects
  // nearest the mouse, facing the camera. A click is a press and release that did not orbit.
  const Snapshot& snap = doc_.snapshot();
  // The coat triangle under the mouse (not hidden by the skin), else the follicle nearest on screen.
  auto featherAt = [&](const glm::vec2& px) {
    int f = -1;
    pipeline::Pipeline* p = doc_.idlePipeline();
    if (p && doc_.upToDate())
      f = pickFeather(p->coatMesh().mesh, snap.skin, pixelRay(camera_.camera(), px, view_.viewSize));
    if (f < 0) f = pickPoint(snap.featherOrigin, snap.featherNormal, camera_.camera(), view_.viewSize, px, 10.0f);
    if (f >= 0 && (size_t(f) >= snap.featherPresent.size() || !snap.featherPresent[size_t(f)])) f = -1;
    return f;
  };
  if (overUi || dragging_ || toolActive || !snap.haveCoat) {
    view_.hoveredFeather = -1;
    hoverAt_ = glm::vec2(-1.0f);
  } else if (mouse != hoverAt_ || hoverResult_ != doc_.resultVersion()) {
    hoverAt_ = mouse;  // the ray is cast again only when the mouse or the coat moved
    hoverResult_ = doc_.resultVersion();
    view_.hoveredFeather = featherAt(mouse);
  }
  view_.hoveredFollicle = -1;  // a follicle readout where no feather is under the mouse
  if (view_.showFollicles && !overUi && !dragging_ && !toolActive && view_.hoveredFeather < 0)
    view_.hoveredFollicle =
        pickPoint(snap.follicle, snap.follicleNormal, camera_.camera(), view_.viewSize, mouse, 6.0f);
  if (leftPressed && !toolActive) clickStart_ = mouse, clickPending_ = true;
  if (clickPending_ && ImGui::IsMouseDown(ImGuiMouseButton_Left) && glm::length(mouse - clickStart_) > 3.0f)
    clickPending_ = false;  // it became an orbit
  if (clickPending_ && ImGui::IsMouseReleased(ImGuiMouseButton_Left)) {
    clickPending_ = false;
    view_.selectedFeather = snap.haveCoat ? featherAt(mouse) : -1;
    view_.selectedHandle.reset();
    if (view_.selectedFeather >= 0) {  // a click replaces the box selection (Delete then means this feather)
      view_.boxFeathers.clear();
      view_.boxFollicles.clear();
      view_.boxHandles.clear();
    }
  }
  const bool anyDown = ImGui::IsMouseDown(ImGuiMouseButton_Left) || ImGui::IsMouseDown(ImGuiMouseButton_Right) ||
                       ImGui::IsMouseDown(ImGuiMouseButton_Middle);
  if (!anyDown) dragging_ = false;
  if (!overUi && (ImGui::IsMouseClicked(ImGuiMouseButton_Left) || ImGui::IsMouseClicked(ImGuiMouseButton_Right) ||
                  ImGui::IsMouseClicked(ImGuiMouseButton_Middle)))
    dragging_ = true;
  if (!dragging_) return;
  const glm::vec2 delta(io.MouseDelta.x, io.MouseDelta.y);
  if (delta.x == 0 && delta.y == 0) return;
  if (ImGui::IsMouseDown(ImGuiMouseButton_Right) || ImGui::IsMouseDown(ImGuiMouseButton_Middle) ||
      (ImGui::IsMouseDown(ImGuiMouseButton_Left) && io.KeyShift)) {
    camera_.panPixels(delta, h);
    viewport_.noteCameraMoved();
  } else if (ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
    camera_.orbitPixels(delta, h);
    viewport_.noteCameraMoved();
  }
}

bool ViewportInput::handleTool(bool pressed, bool down, bool released, const glm::vec2& mouse) {
  const Snapshot& snap = doc_.snapshot();
  const render::Camera& cam = camera_.camera();
  const Ray ray = pixelRay(cam, mouse, view_.viewSize);
  PanelContext& ctx = panels_;
  auto tractIndex = [&] { return size_t(std::max(view_.selectedTract, 0)); };
  if (view_.tool == Tool::PaintFaces || view_.tool == Tool::PaintDensity)
    return handlePaint(pressed, down, released, mouse);

  if (pressed) {
    if (view_.tool == Tool::PlaceKey) {
      const int f = pickPoint(snap.follicle, snap.follicleNormal, cam, view_.viewSize, mouse, 12.0f);
      if (f >= 0) {
        view_.selectedFollicle = f;
        const size_t tract = f < int(snap.follicleTract.size()) ? snap.follicleTract[size_t(f)] : 0;
        guarded(ctx, [&] { actions::addKeyFeather(doc_, tract, view_.toolFeather, snap.follicleId[size_t(f)]); });
        return true;
      }
      return false;
    }
    if (view_.tool == Tool::EditVectors) {
      // Grab the styling vector whose tip is nearest the mouse.
      const Json d = doc_.scene().directions;  // a copy, like the panels' (panels.hpp)
      if (!d.contains("vectors") || !d["vectors"].is_array()) return false;
      const float len = overlayArrowLength(snap);
      std::vector<glm::vec3> tips;
      for (const auto& v : d["vectors"]) {
        glm::vec3 dir = glm::vec3(actions::jsonVec3(v.value("direction", Json()), glm::dvec3(1, 0, 0)));
        if (glm::length(dir) > 0) dir = glm::normalize(dir);
        tips.push_back(glm::vec3(actions::jsonVec3(v.value("at", Json()))) + dir * len);
      }
      const int k = pickPoint(tips, {}, cam, view_.viewSize, mouse, 12.0f);
      if (k < 0) return false;
      const Json& v = d["vectors"][size_t(k)];
      view_.dragVector = k;
      view_.selectedVector = k;
      view_.dragAt = glm::vec3(actions::jsonVec3(v.value("at", Json())));
      view_.dragDirection = tips[size_t(k)] - view_.dragAt;
      // Drag in the plane through the anchor facing the camera's direction of the surface there.
      const auto hit = raycast(snap.skin, Ray{view_.dragAt - cam.forward() * 1e-3f, cam.forward()});
      dragNormal_ = hit ? hit->normal : -cam.forward();
      view_.dragActive = true;
      toolDrag_ = true;
      return true;
    }
    const auto hit = raycast(snap.skin, ray);
    if (!hit) return false;
    const glm::dvec3 at(hit->point);
    switch (view_.tool) {
      case Tool::AddVector:
      case Tool::AddBias:
        view_.dragVector = -1;
        view_.dragAt = hit->point;
        view_.dragDirection = glm::vec3(0);
        dragNormal_ = hit->normal;
        view_.dragActive = true;
        toolDrag_ = true;
        break;
      case Tool::Brush:
        guarded(ctx, [&] { actions::addBrush(doc_, at, view_.brushRadius, view_.brushElevationDeg, view_.brushLift); });
        break;
      case Tool::AddControl:
        guarded(ctx, [&] { view_.selectedControl = int(actions::addControl(doc_, at, view_.controlRadius)); });
        break;
      case Tool::Pin:
        guarded(ctx, [&] {
          actions::ensureTracts(doc_);
          actions::addPinned(doc_, tractIndex(), at);
        });
        break;
      default:
        return false;
    }
    return true;
  }
  if (!toolDrag_) return false;
  glm::vec3 q;
  if (rayPlane(ray, view_.dragAt, dragNormal_, q)) view_.dragDirection = q - view_.dragAt;
  if (down && !released) return true;
  // Release: commit the dragged vector (a click without a drag uses the camera's right, in the plane).
  toolDrag_ = false;
  view_.dragActive = false;
  glm::vec3 dir = view_.dragDirection;
  if (glm::length(dir) < 1e-6f * std::max(1.0f, glm::length(snap.skinHi - snap.skinLo))) {
    dir = glm::cross(cam.forward(), cam.up);
    dir -= dragNormal_ * glm::dot(dir, dragNormal_);
  }
  if (glm::length(dir) == 0) return true;
  const glm::dvec3 at(view_.dragAt), d(glm::normalize(dir));
  guarded(ctx, [&] {
    if (view_.tool == Tool::AddVector) {
      actions::addStylingVector(doc_, at, d, view_.combRadius);
      view_.selectedVector = int(doc_.scene().directions["vectors"].size()) - 1;
    } else if (view_.tool == Tool::AddBias) {
      actions::ensureTracts(doc_);
      actions::addBias(doc_, tractIndex(), at, d, view_.biasSigma, view_.biasStretch);
    } else if (view_.tool == Tool::EditVectors && view_.dragVector >= 0) {
      actions::setStylingVector(doc_, size_t(view_.dragVector), at, d);
    }
  });
  view_.dragVector = -1;
  return true;
}

}  // namespace pteryla::viewer
