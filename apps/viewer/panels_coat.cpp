// Coat panels: tracts (Streit 2003, 6.1), follicles (scatter, Lloyd relaxation with bias vectors,
// 6.1.1-6.1.5), key feathers (6.2), surface directions (6.3.1) and packing with styling brushes
// (6.3.2-6.3.4, 8.3). All edits go through actions.hpp.
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "actions.hpp"
#include "json_widgets.hpp"
#include "panels.hpp"
#include "pteryla/core/error.hpp"
#include "scene_edit.hpp"

namespace pteryla::viewer {

using pipeline::Scene;

namespace {

// Combo over the scene's tracts; keeps view.selectedTract valid. Returns the selected index or -1.
int tractCombo(PanelContext& ctx, const Scene& s, const char* panel, const char* label) {
  const int n = static_cast<int>(s.tracts.size());
  if (n == 0) {
    ImGui::TextDisabled("no tracts (the whole mesh is one tract)");
    if (ImGui::Button("Make the whole-mesh tract explicit")) guarded(ctx, [&] { actions::ensureTracts(ctx.doc); });
    return -1;
  }
  int& sel = ctx.view.selectedTract;
  sel = std::clamp(sel, 0, n - 1);
  for (int i = 0; i < n; ++i)
    if (uiRequested(ctx, panel, "tract", tractName(s, size_t(i)))) sel = i;
  if (ImGui::BeginCombo(label, tractName(s, size_t(sel)).c_str())) {
    for (int i = 0; i < n; ++i)
      if (ImGui::Selectable(tractName(s, size_t(i)).c_str(), i == sel)) sel = i;
    ImGui::EndCombo();
  }
  return sel;
}

size_t folliclesInTract(const Snapshot& snap, size_t t) {
  return static_cast<size_t>(std::count(snap.follicleTract.begin(), snap.follicleTract.end(), uint32_t(t)));
}

const char* toolButtonLabel(bool active, const char* on, const char* off) { return active ? on : off; }

void toolToggle(PanelContext& ctx, Tool tool, const char* label, const char* hint) {
  const bool active = ctx.view.tool == tool;
  if (active) ImGui::PushStyleColor(ImGuiCol_Button, ImVec4(0.8f, 0.45f, 0.1f, 1.0f));
  if (ImGui::Button(toolButtonLabel(active, "Done", label))) ctx.view.tool = active ? Tool::Orbit : tool;
  if (active) ImGui::PopStyleColor();
  if (active) {
    ImGui::SameLine();
    ImGui::TextDisabled("%s", hint);
  }
}

// A packing setting that is "full" or a faster default (`fast`), as a checkbox (on: "full") with its tooltip.
void fullOrFastCheckbox(PanelContext& ctx, const Json& packing, const char* label, const char* key, const char* fast,
                        const char* tip) {
  bool full = packing.value(key, std::string(fast)) == "full";
  if (ImGui::Checkbox(label, &full))
    guarded(ctx, [&] { actions::setPackingValue(ctx.doc, key, full ? "full" : fast); });
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", tip);
}

void metricsTable(const std::optional<pipeline::QualityMetrics>& m) {
  if (!m) {
    ImGui::TextDisabled("no metrics yet");
    return;
  }
  auto num = [](const char* name, const std::optional<double>& v) {
    if (v)
      ImGui::Text("%-28s %.4f", name, *v);
    else
      ImGui::Text("%-28s -", name);
  };
  auto cnt = [](const char* name, const std::optional<size_t>& v) {
    if (v)
      ImGui::Text("%-28s %zu", name, *v);
    else
      ImGui::Text("%-28s -", name);
  };
  cnt("follicles", m->follicles);
  num("hex fraction", m->hexFraction);
  num("nearest-neighbour CV", m->nnCv);
  cnt("feathers", m->feathers);
  cnt("intersecting pairs", m->intersectingPairs);
  cnt("intersecting pairs (unpacked)", m->intersectingPairsUnpacked);
  cnt("skin penetrations", m->skinPenetrations);
  num("coverage", m->coverage);
  if (m->intersectingPairs) cnt("feathers crossing another", m->intersectingFeathers.size());
  if (m->skinPenetrations) cnt("feathers under the skin", m->penetratingFeathers.size());
  if (!m->intersectingFeathers.empty() || !m->penetratingFeathers.empty())
    ImGui::TextDisabled("View > Problems marks them");
}

}  // namespace

void drawTractsPanel(PanelContext& ctx) {
  Document& doc = ctx.doc;
  // A copy: an edit below replaces doc.scene(), and this panel keeps reading what it drew from.
  const Scene s = doc.scene();
  const Snapshot& snap = doc.snapshot();
  if (ImGui::BeginTable("tracts", 3, ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerV | ImGuiTableFlags_ScrollY,
                        ImVec2(0, 150))) {
    ImGui::TableSetupColumn("tract");
    ImGui::TableSetupColumn("faces");
    ImGui::TableSetupColumn("follicles");
    ImGui::TableHeadersRow();
    for (size_t i = 0; i < s.tracts.size(); ++i) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      if (ImGui::Selectable(tractName(s, i).c_str(), ctx.view.selectedTract == int(i),
                            ImGuiSelectableFlags_SpanAllColumns) ||
          uiRequested(ctx, "Tracts", "select", tractName(s, i)))
        ctx.view.selectedTract = int(i);
      ImGui::TableNextColumn();
      if (i < snap.tractFaces.size())
        ImGui::Text("%zu", snap.tractFaces[i].size());
      else
        ImGui::TextDisabled("-");
      ImGui::TableNextColumn();
      ImGui::Text("%zu", folliclesInTract(snap, i));
    }
    ImGui::EndTable();
  }
  const int t = tractCombo(ctx, s, "Tracts", "Tract");
  if (t >= 0) {
    const Json& tj = s.tracts[size_t(t)];
    const bool byCount = tj.contains("count");
    float density = tj.contains("density") && tj["density"].is_number() ? tj["density"].get<float>() : 0.0f;
    int count = byCount && tj["count"].is_number() ? tj["count"].get<int>() : int(folliclesInTract(snap, size_t(t)));
    if (ImGui::InputInt("Follicle count", &count, 10, 100, ImGuiInputTextFlags_EnterReturnsTrue) && count > 0)
      guarded(ctx, [&] { actions::setTractCount(doc, size_t(t), size_t(count)); });
    if (ImGui::InputFloat("Density (per area)", &density, 0, 0, "%.4g", ImGuiInputTextFlags_EnterReturnsTrue) &&
        density > 0)
      guarded(ctx, [&] { actions::setTractDensity(doc, size_t(t), density); });
    ImGui::TextDisabled(byCount ? "using an exact count"
                                : (tj.contains("density") ? "using a density" : "automatic count"));
    if (ImGui::Button("Remove tract")) guarded(ctx, [&] { actions::removeTract(doc, size_t(t)); });
    if (ImGui::TreeNode("Tract JSON")) {
      Json copy = tj;
      if (jsonEditor("tract", copy))
        guarded(ctx,
                [&] { doc.edit("tract " + std::to_string(t), [&](Scene& sc) { sc.tracts.at(size_t(t)) = copy; }); });
      ImGui::TreePop();
    }
  }
  drawFacePaintSection(ctx);
  drawMirrorSection(ctx);
  if (ImGui::TreeNode("New tract from mesh groups")) {
    static std::string name = "tract";
    static std::set<std::string> chosen;
    ImGui::InputText("name", &name);
    ImGui::BeginChild("groups", ImVec2(0, 140), true);
    for (const auto& g : snap.groupNames) {
      bool on = chosen.count(g) > 0;
      if (ImGui::Checkbox(g.c_str(), &on)) {
        if (on)
          chosen.insert(g);
        else
          chosen.erase(g);
      }
    }
    ImGui::EndChild();
    if (ImGui::Button("Add tract")) {
      guarded(ctx, [&] {
        actions::addTract(doc, name, std::vector<std::string>(chosen.begin(), chosen.end()));
        ctx.view.selectedTract = int(doc.scene().tracts.size()) - 1;
      });
    }
    ImGui::SameLine();
    ImGui::TextDisabled(chosen.empty() ? "(no group: whole mesh)" : "");
    ImGui::TreePop();
  }
}

