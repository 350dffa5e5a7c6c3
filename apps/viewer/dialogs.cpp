// The viewer's dialogs (dialogs.hpp): errors, open and save (unsaved changes, replacing a file), autosave
// and the recovery of unsaved work. The Open and Save As browsers are in dialogs_files.cpp.
#include "dialogs.hpp"

#include <imgui.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "pteryla/core/error.hpp"
#include "timeline.hpp"

namespace pteryla::viewer {

Dialogs::Dialogs(Document& doc, ViewState& view, Viewport& viewport, const Options& options)
    : doc_(doc), view_(view), viewport_(viewport), options_(options), autosave_(options.autosaveSeconds) {}

void Dialogs::showOpen(const std::string& path) {
  if (!path.empty()) openPath_ = path;
  popupToOpen_ = "Open scene";
}

void Dialogs::confirmQuit() {
  pending_ = Pending::Quit;
  popupToOpen_ = "Unsaved changes";
}

std::string Dialogs::autosaveNow() { return autosave_.saveNow(doc_); }

// Saved (or never changed): the recovery file is not needed any more. Unsaved work keeps it.
void Dialogs::finish() { autosave_.finish(doc_); }

void Dialogs::showError(const std::string& message) {
  if (options_.scripted) std::fprintf(stderr, "pteryla-viewer: error: %s\n", message.c_str());
  errors_.push_back(message);
  if (popupToOpen_.empty()) popupToOpen_ = "Error";
}

void Dialogs::requestOpen(const std::string& path) {
  if (doc_.modified()) {
    pending_ = Pending::Open;
    pendingPath_ = path;
    popupToOpen_ = "Unsaved changes";
    return;
  }
  openNow(path);
}

void Dialogs::openNow(const std::string& path) {
  try {
    doc_.open(path);
  } catch (const std::exception& e) {
    openPath_ = path;  // the Open dialog starts there, to fix the name or pick another file
    showError(e.what());
    return;
  }
  remember(path);
  // Forget the previous scene's view.
  viewport_.forgetScene();
  view_.selectedTract = 0;
  view_.selectedControl = view_.selectedVector = view_.selectedFollicle = view_.selectedJoint = -1;
  view_.tool = Tool::Orbit;
  view_.playing = false;
  fitTimeRange(doc_, view_);
}

void Dialogs::requestSave() {
  if (!doc_.hasScene()) return;
  if (doc_.path().empty()) {
    requestSaveAs();
    return;
  }
  try {
    doc_.save();
    afterSave();
  } catch (const std::exception& e) {
    showError(e.what());
  }
}

void Dialogs::requestSaveAs(const std::string& path) {
  if (!doc_.hasScene()) return;
  saveAsPath_ =
      doc_.path().empty() ? (std::filesystem::current_path() / (doc_.scene().name + ".json")).string() : doc_.path();
  if (!path.empty()) saveAsPath_ = path;
  popupToOpen_ = "Save scene as";
}

// After a successful save: carry on with what the unsaved-changes dialog was asked to do.
void Dialogs::afterSave() {
  if (pending_ == Pending::Quit) {
    quit_ = true;
  } else if (pending_ == Pending::Open) {
    openNow(pendingPath_);
  }
  pending_ = Pending::None;
}

void Dialogs::autosaveTick() {
  try {
    const double now = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    if (autosave_.tick(doc_, now) && options_.scripted)
      std::fprintf(stderr, "pteryla-viewer: autosaved %s\n", autosave_.written().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pteryla-viewer: autosave failed: %s\n", e.what());
    if (!autosaveErrorShown_) showError(std::string("autosave failed (retrying): ") + e.what());
    autosaveErrorShown_ = true;
  }
}

// At start: unsaved work of the scene given (or, with no scene, the newest) is offered for restoring;
// --recover restores it without asking (scripted sessions), other scripted runs leave it alone.
void Dialogs::offerRecovery() {
  const bool bareMesh = doc_.hasScene() && doc_.path().empty();
  std::optional<std::string> file;
  if (!bareMesh) file = findRecovery(doc_.hasScene() ? doc_.path() : "");
  if (!file) {
    if (options_.recover) throw Error("--recover: no unsaved work to recover", recoveryDir());
    return;
  }
  if (!options_.recover && options_.scripted) return;
  try {
    offered_ = readRecovery(*file);
  } catch (const Error& e) {
    if (options_.recover) throw;
    showError(std::string("a recovery file cannot be read (it is kept): ") + e.what());  // the viewer still starts
    return;
  }
  if (options_.recover)
    restoreOffered();
  else
    popupToOpen_ = "Recover unsaved work";
}

void Dialogs::restoreOffered() {
  if (!offered_) return;
  const Recovery r = std::move(*offered_);
  offered_.reset();
  restoreRecovery(doc_, r);
  autosave_.adopt(r.file, doc_);
  std::fprintf(stderr, "pteryla-viewer: restored unsaved work from %s\n", r.file.c_str());
}

void Dialogs::draw() {
  if (!popupToOpen_.empty()) {
    ImGui::OpenPopup(popupToOpen_.c_str());
    popupToOpen_.clear();
  }
  const ImVec2 centre = ImGui::GetMainViewport()->GetCenter();

  ImGui::SetNextWindowPos(centre, ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  if (ImGui::BeginPopupModal("Error", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    for (const auto& e : errors_) {
      ImGui::PushTextWrapPos(640.0f);
      ImGui::TextColored(ImVec4(1, 0.5f, 0.4f, 1), "%s", e.c_str());
      ImGui::PopTextWrapPos();
    }
    ImGui::TextDisabled("The viewer keeps the scene as it is; undo the last edit or fix the value.");
    if (ImGui::Button("OK")) {
      errors_.clear();
      ImGui::CloseCurrentPopup();
    }
    if (doc_.canUndo()) {
      ImGui::SameLine();
      if (ImGui::Button(("Undo " + doc_.undoLabel()).c_str())) {
        doc_.undo();
        errors_.clear();
        ImGui::CloseCurrentPopup();
      }
    }
    ImGui::EndPopup();
  }

  ImGui::SetNextWindowPos(centre, ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  if (ImGui::BeginPopupModal("Recover unsaved work", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    if (offered_) {
      const std::string what = offered_->scenePath.empty() ? std::string("an untitled scene") : offered_->scenePath;
      ImGui::Text("Unsaved changes to %s were autosaved (%s UTC).", what.c_str(), offered_->savedAt.c_str());
      ImGui::TextDisabled("%s", offered_->file.c_str());
      ImGui::Text("Restore them? The scene file is not changed until you save.");
      if (ImGui::Button("Restore")) {
        ImGui::CloseCurrentPopup();
        try {
          restoreOffered();
          fitTimeRange(doc_, view_);
        } catch (const std::exception& e) {
          showError(std::string("restore failed (the recovery file is kept): ") + e.what());
        }
      }
      ImGui::SameLine();
      if (ImGui::Button("Discard")) {
        ImGui::CloseCurrentPopup();
        removeRecovery(offered_->file);
        offered_.reset();
      }
    } else {
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }

  openDialog();
  saveAsDialog();

  ImGui::SetNextWindowPos(centre, ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  if (ImGui::BeginPopupModal("Replace file?", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::Text("%s exists.", saveAsPath_.c_str());
    ImGui::Text("Replace it with this scene?");
    if (ImGui::Button("Replace")) {
      ImGui::CloseCurrentPopup();
      try {
        doc_.saveAs(saveAsPath_, true);
        remember(saveAsPath_);
        afterSave();
      } catch (const std::exception& e) {
        pending_ = Pending::None;
        showError(e.what());
      }
    }
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) {
      pending_ = Pending::None;
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }

  ImGui::SetNextWindowPos(centre, ImGuiCond_Appearing, ImVec2(0.5f, 0.5f));
  if (ImGui::BeginPopupModal("Unsaved changes", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::Text("The scene has unsaved changes.");
    if (ImGui::Button("Save")) {
      ImGui::CloseCurrentPopup();
      if (doc_.path().empty()) {
        requestSaveAs();  // continues with the pending action after saving
      } else {
        try {
          doc_.save();
          afterSave();
        } catch (const std::exception& e) {
          pending_ = Pending::None;
          showError(e.what());
        }
      }
    }
    ImGui::SameLine();
    if (ImGui::Button("Discard")) {
      ImGui::CloseCurrentPopup();
      autosave_.discard();  // the user threw the changes away: no recovery for them
      if (pending_ == Pending::Quit)
        quit_ = true;
      else if (pending_ == Pending::Open)
        openNow(pendingPath_);
      pending_ = Pending::None;
    }
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) {
      pending_ = Pending::None;
      ImGui::CloseCurrentPopup();
    }
    ImGui::EndPopup();
  }
}

}  // namespace pteryla::viewer
