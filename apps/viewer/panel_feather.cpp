// Feather designer (Streit 2003, Ch.5): Table 5.1 parameters as sliders, key barbs edited by dragging
// their Bezier control vertices in 2D canvases (barb-local top and side views, 5.2.2), a live preview of
// every barb curve, interpolation toward a second feather type (5.2.4) and the growth/wear age (8.1).
// A helical feather (Zhang & Kanai) also shows its speed curves V_e(s), V_b(s) as editable curves.
// The preview is local, with its own undo history (one step per edit or drag); "Apply to scene" writes
// the definition inline into the scene's feather library, "Save feather file" writes a feather file.
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "actions.hpp"
#include "panels.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/bezier.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/helical.hpp"
#include "pteryla/feather/interpolate.hpp"
#include "pteryla/feather/io.hpp"

namespace pteryla::viewer {

using feather::FeatherParams;
using feather::KeyBarb;

namespace {

constexpr float kDeg = 57.29577951308232f;
constexpr const char* kPanel = "Feather designer";  // scripted widgets: `ui "Feather designer" ...`
constexpr size_t kMaxUndo = 200;

FeatherParams featherFromScene(const pipeline::Scene& s, const std::string& name) {
  const Json& j = s.feathers.at(name);
  FeatherParams p;
  if (j.is_string()) {
    p = feather::loadFeather(j.get<std::string>());
  } else {
    JsonReader r(j, s.file, "feathers." + name);
    p = feather::readFeather(r);
    p.sourceFile = s.file;
  }
  p.name = name;
  return p;
}

// Maps a 2D box of model coordinates into a canvas rectangle, uniform scale, y up.
struct CanvasMap {
  ImVec2 origin, size;
  glm::dvec2 lo, hi;
  double scale = 1;
  void fit(const ImVec2& o, const ImVec2& sz, glm::dvec2 l, glm::dvec2 h) {
    origin = o;
    size = sz;
    const glm::dvec2 ext = glm::max(h - l, glm::dvec2(1e-9));
    scale = std::min((sz.x - 16) / ext.x, (sz.y - 16) / ext.y);
    const glm::dvec2 c = 0.5 * (l + h);
    lo = c - glm::dvec2(sz.x, sz.y) * 0.5 / scale;
    hi = c + glm::dvec2(sz.x, sz.y) * 0.5 / scale;
  }
  ImVec2 to(double x, double y) const {
    return ImVec2(origin.x + float((x - lo.x) * scale), origin.y + size.y - float((y - lo.y) * scale));
  }
  glm::dvec2 from(const ImVec2& p) const {
    return {lo.x + (p.x - origin.x) / scale, lo.y + (origin.y + size.y - p.y) / scale};
  }
};

}  // namespace

struct FeatherDesigner::Impl {
  std::string name;  // scene feather being edited
  FeatherParams params, original;
  bool loaded = false;
  std::string other;
  FeatherParams otherParams;
  bool haveOther = false;
  float blend = 0.0f, age = 1.0f;
  int vane = 0, key = 0;
  feather::FeatherCurves curves;
  bool dirty = true;
  std::string previewError;
  std::string filePath;
  bool askOverwrite = false;
  int dragCv = -1, dragView = -1;
  std::vector<glm::vec3> line;
  // Undo history of the design (the preview): `committed` is the design after the last edit; an edit
  // pushes the design before it, a drag (mouse held) is one step.
  std::vector<FeatherParams> undo, redo;
  FeatherParams committed;
  bool gestureOpen = false;
  // Speed curve canvases (0 emitter, 1 barb): the dragged / selected key and the y range of a drag.
  int dragCurve = -1, dragKey = -1;
  double dragYMax = 1;
  int curveKey[2] = {0, 0};

  void load(PanelContext& ctx, const std::string& n) {
    guarded(ctx, [&] {
      params = featherFromScene(ctx.doc.scene(), n);
      original = params;
      committed = params;
      undo.clear();
      redo.clear();
      gestureOpen = false;
      name = n;
      loaded = true;
      dirty = true;
      key = 0;
      if (!params.sourceFile.empty() && ctx.doc.scene().feathers.at(n).is_string()) filePath = params.sourceFile;
    });
  }

  FeatherParams preview() const {
    FeatherParams p = params;
    if (haveOther && blend > 0.0f) p = feather::interpolateFeathers(params, otherParams, blend);
    if (age != 1.0f) p = feather::featherAtAge(p, age, feather::growthScheduleOf(p));
    return p;
  }