void drawFolliclesPanel(PanelContext& ctx) {
  Document& doc = ctx.doc;
  // A copy: an edit below replaces doc.scene(), and this panel keeps reading what it drew from.
  const Scene s = doc.scene();
  const int t = tractCombo(ctx, s, "Follicles", "Tract##f");
  if (t < 0) return;
  const Json& tj = s.tracts[size_t(t)];
  const Json relax = tj.contains("relax") && tj["relax"].is_object() ? tj["relax"] : Json::object();
  static int iterations = 40;
  if (ImGui::Button("Scatter only")) guarded(ctx, [&] { actions::setRelaxIterations(doc, size_t(t), 0); });
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("random follicles, no relaxation (thesis 6.1)");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(100);
  ImGui::InputInt("##it", &iterations);
  iterations = std::clamp(iterations, 0, 100000);
  ImGui::SameLine();
  if (ImGui::Button("Relax")) guarded(ctx, [&] { actions::setRelaxIterations(doc, size_t(t), iterations); });
  ImGui::SameLine();
  if (ImGui::Button("Relax all tracts"))
    guarded(ctx, [&] {
      for (size_t i = 0; i < s.tracts.size(); ++i) actions::setRelaxIterations(doc, i, iterations);
    });
  ImGui::Text("iterations in the scene: %d", relax.contains("iterations") ? relax["iterations"].get<int>() : 40);
  float over = relax.value("over_relaxation", 1.6f);
  if (ImGui::SliderFloat("Over-relaxation", &over, 1.0f, 1.95f))
    guarded(ctx, [&] { actions::setRelaxNumber(doc, size_t(t), "over_relaxation", over); });
  bool fix = relax.value("fix_boundary", true);
  if (ImGui::Checkbox("Fix boundary follicles", &fix))
    guarded(ctx, [&] { actions::setRelaxNumber(doc, size_t(t), "fix_boundary", fix); });

  drawDensityPaintSection(ctx);

  sectionTitle("Bias vectors (6.1.4)");
  ImGui::SliderFloat("sigma", &ctx.view.biasSigma, 0.0f, 2.0f);
  ImGui::SliderFloat("stretch", &ctx.view.biasStretch, 1.0f, 4.0f);
  toolToggle(ctx, Tool::AddBias, "Add bias vector", "press on the skin and drag along the rows");
  if (relax.contains("bias") && relax["bias"].is_array()) {
    for (size_t k = 0; k < relax["bias"].size(); ++k) {
      ImGui::PushID(int(k));
      const Json& b = relax["bias"][k];
      ImGui::Text("bias %zu  sigma %.3g stretch %.3g", k, b.value("sigma", 0.0), b.value("stretch", 1.5));
      ImGui::SameLine();
      if (ImGui::SmallButton("remove"))
        guarded(ctx, [&] {
          doc.edit("remove bias", [&](Scene& sc) {
            Json& arr = sc.tracts.at(size_t(t)).at("relax").at("bias");
            if (k >= arr.size()) throw Error("no bias vector " + std::to_string(k), sc.file, "relax.bias");
            arr.erase(arr.begin() + long(k));
          });
        });
      ImGui::PopID();
    }
  }
  sectionTitle("Pinned follicles (6.1.5)");
  toolToggle(ctx, Tool::Pin, "Pin follicles", "click on the skin");
  if (tj.contains("pinned")) ImGui::Text("%zu pinned", tj["pinned"].size());

  sectionTitle("Metrics");
  if (ImGui::Button("Compute metrics")) doc.requestCheck();
  metricsTable(doc.metrics());
}

