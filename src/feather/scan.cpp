// Feather acquisition from a flatbed scan, Streit 2003 5.2.3 ("not only can the barb length be extracted
// from the scan, but also the placement and control points of key barbs, barb spacing and barb angle")
// and 9.1.1 (texture, shaft curvature and silhouette from the scan; the texture re-sampled). Segmentation
// and the rachis arc come from silhouette.cpp ([GW92] thresholding). Barb orientation is the dominant
// orientation of the structure tensor (Bigun & Granlund 1987; Kass & Witkin 1987) of the Gaussian-smoothed
// scan, refined to the direction of sharpest projection (as in projection-profile skew detection); barb
// spacing the first strong peak of the autocorrelation of the intensity along lines parallel to the
// rachis.
#include "pteryla/feather/scan.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/barbs.hpp"
#include "scan_internal.hpp"

namespace pteryla::feather {

namespace {

using scanning::imageLeft;
using scanning::PixelArc;
using scanning::sample;

// Separable Gaussian blur (sigma in pixels, clamped borders).
std::vector<float> blur(const std::vector<float>& src, int w, int h, double sigma) {
  const int r = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
  std::vector<float> k(2 * r + 1);
  float sum = 0;
  for (int i = -r; i <= r; ++i) sum += k[i + r] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)));
  for (auto& x : k) x /= sum;
  std::vector<float> tmp(src.size()), out(src.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float a = 0;
      for (int i = -r; i <= r; ++i) a += k[i + r] * src[static_cast<size_t>(y) * w + std::clamp(x + i, 0, w - 1)];
      tmp[static_cast<size_t>(y) * w + x] = a;
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float a = 0;
      for (int i = -r; i <= r; ++i) a += k[i + r] * tmp[static_cast<size_t>(std::clamp(y + i, 0, h - 1)) * w + x];
      out[static_cast<size_t>(y) * w + x] = a;
    }
  return out;
}

// Solves the n x n system a x = b (Gaussian elimination, partial pivoting); false when singular.
template <size_t N>
bool solve(std::array<std::array<double, N>, N> a, std::array<double, N> b, std::array<double, N>& x) {
  for (size_t c = 0; c < N; ++c) {
    size_t piv = c;
    for (size_t r = c + 1; r < N; ++r)
      if (std::abs(a[r][c]) > std::abs(a[piv][c])) piv = r;
    if (std::abs(a[piv][c]) < 1e-12) return false;
    std::swap(a[c], a[piv]);
    std::swap(b[c], b[piv]);
    for (size_t r = c + 1; r < N; ++r) {
      const double f = a[r][c] / a[c][c];
      for (size_t k = c; k < N; ++k) a[r][k] -= f * a[c][k];
      b[r] -= f * b[c];
    }
  }
  for (size_t c = N; c-- > 0;) {
    double s = b[c];
    for (size_t k = c + 1; k < N; ++k) s -= a[c][k] * x[k];
    x[c] = s / a[c][c];
  }
  return true;
}

// Largest 8-connected region of the mask (ties: the first in scan order); other pixels cleared.
std::vector<uint8_t> largestRegion(const std::vector<uint8_t>& mask, int w, int h, size_t& size) {
  std::vector<int> label(mask.size(), -1);
  std::vector<size_t> stack;
  int best = -1, next = 0;
  size = 0;
  for (size_t i = 0; i < mask.size(); ++i) {
    if (!mask[i] || label[i] >= 0) continue;
    size_t count = 0;
    stack.assign(1, i);
    label[i] = next;
    while (!stack.empty()) {
      const size_t q = stack.back();
      stack.pop_back();
      ++count;
      const int x = static_cast<int>(q % w), y = static_cast<int>(q / w);
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
          const size_t n = static_cast<size_t>(yy) * w + xx;
          if (mask[n] && label[n] < 0) {
            label[n] = next;
            stack.push_back(n);
          }
        }
    }
    if (count > size) size = count, best = next;
    ++next;
  }
  std::vector<uint8_t> out(mask.size(), 0);
  for (size_t i = 0; i < mask.size(); ++i) out[i] = label[i] == best && best >= 0 ? 1 : 0;
  return out;
}

// Angle in (0, pi) between the rachis tangent at s (toward the tip) and the line `dir`, opening toward
// vane v.
double angleToRachis(const PixelArc& arc, int v, double s, glm::dvec2 dir) {
  const double a = std::atan2(glm::dot(dir, arc.side(v, s)), glm::dot(dir, arc.tangent(s)));
  return a < 0 ? a + kPi : a;
}

// A window's dominant barb direction (image pixels) at distance d across vane v from rachis position s.
struct OrientationWindow {
  double s, d, weight;
  glm::dvec2 dir;
};

// Perpendicular half-width (pixels, >= 1) of vane v at rp, from a silhouette pass with perpendicular rays.
struct VaneWidth {
  const SilhouetteImageResult* perp;
  double len;
  int v;
  double operator()(double rp) const {
    const LengthProfile& p = v == 0 ? perp->relative.left : perp->relative.right;
    return std::max(1.0, p.at(std::clamp(rp, 0.0, 1.0)) * len);
  }
};

// Barbs of a vane: root angle a(rp) and turning over the barb bend(rp), both linear in rp; a barb is a
// circular arc whose tip reaches the vane's edge.
struct VaneModel {
  double a0 = kPi / 4, a1 = kPi / 4, k0 = 0, k1 = 0;
  bool bent = false;  // k0, k1 were fitted (else 0)
  double angle(double rp) const { return a0 + (a1 - a0) * rp; }
  double bend(double rp) const { return k0 + (k1 - k0) * rp; }
};

