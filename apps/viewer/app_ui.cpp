// Menu bar, the panel column, keyboard shortcuts and the Scene JSON, Help and scratchboard windows; every
// body runs guarded (guardedUi), so an exception goes to the error modal (dialogs.hpp) and the frame
// ends cleanly.
#include <imgui.h>
#include <imgui_internal.h>
#include <imgui_stdlib.h>

#include <cstdio>

#include <filesystem>

#include "app.hpp"
#include "glfw_context.hpp"
#include "json_widgets.hpp"
#include "overlays.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/render/renderer.hpp"
#include "pteryla/render/scene_view.hpp"
#include "pteryla/render/scratchboard.hpp"
#include "scene_edit.hpp"

namespace pteryla::viewer {

namespace {

// Closes what an interrupted body left open above `windows` windows on ImGui's window stack (child
// windows, tables, combos, popups, each with its trees, IDs, colours and style variables), then the
// trees, IDs, tables and colours it left in the window it ran in (a panel body starts with none).
void recoverImGuiStack(int windows) {
  ImGuiContext& g = *ImGui::GetCurrentContext();
  while (g.CurrentWindowStack.Size > windows) {
    ImGui::ErrorCheckEndWindowRecover(nullptr);  // may end a table's own child window
    if (g.CurrentWindowStack.Size <= windows) break;
    if (g.CurrentWindow->Flags & ImGuiWindowFlags_ChildWindow)
      ImGui::EndChild();
    else
      ImGui::End();
  }
  ImGui::ErrorCheckEndWindowRecover(nullptr);
}

}  // namespace

void App::guardedUi(const char* what, const std::function<void()>& body) {
  const int windows = ImGui::GetCurrentContext()->CurrentWindowStack.Size;
  try {
    body();
  } catch (const std::exception& e) {
    recoverImGuiStack(windows);
    dialogs_.showError(std::string(what) + ": " + e.what());
  } catch (...) {
    recoverImGuiStack(windows);
    dialogs_.showError(std::string(what) + ": unknown error");
  }
}

void App::buildUi() {
  guardedUi("render frames", [&] {
    if (frames_.step(*context_)) pacing_.noteInput();  // keep drawing while frames are made
  });
  guardedUi("menu", [&] { menuBar(); });
  menuHeight_ = ImGui::GetFrameHeight();
  if (!view_.hidePanels) panelColumn();
  guardedUi("status bar", [&] { drawStatusBar(panels_, kStatusHeight); });
  if (view_.showDesigner && doc_.hasScene())
    guardedUi("Feather designer", [&] { designer_.draw(panels_, &view_.showDesigner); });
  if (view_.showJsonInspector && doc_.hasScene()) guardedUi("Scene JSON", [&] { sceneJsonWindow(); });
  if (view_.showHelp) guardedUi("Help", [&] { helpWindow(); });
  if (doc_.hasScene() && doc_.scene().render.style == "scratchboard")
    guardedUi("Scratchboard preview", [&] { scratchboardWindow(); });
  if (doc_.hasScene() && view_.colourBy != ColourBy::Material) guardedUi("legend", [&] { viewport_.legendWindow(); });
  if (doc_.hasScene() && view_.hoveredHandle && !view_.handleDragging && !ImGui::GetIO().WantCaptureMouse) {
    ImGui::BeginTooltip();
    ImGui::TextUnformatted(handleReadout(doc_.scene(), *view_.hoveredHandle).c_str());
    ImGui::EndTooltip();
  } else if (doc_.hasScene() && view_.hoveredFollicle >= 0 && !ImGui::GetIO().WantCaptureMouse) {
    const Snapshot& snap = doc_.snapshot();
    const size_t f = size_t(view_.hoveredFollicle);
    const uint32_t t = f < snap.follicleTract.size() ? snap.follicleTract[f] : 0;
    ImGui::BeginTooltip();
    ImGui::Text("follicle %zu\nid: %llu\ntract: %s", f,
                static_cast<unsigned long long>(f < snap.follicleId.size() ? snap.follicleId[f] : 0),
                t < snap.tractNames.size() ? snap.tractNames[t].c_str() : "-");
    ImGui::EndTooltip();
  } else if (doc_.hasScene() && view_.hoveredFeather >= 0 && !ImGui::GetIO().WantCaptureMouse) {
    ImGui::BeginTooltip();
    ImGui::TextUnformatted(readoutText(featherReadout(doc_.snapshot(), view_.hoveredFeather)).c_str());
    ImGui::EndTooltip();
  }
  guardedUi("dialog", [&] { dialogs_.draw(); });
  // Keyboard shortcuts (when no text field has the keyboard).
  ImGuiIO& io = ImGui::GetIO();
  if (!io.WantCaptureKeyboard) {
    const bool ctrl = io.KeyCtrl;
    if (ctrl && ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Z))) {
      if (io.KeyShift)
        doc_.redo();
      else
        doc_.undo();
    }
    if (ctrl && ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Y))) doc_.redo();
    if (ctrl && ImGui::IsKeyPressed('S')) dialogs_.requestSave();
    if (ctrl && ImGui::IsKeyPressed('O')) dialogs_.showOpen();
    if (!ctrl && ImGui::IsKeyPressed('F') && !input_.frameBoxSelection()) viewport_.frameSelection();
    if (!ctrl && ImGui::IsKeyPressed('A')) viewport_.frameAll();
    if (!ctrl && ImGui::IsKeyPressed('K') && doc_.hasScene()) input_.keySelected();
    if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Space))) view_.playing = !view_.playing;
    if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape))) {
      if (view_.tool == Tool::Orbit) {  // Esc: end the tool, then the selection
        view_.selectedFeather = -1;
        view_.selectedHandle.reset();
        view_.selectedJoint = view_.selectedControl = -1;
        view_.boxFeathers.clear();
        view_.boxFollicles.clear();
        view_.boxHandles.clear();
      }
      view_.tool = Tool::Orbit;
    }
    if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Tab))) view_.hidePanels = !view_.hidePanels;
    if (ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Delete)) && doc_.hasScene()) input_.deleteSelected();
  }
  // Releasing the mouse ends a gesture: the next slider drag is a new undo step.
  if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) doc_.endGesture();
}