  void regenerate() {
    if (!dirty) return;
    dirty = false;
    previewError.clear();
    try {
      feather::generateBarbs(preview(), curves);
    } catch (const std::exception& e) {
      previewError = e.what();
      curves.clear();
    }
  }

  void drawPreview(const ImVec2& size) {
    regenerate();
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const ImVec2 o = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton("preview", size);
    dl->AddRectFilled(o, ImVec2(o.x + size.x, o.y + size.y), IM_COL32(28, 30, 36, 255));
    if (!previewError.empty()) {
      dl->AddText(ImVec2(o.x + 8, o.y + 8), IM_COL32(255, 110, 90, 255), previewError.c_str());
      return;
    }
    if (curves.shafts.empty()) return;
    // Bounds of shafts and barb end points (feather-local x, y: top view of the feather).
    glm::dvec2 lo(1e30), hi(-1e30);
    for (const auto& s : curves.shafts)
      for (const auto& p : s.points) {
        lo = glm::min(lo, glm::dvec2(p.x, p.y));
        hi = glm::max(hi, glm::dvec2(p.x, p.y));
      }
    for (const auto& c : curves.cvs) {
      lo = glm::min(lo, glm::dvec2(c.x, c.y));
      hi = glm::max(hi, glm::dvec2(c.x, c.y));
    }
    CanvasMap m;
    m.fit(o, size, lo, hi);
    for (const auto& b : curves.barbs) {
      feather::barbPolyline(curves, b, 6, line);
      const ImU32 col = b.part == 1   ? IM_COL32(160, 200, 255, 160)
                        : b.isKey     ? IM_COL32(255, 210, 120, 255)
                        : b.vane == 0 ? IM_COL32(215, 190, 150, 150)
                                      : IM_COL32(190, 170, 140, 150);
      for (size_t i = 1; i < line.size(); ++i)
        dl->AddLine(m.to(line[i - 1].x, line[i - 1].y), m.to(line[i].x, line[i].y), col, b.isKey ? 1.5f : 1.0f);
    }
    for (const auto& s : curves.shafts)
      for (size_t i = 1; i < s.points.size(); ++i)
        dl->AddLine(m.to(s.points[i - 1].x, s.points[i - 1].y), m.to(s.points[i].x, s.points[i].y),
                    IM_COL32(250, 250, 240, 255), std::max(1.5f, float(s.widths[i - 1] * m.scale)));
    dl->AddText(ImVec2(o.x + 6, o.y + 4), IM_COL32(200, 200, 200, 200),
                (std::to_string(curves.barbs.size()) + " barbs (key barbs highlighted)").c_str());
  }

