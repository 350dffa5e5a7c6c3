#pragma once
// "Colour by" view modes (#28 "see the problems"): the coat drawn in flat colours per feather instead of
// its materials, each mode with a legend. Pure data (no GL, no ImGui; tests/viewer/test_colour_by.cpp);
// the App turns the palette into render materials and the per-feather entries into draw ranges.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace pteryla::viewer {

enum class ColourBy {
  Material,   // the feathers' own look (no override)
  Problems,   // the last check: crossing another feather, under the skin, both, clean
  Elevation,  // packed elevation, degrees, in fixed bins
  Layer,      // layer (packing) order, bottom to top, in eighths
  Tract,      // one colour per tract
  Age,        // growth and wear age (growth.md): collar, unfurling, opening, mature, worn, old
  Coverage,   // the last check's bare skin: skin faces by their uncovered share (feathers grey)
};

const std::vector<ColourBy>& allColourModes();
const char* colourByName(ColourBy mode);  // "material", "problems", ...
std::optional<ColourBy> colourByFromName(const std::string& name);

struct LegendEntry {
  glm::vec3 colour{0.0f};
  std::string label;
  size_t feathers = 0;  // present feathers with this colour
  size_t faces = 0;     // skin faces with this colour (coverage)
};

// What a mode reads, per feather (indexed like Pipeline::feathers()); arrays may be shorter (their
// feathers then count as missing that value: grey "no data").
struct ColourInputs {
  size_t featherCount = 0;
  std::vector<float> elevation;  // radians
  std::vector<uint32_t> tract;   // tract index
  std::vector<std::string> tractNames;
  std::vector<uint32_t> layerOrder;  // feather indices, bottom layer first
  std::vector<float> age;
  std::vector<uint8_t> present;
  bool checked = false;  // Problems: a check ran on this coat
  std::vector<uint32_t> intersecting, penetrating;
  // Coverage: per skin triangle, the check's coverage samples and the uncovered ones; the coverage.
  std::vector<uint32_t> faceSamples, faceUncovered;
  double coverage = -1;
};

struct FeatherColouring {
  std::vector<LegendEntry> legend;     // one per palette colour, in legend order
  std::vector<uint32_t> featherEntry;  // per feather: its legend entry
  std::string note;                    // shown under the legend (e.g. "run Check first")
};

// Throws nothing; Material gives an empty colouring.
FeatherColouring colourFeathers(ColourBy mode, const ColourInputs& in);

// Coverage: how bare a skin face is from its samples: 0 covered (or not sampled: outside the tracts),
// 1 partly bare (10 - 50% of its samples uncovered), 2 bare (more than half). Its colour on the skin.
int coverageBin(uint32_t samples, uint32_t uncovered);
glm::vec3 coverageColour(int bin);

}  // namespace pteryla::viewer