void drawKeyFeathersPanel(PanelContext& ctx) {
  Document& doc = ctx.doc;
  // A copy: an edit below replaces doc.scene(), and this panel keeps reading what it drew from.
  const Scene s = doc.scene();
  sectionTitle("Feather library");
  for (auto it = s.feathers.begin(); it != s.feathers.end(); ++it) {
    ImGui::BulletText("%s: %s", it.key().c_str(),
                      it->is_string() ? it->get<std::string>().c_str() : "(designed in the scene)");
  }
  static std::string newName = "covert", newPath;
  ImGui::InputText("name", &newName);
  ImGui::InputText("feather file", &newPath);
  if (ImGui::Button("Add / replace feather")) guarded(ctx, [&] { actions::setFeatherFile(doc, newName, newPath); });

  sectionTitle("Key feathers of a tract (6.2)");
  const int t = tractCombo(ctx, s, "Key feathers", "Tract##k");
  if (t < 0) return;
  const Json& tj = s.tracts[size_t(t)];
  std::vector<std::string> names;
  for (auto it = s.feathers.begin(); it != s.feathers.end(); ++it) names.push_back(it.key());
  const std::string current = tj.value("feather", std::string());
  if (ImGui::BeginCombo("Tract feather", current.empty() ? "(default)" : current.c_str())) {
    for (const auto& n : names)
      if (ImGui::Selectable(n.c_str(), n == current))
        guarded(ctx, [&] { actions::setTractFeather(doc, size_t(t), n); });
    ImGui::EndCombo();
  }
  if (ctx.view.toolFeather.empty() && !names.empty()) ctx.view.toolFeather = names.front();
  if (ImGui::BeginCombo("Key feather type", ctx.view.toolFeather.c_str())) {
    for (const auto& n : names)
      if (ImGui::Selectable(n.c_str(), n == ctx.view.toolFeather)) ctx.view.toolFeather = n;
    ImGui::EndCombo();
  }
  toolToggle(ctx, Tool::PlaceKey, "Place on follicles", "click a follicle (follicles are shown)");
  if (ctx.view.tool == Tool::PlaceKey) ctx.view.showFollicles = true;
  if (tj.contains("key_feathers") && tj["key_feathers"].is_array()) {
    for (size_t k = 0; k < tj["key_feathers"].size(); ++k) {
      ImGui::PushID(int(k));
      const Json& kj = tj["key_feathers"][k];
      if (kj.contains("follicle"))
        ImGui::Text("%s at follicle %s", kj.value("feather", std::string("?")).c_str(), kj["follicle"].dump().c_str());
      else
        ImGui::Text("%s at %s", kj.value("feather", std::string("?")).c_str(), kj.value("at", Json()).dump().c_str());
      ImGui::SameLine();
      if (ImGui::SmallButton("remove") || uiRequested(ctx, "Key feathers", "remove", std::to_string(k)))
        guarded(ctx, [&] { actions::removeKeyFeather(doc, size_t(t), k); });
      ImGui::PopID();
    }
  }
  double jitter = tj.value("scale_jitter", 0.0);
  float jf = float(jitter);
  if (ImGui::SliderFloat("Scale jitter", &jf, 0.0f, 0.5f))
    guarded(ctx, [&] { doc.edit("scale jitter", [&](Scene& sc) { sc.tracts.at(size_t(t))["scale_jitter"] = jf; }); });
}

