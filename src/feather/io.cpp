// Feather files (docs/feather-format.md): the Table 5.1 parameter set of Streit 2003 as strict JSON,
// plus curve export as OBJ polylines.
#include "pteryla/feather/io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/feather/bezier.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/generator.hpp"
#include "pteryla/feather/silhouette.hpp"
#include "keys_internal.hpp"

namespace pteryla::feather {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDeg = kPi / 180.0;

// Lists an optional, absent key among the known keys of `r` (for "unknown key" messages).
void markKnown(JsonReader& r, const std::string& key) {
  if (!r.json().contains(key)) r.number(key, 0.0, -kInf, kInf);
}

// Angle given either in radians as `key` or in degrees as `key_deg` (exactly one of them).
double readAngle(JsonReader& r, const std::string& key, double lo, double hi, const double* def = nullptr) {
  const std::string dkey = key + "_deg";
  const bool hasDeg = r.json().contains(dkey), hasRad = r.json().contains(key);
  if (hasDeg && hasRad) r.fail(dkey, "give either '" + key + "' (radians) or '" + dkey + "' (degrees), not both");
  if (hasDeg) {
    markKnown(r, key);
    return r.number(dkey, lo / kDeg, hi / kDeg) * kDeg;
  }
  markKnown(r, dkey);
  if (def) return r.number(key, *def, lo, hi);
  return r.number(key, lo, hi);
}

std::vector<glm::dvec3> readCvs(JsonReader& r, const std::string& key) {
  const Json& a = r.raw(key);
  const std::string path = r.pathOf(key);
  if (!a.is_array()) r.fail(key, "expected an array of [x, y, z] control vertices");
  if (a.size() < 2) r.fail(key, "a key barb needs at least 2 control vertices, got " + std::to_string(a.size()));
  if (a.size() > 32) r.fail(key, "at most 32 control vertices per key barb");
  std::vector<glm::dvec3> cvs;
  for (size_t i = 0; i < a.size(); ++i) {
    const std::string ep = path + "[" + std::to_string(i) + "]";
    if (!a[i].is_array() || a[i].size() != 3) throw Error("expected [x, y, z]", r.file(), ep);
    glm::dvec3 c;
    for (int k = 0; k < 3; ++k) c[k] = jsonNumber(a[i][k], r.file(), ep + "[" + std::to_string(k) + "]");
    cvs.push_back(c);
  }
  return cvs;
}

VaneParams readVane(JsonReader r) {
  VaneParams v;
  v.baseAngle = readAngle(r, "base_angle", 0, kPi);
  v.tipAngle = readAngle(r, "tip_angle", 0, kPi);
  const Json& kb = r.raw("key_barbs");
  if (!kb.is_array()) r.fail("key_barbs", "expected an array of key barbs (may be empty)");
  auto keyReaders = r.objects("key_barbs");
  for (auto& k : keyReaders) {
    KeyBarb b;
    b.rp = k.number("rp", 0.0, 1.0);
    b.cvs = readCvs(k, "cvs");
    k.finish();
    v.keyBarbs.push_back(std::move(b));
  }
  std::stable_sort(v.keyBarbs.begin(), v.keyBarbs.end(),
                   [](const KeyBarb& a, const KeyBarb& b) { return a.rp < b.rp; });
  r.finish();
  return v;
}

LengthProfile readProfile(JsonReader& r, const std::string& key) {
  const Json& a = r.raw(key);
  const std::string path = r.pathOf(key);
  if (!a.is_array() || a.empty()) r.fail(key, "expected a non-empty array of [rp, length] pairs");
  LengthProfile prof;
  for (size_t i = 0; i < a.size(); ++i) {
    const std::string ep = path + "[" + std::to_string(i) + "]";
    if (!a[i].is_array() || a[i].size() != 2) throw Error("expected [rp, length]", r.file(), ep);
    const double rp = jsonNumber(a[i][0], r.file(), ep + "[0]");
    const double len = jsonNumber(a[i][1], r.file(), ep + "[1]");
    if (rp < 0 || rp > 1) throw Error("rp must be in [0, 1]", r.file(), ep + "[0]");
    if (len < 0) throw Error("barb length must be >= 0", r.file(), ep + "[1]");
    if (i > 0 && rp < prof.points.back().x) throw Error("rp values must not decrease", r.file(), ep + "[0]");
    prof.points.emplace_back(rp, len);
  }
  return prof;
}

FeatherMaterial readMaterial(JsonReader r) {
  FeatherMaterial m;
  m.texture = r.string("texture", "");
  m.alphaTexture = r.string("alpha_texture", "");
  m.pattern = r.string("pattern", "");
  m.uv = r.oneOf("uv", "global", {"global", "barb", "growth"});
  if (r.json().contains("base_color")) {
    const glm::dvec3 c = r.vec3("base_color");
    for (int i = 0; i < 3; ++i)
      if (c[i] < 0 || c[i] > 1) r.fail("base_color", "expected RGB components in [0, 1]");
    m.baseColor = c;
  } else {
    markKnown(r, "base_color");
  }
  if (r.json().contains("brdf")) {
    // Poulin-Fournier barbule parameters, the ranges of the scene's render.brdf (docs/scene-format.md).
    JsonReader b = r.object("brdf");
    if (b.has("d"))
      m.brdfD = b.number("d", 1e-3, 20.0);
    else
      b.allow("d");
    if (b.has("h"))
      m.brdfH = b.number("h", 0.0, 0.999);
    else
      b.allow("h");
    b.finish();
  } else {
    r.allow("brdf");
  }
  r.finish();
  return m;
}

FeatherParams readImpl(JsonReader& r) {
  FeatherParams p;
  if (r.json().contains("pteryla_feather")) {
    const int64_t version = r.integer("pteryla_feather", 0, 1000000);
    if (version != kFeatherFormatVersion)
      r.fail("pteryla_feather", "unsupported feather format version " + std::to_string(version) +
                                    " (this build reads " + std::to_string(kFeatherFormatVersion) + ")");
  } else {
    r.integer("pteryla_feather", 1, 0, 1000000);
  }
  p.name = r.string("name", "");
  p.seed = r.seed("seed", 1);
  {
    JsonReader c = r.object("calamus");
    p.calamusLength = c.number("length", 0, kInf);
    p.calamusWidthRatio = c.number("width_ratio", 0, kInf);
    c.finish();
  }
  {
    JsonReader c = r.object("rachis");
    p.rachisLength = c.number("length", 0, kInf);
    if (!(p.rachisLength > 0)) c.fail("length", "rachis length must be > 0");
    p.rachisWidth = c.number("width", 0, kInf);
    p.rachisLateralCurvature = readAngle(c, "lateral_curvature", -kPi, kPi);
    p.rachisVentralDorsalCurvature = readAngle(c, "ventral_dorsal_curvature", -kPi, kPi);
    if (std::hypot(p.rachisLateralCurvature, p.rachisVentralDorsalCurvature) > kPi)
      c.fail("", "combined rachis curvature exceeds pi radians");
    c.finish();
  }
  {
    JsonReader c = r.object("barbs");
    p.barbLength = c.number("length", 0, kInf);
    p.spacingBase = c.number("spacing_base", 0, kInf);
    if (!(p.spacingBase > 0)) c.fail("spacing_base", "barb spacing must be > 0");
    p.spacingTip = c.number("spacing_tip", 0, kInf);
    if (!(p.spacingTip > 0)) c.fail("spacing_tip", "barb spacing must be > 0");
    if (p.rachisLength / std::min(p.spacingBase, p.spacingTip) > 1e5)
      c.fail("spacing_base", "barb spacing gives more than 100000 barbs on the rachis");
    c.finish();
  }
  p.left = readVane(r.object("left_vane"));
  p.right = readVane(r.object("right_vane"));

  if (r.json().contains("splits")) {
    JsonReader s = r.object("splits");
    const SplitParams d;
    p.splits.count = static_cast<int>(s.integer("count", 0, 1000));
    p.splits.rpMin = s.number("rp_min", d.rpMin, 0, 1);
    p.splits.rpMax = s.number("rp_max", d.rpMax, 0, 1);
    if (p.splits.rpMin > p.splits.rpMax) s.fail("rp_min", "rp_min must not exceed rp_max");
    p.splits.openingAngle = readAngle(s, "opening_angle", 0, kPi / 2, &d.openingAngle);
    p.splits.reach = static_cast<int>(s.integer("reach", d.reach, 0, 1000));
    s.finish();
  } else {
    markKnown(r, "splits");
  }

  if (r.json().contains("silhouette")) {
    JsonReader s = r.object("silhouette");
    if (s.json().contains("outline")) {
      if (s.json().contains("left") || s.json().contains("right"))
        s.fail("outline", "give either 'outline' or 'left'/'right' barb length profiles, not both");
      const Json& a = s.raw("outline");
      const std::string path = s.pathOf("outline");
      if (!a.is_array() || a.size() < 3) s.fail("outline", "expected at least 3 [x, y] points");
      std::vector<glm::dvec2> outline;
      for (size_t i = 0; i < a.size(); ++i) {
        const std::string ep = path + "[" + std::to_string(i) + "]";
        if (!a[i].is_array() || a[i].size() != 2) throw Error("expected [x, y]", r.file(), ep);
        outline.emplace_back(jsonNumber(a[i][0], r.file(), ep + "[0]"), jsonNumber(a[i][1], r.file(), ep + "[1]"));
      }
      const int samples = static_cast<int>(s.integer("samples", 33, 2, 10000));
      p.silhouette = silhouetteFromOutline(outline, p, samples);
    } else {
      s.integer("samples", 33, 2, 10000);
      markKnown(s, "outline");
      if (!s.json().contains("left") && !s.json().contains("right"))
        s.fail("", "expected 'left' and/or 'right' barb length profiles, or an 'outline'");
      if (s.json().contains("left"))
        p.silhouette.left = readProfile(s, "left");
      else
        markKnown(s, "left");
      if (s.json().contains("right"))
        p.silhouette.right = readProfile(s, "right");
      else
        markKnown(s, "right");
    }
    s.finish();
  }

  if (r.json().contains("material"))
    p.material = readMaterial(r.object("material"));
  else
    markKnown(r, "material");

  if (r.json().contains("growth")) {
    JsonReader g = r.object("growth");
    p.growth = std::make_shared<const GrowthSchedule>(readGrowthSchedule(g));
  } else {
    markKnown(r, "growth");
  }

  if (r.json().contains("afterfeather")) {
    JsonReader a = r.object("afterfeather");
    if (a.json().contains("afterfeather")) a.fail("afterfeather", "an afterfeather cannot have its own afterfeather");
    p.afterfeather = std::make_shared<const FeatherParams>(readImpl(a));
  } else {
    markKnown(r, "afterfeather");
  }

  p.generator = r.string("generator", "streit");
  if (p.generator != "streit") {
    const FeatherGenerator* g = findFeatherGenerator(p.generator);
    if (!g) {
      std::string known;
      for (const auto& n : featherGeneratorNames()) known += (known.empty() ? "" : ", ") + n;
      r.fail("generator", "unknown feather generator '" + p.generator + "' (known: " + known + ")");
    }
    g->read(r, p);
  }
  r.finish();
  validateFeatherAt(p, r.file(), r.path());
  return p;
}

Json profileJson(const LengthProfile& prof) {
  Json a = Json::array();
  for (const auto& q : prof.points) a.push_back({q.x, q.y});
  return a;
}

Json vaneJson(const VaneParams& v) {
  Json j;
  j["base_angle"] = v.baseAngle;
  j["tip_angle"] = v.tipAngle;
  Json keys = Json::array();
  for (const KeyBarb& k : v.keyBarbs) {
    Json cvs = Json::array();
    for (const auto& c : k.cvs) cvs.push_back({c.x, c.y, c.z});
    keys.push_back({{"rp", k.rp}, {"cvs", cvs}});
  }
  j["key_barbs"] = keys;
  return j;
}

}  // namespace