// Along (x) and across (y) offset from the root of the point at arc length fraction u of a barb of root
// angle a, turning k, arc length 1.
glm::dvec2 barbOffset(double a, double k, double u) {
  if (std::abs(k) < 1e-6) return u * glm::dvec2(std::cos(a), std::sin(a));
  return {(std::sin(a) - std::sin(a - k * u)) / k, (std::cos(a - k * u) - std::cos(a)) / k};
}

// The root (arc length sRoot along the rachis) of the model barb through the point at distance d across
// the vane from rachis position s, and the fraction u of the barb's length at which it passes there.
// width(rp) is the vane's perpendicular half-width (pixels) at rp; the straight-rachis approximation.
template <class Width>
void traceToRoot(const VaneModel& m, double s, double d, double len, const Width& width, double& sRoot, double& u) {
  sRoot = s - d / std::tan(std::clamp(m.angle(s / len), 0.05, kPi - 0.05));
  for (int it = 0; it < 6; ++it) {
    const double rp = sRoot / len, a = std::clamp(m.angle(rp), 0.05, kPi - 0.05), k = m.bend(rp);
    const glm::dvec2 tip = barbOffset(a, k, 1);
    double arcLen = width(rp) / std::max(1e-3, tip.y);
    for (int j = 0; j < 2; ++j) arcLen = width(rp + arcLen * tip.x / len) / std::max(1e-3, tip.y);
    double lo = 0, hi = 1.5;  // barbOffset(...).y increases with u while the barb points away from the rachis
    for (int j = 0; j < 40; ++j) {
      const double mid = 0.5 * (lo + hi);
      (arcLen * barbOffset(a, k, mid).y < d ? lo : hi) = mid;
    }
    u = 0.5 * (lo + hi);
    sRoot = s - arcLen * barbOffset(a, k, u).x;
  }
}

// Fits the model to the windows (weighted least squares, alternating with traceToRoot). False when too
// few windows span the rachis; bent = false when they do not span the vane's width enough for the bend.
// used: windows kept (not outliers); rms: their root mean square residual, radians.
template <class Width>
bool fitVane(const std::vector<OrientationWindow>& windows, const PixelArc& arc, int v, double len, const Width& width,
             VaneModel& m, int& used, double& rms) {
  rms = 0;
  used = 0;
  if (windows.size() < 2) return false;
  std::vector<double> first;
  for (const auto& o : windows) first.push_back(angleToRachis(arc, v, o.s, o.dir));
  std::nth_element(first.begin(), first.begin() + first.size() / 2, first.end());
  m = VaneModel();
  m.a0 = m.a1 = first[first.size() / 2];
  bool ok = false;
  std::vector<double> keep(windows.size(), 1.0);  // 0 for outliers (a window over the vane's edge, ...)
  for (int it = 0; it < 10; ++it) {
    std::array<std::array<double, 4>, 4> ata{};
    std::array<double, 4> atb{}, x{};
    double umin = 2, umax = -1, rmin = 2, rmax = -1;
    used = 0;
    std::vector<double> residual(windows.size(), -1.0);
    for (size_t i = 0; i < windows.size(); ++i) {
      const OrientationWindow& o = windows[i];
      double sRoot = 0, u = 0;
      traceToRoot(m, o.s, o.d, len, width, sRoot, u);
      const double rp = sRoot / len;
      if (rp < 0 || rp > 1) continue;
      const double angle = angleToRachis(arc, v, sRoot, o.dir);
      residual[i] = std::abs(angle - (m.angle(rp) - m.bend(rp) * u));
      if (keep[i] == 0) continue;
      const std::array<double, 4> row{1 - rp, rp, -(1 - rp) * u, -rp * u};
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) ata[r][c] += o.weight * row[r] * row[c];
        atb[r] += o.weight * row[r] * angle;
      }
      umin = std::min(umin, u), umax = std::max(umax, u), rmin = std::min(rmin, rp), rmax = std::max(rmax, rp);
      ++used;
    }
    if (used < 2 || rmax - rmin < 0.3) return false;
    const VaneModel prev = m;
    if (used >= 6 && umax - umin > 0.2 && solve<4>(ata, atb, x)) {
      m.a0 = x[0], m.a1 = x[1], m.k0 = std::clamp(x[2], -1.5, 1.5), m.k1 = std::clamp(x[3], -1.5, 1.5), m.bent = true;
    } else {
      const std::array<std::array<double, 2>, 2> a2{{{ata[0][0], ata[0][1]}, {ata[1][0], ata[1][1]}}};
      std::array<double, 2> x2{};
      if (!solve<2>(a2, {atb[0], atb[1]}, x2)) return false;
      m.a0 = x2[0], m.a1 = x2[1], m.k0 = m.k1 = 0, m.bent = false;
    }
    m.a0 = std::clamp(m.a0, 0.05, kPi - 0.05), m.a1 = std::clamp(m.a1, 0.05, kPi - 0.05);
    ok = true;
    // From the second fit on, drop windows further from the model than 3x the median residual (at least 2 deg).
    if (it >= 1) {
      std::vector<double> r;
      for (size_t i = 0; i < windows.size(); ++i)
        if (residual[i] >= 0 && keep[i] > 0) r.push_back(residual[i]);
      if (!r.empty()) {
        std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
        const double limit = std::max(2 * kPi / 180, 3 * r[r.size() / 2]);
        for (size_t i = 0; i < windows.size(); ++i)
          if (residual[i] > limit) keep[i] = 0;
      }
    }
    if (it >= 2 &&
        std::abs(m.a0 - prev.a0) + std::abs(m.a1 - prev.a1) + std::abs(m.k0 - prev.k0) + std::abs(m.k1 - prev.k1) <
            1e-5)
      break;
  }
  double sum = 0;
  used = 0;
  for (size_t i = 0; i < windows.size(); ++i) {
    if (keep[i] == 0) continue;
    double sRoot = 0, u = 0;
    traceToRoot(m, windows[i].s, windows[i].d, len, width, sRoot, u);
    const double rp = sRoot / len;
    if (rp < 0 || rp > 1) continue;
    const double e = angleToRachis(arc, v, sRoot, windows[i].dir) - (m.angle(rp) - m.bend(rp) * u);
    sum += e * e, ++used;
  }
  rms = used > 0 ? std::sqrt(sum / used) : 0;
  return ok && used >= 2;
}

