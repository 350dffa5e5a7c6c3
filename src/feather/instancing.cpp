// Instancing (instancing.hpp): leader clustering of barb curves under a tolerance.
#include "pteryla/feather/instancing.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "pteryla/core/hash.hpp"

namespace pteryla::feather {

namespace {

// A hash of what sameCurveStructure compares (equal structures hash equal).
uint64_t structureKey(const FeatherCurves& c) {
  Fnv1a64 f;
  f.add(uint64_t(c.shafts.size()));
  for (const ShaftCurve& s : c.shafts) {
    f.add(s.points.size());
    f.add(static_cast<uint64_t>(s.calamusPoints));
    f.add(s.rachisCvs.size());
  }
  for (uint32_t b : c.barbBegin) f.add(b);
  for (uint32_t b : c.barbEnd) f.add(b);
  f.add(c.barbs.size());
  for (const BarbCurve& b : c.barbs)
    f.add(uint64_t(b.cvCount) | uint64_t(b.vane) << 16 | uint64_t(b.part) << 24 | uint64_t(b.isKey) << 32 |
          uint64_t(b.isSplitEdge) << 33 | uint64_t(b.splitAfter) << 34 | uint64_t(b.cvOffset) << 35);
  f.add(c.cvs.size());
  return f.h;
}

// The sizes curveDistance indexes by (cheap; sameCurveStructure checks the rest).
bool sameSizes(const FeatherCurves& a, const FeatherCurves& b) {
  if (a.shafts.size() != b.shafts.size() || a.barbs.size() != b.barbs.size() || a.cvs.size() != b.cvs.size())
    return false;
  for (size_t s = 0; s < a.shafts.size(); ++s)
    if (a.shafts[s].points.size() != b.shafts[s].points.size() ||
        a.shafts[s].rachisCvs.size() != b.shafts[s].rachisCvs.size() ||
        a.shafts[s].widths.size() != b.shafts[s].widths.size() || a.shafts[s].rp.size() != b.shafts[s].rp.size())
      return false;
  return true;
}

double dist(const glm::vec3& a, const glm::vec3& b) { return glm::length(glm::dvec3(a) - glm::dvec3(b)); }

}  // namespace

double curveExtent(const FeatherCurves& c) {
  double e = 0;
  for (const ShaftCurve& s : c.shafts)
    for (const glm::vec3& p : s.points) e = std::max(e, glm::length(glm::dvec3(p)));
  for (const glm::vec3& p : c.cvs) e = std::max(e, glm::length(glm::dvec3(p)));
  return e;
}

bool sameCurveStructure(const FeatherCurves& a, const FeatherCurves& b) {
  if (!sameSizes(a, b) || a.barbBegin != b.barbBegin || a.barbEnd != b.barbEnd) return false;
  for (size_t s = 0; s < a.shafts.size(); ++s)
    if (a.shafts[s].calamusPoints != b.shafts[s].calamusPoints) return false;
  for (size_t k = 0; k < a.barbs.size(); ++k) {
    const BarbCurve &x = a.barbs[k], &y = b.barbs[k];
    if (x.cvOffset != y.cvOffset || x.cvCount != y.cvCount || x.vane != y.vane || x.part != y.part ||
        x.isKey != y.isKey || x.isSplitEdge != y.isSplitEdge || x.splitAfter != y.splitAfter)
      return false;
  }
  return true;
}

double curveDistance(const FeatherCurves& a, const FeatherCurves& b, double extent, double limit) {
  if (!sameSizes(a, b)) return std::numeric_limits<double>::infinity();
  double d = 0;
  auto over = [&](double v) {
    d = std::max(d, v);
    return !(d <= limit);  // NaN counts as over
  };
  // The tips first (the likeliest to differ), then the bulk of the barbs.
  for (size_t s = 0; s < a.shafts.size(); ++s)
    if (!a.shafts[s].points.empty() && over(dist(a.shafts[s].points.back(), b.shafts[s].points.back()))) return d;
  for (size_t k = 0; k < a.cvs.size(); ++k)
    if (over(dist(a.cvs[k], b.cvs[k]))) return d;
  for (size_t k = 0; k < a.barbs.size(); ++k)
    if (over(dist(a.barbs[k].root, b.barbs[k].root)) ||
        over(extent * std::abs(double(a.barbs[k].rp) - double(b.barbs[k].rp))))
      return d;
  for (size_t s = 0; s < a.shafts.size(); ++s) {
    const ShaftCurve &x = a.shafts[s], &y = b.shafts[s];
    for (size_t k = 0; k < x.points.size(); ++k)
      if (over(dist(x.points[k], y.points[k]))) return d;
    for (size_t k = 0; k < x.widths.size(); ++k)
      if (over(0.5 * std::abs(double(x.widths[k]) - double(y.widths[k])))) return d;
    for (size_t k = 0; k < x.rp.size(); ++k)
      if (over(extent * std::abs(double(x.rp[k]) - double(y.rp[k])))) return d;
    for (size_t k = 0; k < x.rachisCvs.size(); ++k)
      if (over(dist(x.rachisCvs[k], y.rachisCvs[k]))) return d;
    for (int k = 0; k < 2; ++k)
      if (over(extent * dist(x.dorsal[k], y.dorsal[k]))) return d;
  }
  return d;
}

std::vector<uint32_t> shareCurves(const std::vector<const FeatherCurves*>& curves, double tolerance) {
  const size_t n = curves.size();
  std::vector<uint32_t> rep(n);
  for (size_t k = 0; k < n; ++k) rep[k] = static_cast<uint32_t>(k);
  if (!(tolerance > 0)) return rep;
  // Per structure key, the representatives sorted by the x of their first shaft's tip: a curve within
  // `limit` of a representative has its tip x within `limit` of that one's (curveDistance compares the
  // tips), so only that window is compared, and the lowest-numbered match in it is the first in order.
  struct Leader {
    double x;
    uint32_t k;
  };
  auto tipX = [](const FeatherCurves& c) {
    return c.shafts.empty() || c.shafts[0].points.empty() ? 0.0 : double(c.shafts[0].points.back().x);
  };
  std::unordered_map<uint64_t, std::vector<Leader>> leaders;
  for (size_t k = 0; k < n; ++k) {
    const FeatherCurves* c = curves[k];
    if (!c) continue;
    const double extent = curveExtent(*c);
    const double limit = tolerance * extent;
    if (!std::isfinite(limit)) continue;
    const double x = tipX(*c);
    std::vector<Leader>& bucket = leaders[structureKey(*c)];
    auto lo =
        std::lower_bound(bucket.begin(), bucket.end(), x - limit, [](const Leader& l, double v) { return l.x < v; });
    uint32_t best = static_cast<uint32_t>(k);
    for (auto it = lo; it != bucket.end() && it->x <= x + limit; ++it) {
      if (it->k >= best) continue;
      const FeatherCurves& l = *curves[it->k];
      if (curveDistance(*c, l, extent, limit) <= limit && sameCurveStructure(*c, l)) best = it->k;
    }
    rep[k] = best;
    if (best == k) {
      const Leader me{x, static_cast<uint32_t>(k)};
      bucket.insert(std::upper_bound(bucket.begin(), bucket.end(), me,
                                     [](const Leader& a, const Leader& b) { return a.x < b.x; }),
                    me);
    }
  }
  return rep;
}

}  // namespace pteryla::feather
