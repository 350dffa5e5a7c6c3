// The Open and Save As dialogs: a small file browser over std::filesystem (file_browser.hpp), the
// recent files, a file-name field where Enter confirms and a typed name replaces the old one.
#include <imgui.h>
#include <imgui_stdlib.h>

#include <filesystem>

#include "dialogs.hpp"

namespace pteryla::viewer {
namespace {

// The browser's listing in a scrolling child; returns a file the user double-clicked or pressed Enter on.
// A single click on a file puts its name in `name`.
std::optional<std::string> browserList(FileBrowser& b, std::string& name) {
  std::optional<std::string> chosen;
  ImGui::TextUnformatted(b.directory().c_str());
  ImGui::SameLine();
  if (ImGui::SmallButton("Up")) b.up();
  ImGui::SameLine();
  bool hidden = b.showHidden();
  if (ImGui::Checkbox("hidden", &hidden)) b.setShowHidden(hidden);
  if (!b.error().empty()) ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.4f, 1.0f), "%s", b.error().c_str());
  const float rowH = ImGui::GetTextLineHeightWithSpacing();
  if (ImGui::BeginChild("files", ImVec2(560, rowH * 14), true)) {
    const auto entries = b.entries();  // a copy: choose() may list another directory
    for (size_t i = 0; i < entries.size(); ++i) {
      const BrowserEntry& e = entries[i];
      const std::string label = e.directory ? e.name + "/" : e.name;
      ImGui::PushID(int(i));
      if (ImGui::Selectable(label.c_str(), !e.directory && e.name == name, ImGuiSelectableFlags_AllowDoubleClick)) {
        if (e.directory) {
          b.choose(i);  // one click enters a directory
        } else {
          name = e.name;
          if (ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left)) chosen = b.choose(i);
        }
      }
      if (!e.directory) {
        ImGui::SameLine(440);
        ImGui::TextDisabled("%.1f KB", double(e.bytes) / 1024.0);
      }
      ImGui::PopID();
      if (chosen || b.entries().size() != entries.size()) break;
    }
  }
  ImGui::EndChild();
  return chosen;
}

// The file-name field: Enter confirms. Returns the typed path resolved against the browser's directory
// (nullopt for a directory, which is entered, or nothing typed).
std::optional<std::string> nameField(FileBrowser& b, std::string& name, const char* label, bool& focus,
                                     bool& confirmed) {
  ImGui::SetNextItemWidth(440);
  if (focus) {
    ImGui::SetKeyboardFocusHere();
    focus = false;
  }
  const bool enter = ImGui::InputText(label, &name, ImGuiInputTextFlags_EnterReturnsTrue);
  confirmed = enter;
  if (!enter) return std::nullopt;
  const auto path = b.resolveTyped(name);
  if (!path) {
    name.clear();  // a directory was entered
    focus = true;
  }
  return path;
}

}  // namespace

void Dialogs::remember(const std::string& path) {
  if (options_.scripted) return;  // scripts (and tests) leave the user's recent files alone
  recent_.add(path);
}

void Dialogs::openDialog() {
  const ImVec2 centre = ImGui::GetMainViewport()->GetCenter();
  ImGui::SetNextWindowPos(centre, ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  if (!ImGui::BeginPopupModal("Open scene", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) return;
  if (ImGui::IsWindowAppearing()) {
    recent_.load();
    if (!openPath_.empty()) {
      const std::filesystem::path p(openPath_);
      openBrowser_.setDirectory(p.has_parent_path() ? p.parent_path().string() : ".");
      openName_ = p.filename().string();
    }
    focusName_ = true;
  }
  std::optional<std::string> chosen;
  if (!recent_.list().empty()) {
    ImGui::SetNextItemWidth(440);
    if (ImGui::BeginCombo("recent", "a recent file...")) {
      for (const auto& r : recent_.list())
        if (ImGui::Selectable(r.c_str())) chosen = r;
      ImGui::EndCombo();
    }
  }
  if (!chosen) chosen = browserList(openBrowser_, openName_);
  bool confirmed = false;
  if (!chosen) chosen = nameField(openBrowser_, openName_, "scene or mesh", focusName_, confirmed);
  ImGui::TextDisabled("scene (.json) or bare mesh (.obj .ply .off .stl); Enter opens");
  if (ImGui::Button("Open") && !chosen) chosen = openBrowser_.resolveTyped(openName_);
  ImGui::SameLine();
  const bool cancel = ImGui::Button("Cancel") || ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape));
  if (chosen) {
    openPath_ = *chosen;
    ImGui::CloseCurrentPopup();
    requestOpen(*chosen);
  } else if (cancel) {
    ImGui::CloseCurrentPopup();
  }
  ImGui::EndPopup();
}

void Dialogs::saveAsNow(const std::string& path) {
  saveAsPath_ = path;
  try {
    if (doc_.saveAs(path, false)) {
      remember(path);
      afterSave();
    } else {
      popupToOpen_ = "Replace file?";
    }
  } catch (const std::exception& e) {
    pending_ = Pending::None;
    showError(e.what());
  }
}

void Dialogs::saveAsDialog() {
  const ImVec2 centre = ImGui::GetMainViewport()->GetCenter();
  ImGui::SetNextWindowPos(centre, ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  if (!ImGui::BeginPopupModal("Save scene as", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) return;
  if (ImGui::IsWindowAppearing()) {
    const std::filesystem::path p(saveAsPath_);
    saveBrowser_.setDirectory(p.has_parent_path() ? p.parent_path().string() : ".");
    saveName_ = p.filename().string();
    focusName_ = true;
  }
  std::optional<std::string> chosen = browserList(saveBrowser_, saveName_);
  bool confirmed = false;
  if (!chosen) chosen = nameField(saveBrowser_, saveName_, "file (.json)", focusName_, confirmed);
  ImGui::TextDisabled("Enter saves; an existing file is replaced only after you confirm");
  if (ImGui::Button("Save") && !chosen) chosen = saveBrowser_.resolveTyped(saveName_);
  ImGui::SameLine();
  const bool cancel = ImGui::Button("Cancel") || ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape));
  if (chosen) {
    ImGui::CloseCurrentPopup();
    saveAsNow(*chosen);
  } else if (cancel) {
    pending_ = Pending::None;
    ImGui::CloseCurrentPopup();
  }
  ImGui::EndPopup();
}

}  // namespace pteryla::viewer
