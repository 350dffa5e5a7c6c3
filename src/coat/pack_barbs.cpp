// Packing, 6.3.3: per key barb, the height field in its barb slicing plane, and the barb fit against it
// (one flattening fraction, then a lift about the root only if needed).
#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "pteryla/core/error.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat::packing {

// ---- barb fitting (6.3.3)
double curveLength(const std::vector<dvec3>& c) {
  double l = 0;
  for (size_t k = 1; k < c.size(); ++k) l += glm::length(c[k] - c[k - 1]);
  return l;
}

void bernsteinTable(size_t cvs, size_t samples, Scratch& S) {
  if (S.bernCvs == cvs && S.bernSamples == samples) return;
  S.bernCvs = cvs;
  S.bernSamples = samples;
  S.bern.assign(cvs * samples, 0.0);
  const size_t n = cvs - 1;
  for (size_t k = 0; k < samples; ++k) {
    const double u = static_cast<double>(k) / (samples - 1);
    double binom = 1;
    for (size_t j = 0; j <= n; ++j) {
      S.bern[k * cvs + j] = binom * std::pow(u, static_cast<double>(j)) * std::pow(1 - u, static_cast<double>(n - j));
      binom = binom * static_cast<double>(n - j) / static_cast<double>(j + 1);
    }
  }
  S.bernT.resize(cvs * samples);
  for (size_t k = 0; k < samples; ++k)
    for (size_t j = 0; j < cvs; ++j) S.bernT[j * samples + k] = S.bern[k * cvs + j];
}

// Samples (s, z) of the key barb in its slicing plane (x = along from the root, z = up, scene units) after
// flattening mu and lift alpha: control vertices cv in the barb-local unit frame scaled by len.
void barbSamples(const dvec3* cvs, size_t n, double len, double mu, double alpha, Scratch& S, double stretch = 1) {
  S.tmp.resize(n);
  const double ca = std::cos(alpha), sa = std::sin(alpha);
  for (size_t j = 0; j < n; ++j) S.tmp[j] = flattenCv(cvs[j], cvs[0], mu, stretch, ca, sa);
  // Each sample sums its terms in control-vertex order; the samples run in the inner loop (vectorised).
  const size_t m = S.bernSamples;
  S.cx.assign(m, 0.0);
  S.cz.assign(m, 0.0);
  double* cx = S.cx.data();
  double* cz = S.cz.data();
  for (size_t j = 0; j < n; ++j) {
    const double* w = &S.bernT[j * m];
    const double tx = S.tmp[j].x, tz = S.tmp[j].z;
    for (size_t k = 0; k < m; ++k) {
      cx[k] += w[k] * tx;
      cz[k] += w[k] * tz;
    }
  }
  S.curve.resize(m);
  for (size_t k = 0; k < m; ++k) S.curve[k] = {len * cx[k], 0.0, len * cz[k]};
}

double fieldMax(const double* bh, int nb, double cell, double s0, double s1) {
  if (s1 < 0) return -kInf;
  const int b0 = std::max(0, static_cast<int>(std::floor(s0 / cell)));
  const int b1 = std::min(nb - 1, static_cast<int>(std::floor(s1 / cell)));
  double m = -kInf;
  for (int b = b0; b <= b1; ++b) m = std::max(m, bh[b]);
  return m;
}

