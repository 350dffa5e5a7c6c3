// Gizmos in the 3D view (docs/viewer.md, "Gizmos"; gizmo.hpp has the math and the edits): the selected
// expressive control's offset arrow with three axis handles at its tip, and the skeleton's joints
// (a handle at each posed pivot, bones to their parents) with three rotation rings about the selected
// joint. Dragging an axis handle moves the offset along the axis, dragging a ring turns the joint; the
// release writes one edit at the current time. K keys the selected joint's rotation, else the selected
// control (behaviours and offset).
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/geometric.hpp>

#include "input.hpp"
#include "gizmo.hpp"
#include "overlays.hpp"
#include "picking.hpp"

namespace pteryla::viewer {

namespace {

constexpr int kRingSegments = 48;
const ImU32 kAxisColour[3] = {IM_COL32(235, 70, 70, 255), IM_COL32(80, 210, 80, 255), IM_COL32(80, 130, 255, 255)};

// Distance from p to the segment ab, pixels.
float segmentDistance(const glm::vec2& p, const glm::vec2& a, const glm::vec2& b) {
  const glm::vec2 ab = b - a;
  const float len2 = glm::dot(ab, ab);
  const float t = len2 > 0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
  return glm::length(p - (a + t * ab));
}

// Two unit vectors spanning the plane normal to n.
void planeBasis(const glm::dvec3& n, glm::dvec3& u, glm::dvec3& v) {
  const glm::dvec3 helper = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  u = glm::normalize(glm::cross(n, helper));
  v = glm::cross(n, u);
}

// Scene units per pixel of the view at p (the gizmos keep their size on screen as the camera zooms).
double unitsPerPixel(const render::Camera& cam, const glm::dvec3& p, int viewHeight) {
  const double depth = std::max(glm::dot(p - glm::dvec3(cam.eye), glm::dvec3(cam.forward())), 1e-6);
  return 2.0 * depth * std::tan(glm::radians(double(cam.fovYDegrees)) * 0.5) / double(std::max(viewHeight, 1));
}

}  // namespace

GizmoGeometry ViewportInput::gizmoGeometry() {
  GizmoGeometry g;
  if (!doc_.hasScene()) return g;
  const Snapshot& snap = doc_.snapshot();
  const render::Camera& cam = camera_.camera();
  const double t = doc_.time();
  // The selected control's offset arrow and its axis handles.
  if (view_.selectedControl >= 0) {
    if (const auto off = controlOffsetAt(doc_.scene(), size_t(view_.selectedControl), t)) {
      g.control = view_.selectedControl;
      g.at = off->at;
      g.offset = off->offset;
      g.offsetKeyed = off->keyed;
      g.handleLength = 70.0 * unitsPerPixel(cam, g.at + g.offset, view_.viewSize.y);
    }
  }
  // The skeleton's joints, posed at the current time.
  const moult::SkinRig* rig =
      snap.restSkin ? view_.rig.get(doc_.scene(), snap.restSkin->vertexCount(), doc_.changeCount()) : nullptr;
  if (rig) {
    g.rig = rig;
    g.joints = poseJoints(*rig, t);
    if (view_.selectedJoint >= int(rig->skeleton.jointCount())) view_.selectedJoint = -1;
    if (view_.selectedJoint >= 0)
      g.ringRadius = 60.0 * unitsPerPixel(cam, g.joints.pivot[size_t(view_.selectedJoint)], view_.viewSize.y);
  } else {
    view_.selectedJoint = -1;
  }
  return g;
}

// The control's offset tip while dragging (the preview) or as the scene has it.
static glm::dvec3 offsetTip(const GizmoGeometry& g, bool dragging, const glm::dvec3& preview) {
  return g.at + (dragging ? preview : g.offset);
}

glm::dvec3 ViewportInput::ringPoint(const GizmoGeometry& g, int joint, int axis, int k) const {
  const glm::dvec3 n = g.joints.parentFrame[size_t(joint)] * glm::dvec3(axis == 0, axis == 1, axis == 2);
  glm::dvec3 u, v;
  planeBasis(n, u, v);
  const double a = 2.0 * 3.14159265358979323846 * double(k) / double(kRingSegments);
  return g.joints.pivot[size_t(joint)] + g.ringRadius * (std::cos(a) * u + std::sin(a) * v);
}

bool ViewportInput::handleGizmo(const glm::vec2& mouse, bool overUi, bool leftPressed) {
  const render::Camera& cam = camera_.camera();
  const Ray ray = pixelRay(cam, mouse, view_.viewSize);
  const glm::dvec3 ro(ray.origin), rd(glm::normalize(glm::dvec3(ray.direction)));
  if (gizmoDrag_) {
    const GizmoGeometry g = gizmoGeometry();
    if (gizmoRing_) {
      // The angle swept about the ring's axis by where the mouse ray meets the ring's plane.
      const double den = glm::dot(rd, gizmoAxisWorld_);
      if (std::abs(den) > 1e-9) {
        const double s = glm::dot(gizmoPivot_ - ro, gizmoAxisWorld_) / den;
        if (s > 0) {
          const glm::dvec3 hit = ro + s * rd;
          gizmoDegrees_ = glm::degrees(angleAbout(gizmoStartVec_, hit - gizmoPivot_, gizmoAxisWorld_));
          if (std::abs(gizmoDegrees_) > 1e-6) gizmoMoved_ = true;
        }
      }
    } else if (const auto s = closestOnLine(gizmoStartTip_, gizmoAxisWorld_, ro, rd)) {
      gizmoPreview_ = gizmoStartOffset_ + (*s - gizmoStartParam_) * gizmoAxisWorld_;
      if (*s != gizmoStartParam_) gizmoMoved_ = true;
    }
    if (ImGui::IsMouseDown(ImGuiMouseButton_Left)) return true;
    gizmoDrag_ = false;
    if (gizmoMoved_) {
      if (gizmoRing_ && g.rig && gizmoJoint_ >= 0 && size_t(gizmoJoint_) < g.joints.local.size()) {
        const glm::dquat turned = turnLocal(g.joints.local[size_t(gizmoJoint_)], gizmoAxis_, gizmoDegrees_);
        guarded(panels_, [&] { keyJointRotation(doc_, g.rig->skeleton, size_t(gizmoJoint_), doc_.time(), turned); });
      } else if (!gizmoRing_ && g.control >= 0) {
        guarded(panels_, [&] { setControlOffset(doc_, size_t(g.control), gizmoPreview_, doc_.time()); });
      }
      doc_.endGesture();
    }
    return true;
  }
  view_.hoveredJoint = -1;
  gizmoHover_ = -1;
  // A handle being dragged keeps the mouse until its release, even over a gizmo.
  if (overUi || dragging_ || handleDrag_) return false;
  const GizmoGeometry g = gizmoGeometry();
  // Offset axis handles of the selected control.
  if (g.control >= 0) {
    const glm::dvec3 tip = offsetTip(g, false, {});
    for (int a = 0; a < 3; ++a) {
      glm::vec2 p0, p1;
      const glm::dvec3 e(a == 0, a == 1, a == 2);
      if (!projectToPixel(cam, glm::vec3(tip), view_.viewSize, p0) ||
          !projectToPixel(cam, glm::vec3(tip + g.handleLength * e), view_.viewSize, p1))
        continue;
      if (glm::length(mouse - p1) > 8.0f && segmentDistance(mouse, glm::mix(p0, p1, 0.3f), p1) > 4.0f) continue;
      gizmoHover_ = a;
      if (leftPressed) {
        gizmoDrag_ = true;
        gizmoRing_ = false;
        gizmoMoved_ = false;
        gizmoAxis_ = a;
        gizmoAxisWorld_ = e;
        gizmoStartTip_ = tip;
        gizmoStartOffset_ = g.offset;
        gizmoPreview_ = g.offset;
        gizmoStartParam_ = closestOnLine(tip, e, ro, rd).value_or(0.0);
      }
      return true;
    }
  }
  if (!g.rig || !view_.showJoints) return false;
  // Rotation rings of the selected joint.
  if (view_.selectedJoint >= 0) {
    const size_t j = size_t(view_.selectedJoint);
    float best = 6.0f;
    int bestAxis = -1;
    for (int a = 0; a < 3; ++a) {
      glm::vec2 prev;
      bool havePrev = false;
      for (int k = 0; k <= kRingSegments; ++k) {
        glm::vec2 q;
        if (!projectToPixel(cam, glm::vec3(ringPoint(g, int(j), a, k)), view_.viewSize, q)) {
          havePrev = false;
          continue;
        }
        if (havePrev) {
          const float d = segmentDistance(mouse, prev, q);
          if (d < best) best = d, bestAxis = a;
        }
        prev = q;
        havePrev = true;
      }
    }
    if (bestAxis >= 0) {
      gizmoHover_ = 3 + bestAxis;
      if (leftPressed) {
        const glm::dvec3 n = g.joints.parentFrame[j] * glm::dvec3(bestAxis == 0, bestAxis == 1, bestAxis == 2);
        const double den = glm::dot(rd, n);
        const double s = std::abs(den) > 1e-9 ? glm::dot(g.joints.pivot[j] - ro, n) / den : -1.0;
        // Edge-on rings give no plane to turn in: the press then only selects.
        if (s > 0) {
          gizmoDrag_ = true;
          gizmoRing_ = true;
          gizmoMoved_ = false;
          gizmoAxis_ = bestAxis;
          gizmoJoint_ = int(j);
          gizmoAxisWorld_ = n;
          gizmoPivot_ = g.joints.pivot[j];
          gizmoStartVec_ = ro + s * rd - gizmoPivot_;
          gizmoDegrees_ = 0;
        }
      }
      return true;
    }
  }
  // Joint handles: hover readout, a click selects.
  std::vector<glm::vec3> pivots;
  for (const auto& p : g.joints.pivot) pivots.push_back(glm::vec3(p));
  const int k = pickPoint(pivots, {}, cam, view_.viewSize, mouse, 8.0f);
  if (k < 0) return false;
  view_.hoveredJoint = k;
  if (leftPressed) {
    view_.selectedJoint = k;
    view_.selectedHandle.reset();
    view_.selectedFeather = -1;
  }
  return true;
}

void ViewportInput::keySelected() {
  const GizmoGeometry g = gizmoGeometry();
  if (g.rig && view_.selectedJoint >= 0) {
    const size_t j = size_t(view_.selectedJoint);
    guarded(panels_, [&] { keyJointRotation(doc_, g.rig->skeleton, j, doc_.time(), g.joints.local[j]); });
  } else if (g.control >= 0) {
    guarded(panels_, [&] { keyControlAll(doc_, size_t(g.control), doc_.time()); });
  }
}

void ViewportInput::drawGizmos(ImDrawList* dl) {
  const GizmoGeometry g = gizmoGeometry();
  const Projector proj{camera_.camera(), view_.viewSize, view_.viewOrigin};
  const glm::vec2 o = view_.viewOrigin, e = o + glm::vec2(view_.viewSize);
  dl->PushClipRect(ImVec2(o.x, o.y), ImVec2(e.x, e.y), true);
  auto line = [&](const glm::dvec3& a, const glm::dvec3& b, ImU32 col, float thick) {
    ImVec2 pa, pb;
    if (proj(glm::vec3(a), pa) && proj(glm::vec3(b), pb)) dl->AddLine(pa, pb, col, thick);
  };
  char buf[160];
  if (g.control >= 0) {
    const bool dragging = gizmoDrag_ && !gizmoRing_;
    const glm::dvec3 tip = offsetTip(g, dragging, gizmoPreview_);
    line(g.at, tip, IM_COL32(255, 230, 90, 255), 2.5f);  // the offset: direction and aim follow it
    ImVec2 pt;
    if (proj(glm::vec3(tip), pt)) dl->AddCircleFilled(pt, 4.0f, IM_COL32(255, 230, 90, 255));
    for (int a = 0; a < 3; ++a) {
      const glm::dvec3 ax(a == 0, a == 1, a == 2);
      const bool hot = gizmoHover_ == a || (dragging && gizmoAxis_ == a);
      const ImU32 col = hot ? IM_COL32(255, 255, 255, 255) : kAxisColour[a];
      line(tip, tip + g.handleLength * ax, col, hot ? 3.0f : 2.0f);
      ImVec2 ph;
      if (proj(glm::vec3(tip + g.handleLength * ax), ph)) dl->AddCircleFilled(ph, hot ? 6.0f : 5.0f, col);
    }
    const glm::dvec3 shown = dragging ? gizmoPreview_ : g.offset;
    std::snprintf(buf, sizeof buf, "offset %.3f %.3f %.3f%s", shown.x, shown.y, shown.z,
                  g.offsetKeyed ? " (keyed)" : "");
    if (proj(glm::vec3(tip), pt)) dl->AddText(ImVec2(pt.x + 8, pt.y + 6), IM_COL32(255, 230, 90, 255), buf);
  }
  if (g.rig && view_.showJoints) {
    const moult::Skeleton& sk = g.rig->skeleton;
    for (size_t j = 0; j < sk.jointCount(); ++j)
      if (sk.parent[j] >= 0)
        line(g.joints.pivot[size_t(sk.parent[j])], g.joints.pivot[j], IM_COL32(240, 200, 120, 200), 2.0f);
    for (size_t j = 0; j < sk.jointCount(); ++j) {
      ImVec2 p;
      if (!proj(glm::vec3(g.joints.pivot[j]), p)) continue;
      const bool sel = int(j) == view_.selectedJoint, hov = int(j) == view_.hoveredJoint;
      const ImU32 col = sel   ? IM_COL32(80, 230, 255, 255)
                        : hov ? IM_COL32(255, 255, 255, 255)
                              : IM_COL32(240, 200, 120, 255);
      dl->AddRectFilled(ImVec2(p.x - 4, p.y - 4), ImVec2(p.x + 4, p.y + 4), col);
      if (sel || hov) dl->AddText(ImVec2(p.x + 7, p.y - 16), col, sk.names[j].c_str());
    }
    if (view_.selectedJoint >= 0) {
      const int j = view_.selectedJoint;
      for (int a = 0; a < 3; ++a) {
        const bool hot = gizmoHover_ == 3 + a || (gizmoDrag_ && gizmoRing_ && gizmoAxis_ == a);
        const ImU32 col = hot ? IM_COL32(255, 255, 255, 255) : kAxisColour[a];
        for (int k = 0; k < kRingSegments; ++k)
          line(ringPoint(g, j, a, k), ringPoint(g, j, a, k + 1), col, hot ? 3.0f : 1.5f);
      }
      if (gizmoDrag_ && gizmoRing_) {
        line(gizmoPivot_, gizmoPivot_ + gizmoStartVec_, IM_COL32(255, 255, 255, 160), 1.0f);
        const glm::dvec3 now =
            glm::mat3_cast(glm::angleAxis(glm::radians(gizmoDegrees_), gizmoAxisWorld_)) * gizmoStartVec_;
        line(gizmoPivot_, gizmoPivot_ + now, IM_COL32(255, 255, 255, 255), 2.0f);
        std::snprintf(buf, sizeof buf, "%s %+.1f deg about %c", sk.names[size_t(j)].c_str(), gizmoDegrees_,
                      "xyz"[gizmoAxis_]);
      } else {
        const Json r = axisAngleJson(g.joints.local[size_t(j)]);
        std::snprintf(buf, sizeof buf, "%s: %.1f deg about (%.2f %.2f %.2f); drag a ring, K keys",
                      sk.names[size_t(j)].c_str(), r[3].get<double>(), r[0].get<double>(), r[1].get<double>(),
                      r[2].get<double>());
      }
      ImVec2 p;
      if (proj(glm::vec3(g.joints.pivot[size_t(j)]), p))
        dl->AddText(ImVec2(p.x + 7, p.y + 4), IM_COL32(255, 255, 255, 255), buf);
    }
  }
  dl->PopClipRect();
}

// The script's `gizmo-drag`: the press and release points of a drag on the gizmo, in view pixels, as a
// user would make it (the drag itself then runs through handleGizmo like a real mouse).
bool ViewportInput::gizmoDragPoints(bool ring, int axis, double amount, glm::vec2& from, glm::vec2& to) {
  const GizmoGeometry g = gizmoGeometry();
  const render::Camera& cam = camera_.camera();
  if (!ring) {
    if (g.control < 0) return false;
    const glm::dvec3 e(axis == 0, axis == 1, axis == 2);
    const glm::dvec3 handle = g.at + g.offset + g.handleLength * e;
    return projectToPixel(cam, glm::vec3(handle), view_.viewSize, from) &&
           projectToPixel(cam, glm::vec3(handle + amount * e), view_.viewSize, to);
  }
  if (!g.rig || view_.selectedJoint < 0) return false;
  const int j = view_.selectedJoint;
  // Press the ring where it is widest on screen (farthest from the pivot), end turned by `amount`.
  glm::vec2 pivot;
  if (!projectToPixel(cam, glm::vec3(g.joints.pivot[size_t(j)]), view_.viewSize, pivot)) return false;
  int bestK = -1;
  float best = -1;
  for (int k = 0; k < kRingSegments; ++k) {
    glm::vec2 q;
    if (projectToPixel(cam, glm::vec3(ringPoint(g, j, axis, k)), view_.viewSize, q) && glm::length(q - pivot) > best)
      best = glm::length(q - pivot), bestK = k;
  }
  if (bestK < 0) return false;
  const glm::dvec3 n = g.joints.parentFrame[size_t(j)] * glm::dvec3(axis == 0, axis == 1, axis == 2);
  const glm::dvec3 p0 = ringPoint(g, j, axis, bestK);
  const glm::dvec3 p1 = g.joints.pivot[size_t(j)] +
                        glm::mat3_cast(glm::angleAxis(glm::radians(amount), n)) * (p0 - g.joints.pivot[size_t(j)]);
  return projectToPixel(cam, glm::vec3(p0), view_.viewSize, from) &&
         projectToPixel(cam, glm::vec3(p1), view_.viewSize, to);
}

}  // namespace pteryla::viewer