void App::menuBar() {
  if (!ImGui::BeginMainMenuBar()) return;
  if (ImGui::BeginMenu("File")) {
    if (ImGui::MenuItem("Open...", "Ctrl+O")) dialogs_.showOpen();
    if (ImGui::BeginMenu("Open Recent")) {
      if (ImGui::IsWindowAppearing()) dialogs_.recent().load();
      if (dialogs_.recent().list().empty()) ImGui::TextDisabled("no recent files");
      for (const auto& r : dialogs_.recent().list())
        if (ImGui::MenuItem(r.c_str())) dialogs_.requestOpen(r);
      ImGui::EndMenu();
    }
    if (ImGui::MenuItem("Save", "Ctrl+S", false, doc_.hasScene())) dialogs_.requestSave();
    if (ImGui::MenuItem("Save As...", nullptr, false, doc_.hasScene())) dialogs_.requestSaveAs();
    ImGui::Separator();
    if (ImGui::MenuItem("Quit")) {
      if (doc_.modified()) {
        dialogs_.confirmQuit();
      } else {
        quit_ = true;
      }
    }
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Edit")) {
    const std::string u = "Undo " + doc_.undoLabel(), r = "Redo " + doc_.redoLabel();
    if (ImGui::MenuItem(u.c_str(), "Ctrl+Z", false, doc_.canUndo())) doc_.undo();
    if (ImGui::MenuItem(r.c_str(), "Ctrl+Y", false, doc_.canRedo())) doc_.redo();
    ImGui::EndMenu();
  }
  if (ImGui::BeginMenu("Windows")) {
    ImGui::MenuItem("Feather designer", nullptr, &view_.showDesigner);
    ImGui::MenuItem("Scene JSON", nullptr, &view_.showJsonInspector);
    ImGui::MenuItem("Help", nullptr, &view_.showHelp);
    ImGui::MenuItem("Hide panels", "Tab", &view_.hidePanels);
    ImGui::EndMenu();
  }
  if (doc_.hasScene()) {
    const std::string title = doc_.scene().name + (doc_.modified() ? " *" : "") +
                              (doc_.path().empty() ? "  (not saved yet)" : "  " + doc_.path());
    ImGui::TextDisabled("%s", title.c_str());
  }
  ImGui::EndMainMenuBar();
}