// Does the sampled curve clear the field beyond the root zone? Each curve segment must be above the
// largest bin it overlaps, at both ends.
// (fieldMax over [max(s0, 0), s1] with floor(x / cell) computed once per sample: a segment's ends are
// its neighbours' ends.)
bool clears(const Scratch& S, const double* bh, int nb, double cell, double sRoot) {
  const auto& c = S.curve;
  if (c.size() < 2) return true;
  double fPrev = std::floor(c[0].x / cell);
  for (size_t k = 0; k + 1 < c.size(); ++k) {
    const double fNext = std::floor(c[k + 1].x / cell), fThis = fPrev;
    fPrev = fNext;
    const bool nextLow = c[k + 1].x < c[k].x;  // std::min / std::max pick
    const double s0 = nextLow ? c[k + 1].x : c[k].x, s1 = nextLow ? c[k].x : c[k + 1].x;
    if (s1 < sRoot) continue;
    if (s1 < 0) continue;  // fieldMax: -inf
    const double f0 = s0 < 0.0 ? std::floor(0.0 / cell) : (nextLow ? fNext : fThis);
    const double f1 = nextLow ? fThis : fNext;
    const int b0 = std::max(0, static_cast<int>(f0));
    const int b1 = std::min(nb - 1, static_cast<int>(f1));
    double H = -kInf;
    for (int b = b0; b <= b1; ++b) H = std::max(H, bh[b]);
    if (H == -kInf) continue;
    if (c[k].z < H || c[k + 1].z < H) return false;
  }
  return true;
}

// One flattening fraction mu in [0, maxFlatten] (the smallest that clears every bin: the barb flattens
// uniformly and never takes inverse curvature for mu <= 1), then, only if needed, the smallest rotation
// alpha about the root (bisection) that clears.
BarbFit fitBarb(const dvec3* cvs, size_t n, double len, double sExt, const double* bh, int nb, const PackOptions& o,
                Scratch& S) {
  BarbFit fit;
  const double cell = sExt / nb;
  const double sRoot = 0.05 * sExt;  // the root zone belongs to the shaft (the barb sits on the rachis)
  // Quick accept: the curve lies above its lowest control vertex (convex hull).
  double zLow = 0, hMax = -kInf;
  for (size_t j = 0; j < n; ++j) zLow = std::min(zLow, len * cvs[j].z);
  for (int b = 0; b < nb; ++b)
    if ((b + 1) * cell >= sRoot) hMax = std::max(hMax, bh[b]);
  if (hMax <= zLow) return fit;
  bernsteinTable(n, static_cast<size_t>(4 * nb + 1), S);
  barbSamples(cvs, n, len, 0, 0, S);
  if (clears(S, bh, nb, cell, sRoot)) return fit;
  const double arcLength = curveLength(S.curve);
  double mu = 0;
  bool feasible = true;
  const size_t m = S.bernSamples;
  for (size_t k = 0; k + 1 < m; ++k) {
    const double s0 = std::min(S.curve[k].x, S.curve[k + 1].x), s1 = std::max(S.curve[k].x, S.curve[k + 1].x);
    if (s1 < sRoot) continue;
    const double H = fieldMax(bh, nb, cell, std::max(s0, 0.0), s1);
    if (H == -kInf) continue;
    for (size_t e : {k, k + 1}) {
      const double z = S.curve[e].z;
      if (z >= H) continue;
      double f = 0;  // flattening lift at this sample: len * sum B_j max(0, -z_j)
      for (size_t j = 0; j < n; ++j) f += S.bern[e * n + j] * std::max(0.0, -cvs[j].z);
      f *= len;
      if (f <= 1e-12 * len) {
        feasible = false;
        continue;
      }
      mu = std::max(mu, (H - z) / f);
    }
  }
  if (mu > o.maxFlatten) {
    mu = o.maxFlatten;
    feasible = false;
  }
  fit.mu = mu;
  if (o.keepBarbArcLength && mu > 0) {
    // Thesis 6.4: "during packing arc-length was used to simulate a plausibly correct bending": a barb
    // that flattens straightens out, so it is scaled about its root back to the arc length it had.
    barbSamples(cvs, n, len, mu, 0, S);
    const double flat = curveLength(S.curve);
    if (flat > 1e-12 * len && arcLength > flat) fit.stretch = arcLength / flat;
  }
  const double st = fit.stretch;
  if (feasible) {
    barbSamples(cvs, n, len, mu, 0, S, st);
    if (clears(S, bh, nb, cell, sRoot)) return fit;
  }
  double lo = 0, hi = o.maxBarbLift;
  barbSamples(cvs, n, len, mu, hi, S, st);
  if (!clears(S, bh, nb, cell, sRoot)) {
    fit.alpha = hi;
    fit.resolved = false;
    return fit;
  }
  for (int it = 0; it < 24; ++it) {
    const double mid = 0.5 * (lo + hi);
    barbSamples(cvs, n, len, mu, mid, S, st);
    if (clears(S, bh, nb, cell, sRoot))
      hi = mid;
    else
      lo = mid;
  }
  fit.alpha = hi;
  return fit;
}

