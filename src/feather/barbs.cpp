// Barb generation after Streit 2003: rachis and barb placement (5.2, Table 5.1), barbs interpolated from
// key barbs (5.2.2, eq. 5.1) with linear barb angle and spacing, barb length scaling (constant or
// silhouette, 5.2.3), and wear splits in the vane (5.2.5).
#include "pteryla/feather/barbs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/feather/bezier.hpp"
#include "pteryla/feather/generator.hpp"
#include "keys_internal.hpp"

namespace pteryla::feather {

namespace {

// sin and cos for |x| <= pi to ~1e-7 (float output precision) with short polynomials; libm's sincos
// was a quarter of the barb generation time.
inline void fastSinCos(double x, double& s, double& c) {
  double r = x;
  int quadrant = 0;  // 0: |x| <= pi/2, 1: x > pi/2, 2: x < -pi/2
  if (x > kPi / 2) {
    r = x - kPi / 2;
    quadrant = 1;
  } else if (x < -kPi / 2) {
    r = x + kPi / 2;
    quadrant = 2;
  }
  const double r2 = r * r;
  const double sr =
      r * (1 + r2 * (-1.0 / 6 + r2 * (1.0 / 120 + r2 * (-1.0 / 5040 + r2 * (1.0 / 362880 + r2 * (-1.0 / 39916800))))));
  const double cr =
      1 + r2 * (-0.5 + r2 * (1.0 / 24 +
                             r2 * (-1.0 / 720 + r2 * (1.0 / 40320 + r2 * (-1.0 / 3628800 + r2 * (1.0 / 479001600))))));
  if (quadrant == 0) {
    s = sr;
    c = cr;
  } else if (quadrant == 1) {
    s = cr;
    c = -sr;
  } else {
    s = -cr;
    c = sr;
  }
}

// The rachis: a circular arc of length L starting at `base` along +x, bending in the plane spanned by
// +x and n = (0, ny, nz) by a total turning angle theta; frames rotate about b = x cross n.
struct Arc {
  glm::dvec3 base{0.0};
  double length = 1, theta = 0, width = 0;
  double ny = 1, nz = 0;

  Arc(const FeatherParams& p, const glm::dvec3& origin) {
    base = origin + glm::dvec3(p.calamusLength, 0, 0);
    length = p.rachisLength;
    width = p.rachisWidth;
    const double lat = p.rachisLateralCurvature, vd = p.rachisVentralDorsalCurvature;
    theta = std::hypot(lat, vd);
    if (theta > 0) {
      ny = lat / theta;
      nz = -vd / theta;
    }
  }