// Sharpness of the window's intensity projected across direction `angle` (image radians): the
// between-bin sum of squares of the samples binned (0.5 px) by their distance across that direction. Lines
// of that direction project onto few bins, so it peaks at their orientation.
double projectionSharpness(const std::vector<glm::dvec3>& pts, double angle) {
  const glm::dvec2 n(-std::sin(angle), std::cos(angle));
  double lo = 1e300, hi = -1e300;
  for (const auto& q : pts)
    lo = std::min(lo, glm::dot(glm::dvec2(q), n)), hi = std::max(hi, glm::dot(glm::dvec2(q), n));
  const size_t bins = static_cast<size_t>((hi - lo) / 0.5) + 1;
  std::vector<double> sum(bins, 0.0), count(bins, 0.0);
  for (const auto& q : pts) {
    const size_t b = std::min(bins - 1, static_cast<size_t>((glm::dot(glm::dvec2(q), n) - lo) / 0.5));
    sum[b] += q.z, count[b] += 1;
  }
  double acc = 0;
  for (size_t b = 0; b < bins; ++b)
    if (count[b] > 0) acc += sum[b] * sum[b] / count[b];
  return acc;
}

// Dominant barb direction (unit, image pixels) in the window s in [s0, s1], across distance [d0, d1] of
// vane v; coherence in [0, 1] ((l1 - l2) / (l1 + l2) of the structure tensor; 0 when under 80% of the
// window is in the mask). The structure tensor's
// orientation is biased toward the pixel diagonals for fine line patterns (the central difference's
// response falls off at high frequency), so it only seeds a search for the sharpest projection.
glm::dvec2 windowOrientation(const std::vector<float>& pixels, const std::vector<uint8_t>& mask,
                             const std::vector<float>& gx, const std::vector<float>& gy, int w, int h,
                             const PixelArc& arc, int v, double s0, double s1, double d0, double d1,
                             double& coherence) {
  size_t inside = 0;
  double jxx = 0, jxy = 0, jyy = 0;
  std::vector<glm::dvec3> pts;  // x, y relative to the window centre; z intensity
  const glm::dvec2 centre = arc.point(0.5 * (s0 + s1)) + 0.5 * (d0 + d1) * arc.side(v, 0.5 * (s0 + s1));
  for (double s = s0; s <= s1; s += 0.5)
    for (double d = d0; d <= d1; d += 0.5) {
      const glm::dvec2 q = arc.point(s) + d * arc.side(v, s);
      if (q.x < 1 || q.y < 1 || q.x > w - 2 || q.y > h - 2) continue;
      const double a = sample(gx, w, h, q.x, q.y), b = sample(gy, w, h, q.x, q.y);
      jxx += a * a, jxy += a * b, jyy += b * b;
      pts.emplace_back(q - centre, sample(pixels, w, h, q.x, q.y));
      inside += mask[static_cast<size_t>(std::lround(q.y)) * w + static_cast<size_t>(std::lround(q.x))];
    }
  const double tr = jxx + jyy, det = std::sqrt((jxx - jyy) * (jxx - jyy) + 4 * jxy * jxy);
  // A window reaching over the vane's edge sees the edge's direction: ignore it.
  coherence = tr > 1e-20 && inside >= 0.8 * pts.size() ? det / tr : 0;
  // Barbs run across the dominant gradient direction.
  double best = 0.5 * std::atan2(2 * jxy, jxx - jyy) + kPi / 2;
  if (pts.size() < 16) return {std::cos(best), std::sin(best)};
  for (double step : {0.5 * kPi / 180, 0.1 * kPi / 180}) {
    const int reach = step > 0.2 * kPi / 180 ? 16 : 5;
    double bestVal = -1, at = best;
    std::vector<double> vals(2 * reach + 1);
    for (int k = -reach; k <= reach; ++k) {
      vals[k + reach] = projectionSharpness(pts, best + k * step);
      if (vals[k + reach] > bestVal) bestVal = vals[k + reach], at = best + k * step;
    }
    const int i = static_cast<int>(std::lround((at - best) / step)) + reach;
    if (i > 0 && i < 2 * reach) {
      const double a = vals[i - 1], b = vals[i], c = vals[i + 1], den = a - 2 * b + c;
      if (std::abs(den) > 1e-12) at += step * std::clamp(0.5 * (a - c) / den, -0.5, 0.5);
    }
    best = at;
  }
  return {std::cos(best), std::sin(best)};
}