  // One 2D view of a key barb: axes (0: x along the barb, 1: y toward the tip, 2: z dorsal).
  bool drawKeyBarbView(const char* id, KeyBarb& kb, int axisU, int axisV, const ImVec2& size, int view) {
    bool changed = false;
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const ImVec2 o = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton(id, size);
    const bool hovered = ImGui::IsItemHovered(), active = ImGui::IsItemActive();
    dl->AddRectFilled(o, ImVec2(o.x + size.x, o.y + size.y), IM_COL32(24, 26, 32, 255));
    CanvasMap m;
    m.fit(o, size, {-0.1, -0.55}, {1.1, 0.55});
    // Grid: the chord limit (x = 1) and the barb axis.
    dl->AddLine(m.to(-0.1, 0), m.to(1.1, 0), IM_COL32(70, 70, 80, 255));
    dl->AddLine(m.to(1, -0.55), m.to(1, 0.55), IM_COL32(70, 70, 80, 255));
    const char* names[] = {"x along barb", "y toward tip", "z dorsal"};
    dl->AddText(ImVec2(o.x + 4, o.y + 2), IM_COL32(180, 180, 180, 200),
                (std::string(names[axisU]) + " / " + names[axisV]).c_str());
    // Curve.
    std::vector<glm::dvec3> pts;
    feather::sampleBezier(kb.cvs, 32, pts);
    for (size_t i = 1; i < pts.size(); ++i)
      dl->AddLine(m.to(pts[i - 1][axisU], pts[i - 1][axisV]), m.to(pts[i][axisU], pts[i][axisV]),
                  IM_COL32(255, 210, 120, 255), 2.0f);
    for (size_t i = 1; i < kb.cvs.size(); ++i)
      dl->AddLine(m.to(kb.cvs[i - 1][axisU], kb.cvs[i - 1][axisV]), m.to(kb.cvs[i][axisU], kb.cvs[i][axisV]),
                  IM_COL32(120, 120, 140, 200));
    // Control vertices: cv[0] is the attachment point (fixed).
    const ImVec2 mouse = ImGui::GetIO().MousePos;
    int hot = -1;
    float best = 81.0f;
    for (size_t i = 1; i < kb.cvs.size(); ++i) {
      const ImVec2 p = m.to(kb.cvs[i][axisU], kb.cvs[i][axisV]);
      const float d2 = (p.x - mouse.x) * (p.x - mouse.x) + (p.y - mouse.y) * (p.y - mouse.y);
      if (d2 < best) {
        best = d2;
        hot = int(i);
      }
    }
    if (hovered && ImGui::IsMouseClicked(ImGuiMouseButton_Left) && hot > 0) {
      dragCv = hot;
      dragView = view;
    }
    if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) dragView = -1;
    if (active && dragView == view && dragCv > 0 && size_t(dragCv) < kb.cvs.size()) {
      const glm::dvec2 q = m.from(mouse);
      kb.cvs[size_t(dragCv)][axisU] = std::clamp(q.x, -0.5, 1.5);
      kb.cvs[size_t(dragCv)][axisV] = std::clamp(q.y, -1.0, 1.0);
      changed = true;
    }
    for (size_t i = 0; i < kb.cvs.size(); ++i) {
      const ImVec2 p = m.to(kb.cvs[i][axisU], kb.cvs[i][axisV]);
      const bool sel = (dragView == view && int(i) == dragCv) || (hovered && int(i) == hot);
      dl->AddCircleFilled(p, sel ? 6.0f : 4.5f,
                          i == 0 ? IM_COL32(150, 150, 150, 255)
                          : sel  ? IM_COL32(255, 255, 255, 255)
                                 : IM_COL32(90, 200, 255, 255));
    }
    return changed;
  }

