// The Scene panel's "Render frames" section: the timeline range (or any) rendered to DIR/frame_NNNN.png
// in the background with progress and Cancel (frame_render.cpp does the work).
#include <imgui.h>
#include <imgui_stdlib.h>

#include <cmath>
#include <string>

#include "panels.hpp"

namespace pteryla::viewer {

void drawFramesSection(PanelContext& ctx) {
  ViewState& v = ctx.view;
  static std::string dir = "frames";
  static float from = 0.0f, to = 1.0f, fps = 24.0f;
  static bool fromTimeline = true;
  ImGui::Checkbox("the timeline's range and step", &fromTimeline);
  if (fromTimeline) {
    from = v.timeStart;
    to = v.timeEnd;
    fps = v.timeStep > 0 ? 1.0f / v.timeStep : 24.0f;
  }
  ImGui::SetNextItemWidth(90);
  ImGui::InputFloat("from", &from, 0, 0, "%.3g");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(90);
  ImGui::InputFloat("to", &to, 0, 0, "%.3g");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(70);
  ImGui::InputFloat("fps", &fps, 0, 0, "%.3g");
  ImGui::InputText("directory", &dir);
  std::string scripted;
  const bool fromScript = uiRequestedText(ctx, "Scene", "render frames", scripted);
  if (v.framesRunning) {
    const float done = v.framesTotal ? float(v.framesDone) / float(v.framesTotal) : 0.0f;
    const std::string label = std::to_string(v.framesDone) + " / " + std::to_string(v.framesTotal);
    ImGui::ProgressBar(done, ImVec2(-80, 0), label.c_str());
    ImGui::SameLine();
    if (ImGui::Button("Cancel##frames") || uiRequested(ctx, "Scene", "cancel frames")) v.frameCancel = true;
  } else if (ImGui::Button("Render frames") || fromScript) {
    ViewState::FrameRequest rq;
    rq.dir = fromScript && !scripted.empty() ? scripted : dir;
    rq.from = from;
    rq.to = to;
    rq.fps = fps;
    v.frameRequest = rq;
  }
  const pipeline::Scene& s = ctx.doc.scene();
  ImGui::TextDisabled("%d frames at %dx%d, render LOD %.2g, the scene camera",
                      to >= from && fps > 0 ? int(std::floor((to - from) * fps + 1e-6)) + 1 : 0, s.render.width,
                      s.render.height, s.render.lod);
  if (!v.framesStatus.empty()) ImGui::TextWrapped("%s", v.framesStatus.c_str());
}

}  // namespace pteryla::viewer
