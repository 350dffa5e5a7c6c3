// View, render and status panels: level of detail, overlays, camera, lights, render style, textures and
// the Poulin-Fournier BRDF parameters (Streit 2003, 7.1).
#include <imgui.h>
#include <imgui_stdlib.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "actions.hpp"
#include "json_widgets.hpp"
#include "panels.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/feather/io.hpp"

namespace pteryla::viewer {

using pipeline::Scene;

void sectionTitle(const char* title) {
  ImGui::Spacing();
  ImGui::Separator();
  ImGui::TextColored(ImVec4(0.65f, 0.8f, 1.0f, 1.0f), "%s", title);
}

void guarded(PanelContext& ctx, const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    ctx.app.error(e.what());
  }
}

namespace {

// The pending request for `panel`, or nullptr. A "throw" request throws here (in the panel's body).
UiRequest* uiFor(PanelContext& ctx, const char* panel) {
  UiRequest& r = ctx.view.ui;
  if (!r.pending || r.panel != panel) return nullptr;
  if (r.widget == "throw") {
    r.pending = false;
    throw Error("scripted fault inside the panel (ui " + r.panel + " throw)");
  }
  return &r;
}

}  // namespace

bool uiRequested(PanelContext& ctx, const char* panel, const char* widget) {
  UiRequest* r = uiFor(ctx, panel);
  if (!r || r->widget != widget) return false;
  r->pending = false;
  return true;
}

bool uiRequested(PanelContext& ctx, const char* panel, const char* widget, const std::string& value) {
  UiRequest* r = uiFor(ctx, panel);
  if (!r || r->widget != widget || r->value != value) return false;
  r->pending = false;
  return true;
}

bool uiRequestedText(PanelContext& ctx, const char* panel, const char* widget, std::string& value) {
  UiRequest* r = uiFor(ctx, panel);
  if (!r || r->widget != widget) return false;
  r->pending = false;
  value = r->value;
  return true;
}

