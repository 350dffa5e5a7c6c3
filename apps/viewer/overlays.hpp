#pragma once
// Overlays on the 3D view, drawn with ImGui draw lists projected to the screen (so the viewer issues
// no GL of its own for them): follicles, feather directions, the selected tract, key feathers, styling
// vectors / body axis, packing brushes and expressive controls.
#include <glm/vec2.hpp>

#include "panels.hpp"

struct ImDrawList;

namespace pteryla::viewer {

// Draws into the view rectangle ctx.view.viewOrigin / viewSize.
void drawOverlays(ImDrawList* dl, PanelContext& ctx);

// Length of drawn direction arrows, scene units (a fraction of the skin's size).
float overlayArrowLength(const Snapshot& s);

}  // namespace pteryla::viewer