  void frame(double rp, RachisFrame& f, bool fast = false) const {
    f.width = width * (1 - rp);
    if (theta < 1e-12) {
      f.point = base + glm::dvec3(length * rp, 0, 0);
      f.tangent = {1, 0, 0};
      f.left = {0, 1, 0};
      f.dorsal = {0, 0, 1};
      return;
    }
    const double phi = theta * rp;
    double s, c;
    if (fast) {
      fastSinCos(phi, s, c);
    } else {
      s = std::sin(phi);
      c = std::cos(phi);
    }
    const double r = length / theta;
    // 1 - cos without cancellation near phi = 0; near phi = pi (a half-circle rachis) 1 + c vanishes
    // and 1 - c itself is exact.
    const double oneMinusC = 1 + c > 1e-3 ? s * s / (1 + c) : 1 - c;
    // point = base + r (s x + (1 - c) n)
    f.point = base + glm::dvec3(r * s, r * oneMinusC * ny, r * oneMinusC * nz);
    f.tangent = {c, s * ny, s * nz};
    // Rotated n: -s x + c n; b = (0, -nz, ny) is fixed by the rotation.
    const glm::dvec3 rn(-s, c * ny, c * nz);
    const glm::dvec3 b(0, -nz, ny);
    f.dorsal = nz * rn + ny * b;
    f.left = ny * rn - nz * b;
  }
};

void appendShaft(const FeatherParams& p, const Arc& arc, const glm::dvec3& origin, const GenerateOptions& opt,
                 ShaftCurve& sh) {
  sh.points.clear();
  sh.widths.clear();
  sh.rp.clear();
  sh.rachisCvs.clear();
  sh.calamusPoints = 0;
  if (p.calamusLength > 0) {
    const double wBase = p.calamusWidthRatio * p.rachisWidth;
    for (int i = 0; i < 2; ++i) {
      const double u = i / 2.0;
      sh.points.emplace_back(origin + glm::dvec3(p.calamusLength * u, 0, 0));
      sh.widths.push_back(static_cast<float>(wBase * (1 - u) + p.rachisWidth * u));
      sh.rp.push_back(static_cast<float>(u - 1));
    }
    sh.calamusPoints = 2;
  }
  const int segs = std::max(1, opt.shaftSegments);
  RachisFrame f;
  for (int i = 0; i <= segs; ++i) {
    const double rp = static_cast<double>(i) / segs;
    arc.frame(rp, f);
    sh.points.emplace_back(f.point);
    sh.widths.push_back(static_cast<float>(f.width));
    sh.rp.push_back(static_cast<float>(rp));
    if (i == 0) sh.dorsal[0] = glm::vec3(f.dorsal);
    if (i == segs) sh.dorsal[1] = glm::vec3(f.dorsal);
  }
  RachisFrame f0, f1;
  arc.frame(0, f0);
  arc.frame(1, f1);
  const double h = arc.theta < 1e-12 ? arc.length / 3 : (4.0 / 3.0) * std::tan(arc.theta / 4) * arc.length / arc.theta;
  sh.rachisCvs = {glm::vec3(f0.point), glm::vec3(f0.point + h * f0.tangent), glm::vec3(f1.point - h * f1.tangent),
                  glm::vec3(f1.point)};
}

struct Scratch {
  std::vector<double> rps;
  std::vector<RachisFrame> frames;
  std::vector<double> angleDelta;
  std::vector<uint8_t> flags;  // bit 0 split edge, bit 1 split after, bit 2 key
  std::vector<KeyBarb> keys;
  std::vector<glm::vec3> keyCvs;  // keys flattened to float, nk * n
};

void generatePart(const FeatherParams& p, const glm::dvec3& origin, uint8_t part, FeatherCurves& out,
                  const GenerateOptions& opt, Scratch& s) {
  const Arc arc(p, origin);
  appendShaft(p, arc, origin, opt, out.shafts[part]);
  out.barbBegin.push_back(static_cast<uint32_t>(out.barbs.size()));

  barbPositions(p, s.rps);
  const size_t count = s.rps.size();
  s.frames.resize(count);
  for (size_t i = 0; i < count; ++i) arc.frame(s.rps[i], s.frames[i], true);

  for (int v = 0; v < 2; ++v) {
    const VaneParams& vp = p.vane(v);
    const float side = v == 0 ? 1.0f : -1.0f;
    effectiveKeyBarbsInto(p, v, s.keys);
    const std::vector<KeyBarb>& keys = s.keys;
    const size_t n = keys.front().cvs.size();
    const size_t nk = keys.size();
    s.keyCvs.resize(nk * n);
    for (size_t k = 0; k < nk; ++k)
      for (size_t c = 0; c < n; ++c) s.keyCvs[k * n + c] = glm::vec3(keys[k].cvs[c]);

    s.angleDelta.assign(count, 0.0);
    s.flags.assign(count, 0);
    for (const KeyBarb& k : vp.keyBarbs) {
      const auto it = std::lower_bound(s.rps.begin(), s.rps.end(), k.rp);
      size_t idx = static_cast<size_t>(it - s.rps.begin());
      if (idx == count || (idx > 0 && k.rp - s.rps[idx - 1] < s.rps[idx] - k.rp)) --idx;
      s.flags[idx] |= 4;
    }
    if (p.splits.count > 0 && count >= 2) {
      for (const VaneSplit& sp : vaneSplits(p, v)) {
        const size_t hi = static_cast<size_t>(std::lower_bound(s.rps.begin(), s.rps.end(), sp.rp) - s.rps.begin());
        if (hi == 0 || hi >= count) continue;
        const size_t lo = hi - 1;
        s.flags[lo] |= 3;
        s.flags[hi] |= 1;
        const int reach = p.splits.reach;
        for (int k = 0; k < reach; ++k) {
          const double w = 0.5 * sp.opening * (1.0 - static_cast<double>(k) / reach);
          if (lo >= static_cast<size_t>(k)) s.angleDelta[lo - k] += w;
          if (hi + k < count) s.angleDelta[hi + k] -= w;
        }
      }
    }

    const LengthProfile& prof = v == 0 ? p.silhouette.left : p.silhouette.right;
    const std::vector<glm::dvec2>& pp = prof.points;
    size_t pc = 0;  // profile cursor: last point with rp <= current rp
    size_t j = 0;   // last key barb with rp <= current rp
    const size_t barb0 = out.barbs.size();
    const size_t cv0 = out.cvs.size();
    out.barbs.resize(barb0 + count);
    out.cvs.resize(cv0 + count * n);
    BarbCurve* barbOut = out.barbs.data() + barb0;
    glm::vec3* cvOut = out.cvs.data() + cv0;
    for (size_t i = 0; i < count; ++i) {
      const double rp = s.rps[i];
      while (j + 1 < nk && keys[j + 1].rp <= rp) ++j;
      const glm::vec3* lo = &s.keyCvs[j * n];
      const glm::vec3* hi = lo;
      float t = 0;
      if (j + 1 < nk) {
        hi = lo + n;
        t = static_cast<float>((rp - keys[j].rp) / (keys[j + 1].rp - keys[j].rp));
      }
      double angle = vp.baseAngle * (1 - rp) + vp.tipAngle * rp + s.angleDelta[i];
      angle = std::clamp(angle, 0.01, kPi - 0.01);
      double len = p.barbLength;
      if (!pp.empty()) {
        while (pc + 1 < pp.size() && pp[pc + 1].x <= rp) ++pc;
        if (rp < pp.front().x || pc + 1 == pp.size() || pp[pc].x == rp) {
          len = rp < pp.front().x ? pp.front().y : pp[pc].y;
        } else {
          const double u = (rp - pp[pc].x) / (pp[pc + 1].x - pp[pc].x);
          len = pp[pc].y * (1 - u) + pp[pc + 1].y * u;
        }
      }
      const RachisFrame& f = s.frames[i];
      double sinA, cosA;
      fastSinCos(angle, sinA, cosA);
      const float ca = static_cast<float>(cosA), sa = static_cast<float>(sinA);
      const glm::vec3 T(f.tangent), L(f.left), D(f.dorsal);
      const glm::vec3 root = glm::vec3(f.point) + (side * 0.5f * static_cast<float>(f.width)) * L;
      const float lf = static_cast<float>(len);
      const glm::vec3 ul = lf * (ca * T + (side * sa) * L);  // along the barb
      const glm::vec3 wl = lf * (sa * T - (side * ca) * L);  // toward the tip
      const glm::vec3 dl = lf * D;

      BarbCurve& b = barbOut[i];
      b.root = root;
      b.rp = static_cast<float>(rp);
      b.angle = static_cast<float>(angle);
      b.length = lf;
      b.cvOffset = static_cast<uint32_t>(cv0 + i * n);
      b.cvCount = static_cast<uint16_t>(n);
      b.vane = static_cast<uint8_t>(v);
      b.part = part;
      b.isKey = (s.flags[i] & 4) != 0;
      b.isSplitEdge = (s.flags[i] & 1) != 0;
      b.splitAfter = (s.flags[i] & 2) != 0;
      glm::vec3* o = cvOut + i * n;
      for (size_t c = 0; c < n; ++c) {
        const glm::vec3 q = lo[c] + t * (hi[c] - lo[c]);
        o[c] = root + q.x * ul + q.y * wl + q.z * dl;
      }
    }
  }
  out.barbEnd.push_back(static_cast<uint32_t>(out.barbs.size()));
}

// Cheap screen for parameters the generator cannot use; validateFeather() names the culprit.
bool quickValid(const FeatherParams& p) {
  auto ok = [](double x, double lo, double hi) { return std::isfinite(x) && x >= lo && x <= hi; };
  constexpr double inf = std::numeric_limits<double>::infinity();
  bool good = ok(p.calamusLength, 0, inf) && ok(p.calamusWidthRatio, 0, inf) && ok(p.rachisWidth, 0, inf) &&
              ok(p.barbLength, 0, inf) && ok(p.rachisLength, 1e-300, inf) && ok(p.spacingBase, 1e-300, inf) &&
              ok(p.spacingTip, 1e-300, inf) && p.rachisLength / std::min(p.spacingBase, p.spacingTip) <= 1e5 &&
              std::hypot(p.rachisLateralCurvature, p.rachisVentralDorsalCurvature) <= kPi && p.splits.count >= 0 &&
              p.splits.count <= 1000 && p.splits.reach >= 0 && p.splits.reach <= 1000 && ok(p.splits.rpMin, 0, 1) &&
              ok(p.splits.rpMax, p.splits.rpMin, 1) && ok(p.splits.openingAngle, 0, kPi / 2);
  for (int v = 0; v < 2 && good; ++v) {
    const VaneParams& vp = p.vane(v);
    good = ok(vp.baseAngle, 0, kPi) && ok(vp.tipAngle, 0, kPi);
    for (const KeyBarb& k : vp.keyBarbs) {
      good = good && ok(k.rp, 0, 1) && k.cvs.size() >= 2 && k.cvs.size() <= 32;
      for (const auto& c : k.cvs) good = good && std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z);
    }
    const LengthProfile& prof = v == 0 ? p.silhouette.left : p.silhouette.right;
    for (size_t i = 0; i < prof.points.size(); ++i)
      good = good && ok(prof.points[i].x, i ? prof.points[i - 1].x : 0.0, 1) && ok(prof.points[i].y, 0, inf);
  }
  return good;
}

void generateStreit(const FeatherParams& p, FeatherCurves& out, const GenerateOptions& opt) {
  static thread_local Scratch scratch;
  const bool after = p.afterfeather && opt.afterfeather;
  out.shafts.resize(after ? 2 : 1);
  generatePart(p, glm::dvec3(0.0), 0, out, opt, scratch);
  if (after) {
    const glm::dvec3 umbilicus(p.calamusLength, 0, -0.5 * p.rachisWidth);
    generatePart(*p.afterfeather, umbilicus, 1, out, opt, scratch);
  }
}

}  // namespace