  // A helical speed curve (Curve1D, locus s in [0, 1] -> speed > 0): drag its keys in the canvas, type
  // their speeds, add or remove keys. Scripted: `ui "Feather designer" "LABEL K" SPEED` sets key K.
  bool drawSpeedCurve(PanelContext& ctx, const char* label, feather::Curve1D& curve, int id, const ImVec2& size) {
    std::vector<glm::dvec2> keys = curve.keys();
    bool changed = false;
    ImDrawList* dl = ImGui::GetWindowDrawList();
    const ImVec2 o = ImGui::GetCursorScreenPos();
    ImGui::InvisibleButton(label, size);
    const bool hovered = ImGui::IsItemHovered(), active = ImGui::IsItemActive();
    dl->AddRectFilled(o, ImVec2(o.x + size.x, o.y + size.y), IM_COL32(24, 26, 32, 255));
    double ymax = 0;
    for (const auto& k : keys) ymax = std::max(ymax, k.y);
    ymax = dragCurve == id ? dragYMax : std::max(1.3 * ymax, 1e-3);
    const float pad = 10.0f, w = size.x - 2 * pad, h = size.y - 2 * pad;
    auto to = [&](double x, double y) {
      return ImVec2(o.x + pad + float(x) * w, o.y + pad + h - float(std::clamp(y / ymax, 0.0, 1.05)) * h);
    };
    dl->AddLine(to(0, 0), to(1, 0), IM_COL32(70, 70, 80, 255));
    dl->AddLine(to(0.5, 0), to(0.5, ymax), IM_COL32(50, 50, 60, 255));  // the posterior polar (synced)
    for (int i = 1; i <= 64; ++i)
      dl->AddLine(to((i - 1) / 64.0, curve((i - 1) / 64.0)), to(i / 64.0, curve(i / 64.0)),
                  IM_COL32(255, 210, 120, 255), 2.0f);
    char text[96];
    std::snprintf(text, sizeof text, "%s V(s), max %.3g", label, ymax / 1.3);
    dl->AddText(ImVec2(o.x + 4, o.y + 2), IM_COL32(180, 180, 180, 200), text);
    const ImVec2 mouse = ImGui::GetIO().MousePos;
    int hot = -1;
    float best = 81.0f;
    for (size_t k = 0; k < keys.size(); ++k) {
      const ImVec2 p = to(keys[k].x, keys[k].y);
      const float d2 = (p.x - mouse.x) * (p.x - mouse.x) + (p.y - mouse.y) * (p.y - mouse.y);
      if (d2 < best) {
        best = d2;
        hot = int(k);
      }
    }
    if (hovered && ImGui::IsMouseClicked(ImGuiMouseButton_Left) && hot >= 0) {
      dragCurve = id;
      dragKey = hot;
      dragYMax = ymax;
      curveKey[id] = hot;
    }
    if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) dragCurve = -1;
    if (active && dragCurve == id && dragKey >= 0 && size_t(dragKey) < keys.size()) {
      const size_t k = size_t(dragKey);
      const double lo = k > 0 ? keys[k - 1].x + 1e-3 : 0.0, hi = k + 1 < keys.size() ? keys[k + 1].x - 1e-3 : 1.0;
      keys[k].x = std::clamp(double(mouse.x - o.x - pad) / w, lo, std::max(lo, hi));
      keys[k].y = std::max(1e-4, double(o.y + pad + h - mouse.y) / h * ymax);
      changed = true;
    }
    curveKey[id] = std::clamp(curveKey[id], 0, int(keys.size()) - 1);
    for (size_t k = 0; k < keys.size(); ++k) {
      const bool sel = int(k) == curveKey[id];
      dl->AddCircleFilled(to(keys[k].x, keys[k].y), sel ? 6.0f : 4.5f,
                          sel ? IM_COL32(255, 255, 255, 255) : IM_COL32(90, 200, 255, 255));
    }
    // Speeds typed (or set by a script), one field per key.
    for (size_t k = 0; k < keys.size(); ++k) {
      const std::string widget = std::string(label) + " " + std::to_string(k);
      float y = float(keys[k].y);
      ImGui::SetNextItemWidth(std::min(90.0f, size.x / float(keys.size()) - 8));
      bool c = ImGui::DragFloat(("##" + widget).c_str(), &y, 0.0005f, 1e-4f, 100.0f, "%.4f");
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s at s = %.3f", label, keys[k].x);
      if (ImGui::IsItemActivated()) curveKey[id] = int(k);
      c |= uiRequestedNumber(ctx, kPanel, widget.c_str(), y);
      if (c) {
        keys[k].y = std::max(1e-4, double(y));
        changed = true;
      }
      if (k + 1 < keys.size()) ImGui::SameLine();
    }
    const std::string add = std::string("add key##") + label, remove = std::string("remove key##") + label;
    if (ImGui::SmallButton(add.c_str())) {
      // In the widest gap (or beside a single key), on the curve: the curve does not change shape.
      size_t at = keys.size();
      double gap = keys.size() == 1 ? 0.0 : -1.0, x = keys.front().x < 0.5 ? 1.0 : 0.0;
      for (size_t k = 0; k + 1 < keys.size(); ++k)
        if (keys[k + 1].x - keys[k].x > gap) {
          gap = keys[k + 1].x - keys[k].x;
          at = k + 1;
          x = 0.5 * (keys[k].x + keys[k + 1].x);
        }
      if (at == keys.size() && keys.size() == 1) at = x > keys.front().x ? 1 : 0;
      keys.insert(keys.begin() + std::ptrdiff_t(at), glm::dvec2(x, curve(x)));
      curveKey[id] = int(at);
      changed = true;
    }
    ImGui::SameLine();
    if (ImGui::SmallButton(remove.c_str()) && keys.size() > 1) {
      keys.erase(keys.begin() + curveKey[id]);
      curveKey[id] = 0;
      changed = true;
    }
    if (changed) curve.setKeys(std::move(keys));
    return changed;
  }

  // The helical feather's speed curves; an edit re-derives the feather (applyHelical).
  bool drawHelical(PanelContext& ctx, FeatherParams& p) {
    bool changed = false;
    guarded(ctx, [&] {
      JsonReader r(p.generatorParams, p.sourceFile, "helical");
      feather::HelicalParams hp = feather::readHelical(r);
      const float w = (ImGui::GetContentRegionAvail().x - 8) * 0.5f;
      ImGui::BeginGroup();
      bool c = drawSpeedCurve(ctx, "emitter speed", hp.emitterSpeed, 0, ImVec2(w, 150));
      ImGui::EndGroup();
      ImGui::SameLine();
      ImGui::BeginGroup();
      c |= drawSpeedCurve(ctx, "barb speed", hp.barbSpeed, 1, ImVec2(w, 150));
      ImGui::EndGroup();
      ImGui::TextDisabled("locus s on the collar (anterior polar 0 and 1%s); speeds in locus units per time unit",
                          hp.syncSpeedToPolar ? ", posterior polar 0.5" : "");
      if (!c) return;
      FeatherParams q = p;
      q.generatorParams = feather::helicalToJson(hp);
      feather::applyHelical(q, hp);  // validates
      p = std::move(q);
      changed = true;
    });
    return changed;
  }

  void undoStep(FeatherParams& p, bool back) {
    auto& from = back ? undo : redo;
    auto& to = back ? redo : undo;
    if (from.empty()) return;
    to.push_back(p);
    p = std::move(from.back());
    from.pop_back();
    committed = p;
    gestureOpen = false;
    dirty = true;
  }

  // After a frame's widgets: an edit (ch) is one undo step unless it continues a drag.
  void record(bool ch, const FeatherParams& p) {
    const bool held = ImGui::IsMouseDown(ImGuiMouseButton_Left) || ImGui::IsAnyItemActive();
    if (ch) {
      if (!gestureOpen) {
        undo.push_back(committed);
        if (undo.size() > kMaxUndo) undo.erase(undo.begin());
        redo.clear();
      }
      committed = p;
    }
    gestureOpen = ch && held ? true : gestureOpen && held;
  }
};