// lineMax() below for one patch and barb over many intervals: everything but the interval [lo, hi] / wl
// is computed once (wl >= 1e-12).
struct LineRise {
  LineRise(const dvec3& q, const dvec3& g, const dvec3& w, double wl, double rho, double baseR) : rho(rho) {
    const double wt = w.x / wl;
    if (wt > 1e-12) {
      clipLo = true;
      clip = -q.x / wt;
    } else if (wt < -1e-12) {
      clipHi = true;
      clip = -q.x / wt;
    }
    gw = glm::dot(g, w) / wl;
    qw = glm::dot(q, w) / wl;
    const double qq = glm::dot(q, q);
    disc = qw * qw - (qq - baseR * baseR);
    if (disc > 0) sq = std::sqrt(disc);
  }
  // lineMax(q, g, w, wl, rho, lo, hi, baseR) for loW = lo / wl, hiW = hi / wl.
  double top(double loW, double hiW) const {
    double xa = std::max(-rho, loW), xb = std::min(rho, hiW);
    if (clipLo)
      xa = std::max(xa, clip);
    else if (clipHi)
      xb = std::min(xb, clip);
    if (xa > xb) return -kInf;
    double best = -kInf;
    auto take = [&](double a, double b) {
      if (a > b) return;
      best = std::max(best, gw >= 0 ? gw * b : gw * a);
    };
    if (disc <= 0) {
      take(xa, xb);
    } else {
      take(xa, std::min(xb, -qw - sq));
      take(std::max(xa, -qw + sq), xb);
    }
    return best;
  }
  double rho, clip = 0, gw = 0, qw = 0, disc = 0, sq = 0;
  bool clipLo = false, clipHi = false;
};

// Rise of a skin patch along a key barb: the patch's points on the line through the sample along the
// barb (in the patch's tangent plane: q + x w / |w|, |x| <= rho; w = the barb direction in that plane)
// rise over the sample by g.w x / |w| (g = the barb's up direction in the plane). Returns the largest rise
// over the points whose position along the barb falls in [lo, hi] relative to the sample and that lie
// outside the base ball (radius baseR around the follicle, the origin of q) and in front of the follicle
// (t = q.x >= 0), or -inf when there are none.
// Across the barb, the samples between the neighbouring key barbs' planes stand in.
double lineMax(const dvec3& q, const dvec3& g, const dvec3& w, double wl, double rho, double lo, double hi,
               double baseR) {
  if (wl < 1e-12) return (lo <= 0 && hi >= 0) ? 0.0 : -kInf;
  return LineRise(q, g, w, wl, rho, baseR).top(lo / wl, hi / wl);
}

