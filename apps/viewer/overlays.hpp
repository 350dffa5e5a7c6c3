#pragma once
// Overlays on the 3D view, drawn with ImGui draw lists projected to the screen (so the viewer issues
// no GL of its own for them): follicles, feather directions, the selected tract, key feathers, styling
// vectors / body axis, packing brushes and expressive controls.
#include <cstdint>
#include <string>

#include <imgui.h>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "camera_controller.hpp"
#include "panels.hpp"

namespace pteryla::viewer {

// A world point to window pixels in the 3D view rectangle (false behind the camera).
struct Projector {
  const render::Camera& cam;
  glm::ivec2 vp;
  glm::vec2 origin;
  bool operator()(const glm::vec3& p, ImVec2& out) const {
    glm::vec2 q;
    if (!projectToPixel(cam, p, vp, q)) return false;
    out = ImVec2(origin.x + q.x, origin.y + q.y);
    return true;
  }
  // Does a surface at p with normal n face the camera?
  bool facing(const glm::vec3& p, const glm::vec3& n) const {
    const glm::vec3 d = cam.eye - p;
    return n.x * d.x + n.y * d.y + n.z * d.z >= 0.0f;
  }
};

// Draws into the view rectangle ctx.view.viewOrigin / viewSize.
void drawOverlays(ImDrawList* dl, PanelContext& ctx);
// overlays_paint.cpp: face selection, the stroke, the density map and the brush (called by drawOverlays).
void drawPaintOverlays(ImDrawList* dl, PanelContext& ctx);

// What the viewer says of feather `i` (hover tooltip, the `selection` script command): index, tract,
// feather type (its material's name), follicle id, elevation in degrees, age, presence.
struct FeatherReadout {
  int feather = -1;
  std::string tract, type;
  uint64_t follicleId = 0;
  double elevationDeg = 0, age = 1;
  bool present = true;
};
FeatherReadout featherReadout(const Snapshot& s, int feather);
std::string readoutText(const FeatherReadout& r);  // one line per value, for a tooltip

// Length of drawn direction arrows, scene units (a fraction of the skin's size).
float overlayArrowLength(const Snapshot& s);

}  // namespace pteryla::viewer
