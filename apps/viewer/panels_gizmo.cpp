// Panels of the gizmos (docs/viewer.md, "Gizmos"; gizmo.hpp): the selected control's offset (in the
// Expressive controls panel) and the Skeleton panel (joints, the selected joint's rotation, its keys).
// Both key at the current time, as K does in the view.
#include <imgui.h>

#include <cstdio>

#include "actions.hpp"
#include "pteryla/core/error.hpp"
#include "panels.hpp"

namespace pteryla::viewer {

using pipeline::Scene;

void drawControlOffsetSection(PanelContext& ctx, size_t control) {
  Document& doc = ctx.doc;
  const Scene s = doc.scene();  // a copy: the edits below replace doc.scene()
  const auto off = controlOffsetAt(s, control, doc.time());
  if (!off) return;
  sectionTitle("Offset (direction, aim, dynamic)");
  float o[3] = {float(off->offset.x), float(off->offset.y), float(off->offset.z)};
  const std::string label = off->keyed ? "offset (keyed)" : "offset";
  std::string typed;
  bool set = ImGui::DragFloat3(label.c_str(), o, 0.002f, 0.0f, 0.0f, "%.4f");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "Displacement of the control, scene units: `direction` turns feathers toward it, `aim`\n"
        "points them at the control's place plus it, and its motion drives `dynamic`.\n"
        "Drag the axis handles at the arrow's tip in the view.");
  if (uiRequestedText(ctx, "Expressive controls", "offset", typed)) {
    float x = 0, y = 0, z = 0;
    if (std::sscanf(typed.c_str(), "%f %f %f", &x, &y, &z) != 3)
      throw Error("ui Expressive controls offset: expected \"DX DY DZ\", got '" + typed + "'");
    o[0] = x, o[1] = y, o[2] = z;
    set = true;
  }
  if (set) guarded(ctx, [&] { setControlOffset(doc, control, glm::dvec3(o[0], o[1], o[2]), doc.time()); });
  if (ImGui::Button("Key (K)") || uiRequested(ctx, "Expressive controls", "key"))
    guarded(ctx, [&] { keyControlAll(doc, control, doc.time()); });
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Key every behaviour and the offset at the current time");
}

void drawSkeletonPanel(PanelContext& ctx) {
  Document& doc = ctx.doc;
  ViewState& v = ctx.view;
  const Scene s = doc.scene();
  const Snapshot& snap = doc.snapshot();
  const moult::SkinRig* rig = snap.restSkin ? v.rig.get(s, snap.restSkin->vertexCount(), doc.changeCount()) : nullptr;
  if (!rig) {
    ImGui::TextWrapped("%s", v.rig.error().empty() ? "No skeleton: the scene's \"skeleton\" section (docs/moult.md)."
                                                   : v.rig.error().c_str());
    return;
  }
  ImGui::Checkbox("Show joints", &v.showJoints);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Joint handles at their posed pivots; click one to turn it");
  const moult::Skeleton& sk = rig->skeleton;
  for (size_t j = 0; j < sk.jointCount(); ++j) {
    const std::string label = sk.names[j] + "##joint" + std::to_string(j);
    if (ImGui::Selectable(label.c_str(), v.selectedJoint == int(j)) ||
        uiRequested(ctx, "Skeleton", "select", sk.names[j])) {
      v.selectedJoint = int(j);
      v.selectedControl = -1;
      v.showJoints = true;
    }
  }
  if (v.selectedJoint < 0 || size_t(v.selectedJoint) >= sk.jointCount()) return;
  const size_t j = size_t(v.selectedJoint);
  const PosedJoints posed = poseJoints(*rig, doc.time());
  const Json r = axisAngleJson(posed.local[j]);
  sectionTitle(("Joint " + sk.names[j]).c_str());
  ImGui::Text("rotation at t=%.3f: %.2f deg about (%.3f, %.3f, %.3f)", doc.time(), r[3].get<double>(),
              r[0].get<double>(), r[1].get<double>(), r[2].get<double>());
  ImGui::TextDisabled("drag a ring in the view: x red, y green, z blue (the parent's frame)");
  if (ImGui::Button("Key rotation (K)") || uiRequested(ctx, "Skeleton", "key"))
    guarded(ctx, [&] { keyJointRotation(doc, sk, j, doc.time(), posed.local[j]); });
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Key the joint's rotation at the current time (as it is posed now)");
  // The joint's keys, by name or index.
  const Json keys = s.skeleton.value("keys", Json::array());
  for (size_t i = 0; keys.is_array() && i < keys.size(); ++i) {
    const Json& k = keys[i];
    if (!k.is_object()) continue;
    const Json jn = k.value("joint", Json());
    if (!((jn.is_string() && jn.get<std::string>() == sk.names[j]) ||
          (jn.is_number_integer() && jn.get<int64_t>() == int64_t(j))))
      continue;
    ImGui::PushID(int(i));
    const double kt = k.value("t", 0.0);
    ImGui::Text("t=%.3f  %s", kt, k.value("rotation", Json()).dump().c_str());
    ImGui::SameLine();
    if (ImGui::SmallButton("go")) guarded(ctx, [&] { doc.setTime(kt); });
    ImGui::SameLine();
    if (ImGui::SmallButton("x"))
      guarded(ctx, [&] {
        doc.edit("remove joint key", [&](Scene& sc) {
          Json& ks = sc.skeleton.at("keys");
          if (i < ks.size()) ks.erase(ks.begin() + long(i));
        });
      });
    ImGui::PopID();
  }
}

}  // namespace pteryla::viewer