bool uiRequestedNumber(PanelContext& ctx, const char* panel, const char* widget, float& v) {
  UiRequest* r = uiFor(ctx, panel);
  if (!r || r->widget != widget) return false;
  r->pending = false;
  size_t used = 0;
  float x = 0;
  try {
    x = std::stof(r->value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != r->value.size() || !std::isfinite(x))
    throw Error("ui " + r->panel + " " + r->widget + ": expected a number, got '" + r->value + "'");
  v = x;
  return true;
}

void drawViewPanel(PanelContext& ctx) {
  ViewState& v = ctx.view;
  Document& doc = ctx.doc;
  if (v.idle)
    ImGui::Text("idle (last: %.1f ms a frame)", v.frameMs);
  else
    ImGui::Text("%.1f fps, %.1f ms a frame", v.fps, v.frameMs);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "fps: frames drawn per second while something moves; ms: the work of one frame.\n"
        "With nothing to do the viewer draws nothing (idle).");
  float lod = static_cast<float>(doc.lod());
  if (ImGui::SliderFloat("Preview LOD", &lod, 0.02f, 1.0f, "%.2f")) guarded(ctx, [&] { doc.setLod(lod); });
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("fraction of feather geometry drawn here (thesis 7.1.3); not saved");
  if (doc.hasScene()) {
    float renderLod = static_cast<float>(doc.scene().render.lod);
    if (ImGui::SliderFloat("Render LOD", &renderLod, 0.02f, 1.0f, "%.2f"))
      guarded(ctx, [&] { actions::setRenderLod(doc, renderLod); });
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("the scene's render.lod: what renders, exports and the CLI use; saved with the scene");
    float instancing = static_cast<float>(doc.scene().render.instanceTolerance);
    if (ImGui::SliderFloat("Instancing", &instancing, 0.0f, 0.02f, "%.4f"))
      guarded(ctx, [&] { actions::setInstanceTolerance(doc, instancing); });
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "the scene's render.instance_tolerance: feathers within this fraction of their length of an earlier\n"
          "one are meshed from its curves and share one unplaced mesh (less memory, shapes move that much);\n"
          "0 = off; saved with the scene (docs/limits.md, Instancing)");
  }
  ImGui::Checkbox("Coat", &v.showCoat);
  ImGui::SameLine();
  ImGui::Checkbox("Skin", &v.showSkin);
  ImGui::SameLine();
  ImGui::Checkbox("Wireframe", &v.wireframe);
  ImGui::Checkbox("Follicles", &v.showFollicles);
  ImGui::SameLine();
  ImGui::Checkbox("Directions", &v.showDirections);
  ImGui::SameLine();
  ImGui::Checkbox("Tract", &v.showTract);
  ImGui::SameLine();
  ImGui::Checkbox("Problems", &v.showProblems);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("after Check: feathers crossing another feather (red) or with a vertex under the skin (magenta)");
  {
    int mode = 0;
    const auto& modes = allColourModes();
    for (size_t i = 0; i < modes.size(); ++i)
      if (modes[i] == v.colourBy) mode = int(i);
    std::string items;
    for (ColourBy m : modes) items += std::string(colourByName(m)) + '\0';
    if (ImGui::Combo("Colour by", &mode, items.c_str())) v.colourBy = modes[size_t(mode)];
    if (uiRequested(ctx, "View", "colour by")) {
      const auto m = colourByFromName(ctx.view.ui.value);
      if (!m) throw Error("unknown colour mode '" + ctx.view.ui.value + "'", "", "colour by");
      v.colourBy = *m;
    }
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "material: the feathers' look; problems: the last check (crossing, under the skin);\n"
          "elevation (degrees), layer order, tract, age: flat colours with a legend in the view");
  }
  ImGui::Checkbox("Keys", &v.showKeys);
  ImGui::SameLine();
  ImGui::Checkbox("Vectors", &v.showVectors);
  ImGui::SameLine();
  ImGui::Checkbox("Brushes", &v.showBrushes);
  ImGui::SameLine();
  ImGui::Checkbox("Controls", &v.showControls);
  if (ImGui::Checkbox("Fast navigation", &v.fastNavigation)) v.navigationChanged = true;
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("while the camera moves, draw a subset of the feathers");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(140);
  if (ImGui::SliderInt("triangles", &v.navigationBudget, 20000, 1000000, "%d", ImGuiSliderFlags_Logarithmic))
    v.navigationChanged = true;
  ImGui::Checkbox("Full coat when fast", &v.adaptiveNavigation);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("while the camera moves, keep every feather as long as a frame renders within the budget");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(70);
  ImGui::SliderFloat("ms", &v.fullCoatBudgetMs, 20.0f, 500.0f, "%.0f", ImGuiSliderFlags_Logarithmic);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(60);
  ImGui::SliderInt("1/res", &v.navigationScale, 1, 4);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("while the camera moves, render the view at 1/N of its resolution");
  ImGui::Checkbox("Fast playback", &v.fastPlayback);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "while the timeline plays, draw each new frame at 1/res without multisampling; full quality when "
        "paused");
  if (ImGui::Button("Frame all (A)")) ctx.app.frameAll();
  ImGui::SameLine();
  static std::string shot = "screenshot.png";
  if (ImGui::Button("Screenshot")) ctx.app.screenshot(shot);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(-FLT_MIN);
  ImGui::InputText("##shot", &shot);
  if (ImGui::Button("Use this view as the scene camera")) {
    const render::Camera c = ctx.camera.camera();
    guarded(ctx, [&] {
      doc.edit("scene camera", [&](Scene& s) {
        s.camera.autoFrame = false;
        s.camera.eye = glm::dvec3(c.eye);
        s.camera.target = glm::dvec3(c.target);
        s.camera.up = glm::dvec3(c.up);
        s.camera.fovDeg = c.fovYDegrees;
      });
    });
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("pteryla render uses it (camera.eye / target)");
  const auto& cam = ctx.camera.camera();
  ImGui::TextDisabled("eye %.3g %.3g %.3g  target %.3g %.3g %.3g", cam.eye.x, cam.eye.y, cam.eye.z, cam.target.x,
                      cam.target.y, cam.target.z);
}

