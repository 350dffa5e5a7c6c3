// The painting tools of the 3D view (docs/viewer.md, "Painting"): the face brush adds faces to or removes
// them from the selected tract, or (de)selects faces for "new tract from selection"; the density brush
// paints the follicle density factor per vertex. A press on the skin starts a stroke, each move dabs
// where the mouse meets the skin, the release commits the stroke as one undoable edit (a press off the
// skin orbits as usual).
#include <imgui.h>

#include <glm/geometric.hpp>

#include "actions.hpp"
#include "input.hpp"
#include "paint.hpp"
#include "picking.hpp"

namespace pteryla::viewer {

void ViewportInput::updateBrushHover(const glm::vec2& mouse, bool overUi) {
  const bool paintTool = view_.tool == Tool::PaintFaces || view_.tool == Tool::PaintDensity;
  view_.brushVisible = false;
  if (!paintTool || (overUi && !view_.painting)) return;
  const Snapshot& snap = doc_.snapshot();
  if (snap.skin.empty()) return;
  const auto hit = raycast(snap.skin, pixelRay(camera_.camera(), mouse, view_.viewSize));
  if (!hit) return;
  view_.brushVisible = true;
  view_.brushAt = hit->point;
}

bool ViewportInput::handlePaint(bool pressed, bool down, bool released, const glm::vec2& mouse) {
  const Snapshot& snap = doc_.snapshot();
  const auto hit = raycast(snap.skin, pixelRay(camera_.camera(), mouse, view_.viewSize));
  if (pressed) {
    if (!hit || !snap.restSkin) return false;  // off the skin: the drag orbits
    strokeSkin_ = snap.restSkin;
    strokePosed_ = snap.posedVertex;
    view_.painting = true;
    toolDrag_ = true;
    dabbed_ = false;
    view_.strokeFaces.clear();
    view_.strokeDensity.clear();
    if (view_.tool == Tool::PaintDensity) {
      const auto& f = doc_.scene().densityFactor;
      if (f && f->size() == strokeSkin_->positions.size()) view_.strokeDensity = *f;
      view_.strokeDensity.resize(strokeSkin_->positions.size(), 1.0f);
    }
  }
  if (!view_.painting) return false;
  if (hit) paintDab(hit->point);
  if (down && !released) return true;
  commitStroke();
  return true;
}

void ViewportInput::paintDab(const glm::vec3& at) {
  // A dab where the mouse is, once it moved a quarter of the radius (holding still does not pile up).
  const float r = view_.paintRadius;
  if (dabbed_ && glm::length(at - lastDab_) < 0.25f * r) return;
  dabbed_ = true;
  lastDab_ = at;
  if (view_.tool == Tool::PaintFaces)
    view_.strokeFaces = faceUnion(view_.strokeFaces, facesInBrush(*strokeSkin_, strokePosed_, at, r));
  else
    densityDab(view_.strokeDensity, *strokeSkin_, strokePosed_, at, r, view_.densityValue, view_.densityStrength);
}

void ViewportInput::commitStroke() {
  toolDrag_ = false;
  view_.painting = false;
  PanelContext& ctx = panels_;
  if (view_.tool == Tool::PaintFaces && !view_.strokeFaces.empty()) {
    switch (view_.facePaint) {
      case FacePaint::Select:
        view_.faceSelection = faceUnion(view_.faceSelection, view_.strokeFaces);
        break;
      case FacePaint::Deselect:
        view_.faceSelection = faceDifference(view_.faceSelection, view_.strokeFaces);
        break;
      case FacePaint::Add:
      case FacePaint::Remove:
        guarded(ctx, [&] {
          actions::ensureTracts(doc_);
          const size_t t = size_t(std::max(view_.selectedTract, 0));
          actions::paintTractFaces(doc_, *strokeSkin_, t, view_.strokeFaces, view_.facePaint == FacePaint::Add);
        });
        break;
    }
  } else if (view_.tool == Tool::PaintDensity && dabbed_) {
    guarded(ctx, [&] { actions::setDensityFactors(doc_, view_.strokeDensity); });
  }
  doc_.endGesture();  // a stroke is one undo step, the next one another
  view_.strokeFaces.clear();
  view_.strokeDensity.clear();
  strokeSkin_.reset();
  strokePosed_.clear();
}

}  // namespace pteryla::viewer