void drawDirectionsPanel(PanelContext& ctx) {
  Document& doc = ctx.doc;
  // A copy: an edit below replaces doc.scene(), and this panel keeps reading what it drew from.
  const Scene s = doc.scene();
  const Json& d = s.directions;
  const bool axis = d.contains("axis"), vectors = d.contains("vectors");
  const size_t strokes = vectors && d["vectors"].is_array() ? d["vectors"].size() : 0;
  if (axis && strokes > 0)
    ImGui::Text("Field: body axis, combed by %zu styling vector%s", strokes, strokes == 1 ? "" : "s");
  else
    ImGui::Text("Field: %s", axis ? "body axis" : vectors ? "styling vectors" : "fallback only");
  toolToggle(ctx, Tool::AddVector, "Add styling vector", "press on the skin, drag the direction, release");
  if (axis) {
    ImGui::SliderFloat("Comb radius", &ctx.view.combRadius, 0.0f, 2.0f, ctx.view.combRadius > 0 ? "%.3f" : "auto",
                       ImGuiSliderFlags_Logarithmic);
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "Scene units. A new styling vector turns the feathers within about this distance\n"
          "and keeps the body axis elsewhere. auto: a tenth of the axis (%.3f).",
          actions::combRadius(s));
  }
  ImGui::SameLine();
  toolToggle(ctx, Tool::EditVectors, "Drag vectors", "drag an arrow tip");
  if (ctx.view.tool == Tool::AddVector || ctx.view.tool == Tool::EditVectors) ctx.view.showVectors = true;
  if (vectors && d["vectors"].is_array()) {
    for (size_t k = 0; k < d["vectors"].size(); ++k) {
      ImGui::PushID(int(k));
      const Json& v = d["vectors"][k];
      glm::dvec3 at = actions::jsonVec3(v.value("at", Json())), dir = actions::jsonVec3(v.value("direction", Json()));
      float a[3] = {float(at.x), float(at.y), float(at.z)}, di[3] = {float(dir.x), float(dir.y), float(dir.z)};
      if (ImGui::Selectable(("vector " + std::to_string(k)).c_str(), ctx.view.selectedVector == int(k)))
        ctx.view.selectedVector = int(k);
      bool ch = ImGui::DragFloat3("at", a, 0.005f);
      ch |= ImGui::DragFloat3("direction", di, 0.01f);
      if (axis && v.contains("radius") && v["radius"].is_number()) {
        float r = v["radius"].get<float>();
        if (ImGui::DragFloat("radius", &r, 0.002f, 0.001f, 100.0f, "%.3f") && r > 0)
          guarded(ctx, [&] {
            doc.edit("styling vector radius", [&](Scene& sc) { sc.directions["vectors"][k]["radius"] = r; });
          });
      }
      if (ch && (di[0] != 0 || di[1] != 0 || di[2] != 0))
        guarded(ctx, [&] {
          actions::setStylingVector(doc, k, glm::dvec3(a[0], a[1], a[2]), glm::dvec3(di[0], di[1], di[2]));
        });
      if (ImGui::SmallButton("remove")) guarded(ctx, [&] { actions::removeStylingVector(doc, k); });
      ImGui::PopID();
    }
  }
  float falloff = d.value("falloff", 0.0f);
  if (ImGui::SliderFloat("Falloff", &falloff, 0.0f, 2.0f))
    guarded(ctx, [&] { doc.edit("falloff", [&](Scene& sc) { sc.directions["falloff"] = falloff; }); });
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("0: inverse-distance-squared blend; > 0: Gaussian fall-off (scene units)");
  if (ImGui::TreeNode("Directions JSON")) {
    Json copy = d;
    if (jsonEditor("directions", copy))
      guarded(ctx, [&] { doc.edit("directions", [&](Scene& sc) { sc.directions = copy; }); });
    ImGui::TreePop();
  }
}