// Signs of the plane distances glm::dot(q - root[j], w[j]) of n <= 64 key barbs (arrays per coordinate):
// bit j of lt / gt is set when distance j is negative / positive. The same operations as glm::dot, two
// keys at a time with SSE2.
inline void planeSigns(const dvec3& q, const double* rx, const double* ry, const double* rz, const double* wx,
                       const double* wy, const double* wz, size_t n, uint64_t& lt, uint64_t& gt) {
  lt = 0;
  gt = 0;
  size_t j = 0;
#if defined(__SSE2__)
  const __m128d qx = _mm_set1_pd(q.x), qy = _mm_set1_pd(q.y), qz = _mm_set1_pd(q.z), zero = _mm_setzero_pd();
  for (; j + 2 <= n; j += 2) {
    const __m128d a = _mm_mul_pd(_mm_sub_pd(qx, _mm_loadu_pd(rx + j)), _mm_loadu_pd(wx + j));
    const __m128d b = _mm_mul_pd(_mm_sub_pd(qy, _mm_loadu_pd(ry + j)), _mm_loadu_pd(wy + j));
    const __m128d c = _mm_mul_pd(_mm_sub_pd(qz, _mm_loadu_pd(rz + j)), _mm_loadu_pd(wz + j));
    const __m128d d = _mm_add_pd(_mm_add_pd(a, b), c);
    lt |= static_cast<uint64_t>(_mm_movemask_pd(_mm_cmplt_pd(d, zero))) << j;
    gt |= static_cast<uint64_t>(_mm_movemask_pd(_mm_cmpgt_pd(d, zero))) << j;
  }
#endif
  for (; j < n; ++j) {
    const double d = (q.x - rx[j]) * wx[j] + (q.y - ry[j]) * wy[j] + (q.z - rz[j]) * wz[j];
    lt |= static_cast<uint64_t>(d < 0) << j;
    gt |= static_cast<uint64_t>(d > 0) << j;
  }
}

