// Colour-by view modes (colour_by.hpp) on the renderer: flat palette materials, per-feather ranges, the legend.
#include <imgui.h>

#include <algorithm>

#include "viewport.hpp"
#include "pteryla/render/pattern.hpp"
#include "pteryla/render/scene_view.hpp"

namespace pteryla::viewer {

bool Viewport::updateColouring() {
  const Snapshot& s = doc_.snapshot();
  const auto& m = doc_.metrics();
  const std::vector<uint64_t> key = {uint64_t(view_.colourBy), doc_.resultVersion(), m ? 1u : 0u,
                                     m ? m->intersectingFeathers.size() : 0, m ? m->penetratingFeathers.size() : 0};
  if (key == colourKey_) return false;
  colourKey_ = key;
  ColourInputs in;
  in.featherCount = s.featherOrigin.size();
  in.elevation = s.featherElevation;
  in.tract = s.featherTract;
  in.tractNames = s.tractNames;
  in.layerOrder = s.featherLayerOrder;
  in.age = s.featherAge;
  in.present = s.featherPresent;
  if (m) {
    in.checked = true;
    in.intersecting = m->intersectingFeathers;
    in.penetrating = m->penetratingFeathers;
    in.faceSamples = m->faceSamples;
    in.faceUncovered = m->faceUncovered;
    if (m->coverage) in.coverage = *m->coverage;
  }
  colouring_ = colourFeathers(view_.colourBy, in);
  return true;
}

std::vector<render::FeatherDrawRange> Viewport::drawRangesFor(
    const std::vector<pipeline::CoatDrawRange>& ranges) const {
  pipeline::CoatMesh rangesOnly;
  rangesOnly.ranges = ranges;
  if (view_.colourBy != ColourBy::Material && !colouring_.legend.empty())
    for (auto& r : rangesOnly.ranges)
      r.material = r.feather < colouring_.featherEntry.size() ? colouring_.featherEntry[r.feather] : 0;
  return render::drawRanges(rangesOnly);
}

std::vector<render::FeatherMaterial> Viewport::paletteMaterials() const {
  static const render::Image alpha = render::generateBarbAlpha(render::BarbAlphaParams{});
  std::vector<render::FeatherMaterial> out;
  for (const LegendEntry& e : colouring_.legend) {
    render::FeatherMaterial m;
    m.name = "colour by " + std::string(colourByName(view_.colourBy)) + ": " + e.label;
    m.baseColor = e.colour;
    m.alphaImage = alpha;
    m.useBrdf = false;  // flat, so the colours read as the legend's
    m.specular = 0.0f;
    out.push_back(std::move(m));
  }
  if (out.empty()) out.emplace_back();  // never no material
  return out;
}

}  // namespace pteryla::viewer

namespace pteryla::viewer {

void Viewport::legendWindow() {
  ImGui::SetNextWindowPos(ImVec2(view_.viewOrigin.x + 10.0f, view_.viewOrigin.y + float(view_.viewSize.y) - 10.0f),
                          ImGuiCond_Always, ImVec2(0.0f, 1.0f));
  ImGui::SetNextWindowBgAlpha(0.75f);
  ImGui::Begin("##legend", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoSavedSettings |
                   ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav | ImGuiWindowFlags_NoMove);
  ImGui::Text("Colour by %s", colourByName(view_.colourBy));
  ImGui::Separator();
  for (const LegendEntry& e : colouring_.legend) {
    if (e.feathers == 0 && e.faces == 0) continue;  // only what the coat (or the skin) shows
    const ImVec2 p = ImGui::GetCursorScreenPos();
    const float h = ImGui::GetTextLineHeight();
    const auto c = [](float x) { return int(std::clamp(x, 0.0f, 1.0f) * 255.0f + 0.5f); };
    ImGui::GetWindowDrawList()->AddRectFilled(p, ImVec2(p.x + h, p.y + h),
                                              IM_COL32(c(e.colour.r), c(e.colour.g), c(e.colour.b), 255));
    ImGui::Dummy(ImVec2(h, h));
    ImGui::SameLine();
    if (e.faces > 0)
      ImGui::Text("%s  (%zu faces)", e.label.c_str(), e.faces);
    else
      ImGui::Text("%s  (%zu)", e.label.c_str(), e.feathers);
  }
  if (!colouring_.note.empty()) ImGui::TextDisabled("%s", colouring_.note.c_str());
  ImGui::End();
}

}  // namespace pteryla::viewer