// Period (pixels) of the signals (same length, step `step`) from their summed normalized autocorrelation:
// the highest peak, or a peak at a fraction of its lag at least half as high (the fundamental). 0 when
// no peak reaches 0.2.
double period(const std::vector<std::vector<double>>& signals, double step, double minLag) {
  if (signals.empty()) return 0;
  const size_t n = signals.front().size();
  const size_t maxLag = n / 3, lag0 = static_cast<size_t>(std::ceil(minLag / step));
  if (maxLag <= lag0 + 2) return 0;
  std::vector<double> r(maxLag + 1, 0.0);
  for (const auto& sig : signals) {
    double mean = 0;
    for (double x : sig) mean += x;
    mean /= n;
    double var = 0;
    for (double x : sig) var += (x - mean) * (x - mean);
    if (var < 1e-12) continue;
    for (size_t lag = 0; lag <= maxLag; ++lag) {
      double acc = 0;
      for (size_t i = 0; i + lag < n; ++i) acc += (sig[i] - mean) * (sig[i + lag] - mean);
      r[lag] += acc / var * n / static_cast<double>(n - lag) / signals.size();
    }
  }
  std::vector<size_t> peaks;
  for (size_t lag = std::max<size_t>(lag0, 1); lag < maxLag; ++lag)
    if (r[lag] > r[lag - 1] && r[lag] >= r[lag + 1] && r[lag] > 0.2) peaks.push_back(lag);
  if (peaks.empty()) return 0;
  size_t best = peaks.front();
  for (size_t p : peaks)
    if (r[p] > r[best]) best = p;
  for (size_t p : peaks) {
    if (p >= best) break;
    const double ratio = static_cast<double>(best) / p;
    if (r[p] > 0.5 * r[best] && std::abs(ratio - std::round(ratio)) < 0.15) {
      best = p;
      break;
    }
  }
  const double a = r[best - 1], b = r[best], c = r[best + 1], den = a - 2 * b + c;
  const double off = std::abs(den) > 1e-12 ? std::clamp(0.5 * (a - c) / den, -0.5, 0.5) : 0.0;
  return (best + off) * step;
}

// Cubic Bezier of a circular arc of unit chord turning by `bend` (barb-local: x along, y toward the tip).
std::vector<glm::dvec3> bentBarb(double bend) {
  if (std::abs(bend) < 1e-6) return {{0, 0, 0}, {1.0 / 3, 0, 0}, {2.0 / 3, 0, 0}, {1, 0, 0}};
  const double radius = 1 / (2 * std::sin(std::abs(bend) / 2));  // chord 1
  const double h = (4.0 / 3.0) * std::tan(std::abs(bend) / 4) * radius, sg = bend > 0 ? 1.0 : -1.0;
  const glm::dvec3 p3(radius * std::sin(std::abs(bend)), sg * radius * (1 - std::cos(std::abs(bend))), 0);
  const glm::dvec3 t3(std::cos(bend), std::sin(bend), 0);
  return {{0, 0, 0}, {h, 0, 0}, p3 - h * t3, p3};
}

}  // namespace