FeatherDesigner::FeatherDesigner() : impl_(std::make_unique<Impl>()) {}
FeatherDesigner::~FeatherDesigner() = default;

void FeatherDesigner::draw(PanelContext& ctx, bool* open) {
  Impl& d = *impl_;
  ImGui::SetNextWindowPos(ImVec2(ctx.view.viewOrigin.x + 12, ctx.view.viewOrigin.y + 12), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(860, 780), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Feather designer", open)) {
    ImGui::End();
    return;
  }
  const pipeline::Scene scene = ctx.doc.scene();  // a copy: Apply below replaces doc.scene()
  std::vector<std::string> names;
  for (auto it = scene.feathers.begin(); it != scene.feathers.end(); ++it) names.push_back(it.key());
  if ((!d.loaded || !scene.feathers.contains(d.name)) && !names.empty()) d.load(ctx, names.front());
  if (ImGui::BeginCombo("Feather", d.name.c_str())) {
    for (const auto& n : names)
      if (ImGui::Selectable(n.c_str(), n == d.name)) d.load(ctx, n);
    ImGui::EndCombo();
  }
  if (!d.loaded) {
    ImGui::TextDisabled("the scene has no feathers");
    ImGui::End();
    return;
  }
  FeatherParams& p = d.params;
  bool ch = false;

  if (ImGui::BeginTable("designer", 2, ImGuiTableFlags_Resizable)) {
    ImGui::TableNextColumn();
    // ---- Table 5.1 parameters ----
    auto len = [&](const char* label, double& v, double lo, double hi) {
      float f = float(v);
      if (ImGui::DragFloat(label, &f, float(std::max(std::abs(v), 1e-3) * 0.005), float(lo), float(hi), "%.4g")) {
        v = f;
        ch = true;
      }
    };
    auto ang = [&](const char* label, double& v, float lo, float hi) {
      float f = float(v) * kDeg;
      if (ImGui::SliderFloat(label, &f, lo, hi, "%.1f deg")) {
        v = f / kDeg;
        ch = true;
      }
    };
    ImGui::TextColored(ImVec4(0.65f, 0.8f, 1.0f, 1.0f), "Shaft");
    len("calamus length (c_l)", p.calamusLength, 0.0, 100.0);
    {
      float f = float(p.calamusWidthRatio);
      if (ImGui::SliderFloat("calamus width ratio (c_wr)", &f, 0.1f, 2.0f)) {
        p.calamusWidthRatio = f;
        ch = true;
      }
    }
    len("rachis length (r_l)", p.rachisLength, 1e-4, 1000.0);
    len("rachis width (r_w)", p.rachisWidth, 1e-5, 100.0);
    ang("lateral curvature (r_lc)", p.rachisLateralCurvature, -90.0f, 90.0f);
    ang("ventral-dorsal curvature", p.rachisVentralDorsalCurvature, -90.0f, 90.0f);
    ImGui::TextColored(ImVec4(0.65f, 0.8f, 1.0f, 1.0f), "Barbs");
    len("barb length (b_l)", p.barbLength, 1e-4, 1000.0);
    if (!p.silhouette.empty()) ImGui::TextDisabled("(a silhouette profile overrides the barb length)");
    len("spacing at base", p.spacingBase, 1e-5, 100.0);
    len("spacing at tip", p.spacingTip, 1e-5, 100.0);
    ang("left angle at base", p.left.baseAngle, 1.0f, 179.0f);
    ang("left angle at tip", p.left.tipAngle, 1.0f, 179.0f);
    ang("right angle at base", p.right.baseAngle, 1.0f, 179.0f);
    ang("right angle at tip", p.right.tipAngle, 1.0f, 179.0f);
    ImGui::TextColored(ImVec4(0.65f, 0.8f, 1.0f, 1.0f), "Wear splits (5.2.5)");
    ch |= ImGui::SliderInt("splits per vane", &p.splits.count, 0, 20);
    {
      float a = float(p.splits.rpMin), b = float(p.splits.rpMax);
      if (ImGui::DragFloatRange2("split range (rp)", &a, &b, 0.005f, 0.0f, 1.0f)) {
        p.splits.rpMin = a;
        p.splits.rpMax = b;
        ch = true;
      }
    }
    ang("split opening", p.splits.openingAngle, 0.0f, 60.0f);
    ch |= ImGui::SliderInt("split reach (barbs)", &p.splits.reach, 0, 20);
    {
      int seed = int(p.seed);
      if (ImGui::InputInt("seed", &seed) && seed >= 0) {
        p.seed = uint64_t(seed);
        ch = true;
      }
    }

    ImGui::TableNextColumn();
    // ---- Live preview ----
    d.dirty |= ch;
    d.drawPreview(ImVec2(ImGui::GetContentRegionAvail().x, 260));
    {
      if (ImGui::BeginCombo("blend toward", d.other.empty() ? "(none)" : d.other.c_str())) {
        if (ImGui::Selectable("(none)", d.other.empty())) {
          d.other.clear();
          d.haveOther = false;
          d.dirty = true;
        }
        for (const auto& n : names)
          if (n != d.name && ImGui::Selectable(n.c_str(), n == d.other)) {
            guarded(ctx, [&] {
              d.otherParams = featherFromScene(scene, n);
              d.other = n;
              d.haveOther = true;
              d.dirty = true;
            });
          }
        ImGui::EndCombo();
      }
      if (ImGui::SliderFloat("interpolation t (5.2.4)", &d.blend, 0.0f, 1.0f)) d.dirty = true;
      if (ImGui::SliderFloat("age (growth 0-1, wear 1-2)", &d.age, 0.0f, 2.0f)) d.dirty = true;
      if (d.haveOther && d.blend > 0 && ImGui::Button("Use blend as the design")) {
        guarded(ctx, [&] {
          p = feather::interpolateFeathers(p, d.otherParams, d.blend);
          d.blend = 0;
          d.dirty = true;
          ch = true;
        });
      }
    }
    ImGui::EndTable();
  }

  // ---- Key barbs ----
  sectionTitle("Key barbs (drag control vertices)");
  ImGui::RadioButton("left vane", &d.vane, 0);
  ImGui::SameLine();
  ImGui::RadioButton("right vane", &d.vane, 1);
  auto& keys = p.vane(d.vane).keyBarbs;
  ImGui::SameLine();
  if (ImGui::Button("Add key barb")) {
    guarded(ctx, [&] {
      const auto eff = feather::effectiveKeyBarbs(p, d.vane);
      KeyBarb kb;
      kb.rp = 0.5;
      feather::barbShapeAt(eff, kb.rp, kb.cvs);
      keys.push_back(kb);
      std::stable_sort(keys.begin(), keys.end(), [](const KeyBarb& a, const KeyBarb& b) { return a.rp < b.rp; });
      d.key = int(std::find(keys.begin(), keys.end(), kb) - keys.begin());
      ch = true;
    });
  }
  ImGui::SameLine();
  if (ImGui::Button("Copy to other vane")) {
    p.vane(1 - d.vane).keyBarbs = keys;
    ch = true;
  }
  if (keys.empty()) {
    ImGui::TextDisabled("no key barbs: default plumulaceous (down) barbs");
  } else {
    d.key = std::clamp(d.key, 0, int(keys.size()) - 1);
    for (int i = 0; i < int(keys.size()); ++i) {
      ImGui::SameLine();
      char label[32];
      std::snprintf(label, sizeof label, "rp %.2f##%d", keys[size_t(i)].rp, i);
      if (ImGui::Selectable(label, d.key == i, 0, ImVec2(70, 0))) d.key = i;
    }
    KeyBarb& kb = keys[size_t(d.key)];
    float rp = float(kb.rp);
    if (ImGui::SliderFloat("rp (position on the rachis)", &rp, 0.0f, 1.0f)) {
      kb.rp = rp;
      const KeyBarb moved = kb;
      std::stable_sort(keys.begin(), keys.end(), [](const KeyBarb& a, const KeyBarb& b) { return a.rp < b.rp; });
      d.key = int(std::find(keys.begin(), keys.end(), moved) - keys.begin());
      ch = true;
    }
    KeyBarb& cur = keys[size_t(d.key)];
    const float w = (ImGui::GetContentRegionAvail().x - 8) * 0.5f;
    ch |= d.drawKeyBarbView("top", cur, 0, 1, ImVec2(w, 200), 0);
    ImGui::SameLine();
    ch |= d.drawKeyBarbView("side", cur, 0, 2, ImVec2(w, 200), 1);
    if (ImGui::Button("Add control vertex")) {
      cur.cvs = feather::elevateDegree(cur.cvs);
      ch = true;
    }
    ImGui::SameLine();
    if (ImGui::Button("Remove key barb")) {
      keys.erase(keys.begin() + d.key);
      d.key = 0;
      ch = true;
    }
  }
  if (p.generator == "helical") {
    sectionTitle("Helical growth speeds (Zhang & Kanai; drag keys or type speeds)");
    ch |= d.drawHelical(ctx, p);
  }
  d.dirty |= ch;

  // ---- Apply / files ----
  sectionTitle("Apply");
  d.record(ch, p);
  ImGui::BeginDisabled(d.undo.empty());
  const bool undoNow = ImGui::Button("Undo");
  ImGui::EndDisabled();
  if (undoNow || uiRequested(ctx, kPanel, "undo")) d.undoStep(p, true);
  ImGui::SameLine();
  ImGui::BeginDisabled(d.redo.empty());
  const bool redoNow = ImGui::Button("Redo");
  ImGui::EndDisabled();
  if (redoNow || uiRequested(ctx, kPanel, "redo")) d.undoStep(p, false);
  ImGui::SameLine();
  const bool changed = !(p == d.original);
  if (ImGui::Button("Apply to scene")) {
    guarded(ctx, [&] {
      actions::setFeatherInline(ctx.doc, d.name, p);
      d.original = p;
    });
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("writes the definition inline into the scene (re-evaluates the coat)");
  ImGui::SameLine();
  if (ImGui::Button("Revert")) {
    p = d.original;
    d.dirty = true;
    d.record(true, p);
  }
  ImGui::SameLine();
  ImGui::TextDisabled(changed ? "(unapplied changes)" : "");
  ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - 150);
  ImGui::InputText("##file", &d.filePath);
  ImGui::SameLine();
  if (ImGui::Button("Save feather file")) {
    if (fileExists(d.filePath)) {
      d.askOverwrite = true;
      ImGui::OpenPopup("Overwrite feather file?");
    } else {
      guarded(ctx, [&] { feather::saveFeather(d.filePath, p); });
    }
  }
  std::string scripted;
  if (uiRequestedText(ctx, kPanel, "save", scripted)) {
    // `ui "Feather designer" save [PATH]`: writes (replacing) PATH, or the field's file.
    if (!scripted.empty()) d.filePath = scripted;
    guarded(ctx, [&] { feather::saveFeather(d.filePath, p); });
  }
  if (ImGui::BeginPopupModal("Overwrite feather file?", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::Text("%s exists. Replace it?", d.filePath.c_str());
    if (ImGui::Button("Overwrite")) {
      guarded(ctx, [&] { feather::saveFeather(d.filePath, p); });
      ImGui::CloseCurrentPopup();
    }
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }
  ImGui::End();
}

}  // namespace pteryla::viewer
