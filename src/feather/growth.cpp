// Feather growth and wear, Streit 2003, 5.2.5 and 8.1 (Fig. 8.1): staggered interpolation of the feather
// parameters. The shaft grows first, barbs lengthen closed (parallel to the shaft, the thesis's 180
// degree barbs), then a straight pin key barb migrates from the tip to the base opening the vane behind
// it, and in the last 20% the closed pin key barbs give way to the real key barbs and the rachis curves.
// Wear (5.2.5) shortens barbs and adds splits.
#include "pteryla/feather/growth.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/generator.hpp"

namespace pteryla::feather {

namespace {

constexpr const char* kParamNames[kGrowthParamCount] = {
    "shaft_length", "shaft_width",      "barb_length", "opening",     "barb_angle", "pin_key_barbs",
    "key_barbs",    "rachis_curvature", "sheath",      "wear_length", "wear_splits"};
constexpr const char* kEasingNames[] = {"linear", "smooth", "ease_in", "ease_out", "step"};

double ease(Easing e, double t) {
  switch (e) {
    case Easing::Linear:
      return t;
    case Easing::Smooth:
      return t * t * (3 - 2 * t);
    case Easing::EaseIn:
      return t * t;
    case Easing::EaseOut:
      return 1 - (1 - t) * (1 - t);
    case Easing::Step:
      return t >= 1 ? 1.0 : 0.0;
  }
  return t;
}

// Straight key barb of `count` control vertices and chord `len`, turned toward the tip by `beta` in the
// barb-local frame (+x along the barb, +y toward the tip): the barb's angle to the rachis becomes
// (barb angle - beta); beta = barb angle closes it along the shaft.
void straightChord(double beta, double len, size_t count, std::vector<glm::dvec3>& out) {
  out.resize(count);
  const glm::dvec3 d(std::cos(beta), std::sin(beta), 0.0);
  for (size_t i = 0; i < count; ++i) out[i] = (len * static_cast<double>(i) / static_cast<double>(count - 1)) * d;
}

void lerpInto(std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b, double t) {
  for (size_t i = 0; i < a.size(); ++i) a[i] = (1 - t) * a[i] + t * b[i];
}

// Key barbs of vane v at growth state st (see growth.hpp for the phases).
std::vector<KeyBarb> grownKeyBarbs(const FeatherParams& def, int v, const GrowthState& st) {
  const std::vector<KeyBarb> keys = effectiveKeyBarbs(def, v);
  const VaneParams& vp = def.vane(v);
  const size_t n = keys.front().cvs.size();
  const double A = st[GrowthParam::BarbAngle], P = st[GrowthParam::PinKeyBarbs], K = st[GrowthParam::KeyBarbs];
  const double front = 1.0 - st[GrowthParam::Opening];  // rp of the migrating pin key barb

  std::vector<glm::dvec3> open, closed;
  auto shapeAt = [&](double rp, const std::vector<glm::dvec3>& real, std::vector<glm::dvec3>& out) {
    const double angle = vp.baseAngle * (1 - rp) + vp.tipAngle * rp;
    const double len = glm::length(real.back() - real.front());
    straightChord(angle * (1 - A), len, n, open);
    lerpInto(open, real, K);
    if (rp >= front) {
      out = open;
      return;
    }
    straightChord(angle, len, n, closed);
    lerpInto(closed, open, P);
    out = closed;
  };

  std::vector<KeyBarb> result;
  result.reserve(keys.size() + 1);
  bool frontDone = false;
  std::vector<glm::dvec3> real;
  for (const KeyBarb& k : keys) {
    if (!frontDone && front <= k.rp) {
      if (front < k.rp) {
        barbShapeAt(keys, front, real);
        KeyBarb m{front, {}};
        shapeAt(front, real, m.cvs);
        result.push_back(std::move(m));
      }
      frontDone = true;
    }
    KeyBarb g{k.rp, {}};
    shapeAt(k.rp, k.cvs, g.cvs);
    result.push_back(std::move(g));
  }
  return result;
}

void scaleProfile(LengthProfile& prof, double s) {
  for (auto& q : prof.points) q.y *= s;
}

}  // namespace

const char* growthParamName(GrowthParam p) { return kParamNames[static_cast<size_t>(p)]; }
bool isWearParam(GrowthParam p) { return p == GrowthParam::WearLength || p == GrowthParam::WearSplits; }
const char* easingName(Easing e) { return kEasingNames[static_cast<size_t>(e)]; }

double GrowthRamp::weight(double age) const {
  if (age >= end) return 1;
  if (age <= start) return 0;
  return ease(easing, (age - start) / (end - start));
}

const GrowthSchedule& defaultGrowthSchedule() {
  static const GrowthSchedule s = [] {
    GrowthSchedule g;
    using P = GrowthParam;
    g.ramps = {{P::ShaftLength, 0.0, 0.3, Easing::Linear},     {P::ShaftWidth, 0.0, 0.3, Easing::Linear},
               {P::BarbLength, 0.3, 0.5, Easing::Linear},      {P::Opening, 0.5, 0.8, Easing::Linear},
               {P::BarbAngle, 0.5, 0.8, Easing::Linear},       {P::Sheath, 0.5, 0.8, Easing::Linear},
               {P::PinKeyBarbs, 0.8, 1.0, Easing::Linear},     {P::KeyBarbs, 0.8, 1.0, Easing::Linear},
               {P::RachisCurvature, 0.8, 1.0, Easing::Linear}, {P::WearLength, 1.0, 2.0, Easing::Linear},
               {P::WearSplits, 1.0, 2.0, Easing::Linear}};
    return g;
  }();
  return s;
}

const GrowthSchedule& growthScheduleOf(const FeatherParams& p) {
  return p.growth ? *p.growth : defaultGrowthSchedule();
}

bool GrowthSchedule::wears() const {
  for (const GrowthRamp& r : ramps)
    if ((r.parameter == GrowthParam::WearLength && wearMaxShortening > 0) ||
        (r.parameter == GrowthParam::WearSplits && wearMaxSplits > 0))
      return true;
  return false;
}

void validateGrowthSchedule(const GrowthSchedule& s, const std::string& file) {
  bool seen[kGrowthParamCount] = {};
  for (size_t i = 0; i < s.ramps.size(); ++i) {
    const GrowthRamp& r = s.ramps[i];
    const std::string el = "growth.ramps[" + std::to_string(i) + "]";
    const size_t pi = static_cast<size_t>(r.parameter);
    if (pi >= kGrowthParamCount) throw Error("unknown growth parameter", file, el + ".parameter");
    if (seen[pi]) throw Error(std::string("parameter '") + growthParamName(r.parameter) + "' has two ramps", file, el);
    seen[pi] = true;
    if (!std::isfinite(r.start) || !std::isfinite(r.end) || r.start < 0 || r.end < r.start)
      throw Error("expected finite ages 0 <= start <= end", file, el);
    if (!isWearParam(r.parameter) && r.end > 1)
      throw Error("growth ramps must end by age 1 (the mature feather)", file, el + ".end");
    if (isWearParam(r.parameter) && (r.start < 1 || r.end <= 1))
      throw Error("wear ramps must start at age >= 1 and end after age 1", file, el);
    if (static_cast<size_t>(r.easing) >= std::size(kEasingNames)) throw Error("unknown easing", file, el + ".easing");
  }
  if (!std::isfinite(s.wearMaxShortening) || s.wearMaxShortening < 0 || s.wearMaxShortening > 1)
    throw Error("expected a fraction in [0, 1]", file, "growth.wear_max_shortening");
  if (s.wearMaxSplits < 0 || s.wearMaxSplits > 1000)
    throw Error("expected 0..1000 splits", file, "growth.wear_max_splits");
  if (!std::isfinite(s.sheathBand) || s.sheathBand <= 0 || s.sheathBand > 1)
    throw Error("expected a band in (0, 1]", file, "growth.sheath_band");
}

bool GrowthState::grown() const {
  for (size_t i = 0; i < kGrowthParamCount; ++i)
    if (!isWearParam(static_cast<GrowthParam>(i)) && w[i] != 1.0) return false;
  return true;
}

bool GrowthState::mature(const GrowthSchedule& s) const {
  const bool noShortening = (*this)[GrowthParam::WearLength] == 0 || s.wearMaxShortening == 0;
  const bool noSplits = std::lround(s.wearMaxSplits * (*this)[GrowthParam::WearSplits]) == 0;
  return grown() && noShortening && noSplits;
}

GrowthState growthStateAt(double age, const GrowthSchedule& s) {
  GrowthState st;
  for (size_t i = 0; i < kGrowthParamCount; ++i) st.w[i] = isWearParam(static_cast<GrowthParam>(i)) ? 0.0 : 1.0;
  for (const GrowthRamp& r : s.ramps) st[r.parameter] = r.weight(std::max(age, 0.0));
  return st;
}

FeatherParams featherAtState(const FeatherParams& def, const GrowthState& st, const GrowthSchedule& s) {
  if (st.mature(s)) return def;
  if (!st.grown() && def.generator != "streit") {
    // A generator may grow its own way (helical: collar growth, then unfurling; helical.hpp).
    const FeatherGenerator* g = findFeatherGenerator(def.generator);
    if (g && g->grow) return g->grow(def, st, s);
  }
  FeatherParams p = def;
  if (!st.grown()) {
    const double L = std::max(st[GrowthParam::ShaftLength], kMinGrowthScale);
    p.calamusLength *= L;
    p.rachisLength *= L;
    p.spacingBase *= L;  // barbs keep their rachis positions (rp) and count
    p.spacingTip *= L;
    p.rachisWidth *= st[GrowthParam::ShaftWidth];
    const double B = st[GrowthParam::BarbLength];
    p.barbLength *= B;
    scaleProfile(p.silhouette.left, B);
    scaleProfile(p.silhouette.right, B);
    const double C = st[GrowthParam::RachisCurvature];
    p.rachisLateralCurvature *= C;
    p.rachisVentralDorsalCurvature *= C;
    p.splits.openingAngle *= C;
    // Custom generators may not use key barbs; the explicit list is harmless for them.
    for (int v = 0; v < 2; ++v) p.vane(v).keyBarbs = grownKeyBarbs(def, v, st);
  }
  const double shorten = 1.0 - s.wearMaxShortening * st[GrowthParam::WearLength];
  if (shorten != 1.0) {
    p.barbLength *= shorten;
    scaleProfile(p.silhouette.left, shorten);
    scaleProfile(p.silhouette.right, shorten);
  }
  const long extra = std::lround(s.wearMaxSplits * st[GrowthParam::WearSplits]);
  p.splits.count = static_cast<int>(std::min<long>(1000, p.splits.count + extra));
  if (def.afterfeather)
    p.afterfeather = std::make_shared<const FeatherParams>(featherAtState(*def.afterfeather, st, s));
  return p;
}

FeatherParams featherAtAge(const FeatherParams& def, double age, const GrowthSchedule& s) {
  if (!std::isfinite(age)) throw Error("feather age must be a finite number", def.sourceFile, "age");
  return featherAtState(def, growthStateAt(age, s), s);
}

double sheathWeight(double v, double shed, double band) {
  band = std::max(band, 1e-9);
  // Front moves from just above the tip (all sheathed) to just below the base (all shed).
  const double front = (1 - shed) * (1 + band) - 0.5 * band;
  return std::clamp((front - v) / band + 0.5, 0.0, 1.0);
}

GrowthSchedule readGrowthSchedule(JsonReader& r) {
  GrowthSchedule s = defaultGrowthSchedule();
  std::vector<std::string> names(std::begin(kParamNames), std::end(kParamNames));
  std::vector<std::string> easings(std::begin(kEasingNames), std::end(kEasingNames));
  bool given[kGrowthParamCount] = {};
  for (JsonReader& e : r.objects("ramps")) {
    const std::string name = e.string("parameter");
    if (std::find(names.begin(), names.end(), name) == names.end())
      e.fail("parameter", "unknown growth parameter '" + name + "' (see docs/growth.md)");
    const size_t pi = static_cast<size_t>(std::find(names.begin(), names.end(), name) - names.begin());
    if (given[pi]) e.fail("parameter", "parameter '" + name + "' has two ramps");
    given[pi] = true;
    GrowthRamp ramp;
    ramp.parameter = static_cast<GrowthParam>(pi);
    ramp.start = e.number("start", 0.0, 1e6);
    ramp.end = e.number("end", 0.0, 1e6);
    const std::string ez = e.oneOf("easing", "linear", easings);
    ramp.easing = static_cast<Easing>(std::find(easings.begin(), easings.end(), ez) - easings.begin());
    if (ramp.end < ramp.start) e.fail("end", "end age must be >= start age");
    if (!isWearParam(ramp.parameter) && ramp.end > 1)
      e.fail("end", "growth ramps must end by age 1 (the mature feather)");
    if (isWearParam(ramp.parameter) && (ramp.start < 1 || ramp.end <= 1))
      e.fail("start", "wear ramps must start at age >= 1 and end after age 1");
    e.finish();
    auto it = std::find_if(s.ramps.begin(), s.ramps.end(),
                           [&](const GrowthRamp& x) { return x.parameter == ramp.parameter; });
    if (it != s.ramps.end())
      *it = ramp;
    else
      s.ramps.push_back(ramp);
  }
  s.wearMaxShortening = r.number("wear_max_shortening", s.wearMaxShortening, 0.0, 1.0);
  s.wearMaxSplits = static_cast<int>(r.integer("wear_max_splits", s.wearMaxSplits, 0, 1000));
  s.sheathBand = r.number("sheath_band", s.sheathBand, 1e-6, 1.0);
  r.finish();
  validateGrowthSchedule(s, r.file());
  return s;
}

GrowthSchedule loadGrowthSchedule(const std::string& path) {
  const Json j = readJsonFile(path);
  JsonReader top(j, path);
  JsonReader g = top.object("growth");
  GrowthSchedule s = readGrowthSchedule(g);
  top.finish();
  return s;
}

Json growthScheduleToJson(const GrowthSchedule& s) {
  Json ramps = Json::array();
  for (const GrowthRamp& r : s.ramps)
    ramps.push_back({{"parameter", growthParamName(r.parameter)},
                     {"start", r.start},
                     {"end", r.end},
                     {"easing", easingName(r.easing)}});
  return {{"ramps", ramps},
          {"wear_max_shortening", s.wearMaxShortening},
          {"wear_max_splits", s.wearMaxSplits},
          {"sheath_band", s.sheathBand}};
}

}  // namespace pteryla::feather
