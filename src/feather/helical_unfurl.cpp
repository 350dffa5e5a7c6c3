// Zhang & Kanai, "Biological Modeling of Feather Based on Morphogenesis", 4.1 "Termination &
// Conversion" (1D loci to 3D points) and 4.2 Unfurling stage (segments rotated about the collar
// binormal from the distal to the proximal end, weighted by w), plus the barb spacing diagnostics of
// section 5 (inter-barb spacing near the vane edge vs the rachis; abnormal density at the tip).
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/helical.hpp"

namespace pteryla::feather {

namespace {

constexpr double kTipFraction = 0.05;

double wrapAngle(double a) {
  while (a > kPi) a -= 2 * kPi;
  while (a < -kPi) a += 2 * kPi;
  return a;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  double hi = v[m];
  if (v.size() % 2 == 1) return hi;
  const double lo = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m));
  return 0.5 * (lo + hi);
}

// Distance from p to the polyline pts[0..n) in the (x, y) plane of the feather frame.
double distanceToPolyline2(const glm::dvec3& p, const glm::dvec3* pts, size_t n) {
  double best = 1e300;
  for (size_t i = 0; i + 1 < n; ++i) {
    const glm::dvec2 a(pts[i].x, pts[i].y), b(pts[i + 1].x, pts[i + 1].y), q(p.x, p.y);
    const glm::dvec2 ab = b - a;
    const double len2 = ab.x * ab.x + ab.y * ab.y;
    double t = len2 > 0 ? ((q.x - a.x) * ab.x + (q.y - a.y) * ab.y) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    const glm::dvec2 d = a + t * ab - q;
    best = std::min(best, d.x * d.x + d.y * d.y);
  }
  if (n == 1) {
    const double dx = pts[0].x - p.x, dy = pts[0].y - p.y;
    best = dx * dx + dy * dy;
  }
  return std::sqrt(best);
}

// Point at fraction f of the polyline's length from its first point.
glm::dvec3 pointAtFraction(const glm::dvec3* pts, size_t n, double f) {
  double total = 0;
  for (size_t i = 0; i + 1 < n; ++i) total += glm::length(pts[i + 1] - pts[i]);
  double target = f * total;
  for (size_t i = 0; i + 1 < n; ++i) {
    const double seg = glm::length(pts[i + 1] - pts[i]);
    if (target <= seg && seg > 0) return pts[i] + (target / seg) * (pts[i + 1] - pts[i]);
    target -= seg;
  }
  return pts[n - 1];
}

}  // namespace

void unfurlTrail(std::vector<glm::dvec2>& xy, glm::dvec2 anchorDir, double w) {
  const size_t n = xy.size();
  if (n < 2 || w == 0.0) return;
  // Turning angles accumulated from the anchor (proximal) toward the distal end; rotating every joint
  // by w times its alignment angle leaves (1 - w) of each turning angle.
  anchorDir /= std::sqrt(anchorDir.x * anchorDir.x + anchorDir.y * anchorDir.y);
  const double ref = std::atan2(anchorDir.y, anchorDir.x);
  double prev = ref, theta = 0;
  glm::dvec2 pos = xy[n - 1], proximal = xy[n - 1];  // proximal: original position of xy[k + 1]
  for (size_t k = n - 1; k-- > 0;) {
    const glm::dvec2 e = xy[k] - proximal;
    proximal = xy[k];
    const double len = std::sqrt(e.x * e.x + e.y * e.y);
    if (len > 0) {
      const double phi = std::atan2(e.y, e.x);
      theta += wrapAngle(phi - prev);
      prev = phi;
    }
    if (w == 1.0) {
      pos += len * anchorDir;  // fully unfurled: every segment along the anchor direction
    } else {
      const double phiNew = ref + (1.0 - w) * theta;
      pos += len * glm::dvec2(std::cos(phiNew), std::sin(phiNew));
    }
    xy[k] = pos;
  }
}

HelicalFeather helicalFeather(const HelicalGrowth& g) {
  return helicalFeather(g, g.params().unfurlLeft, g.params().unfurlRight);
}

HelicalFeather helicalFeather(const HelicalGrowth& g, double unfurlLeft, double unfurlRight) {
  return helicalFeatherAt(g, g.endTime(), unfurlLeft, unfurlRight);
}

