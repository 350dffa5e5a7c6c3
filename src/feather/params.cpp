// Feather parameters, default key barbs and the key-barb interpolation of Streit 2003, 5.2.2 (eq. 5.1).
#include "pteryla/feather/params.hpp"

#include "pteryla/feather/growth.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/feather/bezier.hpp"
#include "keys_internal.hpp"

namespace pteryla::feather {

double LengthProfile::at(double rp) const {
  if (points.empty()) return 0;
  if (rp < points.front().x) return points.front().y;
  if (rp >= points.back().x) return points.back().y;
  // Last point at or below rp (at an equal-rp jump this is the upper value) and the next one.
  const auto it =
      std::upper_bound(points.begin(), points.end(), rp, [](double r, const glm::dvec2& p) { return r < p.x; });
  const glm::dvec2& hi = *it;
  const glm::dvec2& lo = *(it - 1);
  if (rp == lo.x) return lo.y;
  const double t = (rp - lo.x) / (hi.x - lo.x);
  return lo.y * (1 - t) + hi.y * t;
}

double FeatherParams::barbLengthAt(int v, double rp) const {
  const LengthProfile& prof = v == 0 ? silhouette.left : silhouette.right;
  return prof.empty() ? barbLength : prof.at(rp);
}

bool FeatherParams::equalExceptKeyBarbs(const FeatherParams& o) const {
  const bool afterEq =
      (!afterfeather && !o.afterfeather) || (afterfeather && o.afterfeather && *afterfeather == *o.afterfeather);
  const bool growthEq = growth == o.growth || (growth && o.growth && *growth == *o.growth);
  return afterEq && growthEq && name == o.name && generator == o.generator && generatorParams == o.generatorParams &&
         calamusLength == o.calamusLength && calamusWidthRatio == o.calamusWidthRatio &&
         rachisLength == o.rachisLength && rachisWidth == o.rachisWidth &&
         rachisLateralCurvature == o.rachisLateralCurvature &&
         rachisVentralDorsalCurvature == o.rachisVentralDorsalCurvature && barbLength == o.barbLength &&
         silhouette == o.silhouette && left.baseAngle == o.left.baseAngle && left.tipAngle == o.left.tipAngle &&
         right.baseAngle == o.right.baseAngle && right.tipAngle == o.right.tipAngle && spacingBase == o.spacingBase &&
         spacingTip == o.spacingTip && splits == o.splits && seed == o.seed && material == o.material;
}

bool FeatherParams::operator==(const FeatherParams& o) const {
  return left.keyBarbs == o.left.keyBarbs && right.keyBarbs == o.right.keyBarbs && equalExceptKeyBarbs(o);
}

void fillPlumulaceousBarb(uint64_t seed, glm::dvec3* cvs) {
  // Four control vertices evenly spaced on a unit line, jittered along it, then displaced in the two
  // directions across it by [-0.5, 0.5] weighted by the distance along the barb (more toward the tip).
  Rng rng(seed, 0xD0F1);
  cvs[0] = glm::dvec3(0.0);
  for (int i = 1; i < 4; ++i) {
    const double w = i / 3.0;
    const double x = w + (i < 3 ? rng.uniform(-0.06, 0.06) : 0.0);
    const double y = rng.uniform(-0.5, 0.5) * w;
    const double z = rng.uniform(-0.5, 0.5) * w;
    cvs[i] = {x, y, z};
  }
  const double chord = glm::length(cvs[3]);
  if (chord > 1)
    for (int i = 0; i < 4; ++i) cvs[i] /= chord;
}

std::array<glm::dvec3, 4> defaultPennaceousBarbArray() {
  // Straight barb with a slight front-to-back curvature: bulges dorsally, tip curls ventrally; chord 1.
  const double a = 0.06;  // tip droop, radians
  return {glm::dvec3(0, 0, 0), glm::dvec3(0.34, 0, 0.035), glm::dvec3(0.68, 0, 0.03),
          glm::dvec3(std::cos(a), 0, -std::sin(a))};
}

std::vector<glm::dvec3> defaultPlumulaceousBarb(uint64_t seed) {
  std::vector<glm::dvec3> cvs(4);
  fillPlumulaceousBarb(seed, cvs.data());
  return cvs;
}

std::vector<glm::dvec3> defaultPennaceousBarb() {
  const auto a = defaultPennaceousBarbArray();
  return {a.begin(), a.end()};
}

namespace {
void normalizeCvs(std::vector<glm::dvec3>& cvs) {
  const glm::dvec3 o = cvs.front();
  for (auto& c : cvs) c -= o;
  const double chord = glm::length(cvs.back());
  if (chord > 1)
    for (auto& c : cvs) c /= chord;
}
}  // namespace

void effectiveKeyBarbsInto(const FeatherParams& p, int vane, std::vector<KeyBarb>& keys) {
  // Reuses the storage of `keys` (element vectors keep their capacity) so the barb generator does not
  // allocate once warmed up.
  const VaneParams& vp = p.vane(vane);
  size_t m = 0;
  auto next = [&]() -> KeyBarb& {
    if (keys.size() <= m) keys.emplace_back();
    return keys[m++];
  };
  auto setDf1 = [&](KeyBarb& k, double rp) {
    k.rp = rp;
    k.cvs.resize(4);
    fillPlumulaceousBarb(p.seed, k.cvs.data());
  };
  if (vp.keyBarbs.empty()) {
    setDf1(next(), 0.0);
    setDf1(next(), 1.0);
  } else {
    bool sorted = true;
    for (size_t i = 1; i < vp.keyBarbs.size(); ++i) sorted = sorted && vp.keyBarbs[i - 1].rp <= vp.keyBarbs[i].rp;
    const double first =
        sorted ? vp.keyBarbs.front().rp
               : std::min_element(vp.keyBarbs.begin(), vp.keyBarbs.end(), [](const KeyBarb& a, const KeyBarb& b) {
                   return a.rp < b.rp;
                 })->rp;
    if (first > 0) setDf1(next(), 0.0);
    const size_t begin = m;
    for (const KeyBarb& k : vp.keyBarbs) {
      if (k.cvs.size() < 2) throw Error("a key barb needs at least 2 control vertices", p.sourceFile, "key_barbs.cvs");
      KeyBarb& d = next();
      d.rp = k.rp;
      d.cvs.assign(k.cvs.begin(), k.cvs.end());
      normalizeCvs(d.cvs);
    }
    if (!sorted)
      std::stable_sort(keys.begin() + static_cast<std::ptrdiff_t>(begin), keys.begin() + static_cast<std::ptrdiff_t>(m),
                       [](const KeyBarb& a, const KeyBarb& b) { return a.rp < b.rp; });
    if (keys[m - 1].rp < 1) {
      KeyBarb& d = next();
      d.rp = 1.0;
      const auto df2 = defaultPennaceousBarbArray();
      d.cvs.assign(df2.begin(), df2.end());
    }
  }
  keys.resize(m);
  size_t n = 0;
  for (const auto& k : keys) n = std::max(n, k.cvs.size());
  for (auto& k : keys)
    if (k.cvs.size() < n) k.cvs = elevateTo(k.cvs, n);
}

std::vector<KeyBarb> effectiveKeyBarbs(const FeatherParams& p, int vane) {
  std::vector<KeyBarb> keys;
  effectiveKeyBarbsInto(p, vane, keys);
  return keys;
}

void barbShapeAt(const std::vector<KeyBarb>& keys, double rp, std::vector<glm::dvec3>& out, int hint) {
  PTERYLA_CHECK(!keys.empty(), "barbShapeAt needs key barbs");
  if (hint >= 0 && static_cast<size_t>(hint) < keys.size() && keys[hint].rp == rp) {
    out = keys[hint].cvs;
    return;
  }
  const auto it = std::upper_bound(keys.begin(), keys.end(), rp, [](double r, const KeyBarb& k) { return r < k.rp; });
  if (it == keys.begin()) {
    out = keys.front().cvs;
    return;
  }
  if (it == keys.end()) {
    out = keys.back().cvs;
    return;
  }
  const KeyBarb& above = *it;
  const KeyBarb& below = *(it - 1);
  const double t = (rp - below.rp) / (above.rp - below.rp);
  const size_t n = std::max(above.cvs.size(), below.cvs.size());
  const std::vector<glm::dvec3> a = above.cvs.size() < n ? elevateTo(above.cvs, n) : above.cvs;
  const std::vector<glm::dvec3> b = below.cvs.size() < n ? elevateTo(below.cvs, n) : below.cvs;
  out.resize(n);
  for (size_t i = 0; i < n; ++i) out[i] = (1 - t) * b[i] + t * a[i];
}

namespace {
bool finite(double x) { return std::isfinite(x); }
constexpr double kMaxFeatherLength = 1e6;
constexpr double kMaxKeyBarbCoordinate = 1e3;

void validateImpl(const FeatherParams& p, const std::string& file, const std::string& prefix) {
  auto fail = [&](const std::string& elem, const std::string& what) { throw Error(what, file, prefix + elem); };
  // Lengths and widths are bounded so that products of them stay finite (docs/limits.md).
  auto nonNeg = [&](double v, const char* elem) {
    if (!finite(v) || v < 0 || v > kMaxFeatherLength) fail(elem, "expected a number in [0, 1e6]");
  };
  nonNeg(p.calamusLength, "calamus.length");
  nonNeg(p.calamusWidthRatio, "calamus.width_ratio");
  nonNeg(p.rachisWidth, "rachis.width");
  nonNeg(p.barbLength, "barbs.length");
  if (!finite(p.rachisLength) || p.rachisLength <= 0 || p.rachisLength > kMaxFeatherLength)
    fail("rachis.length", "expected a number in (0, 1e6]");
  if (!finite(p.rachisLateralCurvature) || std::abs(p.rachisLateralCurvature) > kPi)
    fail("rachis.lateral_curvature", "expected a turning angle in [-pi, pi] radians");
  if (!finite(p.rachisVentralDorsalCurvature) || std::abs(p.rachisVentralDorsalCurvature) > kPi)
    fail("rachis.ventral_dorsal_curvature", "expected a turning angle in [-pi, pi] radians");
  if (std::hypot(p.rachisLateralCurvature, p.rachisVentralDorsalCurvature) > kPi)
    fail("rachis", "combined rachis curvature exceeds pi radians");
  if (!finite(p.spacingBase) || p.spacingBase <= 0) fail("barbs.spacing_base", "expected a finite number > 0");
  if (!finite(p.spacingTip) || p.spacingTip <= 0) fail("barbs.spacing_tip", "expected a finite number > 0");
  if (p.rachisLength / std::min(p.spacingBase, p.spacingTip) > 1e5)
    fail("barbs.spacing_base", "barb spacing gives more than 100000 barbs on the rachis");
  for (int v = 0; v < 2; ++v) {
    const std::string vn = v == 0 ? "left_vane" : "right_vane";
    const VaneParams& vp = p.vane(v);
    if (!finite(vp.baseAngle) || vp.baseAngle < 0 || vp.baseAngle > kPi)
      fail(vn + ".base_angle", "expected an angle in [0, pi] radians");
    if (!finite(vp.tipAngle) || vp.tipAngle < 0 || vp.tipAngle > kPi)
      fail(vn + ".tip_angle", "expected an angle in [0, pi] radians");
    for (size_t k = 0; k < vp.keyBarbs.size(); ++k) {
      const std::string kn = vn + ".key_barbs[" + std::to_string(k) + "]";
      const KeyBarb& kb = vp.keyBarbs[k];
      if (!finite(kb.rp) || kb.rp < 0 || kb.rp > 1) fail(kn + ".rp", "expected rp in [0, 1]");
      if (kb.cvs.size() < 2) fail(kn + ".cvs", "a key barb needs at least 2 control vertices");
      if (kb.cvs.size() > 32) fail(kn + ".cvs", "at most 32 control vertices per key barb");
      for (size_t i = 0; i < kb.cvs.size(); ++i)
        if (!finite(kb.cvs[i].x) || !finite(kb.cvs[i].y) || !finite(kb.cvs[i].z) ||
            std::max({std::abs(kb.cvs[i].x), std::abs(kb.cvs[i].y), std::abs(kb.cvs[i].z)}) > kMaxKeyBarbCoordinate)
          fail(kn + ".cvs[" + std::to_string(i) + "]",
               "expected finite coordinates in [-1000, 1000] (key barbs are in units of the barb's chord)");
    }
    const LengthProfile& prof = v == 0 ? p.silhouette.left : p.silhouette.right;
    const std::string sn = std::string("silhouette.") + (v == 0 ? "left" : "right");
    for (size_t i = 0; i < prof.points.size(); ++i) {
      const glm::dvec2 q = prof.points[i];
      const std::string en = sn + "[" + std::to_string(i) + "]";
      if (!finite(q.x) || q.x < 0 || q.x > 1) fail(en, "expected rp in [0, 1]");
      if (!finite(q.y) || q.y < 0 || q.y > kMaxFeatherLength) fail(en, "expected a barb length in [0, 1e6]");
      if (i > 0 && q.x < prof.points[i - 1].x) fail(en, "rp values must not decrease");
    }
  }
  const SplitParams& s = p.splits;
  if (s.count < 0 || s.count > 1000) fail("splits.count", "expected 0..1000 splits per vane");
  if (!finite(s.rpMin) || !finite(s.rpMax) || s.rpMin < 0 || s.rpMax > 1 || s.rpMin > s.rpMax)
    fail("splits.rp_min", "expected 0 <= rp_min <= rp_max <= 1");
  if (!finite(s.openingAngle) || s.openingAngle < 0 || s.openingAngle > kPi / 2)
    fail("splits.opening_angle", "expected an angle in [0, pi/2] radians");
  if (s.reach < 0 || s.reach > 1000) fail("splits.reach", "expected 0..1000 barbs");
  if (p.material.baseColor) {
    const glm::dvec3 c = *p.material.baseColor;
    for (int i = 0; i < 3; ++i)
      if (!finite(c[i]) || c[i] < 0 || c[i] > 1) fail("material.base_color", "expected RGB components in [0, 1]");
  }
  if (p.afterfeather) validateImpl(*p.afterfeather, file, prefix + "afterfeather.");
}
}  // namespace

void validateFeather(const FeatherParams& p, const std::string& file) { validateImpl(p, file, ""); }

void validateFeatherAt(const FeatherParams& p, const std::string& file, const std::string& path) {
  validateImpl(p, file, path.empty() ? "" : path + ".");
}

}  // namespace pteryla::feather