// 6.3.3 barb height fields: per key barb (placed at the feather's elevation: pk), the candidates on its
// side of the shaft between the neighbouring key barbs' slicing planes, binned along the barb (S.bh).
[[gnu::noinline]] void barbFields(const Context& ctx, uint32_t i, Scratch& S, const PlacedKey* pk, size_t nk) {
  const LocalFeather& L = ctx.local[i];
  const PackOptions& o = ctx.opt;
  const int fb = std::max(2, o.barbFieldBins);
  const double ramp = std::max(1e-12, o.baseAllowance * L.totalLength);
  const double sideTol = 0.5 * ctx.coat.params[i].rachisWidth;
  // Key barb roots and slicing-plane normals as arrays: the plane distances of a candidate to every key
  // barb of a vane are one vectorisable loop (the same operations as glm::dot(q - root, w)).
  S.keyRoot[0].resize(nk);
  S.keyRoot[1].resize(nk);
  S.keyRoot[2].resize(nk);
  S.keyW[0].resize(nk);
  S.keyW[1].resize(nk);
  S.keyW[2].resize(nk);
  for (size_t kk = 0; kk < nk; ++kk)
    for (int a = 0; a < 3; ++a) {
      S.keyRoot[a][kk] = pk[kk].root[a];
      S.keyW[a][kk] = pk[kk].w[a];
    }
  const double* rx = S.keyRoot[0].data();
  const double* ry = S.keyRoot[1].data();
  const double* rz = S.keyRoot[2].data();
  const double* wx = S.keyW[0].data();
  const double* wy = S.keyW[1].data();
  const double* wz = S.keyW[2].data();
  double* plane = S.plane.data();
  const double baseR = o.baseAllowance * L.totalLength;
  auto each = [&](const auto& c, auto skinTag) {
    constexpr bool kSkin = decltype(skinTag)::value;
    const dvec3 q(c.t, c.b, c.n);
    double rho = 0;  // a skin patch reaches rho beyond its sample in every direction
    if constexpr (kSkin) rho = c.rho;
    for (int v = 0; v < 2; ++v) {
      const size_t first = v == 0 ? 0 : L.leftKeys, last = v == 0 ? std::min<size_t>(L.leftKeys, nk) : nk;
      if (first >= last) continue;
      // Far on the other side of the shaft: not this vane's.
      if (v == 0 ? c.b < L.shaftYMin - sideTol : c.b > L.shaftYMax + sideTol) continue;
      const double side = v == 0 ? 1.0 : -1.0;
      // Key barb kk takes the candidate when it lies between the neighbouring key barbs' planes.
      auto visit = [&](size_t kk) {
        const LocalKey& k = L.keys[kk];
        const dvec3 rq = q - pk[kk].root;
        if (side * glm::dot(rq, pk[kk].left) < -sideTol) return;
        const double s = glm::dot(rq, pk[kk].u);
        if (s < -rho || s > k.sExt + rho) return;
        const double h = glm::dot(rq, pk[kk].d);
        if constexpr (!kSkin) {
          const int b = std::max(0, std::min(fb - 1, static_cast<int>(s * fb / k.sExt)));
          double& slot = S.bh[kk * fb + b];
          slot = std::max(slot, h + c.rad + ctx.clearance);
          if (o.captureFields) S.bhRaw[kk * fb + b] = std::max(S.bhRaw[kk * fb + b], h);
        } else {
          // A skin patch: per bin, the highest point of the patch along the barb whose position falls in
          // the bin (lineMax), plus rho x cone for faces turned away from the mean normal.
          const double bcell = k.sExt / fb;
          const double rampF = std::min(1.0, (k.rootDist + std::max(0.0, s - rho)) / ramp);
          const dvec3 g = pk[kk].d - glm::dot(pk[kk].d, c.normal) * c.normal;
          const dvec3 wv = pk[kk].u - glm::dot(pk[kk].u, c.normal) * c.normal;
          const double wl = glm::length(wv);
          const int b0 = std::max(0, std::min(fb - 1, static_cast<int>(std::floor((s - rho * wl) / bcell))));
          const int b1 = std::max(0, std::min(fb - 1, static_cast<int>(std::floor((s + rho * wl) / bcell))));
          const double lift = (ctx.skinClearance + rho * c.cone) * rampF;
          auto put = [&](int b, double top) {
            if (top == -kInf) return;
            double& slot = S.bh[kk * fb + b];
            slot = std::max(slot, h + top + lift);
            if (o.captureFields) S.bhRaw[kk * fb + b] = std::max(S.bhRaw[kk * fb + b], h + top);
          };
          if (wl < 1e-12) {
            for (int b = b0; b <= b1; ++b)
              put(b, lineMax(q, g, wv, wl, rho, b * bcell - s, (b + 1) * bcell - s, baseR));
          } else {
            // lineMax per bin with its bin-independent part computed once; a bin's upper end is the next
            // bin's lower end.
            const LineRise line(q, g, wv, wl, rho, baseR);
            double loW = (b0 * bcell - s) / wl;
            for (int b = b0; b <= b1; ++b) {
              const double hiW = ((b + 1) * bcell - s) / wl;
              put(b, line.top(loW, hiW));
              loW = hiW;
            }
          }
        }
      };
      const size_t n = last - first;
      if (n <= 64) {
        // Bit j: plane of key first + j negative (lt) / positive (gt). Key j is skipped when key j - 1's
        // plane is negative or key j + 1's is positive.
        uint64_t lt = 0, gt = 0;
        planeSigns(q, rx + first, ry + first, rz + first, wx + first, wy + first, wz + first, n, lt, gt);
        uint64_t take = ~((lt << 1) | (gt >> 1));
        if (n < 64) take &= (uint64_t(1) << n) - 1;
        while (take) {
          const size_t j = static_cast<size_t>(__builtin_ctzll(take));
          take &= take - 1;
          visit(first + j);
        }
      } else {
        for (size_t kk = first; kk < last; ++kk)
          plane[kk] = (q.x - rx[kk]) * wx[kk] + (q.y - ry[kk]) * wy[kk] + (q.z - rz[kk]) * wz[kk];
        for (size_t kk = first; kk < last; ++kk) {
          if (kk > first && plane[kk - 1] < 0) continue;
          if (kk + 1 < last && plane[kk + 1] > 0) continue;
          visit(kk);
        }
      }
    }
  };
  for (const FeatherCandidate& c : S.cand) each(c, std::false_type());
  for (const SkinCandidate& c : S.skinCand) each(c, std::true_type());
}

}  // namespace pteryla::coat::packing
