// Scene panel: the master seed, the layer ordering and export (#28 "the missing stages").
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <filesystem>

#include "actions.hpp"
#include "panels.hpp"
#include "pteryla/core/error.hpp"
#include "scene_edit.hpp"

namespace pteryla::viewer {

using pipeline::Scene;

namespace {

// Export settings kept between frames (the panel is the only user).
struct ExportUi {
  std::string path;
  int as = 0;  // curves, cards, instances
  bool range = false;
  float from = 0, to = 1, fps = 24, metersPerUnit = 1;
};
ExportUi& exportUi() {
  static ExportUi e;
  return e;
}

void orderingSection(PanelContext& ctx, const Scene& s) {
  Document& doc = ctx.doc;
  const Json& o = s.ordering;
  const std::string method = o.is_object() ? o.value("method", std::string("tracts")) : std::string("tracts");
  static const char* methods[] = {"tracts", "axis", "flow"};
  int m = method == "axis" ? 1 : method == "flow" ? 2 : 0;
  std::string scripted;
  const bool fromScript = uiRequestedText(ctx, "Scene", "ordering", scripted);
  if (fromScript) {
    const auto it = std::find(std::begin(methods), std::end(methods), scripted);
    if (it == std::end(methods)) throw Error("expected tracts, axis or flow, got '" + scripted + "'", "", "ordering");
    m = int(it - std::begin(methods));
  }
  if (ImGui::Combo("Layer order", &m, methods, 3) || fromScript)
    guarded(ctx, [&] {
      doc.edit("ordering", [&](Scene& sc) {
        if (!sc.ordering.is_object()) sc.ordering = Json::object();
        sc.ordering["method"] = methods[m];
        // Axis ordering needs an axis: the body axis of the directions when there is one.
        if (m == 1 && !sc.ordering.contains("axis") && sc.directions.contains("axis"))
          sc.ordering["axis"] = sc.directions["axis"];
      });
    });
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "which feathers lie on top (docs/coat.md): tracts in the listed order, along the body axis\n"
        "(head feathers over tail feathers), or along the direction field (flow)");
  // The listed tracts go first (bottom layers), in this order; move them with the arrows.
  std::vector<std::string> listed;
  if (o.is_object() && o.contains("tracts") && o["tracts"].is_array())
    for (const Json& t : o["tracts"])
      if (t.is_string()) listed.push_back(t.get<std::string>());
  for (size_t i = 0; i < s.tracts.size(); ++i) {
    const std::string name = tractName(s, i);
    if (std::find(listed.begin(), listed.end(), name) == listed.end()) listed.push_back(name);
  }
  ImGui::TextDisabled("bottom layer first:");
  for (size_t i = 0; i < listed.size(); ++i) {
    ImGui::PushID(int(i));
    const bool up = i > 0 && ImGui::ArrowButton("up", ImGuiDir_Up);
    ImGui::SameLine();
    const bool down = i + 1 < listed.size() && ImGui::ArrowButton("down", ImGuiDir_Down);
    ImGui::SameLine();
    ImGui::TextUnformatted(listed[i].c_str());
    if (up || down) {
      std::vector<std::string> next = listed;
      std::swap(next[i], next[up ? i - 1 : i + 1]);
      guarded(ctx, [&] {
        doc.edit("tract order", [&](Scene& sc) {
          if (!sc.ordering.is_object()) sc.ordering = Json::object();
          sc.ordering["tracts"] = next;
        });
      });
    }
    ImGui::PopID();
  }
}

void exportSection(PanelContext& ctx, const Scene& s) {
  Document& doc = ctx.doc;
  ExportUi& e = exportUi();
  if (e.path.empty())
    e.path = (std::filesystem::path(s.file.empty() ? std::filesystem::current_path().string() : s.file).parent_path() /
              ((s.name.empty() ? std::string("coat") : s.name) + ".glb"))
                 .string();
  ImGui::InputText("file", &e.path);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip(".glb .gltf .usda .obj .ply (docs/export.md)");
  static const char* kinds[] = {"curves", "cards", "instances"};
  ImGui::Combo("USD coat as", &e.as, kinds, 3);
  ImGui::Checkbox("Frame range", &e.range);
  if (e.range) {
    ImGui::DragFloat("from", &e.from, 0.05f);
    ImGui::DragFloat("to", &e.to, 0.05f);
    ImGui::DragFloat("fps", &e.fps, 1.0f, 1.0f, 240.0f);
  }
  ImGui::DragFloat("metres per unit", &e.metersPerUnit, 0.001f, 1e-6f, 1e6f, "%.4f");
  std::string scripted;
  const bool fromScript = uiRequestedText(ctx, "Scene", "export", scripted);
  if (fromScript && !scripted.empty()) e.path = scripted;
  if (ImGui::Button("Export") || fromScript)
    guarded(ctx, [&] {
      Document::ExportRequest r;
      r.path = e.path;
      r.options.as = exchange::coatAsOf(kinds[e.as]);
      r.options.metersPerUnit = e.metersPerUnit;
      if (e.range) {
        r.options.times = exchange::frameTimes(e.from, e.to, e.fps);
        r.options.fps = e.fps;
      }
      doc.requestExport(std::move(r));
    });
  if (const auto& last = doc.lastExport()) {
    if (last->result)
      ImGui::TextWrapped("Exported %s: %zu frames, %.1f MB in %.1f s", last->path.c_str(), last->result->frames,
                         double(last->result->bytes) / 1e6, last->result->seconds);
    else
      ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.4f, 1.0f), "Export failed: %s", last->error.c_str());
  }
}

}  // namespace

void drawScenePanel(PanelContext& ctx) {
  Document& doc = ctx.doc;
  const Scene s = doc.scene();  // a copy: edits below replace doc.scene()
  if (doc.busy()) {
    const JobProgress pr = doc.progress();
    ImGui::ProgressBar(float(pr.fraction), ImVec2(-FLT_MIN, 0), pr.stage.c_str());
  }
  uint64_t seed = s.seed;
  std::string scripted;
  const bool seedFromScript = uiRequestedText(ctx, "Scene", "seed", scripted);
  if (seedFromScript) {
    try {
      size_t used = 0;
      seed = std::stoull(scripted, &used);
      if (used != scripted.size()) throw std::invalid_argument("trailing text");
    } catch (const std::exception&) {
      throw Error("expected a non-negative integer, got '" + scripted + "'", "", "seed");
    }
  }
  if (ImGui::InputScalar("Master seed", ImGuiDataType_U64, &seed, nullptr, nullptr, "%llu",
                         ImGuiInputTextFlags_EnterReturnsTrue) ||
      seedFromScript)
    guarded(ctx, [&] { doc.edit("seed", [&](Scene& sc) { sc.seed = seed; }); });
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("every random step (follicles, jitter, moult order) derives from it; Enter applies");
  ImGui::SameLine();
  if (ImGui::SmallButton("next")) guarded(ctx, [&] { doc.edit("seed", [&](Scene& sc) { sc.seed = s.seed + 1; }); });
  sectionTitle("Layer order (6.3, 9.2.1)");
  orderingSection(ctx, s);
  sectionTitle("Export");
  exportSection(ctx, s);
  sectionTitle("Render frames");
  drawFramesSection(ctx);
}

}  // namespace pteryla::viewer