HelicalFeather helicalFeatherAt(const HelicalGrowth& g, double time, double unfurlLeft, double unfurlRight) {
  if (!(unfurlLeft >= 0 && unfurlLeft <= 1 && unfurlRight >= 0 && unfurlRight <= 1))
    throw Error("unfurl weights must be in [0, 1]", {}, "helical.unfurl");
  if (!(time >= 0 && time <= g.endTime())) throw Error("growth time must be in [0, endTime]", {}, "helical.time");
  const HelicalParams& p = g.params();
  const Collar& collar = g.collar();
  // tEnd: the time the feather is taken at (the end of growth for the grown feather); a barb belongs
  // to it once it has fused with the rachial ridge by then.
  const double tEnd = time, v = p.growthSpeed, L = collar.length();
  const glm::dvec2 A = collar.point(0.0), T0 = collar.tangent(0.0), N0 = collar.outwardNormal(0.0);

  HelicalFeather f;
  f.endTime = tEnd;
  f.length = v * tEnd;
  f.rachisWidth = L * (p.anteriorRight + (1.0 - p.anteriorLeft));

  std::vector<double> stamps;
  std::vector<glm::dvec2> xy;
  std::vector<double> height;
  const auto& barbs = g.barbs();
  size_t total = 0;
  for (const HelicalBarb& b : barbs)
    if (b.completionTime <= tEnd) total += g.maxStampCount(b);
  f.points.reserve(total);
  for (int vane = 0; vane < 2; ++vane) {
    const double w = vane == 0 ? unfurlLeft : unfurlRight;
    const glm::dvec2 anchorDir = vane == 0 ? -T0 : T0;
    // Base to tip = latest completion first.
    for (size_t i = g.vaneBegin(vane + 1); i-- > g.vaneBegin(vane);) {
      const HelicalBarb& b = barbs[i];
      if (!(b.completionTime <= tEnd)) continue;
      g.barbStamps(b, tEnd, stamps);
      xy.clear();
      height.clear();
      for (double s : stamps) {
        xy.push_back(collar.point(g.barbLocus(b, s - b.spawnTime)));
        height.push_back(v * (tEnd - s));
      }
      const size_t trail = xy.size();
      // The rachial ridge: from the I_A boundary along the collar to the anterior polar (the anchor).
      const double a = vane == 0 ? p.anteriorLeft : p.anteriorRight;
      const double arc = vane == 0 ? 1.0 - a : a;
      const int m = std::max(2, static_cast<int>(std::ceil(arc * 256)));
      for (int k = 1; k <= m; ++k) {
        const double s = vane == 0 ? a + arc * k / m : a - arc * k / m;
        xy.push_back(collar.point(s));
      }
      unfurlTrail(xy, anchorDir, w);

      HelicalFeatherBarb fb;
      fb.vane = static_cast<uint8_t>(vane);
      fb.growthIndex = static_cast<uint32_t>(i);
      fb.attach = height[trail - 1];
      fb.first = static_cast<uint32_t>(f.points.size());
      fb.count = static_cast<uint32_t>(trail);
      for (size_t k = trail; k-- > 0;) {
        const glm::dvec2 d = xy[k] - A;
        f.points.emplace_back(height[k], -(d.x * T0.x + d.y * T0.y), d.x * N0.x + d.y * N0.y);
      }
      f.barbs.push_back(fb);
    }
  }
  return f;
}

HelicalSpacingStats helicalSpacingStats(const HelicalGrowth& g) {
  const HelicalFeather f = helicalFeather(g, 1.0, 1.0);
  const auto& gb = g.barbs();
  HelicalSpacingStats stats;
  for (int vane = 0; vane < 2; ++vane) {
    // Spawn order (tip to base) = reverse of the feather's base-to-tip order.
    std::vector<const HelicalFeatherBarb*> order;
    for (const auto& b : f.barbs)
      if (b.vane == vane) order.push_back(&b);
    std::reverse(order.begin(), order.end());
    VaneSpacingStats& st = stats.vane[vane];
    st.barbs = static_cast<int>(order.size());
    std::vector<double> all, tip, edge, rachis;
    for (size_t k = 0; k < order.size(); ++k) {
      const HelicalFeatherBarb& b = *order[k];
      const glm::dvec3* pts = &f.points[b.first];
      for (uint32_t q = 0; q < b.count; ++q) st.width = std::max(st.width, std::abs(pts[q].y));
      // The tip: barbs whose distal end lies in the distal 5% of the feather (at least two barbs).
      const bool atTip = k < 2 || pts[b.count - 1].x >= (1.0 - kTipFraction) * f.length;
      if (atTip) ++st.tipBarbs;
      if (k + 1 == order.size()) break;
      const HelicalFeatherBarb& c = *order[k + 1];
      const glm::dvec3* qts = &f.points[c.first];
      const double d = glm::length(qts[c.count - 1] - pts[b.count - 1]);
      all.push_back(d);
      if (atTip) tip.push_back(d);
      if (!gb[b.growthIndex].tipRegion && !gb[c.growthIndex].tipRegion && b.count > 2 && c.count > 2) {
        edge.push_back(distanceToPolyline2(pointAtFraction(pts, b.count, 0.9), qts, c.count));
        rachis.push_back(distanceToPolyline2(pointAtFraction(pts, b.count, 0.1), qts, c.count));
      }
    }
    st.medianSpacing = median(all);
    if (!tip.empty()) {
      double sum = 0;
      for (double d : tip) sum += d;
      st.tipSpacing = sum / static_cast<double>(tip.size());
    }
    st.tipRatio = st.medianSpacing > 0 ? st.tipSpacing / st.medianSpacing : 0.0;
    st.tipMaxRatio =
        st.medianSpacing > 0 && !tip.empty() ? *std::max_element(tip.begin(), tip.end()) / st.medianSpacing : 0.0;
    st.nearEdge = median(edge);
    st.nearRachis = median(rachis);
  }
  return stats;
}

}  // namespace pteryla::feather