std::vector<glm::dvec2> detectRachis(const GrayImage& img) {
  const int w = img.width, h = img.height;
  const Segmentation seg = segmentFeather(img);
  size_t count = 0;
  const std::vector<uint8_t> mask = largestRegion(seg.mask, w, h, count);
  if (count < 50)
    throw Error("no feather found: the largest region off the background has only " + std::to_string(count) +
                    (count == 1 ? " pixel" : " pixels") + " (expected one feather on a plain background)",
                {}, "image");
  // Principal axis of the region.
  glm::dvec2 c(0.0);
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) c += glm::dvec2(i % w, i / w);
  c /= static_cast<double>(count);
  double sxx = 0, sxy = 0, syy = 0;
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) {
      const glm::dvec2 d = glm::dvec2(i % w, i / w) - c;
      sxx += d.x * d.x, sxy += d.x * d.y, syy += d.y * d.y;
    }
  const double phi = 0.5 * std::atan2(2 * sxy, sxx - syy);
  const glm::dvec2 e(std::cos(phi), std::sin(phi)), n = imageLeft(e);
  // Extent across the axis per 1-pixel slice along it.
  double smin = 1e300, smax = -1e300;
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) {
      const double s = glm::dot(glm::dvec2(i % w, i / w) - c, e);
      smin = std::min(smin, s), smax = std::max(smax, s);
    }
  const int bins = static_cast<int>(smax - smin) + 1;
  std::vector<double> lo(bins, 1e300), hi(bins, -1e300), sum(bins, 0.0), num(bins, 0.0);
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) {
      const glm::dvec2 d = glm::dvec2(i % w, i / w) - c;
      const int b = std::clamp(static_cast<int>(glm::dot(d, e) - smin), 0, bins - 1);
      const double q = glm::dot(d, n);
      lo[b] = std::min(lo[b], q), hi[b] = std::max(hi[b], q), sum[b] += q, num[b] += 1;
    }
  double widest = 0;
  for (int b = 0; b < bins; ++b)
    if (num[b] > 0) widest = std::max(widest, hi[b] - lo[b] + 1);
  const double thin = std::max(5.0, 0.06 * widest);
  auto isThin = [&](int b) { return num[b] == 0 || hi[b] - lo[b] + 1 <= thin; };
  int runLo = 0, runHi = 0;
  while (runLo < bins && isThin(runLo)) ++runLo;
  while (runHi < bins && isThin(bins - 1 - runHi)) ++runHi;
  const double minRun = std::max(3.0, 0.03 * bins);
  int base;  // +1: the base is at smin
  if (runLo >= minRun && runLo >= 1.5 * runHi)
    base = 1;
  else if (runHi >= minRun && runHi >= 1.5 * runLo)
    base = -1;
  else
    throw Error(
        "cannot tell the base from the tip: neither end of the feather has a bare calamus clearly longer than the "
        "other's; mark the rachis (base, tip)",
        {}, "rachis");
  // Base: the calamus centre line where the vanes begin.
  auto centre = [&](int from, int to) {
    double q = 0, m = 0;
    for (int b = std::min(from, to); b <= std::max(from, to); ++b)
      if (b >= 0 && b < bins) q += sum[b], m += num[b];
    return m > 0 ? q / m : 0.0;
  };
  const int umb = base > 0 ? runLo : bins - 1 - runHi;   // first bin with vane
  const int cal0 = base > 0 ? runLo - 1 : bins - runHi;  // last calamus bin
  const int cal1 = base > 0 ? runLo - 5 : bins - runHi + 4;
  const glm::dvec2 basePt = c + (smin + umb + 0.5) * e + centre(cal0, cal1) * n;
  // Follow the shaft's ridge from the base: each 1.5-pixel step looks 1 pixel either side of the line
  // ahead for the most shaft-like pixel (the shaft is darker or lighter than the background, as the
  // calamus is) and moves at most 0.5 pixel toward it; the direction follows the last 12 steps and turns
  // at most 0.5 degree a step (a rachis turning by pi over 540 pixels), so barbs crossing the shaft do
  // not pull the track away. The tip is where no pixel ahead is closer to the
  // shaft's level than to the vane's for 3 pixels, or where the track leaves the feather.
  const std::vector<float> smooth = blur(img.pixels, w, h, 1.0);
  const glm::dvec2 calamusPt = basePt - 3.0 * base * e;
  const double polarity = sample(smooth, w, h, calamusPt.x, calamusPt.y) < seg.background ? 1.0 : -1.0;
  const double shaftLevel = polarity * sample(img.pixels, w, h, calamusPt.x, calamusPt.y);
  std::vector<float> vanePixels;
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) vanePixels.push_back(static_cast<float>(polarity) * img.pixels[i]);
  std::nth_element(vanePixels.begin(), vanePixels.begin() + vanePixels.size() / 2, vanePixels.end());
  const double ridgeLimit = 0.5 * (shaftLevel + vanePixels[vanePixels.size() / 2]);
  const auto inFeather = [&](glm::dvec2 q) {
    const int x = static_cast<int>(std::lround(q.x)), y = static_cast<int>(std::lround(q.y));
    return x >= 0 && y >= 0 && x < w && y < h && mask[static_cast<size_t>(y) * w + x];
  };
  std::vector<glm::dvec2> track{basePt};
  glm::dvec2 dir = static_cast<double>(base) * e;
  int misses = 0;
  size_t lastInside = 0;
  const double maxTurn = 0.5 * kPi / 180;
  for (int step = 0; step < 4 * (bins + 10) && misses <= 2; ++step) {
    const glm::dvec2 ahead = track.back() + 1.5 * dir, across = imageLeft(dir);
    double best = 1e300, bestO = 0;
    for (double o = -1; o <= 1; o += 0.25) {
      const glm::dvec2 q = ahead + o * across;
      const double val = polarity * sample(img.pixels, w, h, q.x, q.y) + 1e-3 * std::abs(o);  // ties: straight on
      if (val < best) best = val, bestO = o;
    }
    const bool ridge = best < ridgeLimit;
    const glm::dvec2 q = ridge ? ahead + std::clamp(bestO, -0.5, 0.5) * across : ahead;
    if (q.x < 0 || q.y < 0 || q.x > w - 1 || q.y > h - 1) break;
    track.push_back(q);
    if (ridge && inFeather(q))
      misses = 0, lastInside = track.size() - 1;
    else
      ++misses;
    const glm::dvec2 back = track[track.size() > 12 ? track.size() - 12 : 0];
    if (glm::length(q - back) < 1e-9) continue;
    const glm::dvec2 want = glm::normalize(q - back);
    const double turn = std::atan2(glm::dot(want, imageLeft(dir)), glm::dot(want, dir));
    const double t = std::clamp(turn, -maxTurn, maxTurn);
    dir = std::cos(t) * dir + std::sin(t) * imageLeft(dir);
  }
  track.resize(lastInside + 1);
  if (track.size() < 12) throw Error("no shaft found beyond the calamus; mark the rachis (base, tip)", {}, "rachis");
  // Where the shaft thins out the track follows noise and barbs as readily as the shaft: fit a circular
  // arc to its first 85% and follow that arc, from there, to where it leaves the feather (gaps of 2
  // pixels allowed): the tip.
  const size_t firm = std::max<size_t>(2, track.size() * 85 / 100);
  const glm::dvec2 a = track.front(), b = track[firm - 1];
  const double chord = glm::length(b - a);
  if (chord < 8) throw Error("no shaft found beyond the calamus; mark the rachis (base, tip)", {}, "rachis");
  const glm::dvec2 ce = (b - a) / chord, cl = imageLeft(ce);
  double sagNum = 0, sagDen = 0;  // the chord's sag, as silhouette.cpp fits it
  for (size_t i = 0; i < firm; ++i) {
    const double u = glm::dot(track[i] - a, ce) / chord, basis = 4 * u * (1 - u);
    sagNum += glm::dot(track[i] - a, cl) * basis, sagDen += basis * basis;
  }
  const double turning = std::clamp(-4 * std::atan(2 * (sagDen > 0 ? sagNum / sagDen : 0) / chord), -kPi, kPi);
  const double arcLen = std::abs(turning) < 1e-9 ? chord : chord * (turning / 2) / std::sin(turning / 2);
  PixelArc firmArc({a, b}, turning, arcLen);
  const auto along = [&](double s) {  // the arc's circle continued beyond its end
    if (s <= firmArc.len) return firmArc.point(s);
    PixelArc longer = firmArc;
    longer.len = s, longer.theta = firmArc.theta * s / firmArc.len;
    return longer.point(s);
  };
  double lastIn = arcLen;
  for (double s = arcLen; s - lastIn <= 2.0 && s < 2 * arcLen; s += 0.5)
    if (inFeather(along(s))) lastIn = s;
  // The polyline handed on: the arc, every 8 pixels, to the tip.
  std::vector<glm::dvec2> out;
  for (double s = 0; s < lastIn; s += 8) out.push_back(along(s));
  out.push_back(along(lastIn));
  return out;
}