void drawRenderPanel(PanelContext& ctx) {
  Document& doc = ctx.doc;
  // A copy: an edit below replaces doc.scene(), and this panel keeps reading what it drew from.
  const Scene s = doc.scene();
  int style = s.render.style == "scratchboard" ? 1 : 0;
  const char* styles[] = {"shaded", "scratchboard"};
  if (ImGui::Combo("Style", &style, styles, 2)) guarded(ctx, [&] { actions::setStyle(doc, styles[style]); });
  if (style == 1) ImGui::TextDisabled("scratchboard is drawn on the CPU: see the preview window");
  float d = static_cast<float>(s.render.brdfD), h = static_cast<float>(s.render.brdfH);
  bool brdf = ImGui::SliderFloat("BRDF d", &d, 0.05f, 20.0f, "%.3f", ImGuiSliderFlags_Logarithmic);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Poulin-Fournier: barbule spacing relative to their radius");
  brdf |= ImGui::SliderFloat("BRDF h", &h, 0.0f, 0.99f, "%.3f");
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Poulin-Fournier: height of the floor between barbules");
  if (brdf) guarded(ctx, [&] { actions::setBrdf(doc, d, h); });

  auto colour = [&](const char* label, const glm::dvec3& c, const std::function<void(Scene&, const glm::dvec3&)>& set) {
    float f[3] = {float(c.x), float(c.y), float(c.z)};
    if (ImGui::ColorEdit3(label, f)) {
      const glm::dvec3 n(f[0], f[1], f[2]);
      guarded(ctx, [&] { doc.edit(label, [&](Scene& sc) { set(sc, n); }); });
    }
  };
  colour("Background", s.render.background, [](Scene& sc, const glm::dvec3& c) { sc.render.background = c; });
  colour("Skin colour", s.render.skinColor, [](Scene& sc, const glm::dvec3& c) { sc.render.skinColor = c; });
  float amb = static_cast<float>(s.render.ambient);
  if (ImGui::SliderFloat("Ambient", &amb, 0.0f, 1.0f))
    guarded(ctx, [&] { doc.edit("ambient", [&](Scene& sc) { sc.render.ambient = amb; }); });
  bool shadows = s.render.shadows;
  if (ImGui::Checkbox("Shadows", &shadows))
    guarded(ctx, [&] { doc.edit("shadows", [&](Scene& sc) { sc.render.shadows = shadows; }); });
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("The first light casts the coat's and the skin's shadows (render.shadows)");
  if (shadows) {
    float strength = static_cast<float>(s.render.shadowStrength);
    if (ImGui::SliderFloat("Shadow strength", &strength, 0.0f, 1.0f))
      guarded(ctx, [&] { doc.edit("shadow strength", [&](Scene& sc) { sc.render.shadowStrength = strength; }); });
  }
  int rig = s.render.lightRig == "studio" ? 1 : 0;
  const char* rigs[] = {"scene lights", "studio (key, fill, rim)"};
  if (ImGui::Combo("Lighting", &rig, rigs, 2))
    guarded(ctx, [&] { doc.edit("lighting", [&](Scene& sc) { sc.render.lightRig = rig == 1 ? "studio" : "scene"; }); });
  int tone = s.render.tone == "filmic" ? 1 : 0;
  const char* tones[] = {"linear", "filmic"};
  if (ImGui::Combo("Tone curve", &tone, tones, 2))
    guarded(ctx, [&] { doc.edit("tone curve", [&](Scene& sc) { sc.render.tone = tone == 1 ? "filmic" : "linear"; }); });
  float exposure = static_cast<float>(s.render.exposure);
  if (ImGui::SliderFloat("Exposure (stops)", &exposure, -4.0f, 4.0f, "%.2f"))
    guarded(ctx, [&] { doc.edit("exposure", [&](Scene& sc) { sc.render.exposure = exposure; }); });
  bool ground = s.render.ground;
  if (ImGui::Checkbox("Ground", &ground))
    guarded(ctx, [&] { doc.edit("ground", [&](Scene& sc) { sc.render.ground = ground; }); });
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("A plane under the model that takes its contact shadow (render.ground)");
  if (ground)
    colour("Ground colour", s.render.groundColor, [](Scene& sc, const glm::dvec3& c) { sc.render.groundColor = c; });
  int msaa = s.render.msaa == 8 ? 3 : s.render.msaa == 4 ? 2 : s.render.msaa == 2 ? 1 : 0;
  const char* samples[] = {"off", "2x", "4x", "8x"};
  if (ImGui::Combo("Anti-aliasing", &msaa, samples, 4))
    guarded(ctx, [&] { doc.edit("anti-aliasing", [&](Scene& sc) { sc.render.msaa = msaa == 0 ? 0 : 1 << msaa; }); });
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Multisampling (render.msaa); off while the camera moves");
  if (ImGui::Button("Neutral background"))
    guarded(ctx, [&] { doc.edit("background", [&](Scene& sc) { sc.render.background = glm::dvec3(0.5, 0.5, 0.5); }); });

  if (ImGui::TreeNode("Lights")) {
    for (size_t i = 0; i < s.lights.size(); ++i) {
      ImGui::PushID(static_cast<int>(i));
      const auto& l = s.lights[i];
      float dir[3] = {float(l.direction.x), float(l.direction.y), float(l.direction.z)};
      float col[3] = {float(l.color.x), float(l.color.y), float(l.color.z)};
      float inten = float(l.intensity);
      bool ch = ImGui::DragFloat3("direction", dir, 0.01f);
      ch |= ImGui::ColorEdit3("colour", col);
      ch |= ImGui::SliderFloat("intensity", &inten, 0.0f, 4.0f);
      if (ch && (dir[0] != 0 || dir[1] != 0 || dir[2] != 0))
        guarded(ctx, [&] {
          doc.edit("light " + std::to_string(i), [&](Scene& sc) {
            sc.lights.at(i).direction = {dir[0], dir[1], dir[2]};
            sc.lights.at(i).color = {col[0], col[1], col[2]};
            sc.lights.at(i).intensity = inten;
          });
        });
      if (ImGui::SmallButton("remove light") && s.lights.size() > 1)
        guarded(ctx, [&] {
          doc.edit("remove light", [&](Scene& sc) {
            if (i >= sc.lights.size()) throw Error("no light " + std::to_string(i));
            sc.lights.erase(sc.lights.begin() + long(i));
          });
        });
      ImGui::Separator();
      ImGui::PopID();
    }
    if (ImGui::Button("Add light") && s.lights.size() < 4)
      guarded(ctx, [&] { doc.edit("add light", [&](Scene& sc) { sc.lights.push_back({}); }); });
    ImGui::TreePop();
  }

  // Textures live in the feather definitions (material): editing makes the definition inline.
  if (ImGui::TreeNode("Feather textures")) {
    ImGui::TextDisabled("colour texture, alpha texture or a pattern name per feather type");
    for (auto it = s.feathers.begin(); it != s.feathers.end(); ++it) {
      ImGui::PushID(it.key().c_str());
      if (ImGui::TreeNode(it.key().c_str())) {
        feather::FeatherParams p;
        bool ok = true;
        try {
          if (it->is_string()) {
            p = feather::loadFeather(it->get<std::string>());
          } else {
            JsonReader r(*it, s.file, "feathers." + it.key());
            p = feather::readFeather(r);
          }
        } catch (const std::exception& e) {
          ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", e.what());
          ok = false;
        }
        if (ok) {
          std::string tex = p.material.texture, alpha = p.material.alphaTexture, pattern = p.material.pattern;
          bool ch = ImGui::InputText("texture", &tex, ImGuiInputTextFlags_EnterReturnsTrue);
          ch |= ImGui::InputText("alpha texture", &alpha, ImGuiInputTextFlags_EnterReturnsTrue);
          ch |= ImGui::InputText("pattern", &pattern, ImGuiInputTextFlags_EnterReturnsTrue);
          // Which texture mapping of Streit 7.1.1 the colour follows (material.uv).
          static const char* kMappings[] = {"global", "barb", "growth"};
          int mapping = p.material.uv == "barb" ? 1 : p.material.uv == "growth" ? 2 : 0;
          if (ImGui::Combo("texture mapping", &mapping, kMappings, 3)) {
            p.material.uv = kMappings[mapping];
            ch = true;
          }
          if (ImGui::IsItemHovered())
            ImGui::SetTooltip("global: the whole vane; barb: glued to each barb; growth: the pin-feather cone");
          if (ch) {
            // Relative texture paths were relative to the feather file: make them absolute.
            auto abs = [&](const std::string& t) {
              return t.empty() || p.sourceFile.empty() ? t : resolveRelative(p.sourceFile, t);
            };
            p.material.texture = abs(tex);
            p.material.alphaTexture = abs(alpha);
            p.material.pattern = pattern;
            const std::string name = it.key();
            guarded(ctx, [&] { actions::setFeatherInline(doc, name, p); });
          }
        }
        ImGui::TreePop();
      }
      ImGui::PopID();
    }
    ImGui::TreePop();
  }
}

