// Painting sections of the Tracts and Follicles panels (docs/viewer.md, "Painting"): the face brush
// (add to / remove from the selected tract, or (de)select faces) with "new tract from selection", and
// the follicle density brush with its factor, radius and strength. The strokes themselves are
// app_paint.cpp's; every widget is scriptable with `ui PANEL WIDGET [VALUE]`.
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <string>

#include "actions.hpp"
#include "panels.hpp"

namespace pteryla::viewer {

namespace {

void paintToggle(PanelContext& ctx, Tool tool, const char* label, const char* panel, const char* hint) {
  const bool active = ctx.view.tool == tool;
  if (active) ImGui::PushStyleColor(ImGuiCol_Button, ImVec4(0.8f, 0.45f, 0.1f, 1.0f));
  if (ImGui::Button(active ? "Done##paint" : label) || uiRequested(ctx, panel, "paint"))
    ctx.view.tool = active ? Tool::Orbit : tool;
  if (active) ImGui::PopStyleColor();
  if (active) {
    ImGui::SameLine();
    ImGui::TextDisabled("%s", hint);
  }
}

void radiusSlider(PanelContext& ctx, const char* panel) {
  ImGui::SliderFloat("Brush radius", &ctx.view.paintRadius, 0.001f, 5.0f, "%.3f", ImGuiSliderFlags_Logarithmic);
  uiRequestedNumber(ctx, panel, "radius", ctx.view.paintRadius);
  ctx.view.paintRadius = std::max(ctx.view.paintRadius, 1e-4f);
}

}  // namespace

void drawFacePaintSection(PanelContext& ctx) {
  ViewState& v = ctx.view;
  sectionTitle("Paint faces");
  static const char* const modes[] = {"add", "remove", "select", "deselect"};
  int mode = int(v.facePaint);
  ImGui::RadioButton("Add to tract", &mode, 0);
  ImGui::SameLine();
  ImGui::RadioButton("Remove", &mode, 1);
  ImGui::SameLine();
  ImGui::RadioButton("Select", &mode, 2);
  ImGui::SameLine();
  ImGui::RadioButton("Deselect", &mode, 3);
  for (int i = 0; i < 4; ++i)
    if (uiRequested(ctx, "Tracts", "mode", modes[i])) mode = i;
  v.facePaint = FacePaint(mode);
  radiusSlider(ctx, "Tracts");
  paintToggle(ctx, Tool::PaintFaces, "Paint faces", "Tracts", "drag on the skin; a stroke is one undo step");
  if (v.facePaint == FacePaint::Add || v.facePaint == FacePaint::Remove)
    ImGui::TextDisabled("paints the tract chosen above (its selection becomes a face list when faces are removed)");
  ImGui::Text("selection: %zu faces", v.faceSelection.size());
  ImGui::SameLine();
  if (ImGui::SmallButton("Clear selection") || uiRequested(ctx, "Tracts", "clear selection")) v.faceSelection.clear();
  static std::string name = "painted";
  ImGui::SetNextItemWidth(160);
  ImGui::InputText("##newtract", &name);
  ImGui::SameLine();
  std::string scripted;
  const bool fromScript = uiRequestedText(ctx, "Tracts", "new from selection", scripted);
  if (ImGui::Button("New tract from selection") || fromScript) {
    const std::string n = fromScript && !scripted.empty() ? scripted : name;
    guarded(ctx, [&] {
      actions::addTractFromFaces(ctx.doc, n, v.faceSelection);
      v.selectedTract = int(ctx.doc.scene().tracts.size()) - 1;
      v.faceSelection.clear();
    });
  }
}

void drawDensityPaintSection(PanelContext& ctx) {
  ViewState& v = ctx.view;
  sectionTitle("Density map (painted)");
  ImGui::SliderFloat("Factor", &v.densityValue, 0.0f, 8.0f, "%.2f");
  uiRequestedNumber(ctx, "Follicles", "factor", v.densityValue);
  v.densityValue = std::clamp(v.densityValue, 0.0f, 100.0f);
  ImGui::SliderFloat("Strength", &v.densityStrength, 0.01f, 1.0f, "%.2f");
  uiRequestedNumber(ctx, "Follicles", "strength", v.densityStrength);
  v.densityStrength = std::clamp(v.densityStrength, 0.0f, 1.0f);
  radiusSlider(ctx, "Follicles");
  paintToggle(ctx, Tool::PaintDensity, "Paint density", "Follicles",
              "drag on the skin: density x factor (1 = unpainted)");
  ImGui::Checkbox("Show the density map", &v.showDensity);
  const pipeline::Scene& s = ctx.doc.scene();
  if (s.densityFactor) {
    const auto [lo, hi] = std::minmax_element(s.densityFactor->begin(), s.densityFactor->end());
    ImGui::Text("factors %.3g .. %.3g over %zu vertices", double(*lo), double(*hi), s.densityFactor->size());
    ImGui::TextDisabled("%s", s.densityMap.empty() ? "saved next to the scene on Save" : s.densityMap.c_str());
    if (ImGui::Button("Clear density map") || uiRequested(ctx, "Follicles", "clear density"))
      guarded(ctx, [&] { actions::clearDensityMap(ctx.doc); });
  } else {
    ImGui::TextDisabled("no density map: every factor is 1");
  }
}

}  // namespace pteryla::viewer
