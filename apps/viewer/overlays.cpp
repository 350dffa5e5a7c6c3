#include "overlays.hpp"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>

#include <glm/geometric.hpp>

#include "actions.hpp"

namespace pteryla::viewer {
namespace {

ImU32 tractColour(uint32_t t, int alpha = 255) {
  static const ImU32 base[] = {IM_COL32(230, 90, 70, 255),   IM_COL32(70, 160, 230, 255),  IM_COL32(90, 200, 100, 255),
                               IM_COL32(230, 190, 60, 255),  IM_COL32(180, 100, 220, 255), IM_COL32(60, 200, 200, 255),
                               IM_COL32(240, 130, 200, 255), IM_COL32(150, 150, 150, 255)};
  const ImU32 c = base[t % 8];
  return (c & 0x00FFFFFFu) | (static_cast<ImU32>(alpha) << 24);
}

void arrow(ImDrawList* dl, const Projector& proj, const glm::vec3& from, const glm::vec3& to, ImU32 col, float thick) {
  ImVec2 a, b;
  if (!proj(from, a) || !proj(to, b)) return;
  dl->AddLine(a, b, col, thick);
  const glm::vec2 d(b.x - a.x, b.y - a.y);
  const float len = glm::length(d);
  if (len < 2.0f) return;
  const glm::vec2 u = d / len, n(-u.y, u.x);
  const float h = std::min(10.0f, len * 0.35f);
  dl->AddTriangleFilled(b, ImVec2(b.x - u.x * h + n.x * h * 0.5f, b.y - u.y * h + n.y * h * 0.5f),
                        ImVec2(b.x - u.x * h - n.x * h * 0.5f, b.y - u.y * h - n.y * h * 0.5f), col);
  dl->AddCircleFilled(a, thick + 1.5f, col);
}

// Screen radius of a sphere (centre c, radius r) seen by the camera: project a point offset sideways.
float screenRadius(const Projector& proj, const glm::vec3& c, float r) {
  glm::vec3 side = glm::cross(proj.cam.forward(), proj.cam.up);
  if (glm::length(side) < 1e-9f) side = {1, 0, 0};
  side = glm::normalize(side);
  ImVec2 a, b;
  if (!proj(c, a) || !proj(c + side * r, b)) return 0.0f;
  return std::hypot(b.x - a.x, b.y - a.y);
}

}  // namespace

FeatherReadout featherReadout(const Snapshot& s, int i) {
  FeatherReadout r;
  if (i < 0 || size_t(i) >= s.featherOrigin.size()) return r;
  const size_t f = size_t(i);
  r.feather = i;
  if (f < s.featherTract.size())
    r.tract = s.featherTract[f] < s.tractNames.size() ? s.tractNames[s.featherTract[f]]
                                                      : "tract " + std::to_string(s.featherTract[f]);
  if (f < s.featherMaterial.size() && s.featherMaterial[f] < s.materials.size())
    r.type = s.materials[s.featherMaterial[f]].name;
  if (f < s.featherFollicle.size() && s.featherFollicle[f] < s.follicleId.size())
    r.follicleId = s.follicleId[s.featherFollicle[f]];
  if (f < s.featherElevation.size()) r.elevationDeg = double(s.featherElevation[f]) * 180.0 / 3.14159265358979323846;
  if (f < s.featherAge.size()) r.age = s.featherAge[f];
  if (f < s.featherPresent.size()) r.present = s.featherPresent[f] != 0;
  return r;
}

std::string readoutText(const FeatherReadout& r) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "feather %d%s\ntract: %s\ntype: %s\nfollicle id: %llu\nelevation: %.1f deg\nage: %.2f",
                r.feather, r.present ? "" : " (moulted out)", r.tract.c_str(), r.type.empty() ? "-" : r.type.c_str(),
                static_cast<unsigned long long>(r.follicleId), r.elevationDeg, r.age);
  return buf;
}

float overlayArrowLength(const Snapshot& s) {
  const float diag = glm::length(s.skinHi - s.skinLo);
  return diag > 0 ? diag * 0.06f : 0.1f;
}

