// Colour-by view modes (#28 "see the problems"): every feather lands in the entry its value says, the
// legend counts present feathers, and the problems mode says when there was no check.
#include <gtest/gtest.h>

#include <set>

#include "colour_by.hpp"

using namespace pteryla::viewer;

namespace {
ColourInputs fourFeathers() {
  ColourInputs in;
  in.featherCount = 4;
  in.present = {1, 1, 1, 0};
  return in;
}
}  // namespace

TEST(ColourBy, NamesRoundTripAndMaterialIsNoOverride) {
  for (ColourBy m : allColourModes()) EXPECT_EQ(colourByFromName(colourByName(m)), m);
  EXPECT_FALSE(colourByFromName("rainbow"));
  EXPECT_TRUE(colourFeathers(ColourBy::Material, fourFeathers()).legend.empty());
}

TEST(ColourBy, ElevationBinsAreDegreesWithTheirLabels) {
  ColourInputs in = fourFeathers();
  const double rad = 3.14159265358979323846 / 180.0;
  in.elevation = {float(2 * rad), float(12 * rad), float(50 * rad), float(89 * rad)};
  const FeatherColouring c = colourFeathers(ColourBy::Elevation, in);
  ASSERT_EQ(c.featherEntry.size(), 4u);
  EXPECT_EQ(c.legend[c.featherEntry[0]].label, "0 - 5 deg");
  EXPECT_EQ(c.legend[c.featherEntry[1]].label, "10 - 15 deg");
  EXPECT_EQ(c.legend[c.featherEntry[2]].label, "45 - 60 deg");
  EXPECT_EQ(c.legend[c.featherEntry[3]].label, "60 - 90 deg");
  // Counts are of present feathers: the fourth is moulted out.
  EXPECT_EQ(c.legend[c.featherEntry[3]].feathers, 0u);
  EXPECT_EQ(c.legend[c.featherEntry[0]].feathers, 1u);
  // Steeper is lighter on the ramp (its colours rise in brightness).
  auto lum = [&](size_t i) {
    const auto& k = c.legend[c.featherEntry[i]].colour;
    return 0.2126f * k.r + 0.7152f * k.g + 0.0722f * k.b;
  };
  EXPECT_LT(lum(0), lum(1));
  EXPECT_LT(lum(1), lum(2));
  // No elevation: grey "no elevation".
  in.elevation.resize(2);
  EXPECT_EQ(
      colourFeathers(ColourBy::Elevation, in).legend[colourFeathers(ColourBy::Elevation, in).featherEntry[3]].label,
      "no elevation");
}

TEST(ColourBy, LayerTractAndAge) {
  ColourInputs in = fourFeathers();
  in.layerOrder = {2, 0, 3, 1};  // feather 2 at the bottom, feather 1 on top
  FeatherColouring c = colourFeathers(ColourBy::Layer, in);
  EXPECT_EQ(c.legend[c.featherEntry[2]].label, "bottom eighth");
  EXPECT_EQ(c.legend[c.featherEntry[1]].label, "7th eighth");  // rank 3 of 4: 3 * 8 / 4 = 6
  in.tract = {0, 1, 1, 0};
  in.tractNames = {"spinal", "alar"};
  c = colourFeathers(ColourBy::Tract, in);
  EXPECT_EQ(c.legend[c.featherEntry[0]].label, "spinal");
  EXPECT_EQ(c.legend[c.featherEntry[1]].label, "alar");
  EXPECT_NE(c.legend[0].colour, c.legend[1].colour);
  in.age = {0.3f, 0.9f, 1.0f, 1.8f};
  c = colourFeathers(ColourBy::Age, in);
  EXPECT_EQ(c.legend[c.featherEntry[0]].label.rfind("growing on the collar", 0), 0u);
  EXPECT_EQ(c.legend[c.featherEntry[1]].label.rfind("opening", 0), 0u);
  EXPECT_EQ(c.legend[c.featherEntry[2]].label.rfind("mature", 0), 0u);
  EXPECT_EQ(c.legend[c.featherEntry[3]].label.rfind("old", 0), 0u);
  std::set<uint32_t> distinct(c.featherEntry.begin(), c.featherEntry.end());
  EXPECT_EQ(distinct.size(), 4u);
}

TEST(ColourBy, ProblemsFromTheCheckAndANoteWithoutOne) {
  ColourInputs in = fourFeathers();
  FeatherColouring c = colourFeathers(ColourBy::Problems, in);
  EXPECT_FALSE(c.note.empty()) << "no check: the legend says so";
  for (uint32_t e : c.featherEntry) EXPECT_EQ(c.legend[e].label, "clean");
  in.checked = true;
  in.intersecting = {0, 2};
  in.penetrating = {2, 1, 99};  // 99: not a feather of this coat, ignored
  c = colourFeathers(ColourBy::Problems, in);
  EXPECT_TRUE(c.note.empty());
  EXPECT_EQ(c.legend[c.featherEntry[0]].label, "crosses another feather");
  EXPECT_EQ(c.legend[c.featherEntry[1]].label, "passes under the skin");
  EXPECT_EQ(c.legend[c.featherEntry[2]].label, "both");
  EXPECT_EQ(c.legend[c.featherEntry[3]].label, "clean");
}

TEST(ColourBy, CoverageCountsBareSkinFacesAndGreysTheFeathers) {
  ColourInputs in = fourFeathers();
  // Six faces: unsampled, covered, 9% bare (covered), 10% (partly), 50% (partly), 51% (bare).
  in.faceSamples = {0, 20, 100, 100, 100, 100};
  in.faceUncovered = {0, 0, 9, 10, 50, 51};
  const FeatherColouring none = colourFeathers(ColourBy::Coverage, in);
  EXPECT_NE(none.note.find("no check"), std::string::npos);
  in.checked = true;
  in.coverage = 0.876;
  const FeatherColouring c = colourFeathers(ColourBy::Coverage, in);
  for (uint32_t e : c.featherEntry) EXPECT_EQ(c.legend[e].label, "feathers");
  EXPECT_EQ(c.legend[c.featherEntry[0]].feathers, 3u);
  size_t partly = 0, bare = 0;
  for (const LegendEntry& e : c.legend) {
    if (e.label.rfind("partly bare", 0) == 0) partly = e.faces;
    if (e.label.rfind("bare skin", 0) == 0) bare = e.faces;
  }
  EXPECT_EQ(partly, 2u);
  EXPECT_EQ(bare, 1u);
  EXPECT_NE(c.note.find("87.6%"), std::string::npos) << c.note;
  EXPECT_EQ(coverageBin(0, 0), 0);
  EXPECT_EQ(coverageBin(100, 9), 0);
  EXPECT_EQ(coverageBin(100, 10), 1);
  EXPECT_EQ(coverageBin(100, 50), 1);
  EXPECT_EQ(coverageBin(100, 51), 2);
  EXPECT_NE(coverageColour(2), coverageColour(1));
}
