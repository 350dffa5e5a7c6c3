// Packing, 6.3.2: the candidate points around a feather and its shaft elevation against the shaft height
// field (polar form: the largest angle per radius bin).
#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "pteryla/core/error.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat::packing {

// Minimum of the shaft's polar angle psi(r) per radius bin over the shaft polyline (and its extension along
// the tip tangent to `rMax`), the largest shaft radius and the lateral range of the shaft per bin. Exact for
// the polyline: the polar angle is monotone along a straight segment, so a bin's minimum sits at a segment
// end or where the segment crosses a bin edge.
void shaftProfile(const LocalFeather& L, double rMax, int bins, bool extend, Scratch& S) {
  S.psiMin.assign(bins, kInf);
  S.shaftRadBin.assign(bins, 0.0);
  S.yLo.assign(bins, kInf);
  S.yHi.assign(bins, -kInf);
  const double cell = rMax / bins;
  auto binOf = [&](double r) { return std::min(bins - 1, std::max(0, static_cast<int>(std::floor(r / cell)))); };
  auto note = [&](int b, double psi, double rad, double y) {
    S.psiMin[b] = std::min(S.psiMin[b], psi);
    S.shaftRadBin[b] = std::max(S.shaftRadBin[b], rad);
    S.yLo[b] = std::min(S.yLo[b], y);
    S.yHi[b] = std::max(S.yHi[b], y);
  };
  auto segment = [&](const dvec3& a3, const dvec3& c3, double ra, double rc) {
    const glm::dvec2 a(a3.x, a3.z), c(c3.x, c3.z);
    const glm::dvec2 dd = c - a;
    const double la = glm::length(a), lc = glm::length(c);
    const double psiA = la > 0 ? std::atan2(a.y, a.x) : std::atan2(dd.y, dd.x);
    const double psiC = lc > 0 ? std::atan2(c.y, c.x) : psiA;
    const double rad = std::max(ra, rc);
    if (la <= rMax) note(binOf(la), psiA, rad, a3.y);
    if (lc <= rMax) note(binOf(lc), psiC, rad, c3.y);
    const double A = glm::dot(dd, dd);
    if (A <= 0) return;
    const double hi = std::max(la, lc);
    const double sMin = std::clamp(-glm::dot(a, dd) / A, 0.0, 1.0);
    const double rLow = glm::length(a + sMin * dd);
    const int b0 = binOf(rLow), b1 = binOf(std::min(hi, rMax));
    for (int b = b0 + 1; b <= b1; ++b) {
      const double e = b * cell;
      const double B = 2 * glm::dot(a, dd), C = glm::dot(a, a) - e * e;
      const double disc = B * B - 4 * A * C;
      if (disc < 0) continue;
      const double sq = std::sqrt(disc);
      for (double s : {(-B - sq) / (2 * A), (-B + sq) / (2 * A)}) {
        if (s < 0 || s > 1) continue;
        const glm::dvec2 q = a + s * dd;
        const double psi = std::atan2(q.y, q.x);
        const double y = a3.y + s * (c3.y - a3.y);
        note(b - 1, psi, rad, y);
        note(b, psi, rad, y);
      }
    }
  };
  for (size_t k = 0; k + 1 < L.shaft.size(); ++k) segment(L.shaft[k], L.shaft[k + 1], L.shaftRad[k], L.shaftRad[k + 1]);
  if (extend && L.shaft.size() >= 2) {
    const dvec3 tip = L.shaft.back(), prev = L.shaft[L.shaft.size() - 2];
    glm::dvec2 dir(tip.x - prev.x, tip.z - prev.z);
    const double ld = glm::length(dir);
    if (ld > 0) {
      dir /= ld;
      const glm::dvec2 t2(tip.x, tip.z);
      const double bq = glm::dot(t2, dir), cq = glm::dot(t2, t2) - rMax * rMax;
      const double disc = bq * bq - cq;
      const double s = disc > 0 ? -bq + std::sqrt(disc) : 0.0;
      if (s > 0) segment(tip, dvec3(tip.x + s * dir.x, tip.y, tip.z + s * dir.y), 0.0, 0.0);
    }
  }
}

