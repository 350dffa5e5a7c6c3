#pragma once
// Feather growth and wear (Streit 2003, 5.2.5, 8.1, Fig. 8.1): a feather of a given age is the mature
// definition with its parameters interpolated on a staggered schedule. The schedule is data, a table of
// ramps (parameter, start age, end age, easing), so other growth rates can be given (docs/growth.md).
//
// Ages: 0 = feather primordium (zero length), 1 = the mature, open feather (featherAtAge returns the
// definition unchanged), above 1 = wear (barbs shorten, splits appear), e.g. up to 2.
//
// Each ramp maps age to a weight in [0, 1]: 0 up to `start`, 1 from `end` on, eased in between.
// Growth parameters (weight 1 = mature):
//   shaft_length      calamus and rachis length (barb attachments keep their final rachis positions:
//                     spacing scales with the shaft, so the barb count never changes)
//   shaft_width       rachis (and so calamus) width
//   barb_length       barb length; barbs lengthen closed, parallel to the shaft, pointing to the tip
//   opening           the migrating pin key barb, from the rachis tip (0) to the base (1): barbs
//                     distal to it are open, barbs proximal to it stay closed in the sheath
//   barb_angle        open barbs turn from 0 (closed, along the shaft; the thesis's 180 degrees) to
//                     their final angle
//   pin_key_barbs     removal of the closed pin key barbs below the opening front (1 = removed)
//   key_barbs         open barbs change from straight to the real key barb shapes
//   rachis_curvature  lateral and ventral-dorsal rachis curvature (and split openings)
//   sheath            sheath shedding, tip to base (1 = shed); drives the per-vertex `sheath` attribute
// Wear parameters (weight 0 at age 1, must start at age >= 1):
//   wear_length       barbs shorten by up to GrowthSchedule::wearMaxShortening of their length
//   wear_splits       up to GrowthSchedule::wearMaxSplits extra splits per vane
// A parameter without a ramp is complete at every age (growth 1, wear 0).
#include <array>
#include <string>
#include <vector>

#include "pteryla/core/json.hpp"
#include "pteryla/feather/params.hpp"

namespace pteryla::feather {

enum class GrowthParam : uint8_t {
  ShaftLength,
  ShaftWidth,
  BarbLength,
  Opening,
  BarbAngle,
  PinKeyBarbs,
  KeyBarbs,
  RachisCurvature,
  Sheath,
  WearLength,
  WearSplits,
};
inline constexpr size_t kGrowthParamCount = 11;
const char* growthParamName(GrowthParam p);  // JSON name, e.g. "shaft_length"
bool isWearParam(GrowthParam p);

enum class Easing : uint8_t { Linear, Smooth, EaseIn, EaseOut, Step };
const char* easingName(Easing e);  // "linear", "smooth", "ease_in", "ease_out", "step"

struct GrowthRamp {
  GrowthParam parameter = GrowthParam::ShaftLength;
  double start = 0;  // age
  double end = 1;    // age, >= start
  Easing easing = Easing::Linear;
  // 0 for age <= start (unless age >= end), 1 for age >= end, eased in between.
  double weight(double age) const;
  bool operator==(const GrowthRamp& o) const {
    return parameter == o.parameter && start == o.start && end == o.end && easing == o.easing;
  }
};

struct GrowthSchedule {
  std::vector<GrowthRamp> ramps;   // at most one per parameter
  double wearMaxShortening = 0.3;  // fraction of barb length lost at full wear, [0, 1]
  int wearMaxSplits = 6;           // extra splits per vane at full wear
  double sheathBand = 0.05;        // width of the sheath edge along the shaft (fraction of length)
  bool operator==(const GrowthSchedule& o) const {
    return ramps == o.ramps && wearMaxShortening == o.wearMaxShortening && wearMaxSplits == o.wearMaxSplits &&
           sheathBand == o.sheathBand;
  }
  bool operator!=(const GrowthSchedule& o) const { return !(*this == o); }
  // Does any age above 1 differ from age 1 (a wear ramp with an effect)?
  bool wears() const;
};

// Thesis schedule (Fig. 8.1): shaft length and width over [0, 0.3]; barb length over [0.3, 0.5];
// opening and barb angle over [0.5, 0.8] (the sheath sheds over the same window); pin key barbs
// removed, key barb shapes and rachis curvature over [0.8, 1]; wear over [1, 2].
const GrowthSchedule& defaultGrowthSchedule();
// The schedule a feather grows and wears by: its own (FeatherParams::growth) or the default.
const GrowthSchedule& growthScheduleOf(const FeatherParams& p);

// Throws pteryla::Error (element "growth.ramps[i]...") for bad ranges, duplicate parameters, growth
// ramps ending after age 1 or wear ramps in effect at age 1.
void validateGrowthSchedule(const GrowthSchedule& s, const std::string& file = {});

// Weight of every parameter at `age`.
struct GrowthState {
  std::array<double, kGrowthParamCount> w{};
  double operator[](GrowthParam p) const { return w[static_cast<size_t>(p)]; }
  double& operator[](GrowthParam p) { return w[static_cast<size_t>(p)]; }
  bool grown() const;                          // every growth weight is 1
  bool mature(const GrowthSchedule& s) const;  // grown and wear has no effect
};
GrowthState growthStateAt(double age, const GrowthSchedule& s = defaultGrowthSchedule());

// Smallest length scale used for ages where the shaft weight is 0: lengths and spacing are scaled by
// max(weight, kMinGrowthScale) so the result stays a valid FeatherParams (degenerate, ~zero length).
inline constexpr double kMinGrowthScale = 1e-6;

// The feather of `def` at `age` (finite; clamped below at 0). age >= 1 without wear returns `def`
// exactly. The afterfeather grows on the same schedule. Throws Error for a non-finite age. A growing
// (not grown) state of a feather whose generator has a grow hook (generator.hpp) is grown by it: a
// helical feather by the helical model (helical.hpp, growHelical); wear is the shared path.
FeatherParams featherAtAge(const FeatherParams& def, double age, const GrowthSchedule& s = defaultGrowthSchedule());
FeatherParams featherAtState(const FeatherParams& def, const GrowthState& st, const GrowthSchedule& s);

// Sheath weight of a point at normalized pin-pose position v (uvGrowth.v: 0 base .. 1 tip) for the
// `sheath` growth weight `shed` (0 all sheathed, 1 shed): 1 inside the sheath, 0 outside, linear over
// `band`.
double sheathWeight(double v, double shed, double band);

// JSON (docs/growth.md): the "growth" object. Parameters not listed keep the default ramp.
// readGrowthSchedule calls r.finish().
GrowthSchedule readGrowthSchedule(JsonReader& r);
GrowthSchedule loadGrowthSchedule(const std::string& path);  // file whose top level has "growth"
Json growthScheduleToJson(const GrowthSchedule& s);

}  // namespace pteryla::feather