RachisFrame rachisFrame(const FeatherParams& p, double rp) {
  RachisFrame f;
  Arc(p, glm::dvec3(0.0)).frame(rp, f);
  return f;
}

std::vector<glm::dvec3> rachisBezier(const FeatherParams& p) {
  const Arc arc(p, glm::dvec3(0.0));
  RachisFrame f0, f1;
  arc.frame(0, f0);
  arc.frame(1, f1);
  const double h = arc.theta < 1e-12 ? arc.length / 3 : (4.0 / 3.0) * std::tan(arc.theta / 4) * arc.length / arc.theta;
  return {f0.point, f0.point + h * f0.tangent, f1.point - h * f1.tangent, f1.point};
}

void barbPositions(const FeatherParams& p, std::vector<double>& rps) {
  rps.clear();
  const double L = p.rachisLength, a = p.spacingBase, b = p.spacingTip;
  if (!(L > 0) || !(a > 0) || !(b > 0) || L / std::min(a, b) > 1e5) {
    validateFeather(p, p.sourceFile);
    return;
  }
  if (std::abs(b - a) <= 1e-12 * a) {
    const double kmax = L / a;
    const size_t count = static_cast<size_t>(std::floor(kmax + 1e-9)) + 1;
    rps.resize(count);
    for (size_t k = 0; k < count; ++k) rps[k] = std::min(1.0, static_cast<double>(k) * a / L);
    return;
  }
  const double c = (b - a) / L;
  const double kmax = std::log(b / a) / c;
  const size_t count = static_cast<size_t>(std::floor(kmax + 1e-9)) + 1;
  rps.resize(count);
  for (size_t k = 0; k < count; ++k) rps[k] = std::min(1.0, a * std::expm1(c * static_cast<double>(k)) / c / L);
}

