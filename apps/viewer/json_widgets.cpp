#include "json_widgets.hpp"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <cmath>
#include <cstdint>

#include "scene_edit.hpp"

namespace pteryla::viewer {
namespace {

bool isTriple(const Json& j) {
  return j.is_array() && j.size() == 3 && j[0].is_number() && j[1].is_number() && j[2].is_number();
}

bool leafEditor(const char* label, Json& j) {
  bool changed = false;
  ImGui::SetNextItemWidth(-FLT_MIN);
  if (j.is_boolean()) {
    bool b = j.get<bool>();
    if (ImGui::Checkbox(label, &b)) {
      j = b;
      changed = true;
    }
  } else if (j.is_number_integer()) {
    int64_t v = j.get<int64_t>();
    if (ImGui::DragScalar(label, ImGuiDataType_S64, &v, 1.0f)) {
      j = v;
      changed = true;
    }
  } else if (j.is_number()) {
    double v = j.get<double>();
    const float speed = static_cast<float>(std::max(std::abs(v) * 0.01, 1e-4));
    if (ImGui::DragScalar(label, ImGuiDataType_Double, &v, speed, nullptr, nullptr, "%.6g")) {
      j = v;
      changed = true;
    }
  } else if (j.is_string()) {
    std::string s = j.get<std::string>();
    if (ImGui::InputText(label, &s, ImGuiInputTextFlags_EnterReturnsTrue)) {
      j = s;
      changed = true;
    }
  } else if (isTriple(j)) {
    double v[3] = {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
    const float speed = static_cast<float>(std::max((std::abs(v[0]) + std::abs(v[1]) + std::abs(v[2])) * 0.003, 1e-4));
    if (ImGui::DragScalarN(label, ImGuiDataType_Double, v, 3, speed, nullptr, nullptr, "%.4g")) {
      j = Json::array({v[0], v[1], v[2]});
      changed = true;
    }
  } else if (j.is_null()) {
    ImGui::TextDisabled("null");
  }
  return changed;
}

bool addKeyPopup(Json& j) {
  bool changed = false;
  static std::string key, value;
  if (ImGui::SmallButton(j.is_array() ? "+ element" : "+ key")) {
    key.clear();
    value = j.is_array() && !j.empty() ? j.back().dump() : "0";
    ImGui::OpenPopup("add");
  }
  if (ImGui::BeginPopup("add")) {
    if (j.is_object()) ImGui::InputText("key", &key);
    ImGui::InputText("value (JSON)", &value);
    if (ImGui::Button("Add") && (j.is_array() || !key.empty())) {
      const Json v = parseLooseValue(value);
      if (j.is_array())
        j.push_back(v);
      else
        j[key] = v;
      changed = true;
      ImGui::CloseCurrentPopup();
    }
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) ImGui::CloseCurrentPopup();
    ImGui::EndPopup();
  }
  return changed;
}

bool editNode(Json& j) {
  bool changed = false;
  if (j.is_object()) {
    std::string erase;
    for (auto it = j.begin(); it != j.end(); ++it) {
      ImGui::PushID(it.key().c_str());
      Json& v = it.value();
      if (v.is_object() || (v.is_array() && !isTriple(v))) {
        const bool open = ImGui::TreeNode(it.key().c_str());
        ImGui::SameLine();
        if (ImGui::SmallButton("x")) erase = it.key();
        if (open) {
          changed |= editNode(v);
          ImGui::TreePop();
        }
      } else {
        if (ImGui::SmallButton("x")) erase = it.key();
        ImGui::SameLine();
        ImGui::TextUnformatted(it.key().c_str());
        ImGui::SameLine(160.0f);
        changed |= leafEditor("##v", v);
      }
      ImGui::PopID();
    }
    if (!erase.empty()) {
      j.erase(erase);
      changed = true;
    }
    changed |= addKeyPopup(j);
  } else if (j.is_array()) {
    long erase = -1;
    for (size_t i = 0; i < j.size(); ++i) {
      ImGui::PushID(static_cast<int>(i));
      Json& v = j[i];
      const std::string label = "[" + std::to_string(i) + "]";
      if (v.is_object() || (v.is_array() && !isTriple(v))) {
        std::string title = label;
        if (v.is_object() && v.contains("name") && v["name"].is_string()) title += " " + v["name"].get<std::string>();
        const bool open = ImGui::TreeNode("node", "%s", title.c_str());
        ImGui::SameLine();
        if (ImGui::SmallButton("x")) erase = static_cast<long>(i);
        if (open) {
          changed |= editNode(v);
          ImGui::TreePop();
        }
      } else {
        if (ImGui::SmallButton("x")) erase = static_cast<long>(i);
        ImGui::SameLine();
        ImGui::TextUnformatted(label.c_str());
        ImGui::SameLine(160.0f);
        changed |= leafEditor("##v", v);
      }
      ImGui::PopID();
    }
    if (erase >= 0) {
      j.erase(j.begin() + erase);
      changed = true;
    }
    changed |= addKeyPopup(j);
  } else {
    changed |= leafEditor("##v", j);
  }
  return changed;
}

}  // namespace

bool jsonEditor(const char* id, Json& j) {
  ImGui::PushID(id);
  const bool changed = editNode(j);
  ImGui::PopID();
  return changed;
}

bool jsonTextEditor(const char* id, Json& j, JsonTextState& st, float height) {
  ImGui::PushID(id);
  const std::string now = j.dump(2);
  if (st.shown != now) {
    st.buffer = now;
    st.shown = now;
    st.error.clear();
  }
  ImGui::InputTextMultiline("##text", &st.buffer, ImVec2(-FLT_MIN, height));
  bool applied = false;
  if (ImGui::Button("Apply")) {
    Json v = Json::parse(st.buffer, nullptr, false);
    if (v.is_discarded()) {
      st.error = "not valid JSON";
    } else {
      j = v;
      st.error.clear();
      applied = true;
    }
  }
  ImGui::SameLine();
  if (ImGui::Button("Revert")) {
    st.buffer = now;
    st.error.clear();
  }
  if (!st.error.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", st.error.c_str());
  ImGui::PopID();
  return applied;
}

}  // namespace pteryla::viewer