void drawStatusBar(PanelContext& ctx, float height) {
  Document& doc = ctx.doc;
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(vp->WorkPos.x, vp->WorkPos.y + vp->WorkSize.y - height));
  ImGui::SetNextWindowSize(ImVec2(vp->WorkSize.x, height));
  ImGui::Begin("##status", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoSavedSettings |
                   ImGuiWindowFlags_NoBringToFrontOnFocus);
  const Snapshot& s = doc.snapshot();
  char rate[48];
  if (ctx.view.idle)
    std::snprintf(rate, sizeof rate, "idle");
  else
    std::snprintf(rate, sizeof rate, "%5.1f fps", ctx.view.fps);
  ImGui::Text("%s | %zu feathers | %.2fM triangles | t = %.3f | preview LOD %.2f%s", rate, s.coatFeathers,
              double(s.coatTriangles) / 1e6, doc.time(), doc.lod(), doc.modified() ? " | modified" : "");
  if (doc.busy()) {
    const JobProgress p = doc.progress();
    ImGui::SameLine();
    ImGui::SetNextItemWidth(220);
    ImGui::ProgressBar(static_cast<float>(p.fraction), ImVec2(220, 0), p.stage.c_str());
    ImGui::SameLine();
    if (ImGui::SmallButton("Cancel")) doc.cancel();
  } else if (doc.halted()) {
    ImGui::SameLine();
    ImGui::TextColored(ImVec4(1, 0.8f, 0.3f, 1), "evaluation stopped");
    ImGui::SameLine();
    if (ImGui::SmallButton("Evaluate")) doc.resume();
  } else if (doc.failed()) {
    ImGui::SameLine();
    ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "evaluation failed (undo or fix the last edit)");
  }
  ImGui::End();
}

}  // namespace pteryla::viewer