size_t barbCount(const FeatherParams& p) {
  std::vector<double> rps;
  barbPositions(p, rps);
  return rps.size();
}

std::vector<VaneSplit> vaneSplits(const FeatherParams& p, int vane) {
  std::vector<VaneSplit> out;
  const SplitParams& s = p.splits;
  if (s.count <= 0) return out;
  Rng rng(p.seed, 0x5E117ull + static_cast<uint64_t>(vane));
  out.reserve(static_cast<size_t>(s.count));
  for (int i = 0; i < s.count; ++i) {
    VaneSplit sp;
    sp.rp = rng.uniform(s.rpMin, s.rpMax);
    sp.opening = s.openingAngle * rng.uniform(0.5, 1.0);
    out.push_back(sp);
  }
  std::sort(out.begin(), out.end(), [](const VaneSplit& a, const VaneSplit& b) { return a.rp < b.rp; });
  return out;
}

void FeatherCurves::clear() {
  for (auto& s : shafts) {
    s.points.clear();
    s.widths.clear();
    s.rp.clear();
    s.rachisCvs.clear();
    s.calamusPoints = 0;
  }
  barbBegin.clear();
  barbEnd.clear();
  barbs.clear();
  cvs.clear();
}

FeatherCurves generateBarbs(const FeatherParams& p, const GenerateOptions& opt) {
  FeatherCurves out;
  generateBarbs(p, out, opt);
  return out;
}

void generateBarbs(const FeatherParams& p, FeatherCurves& out, const GenerateOptions& opt) {
  out.clear();
  if (!quickValid(p) || (p.afterfeather && !quickValid(*p.afterfeather)))
    validateFeather(p, p.sourceFile);  // throws naming the bad parameter
  if (p.generator != "streit") {
    const FeatherGenerator* g = findFeatherGenerator(p.generator);
    if (!g) throw Error("unknown feather generator '" + p.generator + "'", p.sourceFile, "generator");
    if (g->generate) {
      g->generate(p, out, opt);
      return;
    }
  }
  generateStreit(p, out, opt);
}

void barbPolyline(const FeatherCurves& c, const BarbCurve& b, int segments, std::vector<glm::vec3>& out) {
  PTERYLA_CHECK_GE(segments, 1, "need at least one segment");
  out.resize(static_cast<size_t>(segments) + 1);
  const glm::vec3* cv = c.cvs.data() + b.cvOffset;
  for (int i = 0; i <= segments; ++i) out[i] = bezierPoint(cv, b.cvCount, static_cast<double>(i) / segments);
}

}  // namespace pteryla::feather
