// The scene file's "packing" object (docs/packing.md): packing settings of Streit 2003, 6.3.2-6.3.3 and
// the styling selections of 8.3.
#include <cmath>
#include <limits>

#include "pteryla/coat/pack.hpp"
#include "pteryla/core/error.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat {

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

PackingSettings parsePackingSettings(JsonReader& r) {
  PackingSettings settings;
  PackOptions& o = settings.options;
  o.method =
      r.oneOf("method", "drape", {"drape", "height_field"}) == "drape" ? PackMethod::Drape : PackMethod::HeightField;
  o.drapeMaxSlopeDeg = r.number("drape_max_slope_deg", o.drapeMaxSlopeDeg, 0.0, 60.0);
  o.clearance = r.number("clearance", 0.0, 0.0, kInf);
  o.skinClearance = r.number("skin_clearance", 0.0, 0.0, kInf);
  o.minElevation = r.number("min_elevation_deg", 0.0, -90.0, 180.0) * kDeg;
  o.maxElevation = r.number("max_elevation_deg", 90.0, -90.0, 180.0) * kDeg;
  if (o.maxElevation < o.minElevation) r.fail("max_elevation_deg", "must not be below min_elevation_deg");
  o.conflictElevation = r.number("conflict_elevation_deg", o.conflictElevation / kDeg, 0.0, 180.0) * kDeg;
  o.openingAge = r.number("opening_age", o.openingAge, 0.0, 1.0);
  o.baseAllowance = r.number("base_allowance", o.baseAllowance, 0.0, 1.0);
  o.shaftBand = r.number("shaft_band", o.shaftBand, 0.0, 1.0);
  o.keyBarbsPerVane = static_cast<int>(r.integer("key_barbs_per_vane", o.keyBarbsPerVane, 2, 64));
  o.barbSamples = static_cast<int>(r.integer("barb_samples", o.barbSamples, 1, 64));
  o.shaftSamples = static_cast<int>(r.integer("shaft_samples", o.shaftSamples, 2, 256));
  o.heightFieldBins = static_cast<int>(r.integer("height_field_bins", o.heightFieldBins, 4, 4096));
  o.barbFieldBins = static_cast<int>(r.integer("barb_field_bins", o.barbFieldBins, 2, 1024));
  o.maxFlatten = r.number("max_flatten", o.maxFlatten, 0.0, 2.0);
  o.keepBarbArcLength = r.boolean("keep_barb_arc_length", o.keepBarbArcLength);
  o.maxBarbLift = r.number("max_barb_lift_deg", o.maxBarbLift / kDeg, 0.0, 90.0) * kDeg;
  o.elevateBarbs = r.boolean("elevate_barbs", o.elevateBarbs);
  o.extendShaft = r.boolean("extend_shaft", o.extendShaft);
  o.skin = r.boolean("skin", o.skin);
  o.skinSampleSpacing = r.number("skin_sample_spacing", 0.0, 0.0, 1e6);
  o.threads = static_cast<int>(r.integer("threads", 0, 0, 1024));
  settings.moultOver = r.oneOf("moult_pack", "over", {"over", "full"}) == "over";
  settings.poseTolerance = r.number("pose_tolerance", settings.poseTolerance, 0.0, 1.0);
  settings.carryPosedDrape = r.oneOf("posed_drape", "carry", {"carry", "full"}) == "carry";
  for (JsonReader& s : r.objects("styling")) settings.styling.push_back(parseStyleSelection(s));
  r.finish();
  return settings;
}

