#include "colour_by.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace pteryla::viewer {
namespace {

constexpr glm::vec3 kNoData{0.45f, 0.45f, 0.45f};

// Eight steps of a perceptually ordered ramp (dark blue, teal, green, yellow), close to viridis.
const glm::vec3 kRamp[8] = {{0.27f, 0.00f, 0.33f}, {0.28f, 0.19f, 0.50f}, {0.21f, 0.36f, 0.55f}, {0.15f, 0.50f, 0.56f},
                            {0.12f, 0.63f, 0.53f}, {0.29f, 0.76f, 0.43f}, {0.63f, 0.85f, 0.22f}, {0.99f, 0.91f, 0.14f}};

// Twelve distinct categorical colours for tracts.
const glm::vec3 kCategories[12] = {{0.90f, 0.33f, 0.26f}, {0.26f, 0.55f, 0.85f}, {0.40f, 0.75f, 0.32f},
                                   {0.95f, 0.70f, 0.20f}, {0.62f, 0.38f, 0.80f}, {0.25f, 0.80f, 0.80f},
                                   {0.90f, 0.45f, 0.70f}, {0.60f, 0.50f, 0.30f}, {0.75f, 0.85f, 0.35f},
                                   {0.35f, 0.35f, 0.75f}, {0.95f, 0.55f, 0.40f}, {0.55f, 0.75f, 0.60f}};

std::string degrees(double a, double b) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%g - %g deg", a, b);
  return buf;
}

}  // namespace

const std::vector<ColourBy>& allColourModes() {
  static const std::vector<ColourBy> all = {ColourBy::Material, ColourBy::Problems, ColourBy::Elevation,
                                            ColourBy::Layer,    ColourBy::Tract,    ColourBy::Age,
                                            ColourBy::Coverage};
  return all;
}

const char* colourByName(ColourBy m) {
  switch (m) {
    case ColourBy::Material:
      return "material";
    case ColourBy::Problems:
      return "problems";
    case ColourBy::Elevation:
      return "elevation";
    case ColourBy::Layer:
      return "layer";
    case ColourBy::Tract:
      return "tract";
    case ColourBy::Age:
      return "age";
    case ColourBy::Coverage:
      return "coverage";
  }
  return "material";
}

std::optional<ColourBy> colourByFromName(const std::string& name) {
  for (ColourBy m : allColourModes())
    if (name == colourByName(m)) return m;
  return std::nullopt;
}