void drawOverlays(ImDrawList* dl, PanelContext& ctx) {
  const Snapshot& snap = ctx.doc.snapshot();
  const pipeline::Scene& scene = ctx.doc.scene();
  const ViewState& v = ctx.view;
  const Projector proj{ctx.camera.camera(), v.viewSize, v.viewOrigin};
  dl->PushClipRect(ImVec2(v.viewOrigin.x, v.viewOrigin.y),
                   ImVec2(v.viewOrigin.x + float(v.viewSize.x), v.viewOrigin.y + float(v.viewSize.y)), true);
  const float arrowLen = overlayArrowLength(snap);

  // Selected tract: its triangles, translucent, front-facing only.
  if (v.showTract && v.selectedTract >= 0 && size_t(v.selectedTract) < snap.tractFaces.size() && !snap.skin.empty()) {
    const ImU32 col = tractColour(uint32_t(v.selectedTract), 70);
    const TriMesh& m = snap.skin;
    for (uint32_t f : snap.tractFaces[size_t(v.selectedTract)]) {
      if (3 * size_t(f) + 2 >= m.indices.size()) continue;
      const glm::vec3& a = m.positions[m.indices[3 * f]];
      const glm::vec3& b = m.positions[m.indices[3 * f + 1]];
      const glm::vec3& c = m.positions[m.indices[3 * f + 2]];
      if (!proj.facing(a, glm::cross(b - a, c - a))) continue;
      ImVec2 pa, pb, pc;
      if (proj(a, pa) && proj(b, pb) && proj(c, pc)) dl->AddTriangleFilled(pa, pb, pc, col);
    }
  }

  if (v.showFollicles) {
    for (size_t i = 0; i < snap.follicle.size(); ++i) {
      if (i < snap.follicleNormal.size() && !proj.facing(snap.follicle[i], snap.follicleNormal[i])) continue;
      ImVec2 p;
      if (!proj(snap.follicle[i], p)) continue;
      const uint32_t t = i < snap.follicleTract.size() ? snap.follicleTract[i] : 0;
      const bool sel = int(i) == v.selectedFollicle;
      dl->AddCircleFilled(p, sel ? 5.0f : 2.5f, sel ? IM_COL32(255, 255, 255, 255) : tractColour(t));
    }
  }

  if (v.showDirections) {
    for (size_t i = 0; i < snap.featherOrigin.size(); ++i) {
      if (!proj.facing(snap.featherOrigin[i], snap.featherNormal[i])) continue;
      if (i < snap.featherPresent.size() && !snap.featherPresent[i]) continue;
      ImVec2 a, b;
      const glm::vec3 tip = snap.featherOrigin[i] + snap.featherTangent[i] * arrowLen * 0.5f;
      if (proj(snap.featherOrigin[i], a) && proj(tip, b)) dl->AddLine(a, b, IM_COL32(250, 230, 80, 220), 1.0f);
    }
  }

  // The selected feather (cyan) and the one under the mouse (white): a ring at the follicle and the shaft.
  auto ringAndShaft = [&](int i, ImU32 col, float thick) {
    if (i < 0 || size_t(i) >= snap.featherOrigin.size()) return;
    ImVec2 a, b;
    if (!proj(snap.featherOrigin[size_t(i)], a)) return;
    dl->AddCircle(a, 7.0f, col, 16, thick);
    const float len = size_t(i) < snap.featherLength.size() ? snap.featherLength[size_t(i)] : arrowLen;
    if (proj(snap.featherOrigin[size_t(i)] + snap.featherTangent[size_t(i)] * len, b)) dl->AddLine(a, b, col, thick);
  };
  ringAndShaft(v.hoveredFeather, IM_COL32(255, 255, 255, 200), 1.5f);
  ringAndShaft(v.selectedFeather, IM_COL32(40, 230, 255, 255), 2.5f);

  // The last check's offending feathers (the metrics are dropped on every edit, so they are this coat's):
  // a red shaft for a feather crossing another, a magenta ring for one under the skin.
  if (v.showProblems && ctx.doc.metrics()) {
    const pipeline::QualityMetrics& m = *ctx.doc.metrics();
    auto mark = [&](uint32_t i, ImU32 col, bool ring) {
      if (i >= snap.featherOrigin.size()) return;
      if (i < snap.featherNormal.size() && !proj.facing(snap.featherOrigin[i], snap.featherNormal[i])) return;
      ImVec2 a, b;
      if (!proj(snap.featherOrigin[i], a)) return;
      if (ring) {
        dl->AddCircle(a, 6.0f, col, 12, 2.0f);
      } else {
        dl->AddCircleFilled(a, 3.5f, col);
        if (proj(snap.featherOrigin[i] + snap.featherTangent[i] * arrowLen * 0.6f, b)) dl->AddLine(a, b, col, 2.5f);
      }
    };
    for (uint32_t i : m.intersectingFeathers) mark(i, IM_COL32(235, 40, 40, 235), false);
    for (uint32_t i : m.penetratingFeathers) mark(i, IM_COL32(230, 40, 230, 235), true);
  }

  // Key feathers: by follicle id, or at a point.
  if (v.showKeys && !snap.follicle.empty()) {
    std::unordered_map<uint64_t, size_t> byId;
    for (size_t i = 0; i < snap.follicleId.size(); ++i) byId[snap.follicleId[i]] = i;
    for (size_t t = 0; t < scene.tracts.size(); ++t) {
      const Json& tr = scene.tracts[t];
      if (!tr.is_object() || !tr.contains("key_feathers") || !tr["key_feathers"].is_array()) continue;
      for (const auto& k : tr["key_feathers"]) {
        glm::vec3 at;
        if (k.contains("follicle") && k["follicle"].is_number_unsigned()) {
          auto it = byId.find(k["follicle"].get<uint64_t>());
          if (it == byId.end()) continue;
          at = snap.follicle[it->second];
        } else if (k.contains("at")) {
          at = glm::vec3(actions::jsonVec3(k["at"]));
        } else {
          continue;
        }
        ImVec2 p;
        if (!proj(at, p)) continue;
        dl->AddCircle(p, 7.0f, IM_COL32(255, 255, 255, 255), 12, 2.0f);
        const std::string name = k.value("feather", std::string());
        dl->AddText(ImVec2(p.x + 8, p.y - 8), IM_COL32(255, 255, 255, 230), name.c_str());
      }
    }
  }

  if (v.showVectors) {
    const Json& d = scene.directions;
    if (d.contains("vectors") && d["vectors"].is_array()) {
      for (size_t k = 0; k < d["vectors"].size(); ++k) {
        const Json& sv = d["vectors"][k];
        glm::vec3 at = glm::vec3(actions::jsonVec3(sv.value("at", Json())));
        glm::vec3 dir = glm::vec3(actions::jsonVec3(sv.value("direction", Json()), glm::dvec3(1, 0, 0)));
        if (v.dragActive && v.dragVector == int(k)) {
          at = v.dragAt;
          dir = v.dragDirection;
        }
        if (glm::length(dir) > 0) dir = glm::normalize(dir);
        const bool sel = int(k) == v.selectedVector;
        arrow(dl, proj, at, at + dir * arrowLen, sel ? IM_COL32(255, 255, 255, 255) : IM_COL32(80, 220, 255, 255),
              2.5f);
      }
    }
    if (d.contains("axis") && d["axis"].is_array()) {
      for (size_t k = 1; k < d["axis"].size(); ++k)
        arrow(dl, proj, glm::vec3(actions::jsonVec3(d["axis"][k - 1])), glm::vec3(actions::jsonVec3(d["axis"][k])),
              IM_COL32(80, 220, 255, 160), 1.5f);
    }
    // A vector being added with the drag tool.
    if (v.dragActive && v.dragVector < 0)
      arrow(dl, proj, v.dragAt,
            v.dragAt + (glm::length(v.dragDirection) > 0 ? glm::normalize(v.dragDirection) : glm::vec3(0)) * arrowLen,
            IM_COL32(255, 255, 255, 255), 2.5f);
  }

  // Relaxation bias vectors of the tracts.
  if (v.showVectors) {
    for (const auto& tr : scene.tracts) {
      if (!tr.is_object() || !tr.contains("relax") || !tr["relax"].is_object() || !tr["relax"].contains("bias"))
        continue;
      for (const auto& b : tr["relax"]["bias"]) {
        const glm::vec3 at = glm::vec3(actions::jsonVec3(b.value("at", Json())));
        glm::vec3 dir = glm::vec3(actions::jsonVec3(b.value("direction", Json()), glm::dvec3(1, 0, 0)));
        if (glm::length(dir) > 0) dir = glm::normalize(dir);
        arrow(dl, proj, at - dir * arrowLen * 0.5f, at + dir * arrowLen * 0.5f, IM_COL32(255, 150, 60, 255), 2.0f);
      }
    }
  }

  if (v.showBrushes && scene.packing.contains("styling") && scene.packing["styling"].is_array()) {
    for (const auto& s : scene.packing["styling"]) {
      if (s.value("select", std::string("ids")) != "sphere") continue;
      const glm::vec3 c = glm::vec3(actions::jsonVec3(s.value("center", Json())));
      const float r = static_cast<float>(s.value("radius", 0.0));
      ImVec2 p;
      if (!proj(c, p)) continue;
      dl->AddCircle(p, screenRadius(proj, c, r), IM_COL32(255, 120, 200, 230), 32, 1.5f);
      if (s.contains("elevation_deg"))
        dl->AddText(ImVec2(p.x + 4, p.y + 4), IM_COL32(255, 120, 200, 255),
                    (std::to_string(int(std::lround(s["elevation_deg"].get<double>()))) + " deg").c_str());
    }
  }

  if (v.showControls) {
    for (size_t k = 0; k < scene.controls.size(); ++k) {
      const Json& c = scene.controls[k];
      if (!c.is_object() || !c.contains("at")) continue;
      const glm::vec3 at = glm::vec3(actions::jsonVec3(c["at"]));
      const float r = static_cast<float>(c.value("radius", 0.0));
      ImVec2 p;
      if (!proj(at, p)) continue;
      const bool sel = int(k) == v.selectedControl;
      const ImU32 col = sel ? IM_COL32(255, 255, 255, 255) : IM_COL32(120, 255, 120, 230);
      dl->AddCircle(p, std::max(screenRadius(proj, at, r), 4.0f), col, 32, sel ? 2.5f : 1.5f);
      dl->AddCircleFilled(p, 4.0f, col);
      dl->AddText(ImVec2(p.x + 6, p.y - 16), col, c.value("name", "control " + std::to_string(k)).c_str());
    }
  }
  drawPaintOverlays(dl, ctx);
  dl->PopClipRect();
}

}  // namespace pteryla::viewer
