#pragma once
// Overlays on the 3D view, drawn with ImGui draw lists projected to the screen (so the viewer issues
// no GL of its own for them): follicles, feather directions, the selected tract, key feathers, styling
// vectors / body axis, packing brushes and expressive controls.
#include <cstdint>
#include <string>

#include <glm/vec2.hpp>

#include "panels.hpp"

struct ImDrawList;

namespace pteryla::viewer {

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