FeatherColouring colourFeathers(ColourBy mode, const ColourInputs& in) {
  FeatherColouring out;
  if (mode == ColourBy::Material) return out;
  const size_t n = in.featherCount;
  out.featherEntry.assign(n, 0);
  auto add = [&](glm::vec3 c, std::string label) {
    out.legend.push_back({c, std::move(label), 0});
    return uint32_t(out.legend.size() - 1);
  };
  switch (mode) {
    case ColourBy::Material:
      break;
    case ColourBy::Problems: {
      const uint32_t clean = add({0.78f, 0.78f, 0.74f}, "clean");
      const uint32_t crossing = add({0.92f, 0.16f, 0.14f}, "crosses another feather");
      const uint32_t under = add({0.90f, 0.20f, 0.90f}, "passes under the skin");
      const uint32_t both = add({1.00f, 0.55f, 0.05f}, "both");
      std::vector<uint8_t> flags(n, 0);
      for (uint32_t i : in.intersecting)
        if (i < n) flags[i] |= 1;
      for (uint32_t i : in.penetrating)
        if (i < n) flags[i] |= 2;
      for (size_t i = 0; i < n; ++i)
        out.featherEntry[i] = flags[i] == 3 ? both : flags[i] == 2 ? under : flags[i] == 1 ? crossing : clean;
      if (!in.checked) out.note = "no check of this coat yet: press Check (Follicles panel) or run 'check'";
      break;
    }
    case ColourBy::Elevation: {
      static const double edges[9] = {0, 5, 10, 15, 20, 30, 45, 60, 90};
      for (int b = 0; b < 8; ++b) add(kRamp[b], degrees(edges[b], edges[b + 1]));
      const uint32_t none = add(kNoData, "no elevation");
      for (size_t i = 0; i < n; ++i) {
        if (i >= in.elevation.size() || !std::isfinite(in.elevation[i])) {
          out.featherEntry[i] = none;
          continue;
        }
        const double d = double(in.elevation[i]) * 180.0 / 3.14159265358979323846;
        int b = 0;
        while (b < 7 && d >= edges[b + 1]) ++b;
        out.featherEntry[i] = uint32_t(b);
      }
      break;
    }
    case ColourBy::Layer: {
      static const char* names[8] = {"bottom eighth", "2nd eighth", "3rd eighth", "4th eighth",
                                     "5th eighth",    "6th eighth", "7th eighth", "top eighth"};
      for (int b = 0; b < 8; ++b) add(kRamp[b], names[b]);
      const uint32_t none = add(kNoData, "not in the layer order");
      std::fill(out.featherEntry.begin(), out.featherEntry.end(), none);
      const size_t m = in.layerOrder.size();
      for (size_t r = 0; r < m; ++r)
        if (in.layerOrder[r] < n) out.featherEntry[in.layerOrder[r]] = uint32_t(std::min<size_t>(7, r * 8 / m));
      break;
    }
    case ColourBy::Tract: {
      size_t tracts = in.tractNames.size();
      for (uint32_t t : in.tract) tracts = std::max<size_t>(tracts, size_t(t) + 1);
      for (size_t t = 0; t < tracts; ++t)
        add(kCategories[t % 12], t < in.tractNames.size() ? in.tractNames[t] : "tract " + std::to_string(t));
      const uint32_t none = add(kNoData, "no tract");
      for (size_t i = 0; i < n; ++i) out.featherEntry[i] = i < in.tract.size() ? in.tract[i] : none;
      if (tracts > 12) out.note = "more than 12 tracts: colours repeat";
      break;
    }
    case ColourBy::Age: {
      const uint32_t collar = add({0.55f, 0.60f, 0.90f}, "growing on the collar (< 0.5)");
      const uint32_t unfurl = add({0.30f, 0.75f, 0.85f}, "unfurling (0.5 - 0.8)");
      const uint32_t opening = add({0.35f, 0.80f, 0.40f}, "opening (0.8 - 1)");
      const uint32_t mature = add({0.85f, 0.85f, 0.80f}, "mature (1)");
      const uint32_t worn = add({0.90f, 0.65f, 0.30f}, "wearing (1 - 1.5)");
      const uint32_t old = add({0.70f, 0.30f, 0.20f}, "old (> 1.5)");
      const uint32_t none = add(kNoData, "no age");
      for (size_t i = 0; i < n; ++i) {
        if (i >= in.age.size() || !std::isfinite(in.age[i])) {
          out.featherEntry[i] = none;
          continue;
        }
        const float a = in.age[i];
        out.featherEntry[i] = a < 0.5f    ? collar
                              : a < 0.8f  ? unfurl
                              : a < 1.0f  ? opening
                              : a == 1.0f ? mature
                              : a <= 1.5f ? worn
                                          : old;
      }
      break;
    }
    case ColourBy::Coverage: {
      add({0.62f, 0.62f, 0.60f}, "feathers");  // every feather: entry 0
      const uint32_t partly = add(coverageColour(1), "partly bare skin (10 - 50%)");
      const uint32_t bare = add(coverageColour(2), "bare skin (> 50%)");
      const size_t faces = std::min(in.faceSamples.size(), in.faceUncovered.size());
      for (size_t f = 0; f < faces; ++f) {
        const int b = coverageBin(in.faceSamples[f], in.faceUncovered[f]);
        if (b == 1) ++out.legend[partly].faces;
        if (b == 2) ++out.legend[bare].faces;
      }
      char buf[96];
      if (!in.checked) {
        out.note = "no check of this coat yet: press Check (Follicles panel) or run 'check'";
      } else if (in.coverage >= 0) {
        std::snprintf(buf, sizeof buf, "coverage %.1f%% of the tracts' skin", 100.0 * in.coverage);
        out.note = buf;
      }
      break;
    }
  }
  for (size_t i = 0; i < n; ++i)
    if (i >= in.present.size() || in.present[i]) ++out.legend[out.featherEntry[i]].feathers;
  return out;
}

int coverageBin(uint32_t samples, uint32_t uncovered) {
  if (samples == 0 || uncovered * 10u < samples) return 0;  // under 10% uncovered
  return uncovered * 2u > samples ? 2 : 1;
}

glm::vec3 coverageColour(int bin) {
  return bin == 2 ? glm::vec3(0.95f, 0.12f, 0.35f) : bin == 1 ? glm::vec3(1.0f, 0.62f, 0.10f) : glm::vec3(0.0f);
}

}  // namespace pteryla::viewer