ScanResult acquireScan(const GrayImage& img, const ScanOptions& opt) {
  const int w = img.width, h = img.height;
  if (!(opt.pixelsPerUnit > 0) || !std::isfinite(opt.pixelsPerUnit))
    throw Error("expected pixels per scene unit > 0", {}, "pixels_per_unit");
  ScanResult res;
  FeatherParams& p = res.feather;
  p.seed = opt.seed;
  SilhouetteImageOptions so;
  so.samples = opt.samples;
  so.gapTolerance = opt.gapTolerance;
  so.rachis = opt.rachis;
  if (so.rachis.empty()) {
    so.rachis = detectRachis(img);
    res.rachisDetected = true;
  }
  // Pass 1: rachis arc and perpendicular vane widths (rays at 90 degrees).
  const SilhouetteImageResult perp = extractSilhouette(img, so);
  res.rachis = perp.rachis;
  res.rachisLengthPixels = perp.rachisLengthPixels;
  const double len = perp.rachisLengthPixels;
  if (len < 16) throw Error("the rachis is shorter than 16 pixels: too small to measure", {}, "rachis");
  const PixelArc arc(perp.rachis, perp.lateralCurvature, len);
  const double ppu = opt.pixelsPerUnit;

  // Calamus: bare shaft continuing below the base, mask within 2 pixels of the line, 2-pixel gaps allowed.
  const auto inMask = [&](glm::dvec2 q) {
    const int x = static_cast<int>(std::lround(q.x)), y = static_cast<int>(std::lround(q.y));
    return x >= 0 && y >= 0 && x < w && y < h && perp.mask[static_cast<size_t>(y) * w + x];
  };
  double lastIn = 0;
  for (double s = 0; s > -len; s -= 0.5) {
    bool hit = false;
    for (double d = -2; d <= 2 && !hit; d += 1) hit = inMask(arc.point(s) + d * arc.side(0, s));
    if (hit)
      lastIn = s;
    else if (lastIn - s > opt.gapTolerance)
      break;
  }
  res.calamusLengthPixels = -lastIn;
  if (res.calamusLengthPixels >= 4) {
    // Width across the calamus half-way down: the run of mask through the centre line.
    const double s = 0.5 * lastIn;
    double a = 0, b = 0;
    while (a < 0.25 * len && inMask(arc.point(s) + (a + 0.5) * arc.side(0, s))) a += 0.5;
    while (b < 0.25 * len && inMask(arc.point(s) - (b + 0.5) * arc.side(0, s))) b += 0.5;
    // The calamus tapers from calamusWidthRatio x the rachis width at the follicle to the rachis width.
    res.rachisWidthPixels = (a + b + 0.5) * 2 / (1 + p.calamusWidthRatio);
  } else {
    res.notes.push_back("no calamus below the rachis base: calamus length 0, rachis width 1.6% of its length");
  }
  p.rachisLength = len / ppu;
  p.calamusLength = res.calamusLengthPixels / ppu;
  p.rachisWidth = res.rachisWidthPixels > 0 ? res.rachisWidthPixels / ppu : 0.016 * p.rachisLength;
  p.rachisLateralCurvature = std::clamp(perp.lateralCurvature, -kPi, kPi);
  p.rachisVentralDorsalCurvature = 0;
  const double clear = 2 + 0.5 * std::max(res.rachisWidthPixels, 0.016 * len);  // pixels beside the rachis centre

  // Barb orientation: structure tensor windows over rp and across the vane.
  const std::vector<float> smooth = blur(img.pixels, w, h, 1.0);
  std::vector<float> gx(smooth.size(), 0.0f), gy(smooth.size(), 0.0f);
  for (int y = 1; y + 1 < h; ++y)
    for (int x = 1; x + 1 < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      gx[i] = 0.5f * (smooth[i + 1] - smooth[i - 1]);
      gy[i] = 0.5f * (smooth[i + w] - smooth[i - w]);
    }
  constexpr double kBands[3][2] = {{0.12, 0.37}, {0.37, 0.62}, {0.62, 0.87}};
  const double halfWindow = 0.05 * len;
  std::vector<OrientationWindow> windows[2];
  for (int v = 0; v < 2; ++v)
    for (double rpc = 0.12; rpc < 0.93; rpc += 0.1) {
      const double sc = rpc * len, width = VaneWidth{&perp, len, v}(rpc);
      for (const auto& band : kBands) {
        const double d0 = std::max(clear, band[0] * width), d1 = band[1] * width;
        if (d1 - d0 < 3) continue;
        double coherence = 0;
        const glm::dvec2 dir = windowOrientation(img.pixels, perp.mask, gx, gy, w, h, arc, v, sc - halfWindow,
                                                 sc + halfWindow, d0, d1, coherence);
        if (coherence >= 0.3) windows[v].push_back({sc, 0.5 * (d0 + d1), coherence, dir});
      }
    }
  VaneModel models[2];
  // Fits vane v's angles and key barbs to its windows; returns a note when it could not.
  const auto fitOrientation = [&](int v) -> std::string {
    ScanVaneFit& fit = res.vanes[v];
    VaneParams& vp = p.vane(v);
    VaneModel& model = models[v];
    fit = ScanVaneFit();
    double rms = 0;
    fit.measured = fitVane(windows[v], arc, v, len, VaneWidth{&perp, len, v}, model, fit.windows, rms);
    // A fit that ran into its limits, kept under half the windows or leaves them scattered is no measurement
    // (barbs too fine for the scan's resolution, or disordered).
    const bool atLimit = std::min(model.a0, model.a1) <= 0.051 || std::max(model.a0, model.a1) >= kPi - 0.051 ||
                         std::max(std::abs(model.k0), std::abs(model.k1)) >= 1.49;
    const bool consistent = !atLimit && 2 * fit.windows >= static_cast<int>(windows[v].size()) && rms <= 4 * kPi / 180;
    const std::string vaneName = v == 0 ? "left" : "right";
    std::string note;
    if (fit.measured && !consistent) {
      fit.measured = false;
      char why[160];
      std::snprintf(why, sizeof why, " vane: barb orientation inconsistent (%d of %zu windows agree, rms %.1f deg%s)",
                    fit.windows, windows[v].size(), rms * 180 / kPi, atLimit ? ", fit at its limits" : "");
      note = vaneName + why + ": default angles and straight key barbs";
    } else if (!fit.measured) {
      note = vaneName + " vane: barb orientation not measurable (" + std::to_string(windows[v].size()) +
             " coherent windows): default angles and straight key barbs";
    }
    if (!fit.measured) {
      const FeatherParams defaults;
      vp.baseAngle = fit.baseAngle = defaults.vane(v).baseAngle;
      vp.tipAngle = fit.tipAngle = defaults.vane(v).tipAngle;
      vp.keyBarbs = {{0.0, bentBarb(0)}, {1.0, bentBarb(0)}};
      model = VaneModel();
      model.a0 = vp.baseAngle, model.a1 = vp.tipAngle;
      return note;
    }
    fit.baseAngle = std::clamp(model.a0, 0.05, kPi - 0.05);
    fit.tipAngle = std::clamp(model.a1, 0.05, kPi - 0.05);
    fit.bendBase = std::clamp(model.k0, -1.5, 1.5);
    fit.bendTip = std::clamp(model.k1, -1.5, 1.5);
    vp.baseAngle = fit.baseAngle;
    vp.tipAngle = fit.tipAngle;
    vp.keyBarbs = {{0.0, bentBarb(fit.bendBase)}, {1.0, bentBarb(fit.bendTip)}};
    return model.bent ? std::string()
                      : vaneName + " vane: too few windows across the vane for barb curvature: straight key barbs";
  };

  // Barb spacing: periodicity along lines parallel to the rachis at 30%, 50%, 70% of each vane's width.
  // Returns a note when there is none.
  const auto measureSpacing = [&]() -> std::string {
    std::vector<glm::dvec2> spacing;  // (rp of the roots, period in pixels)
    std::vector<double> weights;
    const double step = 0.25, halfLine = 0.08 * len;
    for (int v = 0; v < 2; ++v) {
      const VaneWidth vaneWidth{&perp, len, v};
      for (double rpc = 0.15; rpc < 0.86; rpc += 0.1) {
        const double sc = rpc * len, width = vaneWidth(rpc);
        std::vector<std::vector<double>> lines;
        double dSum = 0;
        for (double f : {0.3, 0.5, 0.7}) {
          const double d = f * width;
          if (d < clear + 1 || width < 8) continue;
          std::vector<double> line;
          for (double s = sc - halfLine; s <= sc + halfLine; s += step) {
            const glm::dvec2 q = arc.point(s) + d * arc.side(v, s);
            line.push_back(sample(img.pixels, w, h, q.x, q.y));
          }
          lines.push_back(std::move(line));
          dSum += d;
        }
        if (lines.empty()) continue;
        const double per = period(lines, step, 2.0);
        if (per <= 0) continue;
        // The barbs crossing a line at distance d are rooted further down (traceToRoot); where their angle
        // falls toward the tip they fan out, so the line sees the spacing stretched by dx/dsRoot.
        const double d = dSum / lines.size();
        double sRoot = 0, s0 = 0, s1 = 0, u = 0;
        traceToRoot(models[v], sc, d, len, vaneWidth, sRoot, u);
        traceToRoot(models[v], sc - 2, d, len, vaneWidth, s0, u);
        traceToRoot(models[v], sc + 2, d, len, vaneWidth, s1, u);
        const double rpRoot = sRoot / len, stretch = 4 / std::max(1e-6, s1 - s0);
        if (rpRoot < 0 || rpRoot > 1 || !(stretch > 0.2 && stretch < 5)) continue;
        spacing.emplace_back(rpRoot, per / stretch);
        weights.push_back(1.0);
      }
    }
    res.spacingBasePixels = res.spacingTipPixels = 0;
    if (spacing.size() >= 2) {
      // Robust line fit: least squares, drop windows off by more than 25% (a missed or doubled period), refit.
      double a = 0, b = 0;
      for (int pass = 0; pass < 2; ++pass) {
        std::array<std::array<double, 2>, 2> m{};
        std::array<double, 2> r{}, q{};
        for (size_t i = 0; i < spacing.size(); ++i) {
          const double u = spacing[i].x, wgt = weights[i];
          m[0][0] += wgt * (1 - u) * (1 - u), m[0][1] += wgt * (1 - u) * u, m[1][1] += wgt * u * u;
          r[0] += wgt * (1 - u) * spacing[i].y, r[1] += wgt * u * spacing[i].y;
        }
        m[1][0] = m[0][1];
        if (!solve<2>(m, r, q)) break;
        a = q[0], b = q[1];
        for (size_t i = 0; i < spacing.size(); ++i) {
          const double pred = a + (b - a) * spacing[i].x;
          weights[i] = std::abs(spacing[i].y - pred) <= 0.25 * pred ? 1.0 : 0.0;
        }
      }
      // Trusted when most windows agree with the line and it stays above the 2-pixel search limit.
      size_t agree = 0;
      for (double wgt : weights) agree += wgt > 0 ? 1 : 0;
      if (a > 2 && b > 2 && std::max(a, b) < 3 * std::min(a, b) && agree >= 3 && 3 * agree >= 2 * spacing.size()) {
        res.spacingBasePixels = a, res.spacingTipPixels = b;
        p.spacingBase = a / ppu, p.spacingTip = b / ppu;
        res.spacingWindows = static_cast<int>(agree);
      }
    }
    if (res.spacingBasePixels > 0) return std::string();
    p.spacingBase = p.spacingTip = 0.01 * p.rachisLength;
    res.spacingWindows = 0;
    return "no consistent barb periodicity (" + std::to_string(spacing.size()) +
           " windows): barb spacing 1% of the rachis length";
  };

  std::string notes[3] = {fitOrientation(0), fitOrientation(1), measureSpacing()};
  // Barbs closer than 3.5 pixels (across their direction) alias with the pixel grid into patterns of
  // another orientation (on synthetic scans the error reaches 5 degrees at 2.8 pixels): with the spacing
  // known, drop those windows and fit again.
  if (res.spacingBasePixels > 0) {
    bool dropped = false;
    for (int v = 0; v < 2; ++v) {
      const VaneWidth vaneWidth{&perp, len, v};
      std::vector<OrientationWindow> kept;
      for (const OrientationWindow& o : windows[v]) {
        double sRoot = 0, u = 0;
        traceToRoot(models[v], o.s, o.d, len, vaneWidth, sRoot, u);
        const double rp = std::clamp(sRoot / len, 0.0, 1.0);
        const double across = (res.spacingBasePixels + (res.spacingTipPixels - res.spacingBasePixels) * rp) *
                              std::sin(std::clamp(models[v].angle(rp) - models[v].bend(rp) * u, 0.05, kPi - 0.05));
        if (across >= 3.5) kept.push_back(o);
      }
      dropped = dropped || kept.size() < windows[v].size();
      windows[v] = std::move(kept);
    }
    if (dropped) notes[0] = fitOrientation(0), notes[1] = fitOrientation(1), notes[2] = measureSpacing();
  }
  for (const std::string& n : notes)
    if (!n.empty()) res.notes.push_back(n);
  if (res.spacingBasePixels > 0 && !(res.vanes[0].measured && res.vanes[1].measured))
    res.notes.push_back("barb spacing corrected for the barbs' fanning with default angles: off by up to 15%");

  // Pass 2: barb lengths along each barb's chord (a key barb of chord 1 reaches exactly the barb length),
  // which leaves the root at the barb angle minus half the bend, measured from the rachis edge.
  double chordBase[2], chordTip[2];
  for (int v = 0; v < 2; ++v) {
    chordBase[v] = std::clamp(p.vane(v).baseAngle - 0.5 * res.vanes[v].bendBase, 0.05, kPi - 0.05);
    chordTip[v] = std::clamp(p.vane(v).tipAngle - 0.5 * res.vanes[v].bendTip, 0.05, kPi - 0.05);
  }
  so.leftBaseAngle = chordBase[0], so.leftTipAngle = chordTip[0];
  so.rightBaseAngle = chordBase[1], so.rightTipAngle = chordTip[1];
  res.silhouette = extractSilhouette(img, so);
  for (int v = 0; v < 2; ++v) {
    const LengthProfile& rel = v == 0 ? res.silhouette.relative.left : res.silhouette.relative.right;
    LengthProfile& dst = v == 0 ? p.silhouette.left : p.silhouette.right;
    for (const auto& q : rel.points) {
      const double a = chordBase[v] * (1 - q.x) + chordTip[v] * q.x;
      const double halfWidth = 0.5 * p.rachisWidth * (1 - q.x) / std::max(1e-3, std::sin(a));
      dst.points.emplace_back(q.x, std::max(0.0, q.y * p.rachisLength - halfWidth));
    }
  }
  double longest = 0;
  for (const auto& q : p.silhouette.left.points) longest = std::max(longest, q.y);
  for (const auto& q : p.silhouette.right.points) longest = std::max(longest, q.y);
  p.barbLength = longest > 0 ? longest : 0.3 * p.rachisLength;
  validateFeather(p);
  return res;
}

}  // namespace pteryla::feather
