// Painting sections of the Tracts and Follicles panels (docs/viewer.md, "Painting"): the face brush
// (add to / remove from the selected tract, or (de)select faces) with "new tract from selection", and
// the follicle density brush with its factor, radius and strength. The strokes themselves are
// input_paint.cpp's; every widget is scriptable with `ui PANEL WIDGET [VALUE]`.
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <string>

#include "actions.hpp"
#include "mirror.hpp"
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

void drawMirrorSection(PanelContext& ctx) {
  ViewState& v = ctx.view;
  const UiRequest& ui = v.ui;
  if (ui.pending && ui.panel == "Tracts" && ui.widget.rfind("mirror", 0) == 0) ImGui::SetNextItemOpen(true);
  if (!ImGui::TreeNode("Mirror left/right")) return;
  ImGui::Checkbox("the tract chosen above", &v.mirrorTract);
  ImGui::Checkbox("packing brushes", &v.mirrorBrushes);
  ImGui::SameLine();
  ImGui::Checkbox("controls", &v.mirrorControls);
  ImGui::SameLine();
  ImGui::Checkbox("styling vectors", &v.mirrorVectors);
  static const char* const planes[] = {"x = offset", "y = offset", "z = offset", "body symmetry plane"};
  static const char* const planeNames[] = {"x", "y", "z", "symmetry"};
  ImGui::SetNextItemWidth(180);
  ImGui::Combo("Plane", &v.mirrorAxis, planes, 4);
  for (int i = 0; i < 4; ++i)
    if (uiRequested(ctx, "Tracts", "mirror plane", planeNames[i])) v.mirrorAxis = i;
  if (v.mirrorAxis < 3) {
    ImGui::SetNextItemWidth(180);
    ImGui::InputFloat("Offset", &v.mirrorOffset, 0, 0, "%.4g");
    uiRequestedNumber(ctx, "Tracts", "mirror offset", v.mirrorOffset);
  }
  const auto rest = ctx.doc.snapshot().restSkin;
  // The symmetry plane of the skin shown (estimated once per skin).
  static std::weak_ptr<const coat::SkinMesh> planeOf;  // (a weak pointer: the address is not reused)
  static MirrorPlane symmetry;
  if (rest && v.mirrorAxis == 3) {
    if (planeOf.lock() != rest) symmetry = symmetryPlane(*rest), planeOf = rest;
    ImGui::TextDisabled("%c = %.4g", "xyz"[symmetry.axis], symmetry.offset);
  }
  if ((ImGui::Button("Mirror") || uiRequested(ctx, "Tracts", "mirror")) && rest) {
    guarded(ctx, [&] {
      MirrorRequest q;
      if (v.mirrorTract && !ctx.doc.scene().tracts.empty())
        q.tracts.push_back(size_t(std::clamp(v.selectedTract, 0, int(ctx.doc.scene().tracts.size()) - 1)));
      q.brushes = v.mirrorBrushes;
      q.controls = v.mirrorControls;
      q.vectors = v.mirrorVectors;
      q.plane = v.mirrorAxis == 3 ? symmetryPlane(*rest) : MirrorPlane{v.mirrorAxis, double(v.mirrorOffset)};
      mirrorScene(ctx.doc, *rest, q);
    });
  }
  ImGui::SameLine();
  ImGui::TextDisabled("one undo step; copies already there are not added again");
  ImGui::TreePop();
}

}  // namespace pteryla::viewer
