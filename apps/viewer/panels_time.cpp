// Timeline (moult over time, Streit 2003 Ch.8) and expressive controls (Grier 2019, AnimFur: lift, aim,
// direction, random twist and dynamic blend, keyframed by animators).
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>

#include "actions.hpp"
#include "json_widgets.hpp"
#include "panels.hpp"
#include "pteryla/moult/schedule.hpp"
#include "scene_edit.hpp"

namespace pteryla::viewer {

using pipeline::Scene;

namespace {

// The moult options of docs/moult.md (moult/schedule.hpp readMoultOptions) as widgets; keys not set keep
// their defaults (or the scene's, for a tract). Other keys stay editable in the JSON tree below.
bool moultEditor(const char* id, Json& m) {
  ImGui::PushID(id);
  bool ch = false;
  auto num = [&](const char* key, float def, float lo, float hi, const char* fmt = "%.3f") {
    float v = m.contains(key) && m[key].is_number() ? m[key].get<float>() : def;
    if (ImGui::SliderFloat(key, &v, lo, hi, fmt)) {
      m[key] = v;
      ch = true;
    }
  };
  bool enabled = m.value("enabled", true);
  if (ImGui::Checkbox("enabled", &enabled)) {
    m["enabled"] = enabled;
    ch = true;
  }
  num("start", 0.0f, -10.0f, 100.0f);
  num("duration", 1.0f, 0.01f, 100.0f);
  num("window", 0.2f, 0.001f, 1.0f);
  num("gap", 0.05f, 0.0f, 0.99f);
  num("random", 0.0f, 0.0f, 1.0f);
  num("size_exponent", 0.0f, 0.0f, 8.0f);
  num("boundary_slowdown", 0.0f, 0.0f, 10.0f);
  num("old_age", 1.0f, 1.0f, 2.0f);      // wear of the old plumage (docs/growth.md)
  num("wear_time", 0.0f, 0.0f, 100.0f);  // time a renewed feather takes to wear fully
  const std::string seq = m.value("sequence", std::string("centre_out"));
  if (ImGui::BeginCombo("sequence", seq.c_str())) {
    for (int i = 0; i <= int(moult::MoultSequence::Random); ++i)
      if (const char* q = moult::moultSequenceName(moult::MoultSequence(i)); ImGui::Selectable(q, seq == q)) {
        m["sequence"] = q;
        ch = true;
      }
    ImGui::EndCombo();
  }
  const std::string pace = m.value("pace", std::string("order"));
  int p = pace == "distance" ? 1 : 0;
  bool paced = ImGui::RadioButton("order", &p, 0);
  ImGui::SameLine();
  paced |= ImGui::RadioButton("distance", &p, 1);
  ImGui::SameLine();
  ImGui::TextUnformatted("pace");
  if (paced) {
    m["pace"] = p ? "distance" : "order";
    ch = true;
  }
  if (ImGui::TreeNode("JSON")) {
    ch |= jsonEditor("json", m);
    ImGui::TreePop();
  }
  ImGui::PopID();
  return ch;
}

}  // namespace

void drawTimelinePanel(PanelContext& ctx) {
  Document& doc = ctx.doc;
  ViewState& v = ctx.view;
  if (ImGui::Button(v.playing ? "Pause" : "Play")) v.playing = !v.playing;
  ImGui::SameLine();
  if (ImGui::Button("|<")) guarded(ctx, [&] { doc.setTime(v.timeStart); });
  ImGui::SameLine();
  if (ImGui::Button("<")) guarded(ctx, [&] { doc.setTime(std::max<double>(v.timeStart, doc.time() - v.timeStep)); });
  ImGui::SameLine();
  if (ImGui::Button(">")) guarded(ctx, [&] { doc.setTime(std::min<double>(v.timeEnd, doc.time() + v.timeStep)); });
  ImGui::SameLine();
  ImGui::Checkbox("Loop", &v.loop);
  float t = static_cast<float>(v.playing ? v.shownTime : doc.time());
  ImGui::SetNextItemWidth(-FLT_MIN);
  if (ImGui::SliderFloat("##time", &t, v.timeStart, v.timeEnd, "t = %.3f")) guarded(ctx, [&] { doc.setTime(t); });
  // Scrubbing: a low level of detail while the slider is held, the preview's again on release.
  if (ImGui::IsItemActivated() && v.scrubLowLod && doc.lod() > double(v.scrubLod) + 1e-9) {
    v.scrubSavedLod = doc.lod();
    guarded(ctx, [&] { doc.setLod(double(v.scrubLod)); });
  }
  if (ImGui::IsItemDeactivated() && v.scrubSavedLod > 0) {
    const double lod = v.scrubSavedLod;
    v.scrubSavedLod = 0;
    guarded(ctx, [&] { doc.setLod(lod); });
  }
  ImGui::SetNextItemWidth(200);
  ImGui::DragFloatRange2("Range", &v.timeStart, &v.timeEnd, 0.1f, -1000.0f, 1000.0f, "%.2f");
  ImGui::SetNextItemWidth(120);
  ImGui::InputFloat("Frame step", &v.timeStep, 0.0f, 0.0f, "%.4f");
  v.timeStep = std::max(v.timeStep, 1e-4f);
  ImGui::SetNextItemWidth(120);
  ImGui::InputFloat("Play fps", &v.playFps, 0.0f, 0.0f, "%.1f");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("frames a second of wall time; a frame not ready in time is dropped, not waited for");
  v.playFps = std::clamp(v.playFps, 0.1f, 240.0f);
  ImGui::Checkbox("Low detail while scrubbing", &v.scrubLowLod);
  if (v.scrubLowLod) {
    ImGui::SameLine();
    ImGui::SetNextItemWidth(80);
    ImGui::SliderFloat("##scrublod", &v.scrubLod, 0.01f, 1.0f, "%.2f");
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("level of detail while the time slider is held (fraction)");
  }
  ImGui::SetNextItemWidth(120);
  ImGui::InputInt("Flipbook MB", &v.flipbookMB);
  v.flipbookMB = std::clamp(v.flipbookMB, 0, 65536);
  ImGui::TextDisabled("flipbook: %zu frames, %.0f MB (drawn frames show at once when scrubbed or played)",
                      v.flipbookFrames, double(v.flipbookBytes) / (1 << 20));
  if (v.caching) {
    ImGui::ProgressBar(v.cacheProgress, ImVec2(200, 0), "caching");
  } else if (ImGui::Button("Cache range") || uiRequested(ctx, "Timeline", "cache range")) {
    v.cacheRangeRequested = true;
  }
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("evaluate and draw every frame of the range into the flipbook, so it plays at the frame rate");
  if (!v.playReadout.empty()) ImGui::TextDisabled("%s", v.playReadout.c_str());

  sectionTitle("Moult (scene)");
  ImGui::TextDisabled("defaults for every tract (docs/moult.md)");
  {
    Json copy = doc.scene().moult;
    if (moultEditor("moult", copy)) guarded(ctx, [&] { doc.edit("moult", [&](Scene& s) { s.moult = copy; }); });
  }
  sectionTitle("Moult (per tract)");
  // A copy: an edit below replaces doc.scene(), and this panel keeps reading what it drew from.
  const Scene s = doc.scene();
  if (s.tracts.empty()) {
    ImGui::TextDisabled("no tracts");
    return;
  }
  int& sel = v.selectedTract;
  sel = std::clamp(sel, 0, int(s.tracts.size()) - 1);
  if (ImGui::BeginCombo("Tract##m", tractName(s, size_t(sel)).c_str())) {
    for (int i = 0; i < int(s.tracts.size()); ++i)
      if (ImGui::Selectable(tractName(s, size_t(i)).c_str(), i == sel)) sel = i;
    ImGui::EndCombo();
  }
  const Json& tj = s.tracts[size_t(sel)];
  if (!tj.contains("moult")) {
    if (ImGui::Button("Add moult settings to this tract"))
      guarded(ctx, [&] {
        doc.edit("tract moult", [&](Scene& sc) { sc.tracts.at(size_t(sel))["moult"] = Json::object(); });
      });
  } else {
    Json copy = tj["moult"].is_object() ? tj["moult"] : Json::object();
    if (moultEditor("tract_moult", copy))
      guarded(ctx, [&] {
        doc.edit("tract moult " + std::to_string(sel), [&](Scene& sc) { sc.tracts.at(size_t(sel))["moult"] = copy; });
      });
    if (ImGui::SmallButton("Remove moult settings"))
      guarded(ctx, [&] { doc.edit("tract moult", [&](Scene& sc) { sc.tracts.at(size_t(sel)).erase("moult"); }); });
  }
}

void drawControlsPanel(PanelContext& ctx) {
  Document& doc = ctx.doc;
  ViewState& v = ctx.view;
  // A copy: an edit below replaces doc.scene(), and this panel keeps reading what it drew from.
  const Scene s = doc.scene();
  ImGui::SliderFloat("New control radius", &v.controlRadius, 0.001f, 5.0f, "%.3f", ImGuiSliderFlags_Logarithmic);
  const bool active = v.tool == Tool::AddControl;
  if (ImGui::Button(active ? "Done placing" : "Place control")) v.tool = active ? Tool::Orbit : Tool::AddControl;
  if (active) {
    ImGui::SameLine();
    ImGui::TextDisabled("click on the skin");
  }
  for (size_t k = 0; k < s.controls.size(); ++k) {
    const Json& c = s.controls[k];
    const std::string name =
        c.is_object() ? c.value("name", "control " + std::to_string(k)) : "control " + std::to_string(k);
    if (ImGui::Selectable((name + "##" + std::to_string(k)).c_str(), v.selectedControl == int(k)) ||
        uiRequested(ctx, "Expressive controls", "select", name))
      v.selectedControl = int(k);
  }
  if (v.selectedControl < 0 || size_t(v.selectedControl) >= s.controls.size()) {
    v.selectedControl = -1;
    return;
  }
  const size_t k = size_t(v.selectedControl);
  const Json& c = s.controls[k];
  if (!c.is_object()) return;
  sectionTitle("Behaviours");
  const actions::ControlNow now = actions::controlAt(s, k, doc.time());
  for (int i = 0; i < 5; ++i) {
    const char* b = actions::kControlBehaviours[i];
    float value = float(now.value[i]);
    const std::string label = std::string(b) + (now.keyed[i] ? " (keyed)" : "");
    if (ImGui::SliderFloat(label.c_str(), &value, 0.0f, 1.0f) ||
        uiRequestedNumber(ctx, "Expressive controls", b, value))
      guarded(ctx, [&] { actions::setControlValue(doc, k, b, value, doc.time()); });
  }
  drawControlOffsetSection(ctx, k);
  glm::dvec3 at = actions::jsonVec3(c.value("at", Json()));
  float a[3] = {float(at.x), float(at.y), float(at.z)};
  float radius = c.value("radius", 0.0f);
  bool moved = ImGui::DragFloat3("at", a, 0.005f);
  moved |= ImGui::DragFloat("radius", &radius, 0.002f, 1e-4f, 100.0f);
  if (moved) guarded(ctx, [&] { actions::setControlPoint(doc, k, glm::dvec3(a[0], a[1], a[2]), radius); });

  sectionTitle("Keyframes");
  if (ImGui::Button("Key all behaviours at current time"))
    guarded(ctx, [&] { actions::addControlKeyframe(doc, k, doc.time()); });
  if (c.contains("keys") && c["keys"].is_array()) {
    for (size_t i = 0; i < c["keys"].size(); ++i) {
      ImGui::PushID(int(i));
      const Json& key = c["keys"][i];
      const double kt = key.value("t", 0.0);
      std::string values;
      for (const char* b : actions::kControlBehaviours)
        if (key.contains(b) && key[b].is_number())
          values += std::string(" ") + b + " " + std::to_string(key[b].get<double>()).substr(0, 4);
      ImGui::Text("t=%.3f%s", kt, values.c_str());
      ImGui::SameLine();
      if (ImGui::SmallButton("go")) guarded(ctx, [&] { doc.setTime(kt); });
      ImGui::SameLine();
      if (ImGui::SmallButton("x")) guarded(ctx, [&] { actions::removeControlKeyframe(doc, k, i); });
      ImGui::PopID();
    }
  }
  {
    const char* interps[] = {"linear", "smooth", "step"};
    const std::string cur = c.value("interpolation", std::string("linear"));
    int idx = cur == "smooth" ? 1 : cur == "step" ? 2 : 0;
    if (ImGui::Combo("interpolation", &idx, interps, 3))
      guarded(ctx, [&] {
        doc.edit("interpolation", [&](Scene& sc) { sc.controls.at(k)["interpolation"] = interps[idx]; });
      });
  }
  if (ImGui::Button("Remove control")) {
    guarded(ctx, [&] { actions::removeControl(doc, k); });
    v.selectedControl = -1;
    return;
  }
  if (ImGui::TreeNode("Control JSON")) {
    Json copy = c;
    if (jsonEditor("control", copy))
      guarded(ctx, [&] { doc.edit("control " + std::to_string(k), [&](Scene& sc) { sc.controls.at(k) = copy; }); });
    ImGui::TreePop();
  }
}

}  // namespace pteryla::viewer