FeatherParams readFeather(JsonReader& r) { return readImpl(r); }

Json featherToJson(const FeatherParams& p, bool withVersion) {
  Json j = Json::object();
  if (withVersion) j["pteryla_feather"] = kFeatherFormatVersion;
  if (!p.name.empty()) j["name"] = p.name;
  if (p.generator != "streit") j["generator"] = p.generator;
  j["seed"] = p.seed;
  j["calamus"] = {{"length", p.calamusLength}, {"width_ratio", p.calamusWidthRatio}};
  j["rachis"] = {{"length", p.rachisLength},
                 {"width", p.rachisWidth},
                 {"lateral_curvature", p.rachisLateralCurvature},
                 {"ventral_dorsal_curvature", p.rachisVentralDorsalCurvature}};
  j["barbs"] = {{"length", p.barbLength}, {"spacing_base", p.spacingBase}, {"spacing_tip", p.spacingTip}};
  j["left_vane"] = vaneJson(p.left);
  j["right_vane"] = vaneJson(p.right);
  if (!(p.splits == SplitParams())) {
    j["splits"] = {{"count", p.splits.count},
                   {"rp_min", p.splits.rpMin},
                   {"rp_max", p.splits.rpMax},
                   {"opening_angle", p.splits.openingAngle},
                   {"reach", p.splits.reach}};
  }
  if (!p.silhouette.empty()) {
    Json s = Json::object();
    if (!p.silhouette.left.empty()) s["left"] = profileJson(p.silhouette.left);
    if (!p.silhouette.right.empty()) s["right"] = profileJson(p.silhouette.right);
    j["silhouette"] = s;
  }
  if (!p.material.empty()) {
    Json m = Json::object();
    if (!p.material.texture.empty()) m["texture"] = p.material.texture;
    if (!p.material.alphaTexture.empty()) m["alpha_texture"] = p.material.alphaTexture;
    if (!p.material.pattern.empty()) m["pattern"] = p.material.pattern;
    if (p.material.baseColor)
      m["base_color"] = {p.material.baseColor->x, p.material.baseColor->y, p.material.baseColor->z};
    if (p.material.uv != "global") m["uv"] = p.material.uv;
    if (p.material.brdfD || p.material.brdfH) {
      Json b = Json::object();
      if (p.material.brdfD) b["d"] = *p.material.brdfD;
      if (p.material.brdfH) b["h"] = *p.material.brdfH;
      m["brdf"] = b;
    }
    j["material"] = m;
  }
  if (p.growth) j["growth"] = growthScheduleToJson(*p.growth);
  if (p.afterfeather) j["afterfeather"] = featherToJson(*p.afterfeather, false);
  if (p.generator != "streit") {
    const FeatherGenerator* g = findFeatherGenerator(p.generator);
    if (!g) throw Error("unknown feather generator '" + p.generator + "'", p.sourceFile, "generator");
    g->write(p, j);
  }
  return j;
}