Json packingSettingsToJson(const PackingSettings& settings) {
  const PackOptions& o = settings.options;
  const PackOptions d;
  Json j = Json::object();
  if (o.method != d.method) j["method"] = o.method == PackMethod::Drape ? "drape" : "height_field";
  if (o.drapeMaxSlopeDeg != d.drapeMaxSlopeDeg) j["drape_max_slope_deg"] = o.drapeMaxSlopeDeg;
  if (o.clearance != d.clearance) j["clearance"] = o.clearance;
  if (o.skinClearance != d.skinClearance) j["skin_clearance"] = o.skinClearance;
  if (o.minElevation != d.minElevation) j["min_elevation_deg"] = o.minElevation / kDeg;
  if (o.maxElevation != d.maxElevation) j["max_elevation_deg"] = o.maxElevation / kDeg;
  if (o.conflictElevation != d.conflictElevation) j["conflict_elevation_deg"] = o.conflictElevation / kDeg;
  if (o.openingAge != d.openingAge) j["opening_age"] = o.openingAge;
  if (o.baseAllowance != d.baseAllowance) j["base_allowance"] = o.baseAllowance;
  if (o.shaftBand != d.shaftBand) j["shaft_band"] = o.shaftBand;
  if (o.keyBarbsPerVane != d.keyBarbsPerVane) j["key_barbs_per_vane"] = o.keyBarbsPerVane;
  if (o.barbSamples != d.barbSamples) j["barb_samples"] = o.barbSamples;
  if (o.shaftSamples != d.shaftSamples) j["shaft_samples"] = o.shaftSamples;
  if (o.heightFieldBins != d.heightFieldBins) j["height_field_bins"] = o.heightFieldBins;
  if (o.barbFieldBins != d.barbFieldBins) j["barb_field_bins"] = o.barbFieldBins;
  if (o.maxFlatten != d.maxFlatten) j["max_flatten"] = o.maxFlatten;
  if (o.keepBarbArcLength != d.keepBarbArcLength) j["keep_barb_arc_length"] = o.keepBarbArcLength;
  if (o.maxBarbLift != d.maxBarbLift) j["max_barb_lift_deg"] = o.maxBarbLift / kDeg;
  if (o.elevateBarbs != d.elevateBarbs) j["elevate_barbs"] = o.elevateBarbs;
  if (o.extendShaft != d.extendShaft) j["extend_shaft"] = o.extendShaft;
  if (o.skin != d.skin) j["skin"] = o.skin;
  if (o.skinSampleSpacing != d.skinSampleSpacing) j["skin_sample_spacing"] = o.skinSampleSpacing;
  if (o.threads != d.threads) j["threads"] = o.threads;
  if (settings.moultOver != PackingSettings().moultOver) j["moult_pack"] = settings.moultOver ? "over" : "full";
  if (settings.poseTolerance != PackingSettings().poseTolerance) j["pose_tolerance"] = settings.poseTolerance;
  if (settings.carryPosedDrape != PackingSettings().carryPosedDrape)
    j["posed_drape"] = settings.carryPosedDrape ? "carry" : "full";
  if (!settings.styling.empty()) {
    Json a = Json::array();
    for (const auto& s : settings.styling) a.push_back(styleSelectionToJson(s));
    j["styling"] = a;
  }
  return j;
}

// A field added to PackOptions must be compared here (the size tells).
static_assert(sizeof(PackOptions) == 152, "compare the new PackOptions field in packing::sameKnobs");

bool packing::sameKnobs(const PackOptions& a, const PackOptions& b) {
  return a.method == b.method && a.drapeMaxSlopeDeg == b.drapeMaxSlopeDeg && a.clearance == b.clearance &&
         a.skinClearance == b.skinClearance && a.minElevation == b.minElevation && a.maxElevation == b.maxElevation &&
         a.conflictElevation == b.conflictElevation && a.openingAge == b.openingAge &&
         a.baseAllowance == b.baseAllowance && a.shaftBand == b.shaftBand && a.keyBarbsPerVane == b.keyBarbsPerVane &&
         a.barbSamples == b.barbSamples && a.shaftSamples == b.shaftSamples && a.heightFieldBins == b.heightFieldBins &&
         a.barbFieldBins == b.barbFieldBins && a.maxFlatten == b.maxFlatten &&
         a.keepBarbArcLength == b.keepBarbArcLength && a.maxBarbLift == b.maxBarbLift &&
         a.elevateBarbs == b.elevateBarbs && a.extendShaft == b.extendShaft && a.skin == b.skin &&
         a.skinSampleSpacing == b.skinSampleSpacing && a.captureFields == b.captureFields;
}

PackOptions withDefaultSampling(PackOptions o) {
  const PackOptions d;
  o.keyBarbsPerVane = d.keyBarbsPerVane;
  o.barbSamples = d.barbSamples;
  o.shaftSamples = d.shaftSamples;
  o.barbFieldBins = d.barbFieldBins;
  o.heightFieldBins = d.heightFieldBins;
  o.skinSampleSpacing = d.skinSampleSpacing;
  return o;
}

}  // namespace pteryla::coat