void App::panelColumn() {
  const ImGuiViewport* vp = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(vp->WorkPos, ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(view_.viewOrigin.x, vp->WorkSize.y - kStatusHeight), ImGuiCond_Always);
  // Resizable from its right edge: the width it ends the frame with lays out the next frame.
  ImGui::SetNextWindowSizeConstraints(ImVec2(260.0f, 0.0f), ImVec2(0.7f * vp->WorkSize.x, FLT_MAX));
  ImGui::Begin("Panels", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoTitleBar |
                   ImGuiWindowFlags_NoBringToFrontOnFocus);
  if (!view_.hidePanels) view_.panelWidth = ImGui::GetWindowWidth();
  if (!doc_.hasScene()) {
    ImGui::TextWrapped("No scene. Open a scene file (.json) or a bare mesh (.obj, .ply, .off, .stl).");
    if (ImGui::Button("Open...")) dialogs_.showOpen();
    if (ImGui::IsWindowAppearing()) dialogs_.recent().load();
    if (!dialogs_.recent().list().empty()) ImGui::TextDisabled("Recent:");
    for (const auto& r : dialogs_.recent().list())
      if (ImGui::Selectable(r.c_str())) dialogs_.requestOpen(r);
    ImGui::End();
    return;
  }
  PanelContext& ctx = panels_;
  // Scripts can open and close headers (panelRequests); a request applies once.
  auto header = [&](const char* name, bool defaultOpen) {
    auto it = view_.panelRequests.find(name);
    if (it == view_.panelRequests.end()) it = view_.panelRequests.find("*");
    if (it != view_.panelRequests.end()) ImGui::SetNextItemOpen(it->second != 0);
    return ImGui::CollapsingHeader(name, defaultOpen ? ImGuiTreeNodeFlags_DefaultOpen : 0);
  };
  // Each panel body is guarded on its own: an exception from one shows in the error modal, and the
  // other panels, the window and the frame go on.
  auto panel = [&](const char* name, bool defaultOpen, void (*draw)(PanelContext&)) {
    if (header(name, defaultOpen)) guardedUi(name, [&] { draw(ctx); });
  };
  panel("View", true, drawViewPanel);
  panel("Scene", false, drawScenePanel);
  if (header("Feather designer", false)) ImGui::Checkbox("Show the designer window", &view_.showDesigner);
  panel("Tracts", false, drawTractsPanel);
  panel("Follicles", false, drawFolliclesPanel);
  panel("Key feathers", false, drawKeyFeathersPanel);
  panel("Directions", false, drawDirectionsPanel);
  panel("Packing", false, drawPackingPanel);
  panel("Timeline", true, drawTimelinePanel);
  panel("Expressive controls", false, drawControlsPanel);
  panel("Skeleton", false, drawSkeletonPanel);
  panel("Render", false, drawRenderPanel);
  if (header("Stage timings", false)) {
    const Snapshot& s = doc_.snapshot();
    for (size_t i = 0; i < pipeline::kStageCount; ++i)
      ImGui::Text("%-12s %8.3f s", pipeline::stageName(pipeline::Stage(i)), s.stageSeconds[i]);
    ImGui::Text("%-12s %8.3f s", "view render", viewport_.lastRenderSeconds());
  }
  view_.panelRequests.clear();
  ImGui::End();
}