FeatherParams loadFeather(const std::string& path) {
  const Json j = readJsonFile(path);
  JsonReader r(j, path);
  if (!j.contains("pteryla_feather"))
    r.fail("pteryla_feather", "missing required field (feather files start with \"pteryla_feather\": 1)");
  FeatherParams p = readFeather(r);
  p.sourceFile = path;
  return p;
}

void saveFeather(const std::string& path, const FeatherParams& p) {
  validateFeather(p, path);
  writeJsonFile(path, featherToJson(p, true));
}

void writeCurvesObj(const std::string& path, const FeatherCurves& curves, int barbSegments) {
  std::ostringstream out;
  out << "# pteryla feather curves: " << curves.partCount() << " shaft(s), " << curves.barbs.size() << " barbs\n";
  size_t next = 1;  // OBJ indices are 1-based
  char buf[96];
  auto vertex = [&](const glm::vec3& v) {
    std::snprintf(buf, sizeof buf, "v %.7g %.7g %.7g\n", v.x, v.y, v.z);
    out << buf;
  };
  for (size_t s = 0; s < curves.shafts.size(); ++s) {
    const ShaftCurve& sh = curves.shafts[s];
    if (sh.points.size() < 2) continue;
    out << "o shaft" << s << "\n";
    for (const auto& v : sh.points) vertex(v);
    out << "l";
    for (size_t i = 0; i < sh.points.size(); ++i) out << ' ' << next + i;
    out << "\n";
    next += sh.points.size();
  }
  std::vector<glm::vec3> poly;
  const int segs = std::max(1, barbSegments);
  out << "o barbs\n";
  for (const BarbCurve& b : curves.barbs) {
    barbPolyline(curves, b, segs, poly);
    for (const auto& v : poly) vertex(v);
    out << "l";
    for (size_t i = 0; i < poly.size(); ++i) out << ' ' << next + i;
    out << "\n";
    next += poly.size();
  }
  const std::string text = out.str();
  if (text.find("nan") != std::string::npos || text.find("inf") != std::string::npos)
    throw Error("the feather curves have non-finite coordinates; nothing written", path);
  writeFileAtomic(path, text);
}

}  // namespace pteryla::feather