void drawPackingPanel(PanelContext& ctx) {
  Document& doc = ctx.doc;
  // A copy: an edit below replaces doc.scene(), and this panel keeps reading what it drew from.
  const Scene s = doc.scene();
  const Json& p = s.packing;
  if (doc.busy()) {
    const JobProgress pr = doc.progress();
    ImGui::ProgressBar(float(pr.fraction), ImVec2(-FLT_MIN, 0), pr.stage.c_str());
  } else if (ImGui::Button(doc.halted() ? "Run (evaluation stopped)" : "Run")) {
    doc.resume();
  }
  float clearance = p.value("clearance", 0.0f);
  if (ImGui::DragFloat("Clearance (0 = auto)", &clearance, 0.0005f, 0.0f, 10.0f, "%.4f"))
    guarded(ctx, [&] { actions::setPackingValue(doc, "clearance", clearance); });
  float minE = p.value("min_elevation_deg", 0.0f), maxE = p.value("max_elevation_deg", 90.0f);
  if (ImGui::SliderFloat("Min elevation (deg)", &minE, -90.0f, 90.0f))
    guarded(ctx, [&] { actions::setPackingValue(doc, "min_elevation_deg", minE); });
  if (ImGui::SliderFloat("Max elevation (deg)", &maxE, 0.0f, 180.0f))
    guarded(ctx, [&] { actions::setPackingValue(doc, "max_elevation_deg", maxE); });
  bool barbs = p.value("elevate_barbs", true);
  if (ImGui::Checkbox("Elevate barbs (6.3.3)", &barbs))
    guarded(ctx, [&] { actions::setPackingValue(doc, "elevate_barbs", barbs); });
  bool skin = p.value("skin", true);
  ImGui::SameLine();
  if (ImGui::Checkbox("Pack against skin", &skin)) guarded(ctx, [&] { actions::setPackingValue(doc, "skin", skin); });
  fullOrFastCheckbox(ctx, p, "Moult frames: repack every feather", "moult_pack", "over",
                     "Off: lost and growing feathers are packed over the mature coat (fast scrubbing).\n"
                     "On: every feather is repacked (tighter, a full pack per frame; for final renders).");
  fullOrFastCheckbox(ctx, p, "Posed frames: drape in full", "posed_drape", "carry",
                     "Off: a posed frame of a draped coat carries the rest pose's drape with the skin (fast "
                     "scrubbing).\nOn: every posed frame is draped whole on the posed skin (a full drape per frame).");

  sectionTitle("Brush: fixed angle or lift (8.3)");
  ImGui::SliderFloat("Radius", &ctx.view.brushRadius, 0.001f, 2.0f, "%.3f", ImGuiSliderFlags_Logarithmic);
  ImGui::SliderFloat("Elevation (deg)", &ctx.view.brushElevationDeg, -10.0f, 90.0f);
  if (ImGui::RadioButton("fixed angle", !ctx.view.brushLift)) ctx.view.brushLift = false;
  ImGui::SameLine();
  if (ImGui::RadioButton("lift (at least)", ctx.view.brushLift)) ctx.view.brushLift = true;
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "fixed angle: the feathers under the brush are set to the elevation (a low one flattens);\n"
        "lift: they stand at least that high and pack over what is under them");
  toolToggle(ctx, Tool::Brush, "Brush", "click on the skin");
  if (p.contains("styling") && p["styling"].is_array()) {
    for (size_t k = 0; k < p["styling"].size(); ++k) {
      ImGui::PushID(int(k));
      const Json& st = p["styling"][k];
      // What the selection sets: a fixed elevation, a lower bound, a direction and/or a shaft band.
      std::string sets;
      auto num = [&](const char* key, const char* label) {
        if (!st.contains(key) || !st[key].is_number()) return;
        char buf[48];
        std::snprintf(buf, sizeof buf, " %s=%.4g", label, st[key].get<double>());
        sets += buf;
      };
      num("elevation_deg", "elev");
      num("min_elevation_deg", "min");
      num("shaft_band", "band");
      if (st.contains("direction")) sets += " dir";
      ImGui::Text("%s r=%.3g%s", st.value("select", std::string("ids")).c_str(), st.value("radius", 0.0), sets.c_str());
      ImGui::SameLine();
      if (ImGui::SmallButton("remove")) guarded(ctx, [&] { actions::removeBrush(doc, k); });
      ImGui::PopID();
    }
  }
  sectionTitle("Checker");
  if (ImGui::Button("Check coat")) doc.requestCheck();
  metricsTable(doc.metrics());
  if (ImGui::TreeNode("Packing JSON")) {
    Json copy = p;
    if (jsonEditor("packing", copy)) guarded(ctx, [&] { doc.edit("packing", [&](Scene& sc) { sc.packing = copy; }); });
    ImGui::TreePop();
  }
}

}  // namespace pteryla::viewer
