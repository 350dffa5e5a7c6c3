// Overlays on the skin (drawn with the other overlays, overlays.cpp): bare skin in the coverage colour
// mode, and the painting tools': the view's face selection, the faces under a face stroke, the painted
// density map and the brush itself.
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/geometric.hpp>

#include "overlays.hpp"

namespace pteryla::viewer {

namespace {

// Density factor as a colour: below 1 blue, above 1 red, more opaque the further from 1.
ImU32 densityColour(float f) {
  const float t = std::clamp(std::abs(std::log2(std::max(f, 1e-3f))) / 2.0f, 0.0f, 1.0f);
  const int a = int(40 + 150 * t);
  return f < 1.0f ? IM_COL32(40, 110, 255, a) : IM_COL32(255, 70, 40, a);
}

}  // namespace

void drawPaintOverlays(ImDrawList* dl, PanelContext& ctx) {
  const Snapshot& snap = ctx.doc.snapshot();
  const ViewState& v = ctx.view;
  const Projector proj{ctx.camera.camera(), v.viewSize, v.viewOrigin};
  const std::shared_ptr<const coat::SkinMesh> rest = snap.restSkin;
  const bool painting = v.tool == Tool::PaintFaces || v.tool == Tool::PaintDensity;
  // Colour by coverage: the skin faces the last check found (partly) bare, front-facing, over the view.
  const auto& metrics = ctx.doc.metrics();
  const TriMesh& skin = snap.skin;
  if (v.colourBy == ColourBy::Coverage && metrics && metrics->faceSamples.size() * 3 == skin.indices.size() &&
      metrics->faceUncovered.size() == metrics->faceSamples.size()) {
    for (size_t t = 0; t < metrics->faceSamples.size(); ++t) {
      const int bin = coverageBin(metrics->faceSamples[t], metrics->faceUncovered[t]);
      if (bin == 0) continue;
      const glm::vec3 a = skin.positions[skin.indices[3 * t]], b = skin.positions[skin.indices[3 * t + 1]],
                      c = skin.positions[skin.indices[3 * t + 2]];
      if (glm::dot(glm::cross(b - a, c - a), proj.cam.eye - a) < 0.0f) continue;
      const glm::vec3 col = coverageColour(bin);
      ImVec2 pa, pb, pc;
      if (proj(a, pa) && proj(b, pb) && proj(c, pc))
        dl->AddTriangleFilled(pa, pb, pc, IM_COL32(int(col.r * 255), int(col.g * 255), int(col.b * 255), 170));
    }
  }
  if (rest && snap.posedVertex.size() == rest->positions.size()) {
    const auto& P = snap.posedVertex;
    // Per source face: 1 selected, 2 under the stroke.
    std::vector<uint8_t> mark(rest->sourceFaceCount + 1, 0);
    auto markAll = [&](const std::vector<uint32_t>& faces, uint8_t m) {
      for (uint32_t f : faces)
        if (f < mark.size()) mark[f] = m;
    };
    markAll(v.faceSelection, 1);
    markAll(v.strokeFaces, 2);
    const bool anyFaces = !v.faceSelection.empty() || !v.strokeFaces.empty();
    const std::vector<float>* density = !v.strokeDensity.empty()        ? &v.strokeDensity
                                        : ctx.doc.scene().densityFactor ? ctx.doc.scene().densityFactor.get()
                                                                        : nullptr;
    if (density && density->size() != P.size()) density = nullptr;
    const bool showDensity = density && (v.showDensity || v.tool == Tool::PaintDensity);
    const ImU32 strokeCol = v.facePaint == FacePaint::Remove     ? IM_COL32(255, 60, 60, 110)
                            : v.facePaint == FacePaint::Add      ? IM_COL32(60, 230, 90, 110)
                            : v.facePaint == FacePaint::Deselect ? IM_COL32(120, 120, 120, 110)
                                                                 : IM_COL32(255, 220, 60, 110);
    if (anyFaces || showDensity) {
      for (size_t t = 0; t < rest->faces.size(); ++t) {
        const auto& f = rest->faces[t];
        const glm::vec3 a = P[f[0]], b = P[f[1]], c = P[f[2]];
        if (glm::dot(glm::cross(b - a, c - a), proj.cam.eye - a) < 0.0f) continue;  // back-facing
        const uint32_t src = t < rest->sourceFace.size() ? rest->sourceFace[t] : uint32_t(t);
        const uint8_t m = src < mark.size() ? mark[src] : 0;
        ImU32 col = 0;
        if (m == 2)
          col = strokeCol;
        else if (m == 1)
          col = IM_COL32(255, 220, 60, 90);
        else if (showDensity) {
          const float d = ((*density)[f[0]] + (*density)[f[1]] + (*density)[f[2]]) / 3.0f;
          if (d != 1.0f) col = densityColour(d);
        }
        if (!col) continue;
        ImVec2 pa, pb, pc;
        if (proj(a, pa) && proj(b, pb) && proj(c, pc)) dl->AddTriangleFilled(pa, pb, pc, col);
      }
    }
  }
  // Handles: the hovered one ringed in white, the selected one in cyan, a dragged one's new place.
  auto ring = [&](const std::optional<Handle>& h, ImU32 col, float thick) {
    const std::optional<Handle> now = h ? findHandle(ctx.doc.scene(), *h) : std::nullopt;  // where it is now
    ImVec2 c;
    if (now && proj(now->at, c)) dl->AddCircle(c, 9.0f, col, 24, thick);
  };
  ring(v.hoveredHandle, IM_COL32(255, 255, 255, 230), 1.5f);
  ring(v.selectedHandle, IM_COL32(60, 230, 255, 255), 2.5f);
  if (v.handleDragging && v.selectedHandle) {
    ImVec2 a, b;
    if (proj(v.selectedHandle->at, a) && proj(v.handlePreview, b)) {
      dl->AddLine(a, b, IM_COL32(60, 230, 255, 200), 1.5f);
      dl->AddCircleFilled(b, 5.0f, IM_COL32(60, 230, 255, 255));
    }
  }
  // Box selection: the rectangle being dragged, the boxed feathers' bases and follicles, and a count.
  const ImVec2 o(v.viewOrigin.x, v.viewOrigin.y);
  if (v.boxActive)
    dl->AddRect(ImVec2(o.x + std::min(v.boxFrom.x, v.boxTo.x), o.y + std::min(v.boxFrom.y, v.boxTo.y)),
                ImVec2(o.x + std::max(v.boxFrom.x, v.boxTo.x), o.y + std::max(v.boxFrom.y, v.boxTo.y)),
                IM_COL32(60, 230, 255, 220), 0.0f, 0, 1.5f);
  for (int f : v.boxFeathers) {
    ImVec2 c;
    if (size_t(f) < snap.featherOrigin.size() && proj(snap.featherOrigin[size_t(f)], c))
      dl->AddCircle(c, 5.0f, IM_COL32(60, 230, 255, 230), 12, 1.5f);
  }
  for (int f : v.boxFollicles) {
    ImVec2 c;
    if (size_t(f) < snap.follicle.size() && proj(snap.follicle[size_t(f)], c))
      dl->AddCircleFilled(c, 3.0f, IM_COL32(60, 230, 255, 255));
  }
  for (const Handle& h : v.boxHandles) {
    const std::optional<Handle> now = findHandle(ctx.doc.scene(), h);
    ImVec2 c;
    if (now && proj(now->at, c)) dl->AddCircle(c, 9.0f, IM_COL32(60, 230, 255, 255), 24, 2.0f);
  }
  if (!v.boxFeathers.empty() || !v.boxFollicles.empty() || !v.boxHandles.empty()) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "%zu feathers, %zu follicles, %zu handles boxed (F frames, Delete removes the handles, Esc clears)",
                  v.boxFeathers.size(), v.boxFollicles.size(), v.boxHandles.size());
    dl->AddText(ImVec2(o.x + 10, o.y + 8), IM_COL32(20, 60, 80, 255), text);
  }
  if (painting && v.brushVisible) {
    glm::vec3 side = glm::cross(proj.cam.forward(), proj.cam.up);
    side = glm::length(side) > 1e-9f ? glm::normalize(side) : glm::vec3(1, 0, 0);
    ImVec2 c, e;
    if (proj(v.brushAt, c) && proj(v.brushAt + side * v.paintRadius, e)) {
      const float r = std::hypot(e.x - c.x, e.y - c.y);
      dl->AddCircle(c, r, IM_COL32(255, 255, 255, 220), 48, 1.5f);
      char label[64];
      if (v.tool == Tool::PaintDensity)
        std::snprintf(label, sizeof label, "x%.2f", v.densityValue);
      else
        std::snprintf(label, sizeof label, "%s",
                      v.facePaint == FacePaint::Add      ? "add"
                      : v.facePaint == FacePaint::Remove ? "remove"
                      : v.facePaint == FacePaint::Select ? "select"
                                                         : "deselect");
      dl->AddText(ImVec2(c.x + r + 4, c.y - 7), IM_COL32(255, 255, 255, 230), label);
    }
  }
}

}  // namespace pteryla::viewer