// Candidate points in the follicle frame (6.3.2: "the data points of the surrounding feathers"): packed
// points of the dependencies and skin samples inside the footprint and the vane outline.
[[gnu::noinline]] void gatherCandidates(const Context& ctx, uint32_t i, Scratch& S, const Output& out) {
  const LocalFeather& L = ctx.local[i];
  const FeatherFrame& F = ctx.coat.frames[i];
  const PackOptions& o = ctx.opt;
  PackStats& st = S.stats;
  S.cand.clear();
  S.skinCand.clear();
  const dvec3 T = F.tangent, B = F.binormal, N = F.normal, O = F.origin;
  // Sphere (centre c in the follicle frame, radius r) can touch the footprint?
  auto sphereIn = [&](const dvec3& c, double r) {
    return c.x + r >= 0 && c.x - r <= L.reach && c.y + r >= L.yMin && c.y - r <= L.yMax &&
           glm::dot(c, c) <= (L.reach + r) * (L.reach + r);
  };
  auto frame = [&](const dvec3& w) {
    const dvec3 r = w - O;
    return dvec3(glm::dot(r, T), glm::dot(r, B), glm::dot(r, N));
  };
  for (uint32_t k = ctx.depOff[i]; k < ctx.depOff[i + 1]; ++k) {
    const uint32_t j = ctx.deps[k];
    const glm::dvec4& bj = out.bounds[j];
    if (!sphereIn(frame(dvec3(bj)), bj.w)) continue;
    const uint32_t gEnd = out.groupOffset[j + 1];
    for (uint32_t c = out.chunkOffset[j], g0 = out.groupOffset[j]; g0 < gEnd; ++c, g0 += kChunk) {
      const glm::dvec4& cb = out.chunkBounds[c];
      if (!sphereIn(frame(dvec3(cb)), cb.w)) continue;
      for (uint32_t g = g0; g < std::min(gEnd, g0 + kChunk); ++g) {
        const glm::vec4& gb = out.groupBounds[g];
        if (!sphereIn(frame(dvec3(gb.x, gb.y, gb.z)), gb.w)) continue;
        for (uint32_t q = out.groupPoint[g]; q < out.groupPoint[g + 1]; ++q) {
          const glm::vec4& pq = out.points[q];
          const dvec3 r(pq.x - O.x, pq.y - O.y, pq.z - O.z);
          const double t = glm::dot(r, T);
          const double m = L.reach + pq.w;
          if (t < 0 || t > m) continue;
          const double b = glm::dot(r, B);
          if (b < L.yMin - pq.w || b > L.yMax + pq.w) continue;
          const double n = glm::dot(r, N);
          if (t * t + b * b + n * n > m * m) continue;
          if (!L.inOutline(b, std::sqrt(t * t + n * n))) continue;
          S.cand.push_back({t, b, n, pq.w});
        }
      }
    }
  }
  const double base2 = std::pow(o.baseAllowance * L.totalLength, 2);
  if (o.skin && ctx.skinData && !ctx.skinData->pts.empty()) {
    const detail::PackSkinSamples& sd = *ctx.skinData;
    // World bounds of the footprint box (t in [0, R], b in [yMin, yMax], n in [-R, R]) clipped to the ball;
    // grid cells are culled against the footprint before their points are read.
    detail::Box box;
    for (int k = 0; k < 8; ++k) {
      const dvec3 lp((k & 1) ? L.reach : 0.0, (k & 2) ? L.yMax : L.yMin, (k & 4) ? L.reach : -L.reach);
      box.add(O + lp.x * T + lp.y * B + lp.z * N);
    }
    // A footprint narrower than a skin patch (a pin feather's shaft, its barbs still closed) can fall
    // between the samples: for it, patches reaching sideways into the footprint count too. Wider
    // footprints take the samples inside them.
    const double halfWidth = 0.5 * (L.yMax - L.yMin);
    const double sidePad = std::max(0.0, sd.maxRho - halfWidth);
    box.lo = glm::max(box.lo - dvec3(sidePad), O - dvec3(L.reach + sidePad));
    box.hi = glm::min(box.hi + dvec3(sidePad), O + dvec3(L.reach + sidePad));
    sd.grid.query(
        box.lo, box.hi, [&](const dvec3& centre, double half) { return sphereIn(frame(centre), half + sidePad); },
        [&](uint32_t k) {
          // Samples inside the footprint; each carries its patch (radius, normal, cone) into the fields.
          const double rho = sd.rho[k];
          const double pad = std::max(0.0, rho - halfWidth);
          const dvec3 r = sd.pts[k] - O;
          const double t = glm::dot(r, T);
          if (t < 0 || t > L.reach) return;
          const double b = glm::dot(r, B);
          if (b < L.yMin - pad || b > L.yMax + pad) return;
          const double n = glm::dot(r, N);
          const double d2 = t * t + b * b + n * n;
          // The calamus sits in its follicle: skin within the base allowance is not an obstacle (the
          // checker exempts the same zone).
          if (d2 > (L.reach + pad) * (L.reach + pad) || d2 < base2) return;
          if (pad > 0 ? !L.nearOutline(b, std::sqrt(t * t + n * n), pad) : !L.inOutline(b, std::sqrt(t * t + n * n)))
            return;
          const dvec3& nw = sd.normal[k];
          S.skinCand.push_back({t, b, n, rho, sd.cone[k], dvec3(glm::dot(nw, T), glm::dot(nw, B), glm::dot(nw, N))});
        });
  }
  st.candidatePoints += S.cand.size() + S.skinCand.size();
}