void App::sceneJsonWindow() {
  ImGui::SetNextWindowPos(ImVec2(view_.viewOrigin.x + 24, view_.viewOrigin.y + 24), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(560, 620), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Scene JSON", &view_.showJsonInspector)) {
    ImGui::End();
    return;
  }
  static JsonTextState state;
  Json j = sceneJson(doc_.scene());
  ImGui::TextDisabled("the whole scene (absolute paths); Apply re-reads it strictly");
  if (jsonTextEditor("scene", j, state, ImGui::GetContentRegionAvail().y - 60)) {
    try {
      pipeline::Scene next = pipeline::sceneFromJson(j, doc_.scene().file);
      keepPaintedDensity(doc_.scene(), next);
      doc_.edit("scene JSON", [&](pipeline::Scene& s) { s = next; });
    } catch (const std::exception& e) {
      dialogs_.showError(e.what());
    }
  }
  ImGui::End();
}

void App::helpWindow() {
  ImGui::SetNextWindowPos(ImVec2(view_.viewOrigin.x + 24, view_.viewOrigin.y + 24), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(620, 560), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Help", &view_.showHelp)) {
    ImGui::End();
    return;
  }
  ImGui::TextWrapped(
      "Mouse: left drag orbits, right or middle drag (or shift + left) pans, the wheel zooms. F frames all, "
      "Ctrl+Z / Ctrl+Y undo and redo, Ctrl+S saves, Ctrl+O opens, Space plays the timeline, Esc ends a tool.\n"
      "Click a handle to select it (drag moves it, Delete removes it); Ctrl + drag boxes feathers and handles "
      "(Delete removes the boxed handles). A selected control shows its offset gizmo, a selected skeleton joint "
      "its rotation rings: drag them; K keys the joint, else the control, at the current time.\n"
      "Edits re-run only the stages after them, in the background; the status bar shows progress and "
      "Cancel. docs/viewer.md has the details.");
  ImGui::Separator();
  ImGui::TextUnformatted(scriptHelp());
  ImGui::End();
}

void App::scratchboardWindow() {
  ImGui::SetNextWindowPos(ImVec2(view_.viewOrigin.x + 24, view_.viewOrigin.y + 24), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(520, 460), ImGuiCond_FirstUseEver);
  ImGui::Begin("Scratchboard preview");
  const bool ready = doc_.upToDate() && doc_.idlePipeline();
  if (ImGui::Button("Render from this view") && ready) {
    try {
      pipeline::Pipeline& p = *doc_.idlePipeline();
      render::ScratchboardSettings ss;
      ss.width = std::max(64, viewport_.framebufferSize().x / 2);
      ss.height = std::max(64, viewport_.framebufferSize().y / 2);
      const render::Image img = render::renderScratchboard(p.coatMesh().mesh, p.skinTriMesh(), camera_.camera(),
                                                           render::sceneLights(doc_.scene()), ss);
      if (!scratchTexture_) scratchTexture_ = std::make_unique<render::ImageTexture>(*context_);
      scratchTexture_->upload(img);
      scratchError_.clear();
    } catch (const std::exception& e) {
      scratchError_ = e.what();
    }
  }
  if (!ready) {
    ImGui::SameLine();
    ImGui::TextDisabled("(waiting for the evaluation)");
  }
  if (!scratchError_.empty()) ImGui::TextColored(ImVec4(1, 0.4f, 0.3f, 1), "%s", scratchError_.c_str());
  if (scratchTexture_ && scratchTexture_->id()) {
    const float w = ImGui::GetContentRegionAvail().x;
    ImGui::Image(reinterpret_cast<ImTextureID>(static_cast<intptr_t>(scratchTexture_->id())),
                 ImVec2(w, w * float(scratchTexture_->height()) / float(std::max(scratchTexture_->width(), 1))));
  }
  ImGui::End();
}

}  // namespace pteryla::viewer