// 6.3.2 shaft rotation against the candidates; returns the elevation.
[[gnu::noinline]] double shaftElevation(const Context& ctx, uint32_t i, Scratch& S) {
  const LocalFeather& L = ctx.local[i];
  const PackOptions& o = ctx.opt;
  PackStats& st = S.stats;
  // ---- 6.3.2 shaft rotation: polar height field in the shaft slicing plane.
  const double rMax = L.reach;
  const int bins = std::max(4, o.heightFieldBins);
  const double cell = rMax / bins;
  const double ramp = std::max(1e-12, o.baseAllowance * L.totalLength);
  double e;
  const double fixedE = ctx.fixed.empty() ? kNaN : ctx.fixed[i];
  if (!std::isnan(fixedE)) {
    e = fixedE;
    ++st.fixed;
  } else {
    shaftProfile(L, rMax, bins, o.extendShaft, S);
    S.best.assign(bins, glm::dvec2(0));
    std::vector<double>& bestKey = S.plane;  // pseudo-angle of S.best per bin
    bestKey.assign(bins, -1.0);
    const double bandOf = ctx.shaftBand.empty() || std::isnan(ctx.shaftBand[i]) ? o.shaftBand : ctx.shaftBand[i];
    const double band = bandOf * L.vaneHalf;
    const double r2Min = 1e-24 * rMax * rMax;
    // The candidates in gathering order (feather points, then skin): a bin keeps the first of equal angles.
    // Bins within reach of the shaft whose lateral band holds lateral offset y (widened by `pad`)?
    auto anyBin = [&](int b0, int b1, double y, double padLo, double padHi) {
      for (int b = b0; b <= b1; ++b)
        if (S.psiMin[b] != kInf && !(y < S.yLo[b] - band - padLo) && !(y > S.yHi[b] + band + padHi)) return true;
      return false;
    };
    auto offer = [&](int b0, int b1, double y, double padLo, double padHi, double vx, double vy) {
      const double pa = pseudoAngle(vx, vy);
      for (int b = b0; b <= b1; ++b) {
        if (S.psiMin[b] == kInf) continue;  // beyond the shaft's reach
        if (y < S.yLo[b] - band - padLo || y > S.yHi[b] + band + padHi) continue;
        if (pa > bestKey[b]) {
          bestKey[b] = pa;
          S.best[b] = {vx, vy};
        }
      }
    };
    const double rMax2 = rMax * rMax;
    for (const FeatherCandidate& c : S.cand) {
      const double r2 = c.t * c.t + c.n * c.n;
      if (!(r2 > r2Min) || r2 > rMax2) continue;
      const double r = std::sqrt(r2);
      const int b0 = std::min(bins - 1, static_cast<int>(r / cell));
      // (y - band - rad) per bin: the test below is that of a skin patch with rho = 0.
      if (!anyBin(b0, b0, c.b, c.rad, c.rad)) continue;
      const double gap = c.rad + S.shaftRadBin[b0] + ctx.clearance;
      const double sd = std::min(1.0, gap / r), cd = std::sqrt(1 - sd * sd);
      // (t, n) turned up by the clearance angle delta = asin(gap / r).
      offer(b0, b0, c.b, c.rad, c.rad, c.t * cd - c.n * sd, c.t * sd + c.n * cd);
    }
    for (const SkinCandidate& c : S.skinCand) {
      const double r2 = c.t * c.t + c.n * c.n;
      if (!(r2 > r2Min) || r2 > (rMax + c.rho) * (rMax + c.rho)) continue;
      const double r = std::sqrt(r2);
      // A skin patch covers the radii r +- rho: every bin it reaches gets its highest angle.
      const int b0 = std::min(bins - 1, static_cast<int>(std::max(0.0, r - c.rho) / cell));
      const int b1 = std::min(bins - 1, static_cast<int>((r + c.rho) / cell));
      if (!anyBin(b0, b1, c.b, c.rho, c.rho)) continue;
      double radMax = 0;
      for (int b = b0; b <= b1; ++b) radMax = std::max(radMax, S.shaftRadBin[b]);
      // Clearance ramps up over the base zone (the calamus sits in its follicle; the checker exempts it).
      const double rampF = std::min(1.0, std::max(0.0, r - c.rho) / ramp);
      double gap = (radMax + ctx.skinClearance) * rampF;
      if (c.rho > 0) {
        // The tangent from the follicle to the patch (grown by gap), turned by delta from the ray to its
        // centre, touches it where r sin(delta) = gap + the patch's extent along the tangent's normal
        // a(delta) (rise): two fixed-point steps from delta = 0, keeping the largest extent seen.
        const double ct = c.t / r, cn = c.n / r;
        double extra = c.rise(dvec3(-cn, 0.0, ct)) * rampF;
        for (int it = 0; it < 2; ++it) {
          const double sd0 = std::min(1.0, (gap + extra) / r), cd0 = std::sqrt(1 - sd0 * sd0);
          extra = std::max(extra, c.rise(dvec3(-(cn * cd0 + ct * sd0), 0.0, ct * cd0 - cn * sd0)) * rampF);
        }
        gap += extra;
      }
      const double sd = std::min(1.0, gap / r), cd = std::sqrt(1 - sd * sd);
      offer(b0, b1, c.b, c.rho, c.rho, c.t * cd - c.n * sd, c.t * sd + c.n * cd);
    }
    // A bin that asks for more than conflictElevation comes from a layer-order conflict (a neighbour
    // packed earlier whose material sits right over this follicle, e.g. at a tract border): standing up
    // would not clear it either, and would push every feather above up with it. Such bins are left out.
    double req = -kInf;
    bool conflict = false;
    for (int b = 0; b < bins; ++b) {
      if (bestKey[b] < 0 || S.psiMin[b] == kInf) continue;
      const double v = std::atan2(S.best[b].y, S.best[b].x) - S.psiMin[b];
      if (v > o.conflictElevation) {
        conflict = true;
        continue;
      }
      req = std::max(req, v);
    }
    if (conflict) ++st.conflicts;
    if (req == -kInf || req <= o.minElevation) ++st.free;
    e = std::max(o.minElevation, req);
    if (!ctx.minElevation.empty() && !std::isnan(ctx.minElevation[i])) e = std::max(e, ctx.minElevation[i]);
    if (e > o.maxElevation) {
      ++st.shaftClamped;
      e = o.maxElevation;
    }
  }
  return e;
}

}  // namespace pteryla::coat::packing
