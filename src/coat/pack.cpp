// Feather packing: Streit 2003, 6.3.2 (shaft rotation against a height field in the shaft slicing plane),
// 6.3.3 (key barb elevation against height fields in the barb slicing planes), 6.3.4 (summary), 6.4
// (key-barb control vertices bound the feather), 8.3 (unopened feathers pack as straight shafts; fixed
// angles for styling) and 9.1.2 (the skin under the feather is part of what the feather packs against).
//
// Differences from the thesis, all on the conservative side:
//  - candidates are selected per point (any packed point inside the footprint), not per follicle, so a
//    neighbour whose follicle lies outside the footprint but whose vane reaches in is still seen;
//  - the shaft height field is kept in polar form (largest angle per radius bin), which makes "the
//    largest rotation such that the shaft stays above it" exact for the shaft polyline;
//  - the skin is sampled into points that join the candidates, so convex and concave skin, coarse
//    facets and skin outside the follicle's polygon are all handled by the same height fields;
//  - barb fitting uses one flattening fraction per key barb (the smallest that clears every bin), so
//    barbs flatten smoothly and never take inverse curvature; only if a flat barb still cannot clear the
//    field is it rotated up about its root (reported in stats.barbsLifted).
#include "pteryla/coat/pack.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>

#include <glm/geometric.hpp>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_for_each.h>
#include <tbb/task_arena.h>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/bezier.hpp"
#include "arena.hpp"
#include "spatial.hpp"

namespace pteryla::coat {

using glm::dvec3;
using feather::kPi;

double HeightField1D::at(double s) const {
  const double b = std::floor((s - origin) / cell);
  if (!(b >= 0) || b >= static_cast<double>(h.size())) return -std::numeric_limits<double>::infinity();
  return h[static_cast<size_t>(b)];
}

glm::dvec3 placeDirection(const FeatherFrame& f, double e, const glm::dvec3& d) {
  const double c = std::cos(e), s = std::sin(e);
  const dvec3 t = c * f.tangent + s * f.normal;
  const dvec3 n = -s * f.tangent + c * f.normal;
  return d.x * t + d.y * f.binormal + d.z * n;
}

glm::dvec3 placePoint(const FeatherFrame& f, double e, const glm::dvec3& p) { return f.origin + placeDirection(f, e, p); }

namespace detail {
// Skin samples. Each stands for the patch of the skin around it: the points of the faces holding the
// sample within rho of it (every skin point lies in some sample's patch), with the faces' normals within
// cone (a sine bound) of normal. Packing against the patches instead of the points keeps feathers off
// the skin between the samples, at any sample spacing.
struct PackSkinSamples {
  // Sized first and written once per sample, in parallel over the faces (not zero-filled serially).
  std::vector<glm::dvec3, UninitializedAllocator<glm::dvec3>> pts, normal;
  std::vector<float, UninitializedAllocator<float>> rho, cone;
  PointGrid grid;
  double maxRho = 0;                      // largest patch radius
  std::vector<glm::dvec3> skinPositions;  // the skin they were sampled from (packOver checks it)
};
}  // namespace detail

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// ------------------------------------------------------------------ feather-local geometry

struct LocalKey {
  double rp = 0;
  uint8_t vane = 0;
  dvec3 root{0}, u{1, 0, 0}, w{0, 1, 0}, d{0, 0, 1}, left{0, 1, 0};
  double len = 0;
  double sExt = 0;  // extent along u (len * max cv.x)
  double rootDist = 0;  // |root|
  uint32_t cvOff = 0;
  uint16_t cvCount = 0;
};

struct LocalFeather {
  bool packable = false;
  bool unopened = false;
  double reach = 0;            // bound on |p| for every point in any packed state
  double yMin = 0, yMax = 0;   // lateral footprint (bound over packed states)
  double vaneHalf = 0;         // largest lateral reach of a barb from its root (unpacked)
  double shaftYMin = 0, shaftYMax = 0;
  double totalLength = 0;
  // Arrays live in the pack's per-thread arenas (detail::HugeArena).
  detail::ArenaArray<dvec3> shaft;    // polyline from the follicle to the tip, feather-local
  detail::ArenaArray<double> shaftRad;
  detail::ArenaArray<LocalKey> keys;  // left vane first, ascending rp within a vane; afterfeather keys last
  uint32_t leftKeys = 0;
  uint32_t mainKeys = 0;       // keys of the main feather (the packed ones); the rest are the afterfeather's
  detail::ArenaArray<dvec3> after;    // afterfeather shaft polyline (not packed, but handed to later feathers)
  detail::ArenaArray<double> afterRad;
  detail::ArenaArray<dvec3> cvs;      // key barb control vertices, barb-local unit frame
  uint32_t pointCount = 0;
  // Vane outline, invariant under elevation (a rotation about B keeps y and the xz radius): per lateral bin
  // of [yMin, yMax], the smallest and largest xz radius of feather points with that lateral offset.
  static constexpr int kOutlineBins = 32;
  float rLo[kOutlineBins], rHi[kOutlineBins];
  bool inOutline(double b, double r) const {
    const int k = static_cast<int>((b - yMin) * kOutlineBins / (yMax - yMin));
    if (k < 0 || k >= kOutlineBins) return false;
    return r >= rLo[k] && r <= rHi[k];
  }
  // Whether a disc of radius pad around (b, r) can touch the outline.
  bool nearOutline(double b, double r, double pad) const {
    const double w = (yMax - yMin) / kOutlineBins;
    const int k0 = std::max(0, static_cast<int>(std::floor((b - pad - yMin) / w)));
    const int k1 = std::min(kOutlineBins - 1, static_cast<int>(std::floor((b + pad - yMin) / w)));
    for (int k = k0; k <= k1; ++k)
      if (r + pad >= rLo[k] && r - pad <= rHi[k]) return true;
    return false;
  }
};

// feather::bezierPoint at two parameters at once: de Casteljau with the two curves in the two SSE2 lanes
// (the same operations per lane as bezierPoint, so the same bits). count <= 16.
inline void bezierPair(const dvec3* cvs, size_t count, double u0, double u1, dvec3& p0, dvec3& p1) {
#if defined(__SSE2__)
  if (count >= 1 && count <= 16) {
    __m128d x[16], y[16], z[16];
    for (size_t i = 0; i < count; ++i) {
      x[i] = _mm_set1_pd(cvs[i].x);
      y[i] = _mm_set1_pd(cvs[i].y);
      z[i] = _mm_set1_pd(cvs[i].z);
    }
    const __m128d a = _mm_set_pd(1.0 - u1, 1.0 - u0), b = _mm_set_pd(u1, u0);
    for (size_t level = count - 1; level > 0; --level)
      for (size_t i = 0; i < level; ++i) {
        x[i] = _mm_add_pd(_mm_mul_pd(a, x[i]), _mm_mul_pd(b, x[i + 1]));
        y[i] = _mm_add_pd(_mm_mul_pd(a, y[i]), _mm_mul_pd(b, y[i + 1]));
        z[i] = _mm_add_pd(_mm_mul_pd(a, z[i]), _mm_mul_pd(b, z[i + 1]));
      }
    double xs[2], ys[2], zs[2];
    _mm_storeu_pd(xs, x[0]);
    _mm_storeu_pd(ys, y[0]);
    _mm_storeu_pd(zs, z[0]);
    p0 = dvec3(xs[0], ys[0], zs[0]);
    p1 = dvec3(xs[1], ys[1], zs[1]);
    return;
  }
#endif
  p0 = feather::bezierPoint(cvs, count, u0);
  p1 = feather::bezierPoint(cvs, count, u1);
}

// Fills the vane outline from the shaft polyline and the key barbs, with barbs interpolated between
// consecutive key barbs, dilated by one lateral bin and by `margin` in radius.
void buildOutline(LocalFeather& L, const PackOptions& o) {
  constexpr int nb = LocalFeather::kOutlineBins;
  float lo[nb], hi[nb];
  for (int k = 0; k < nb; ++k) {
    lo[k] = std::numeric_limits<float>::infinity();
    hi[k] = -std::numeric_limits<float>::infinity();
  }
  const double w = (L.yMax - L.yMin) / nb;
  auto add = [&](const dvec3& p, double rad) {
    const double r = std::sqrt(p.x * p.x + p.z * p.z);
    const int k0 = static_cast<int>(std::floor((p.y - rad - L.yMin) / w)), k1 = static_cast<int>(std::floor((p.y + rad - L.yMin) / w));
    for (int k = std::max(0, k0); k <= std::min(nb - 1, k1); ++k) {
      lo[k] = std::min(lo[k], static_cast<float>(r - rad));
      hi[k] = std::max(hi[k], static_cast<float>(r + rad));
    }
  };
  // add(p, 0): one lateral bin, the radius itself (p.y -+ 0 and r -+ 0 are p.y and r).
  auto add0 = [&](const dvec3& p) {
    const double r = std::sqrt(p.x * p.x + p.z * p.z);
    const int k = static_cast<int>(std::floor((p.y - L.yMin) / w));
    if (k < 0 || k >= nb) return;
    lo[k] = std::min(lo[k], static_cast<float>(r));
    hi[k] = std::max(hi[k], static_cast<float>(r));
  };
  for (size_t k = 0; k < L.after.size(); ++k) add(L.after[k], L.afterRad[k]);
  for (size_t k = 0; k < L.shaft.size(); ++k) {
    add(L.shaft[k], L.shaftRad[k]);
    if (k + 1 < L.shaft.size()) add(0.5 * (L.shaft[k] + L.shaft[k + 1]), L.shaftRad[k]);
  }
  constexpr int kAlong = 8, kBetween = 3;
  // Samples along every key barb once; barbs between two key barbs are approximated by blending them.
  std::vector<dvec3> samples(L.keys.size() * (kAlong + 1));
  for (size_t kk = 0; kk < L.keys.size(); ++kk) {
    const LocalKey& a = L.keys[kk];
    dvec3 c[kAlong + 2];
    for (int s = 0; s <= kAlong; s += 2)
      bezierPair(&L.cvs[a.cvOff], a.cvCount, static_cast<double>(s) / kAlong, static_cast<double>(s + 1) / kAlong, c[s],
                 c[s + 1]);
    for (int s = 0; s <= kAlong; ++s)
      samples[kk * (kAlong + 1) + s] = a.root + a.len * (c[s].x * a.u + c[s].y * a.w + c[s].z * a.d);
  }
  for (size_t kk = 0; kk < L.keys.size(); ++kk) {
    const bool hasNext = kk + 1 < L.keys.size() && L.keys[kk + 1].vane == L.keys[kk].vane;
    const dvec3* pa = &samples[kk * (kAlong + 1)];
    const dvec3* pb = hasNext ? &samples[(kk + 1) * (kAlong + 1)] : pa;
    for (int m = 0; m < (hasNext ? kBetween : 1); ++m) {
      const double f = static_cast<double>(m) / kBetween;
      for (int s = 0; s <= kAlong; ++s) add0((1 - f) * pa[s] + f * pb[s]);
    }
  }
  // Dilate: one bin sideways, and in radius by the sampling gap plus the largest clearance anyone needs.
  const double dr = 0.05 * L.reach + 4 * o.clearance + 2 * (L.shaftRad.empty() ? 0.0 : L.shaftRad.front());
  for (int k = 0; k < nb; ++k) {
    float a = lo[k], b = hi[k];
    if (k > 0) { a = std::min(a, lo[k - 1]); b = std::max(b, hi[k - 1]); }
    if (k + 1 < nb) { a = std::min(a, lo[k + 1]); b = std::max(b, hi[k + 1]); }
    L.rLo[k] = std::max(0.0f, static_cast<float>(a - dr));
    L.rHi[k] = static_cast<float>(b + dr);
  }
}

void buildLocal(const CoatFeathers& coat, uint32_t i, const PackOptions& o, detail::HugeArena& arena, LocalFeather& L) {
  // Built in this thread's reusable vectors, then copied to the arena at their final sizes.
  struct Build {
    std::vector<dvec3> shaft, after, cvs;
    std::vector<double> shaftRad, afterRad;
    std::vector<LocalKey> keys;
  };
  thread_local Build B;
  const feather::FeatherParams& p = coat.params[i];
  L.unopened = !coat.age.empty() && coat.age[i] < o.openingAge;
  L.totalLength = p.totalLength();
  B.shaft.clear();
  B.shaftRad.clear();
  B.keys.clear();
  B.cvs.clear();
  L.leftKeys = 0;
  L.mainKeys = 0;
  B.after.clear();
  B.afterRad.clear();
  L.vaneHalf = 0;
  const int segs = std::max(2, o.shaftSamples);
  if (L.unopened) {
    // 8.3: a pin or partly opened feather is straight and stiff.
    const double r = 0.5 * p.rachisWidth;
    for (int k = 0; k <= segs; ++k) {
      B.shaft.emplace_back(L.totalLength * k / segs, 0, 0);
      B.shaftRad.push_back(r);
    }
  } else {
    const double wBase = p.calamusWidthRatio * p.rachisWidth;
    if (p.calamusLength > 0) {
      B.shaft.emplace_back(0, 0, 0);
      B.shaftRad.push_back(0.5 * wBase);
      B.shaft.emplace_back(0.5 * p.calamusLength, 0, 0);
      B.shaftRad.push_back(0.25 * (wBase + p.rachisWidth));
    }
    for (int k = 0; k <= segs; ++k) {
      const feather::RachisFrame f = feather::rachisFrame(p, static_cast<double>(k) / segs);
      B.shaft.push_back(f.point);
      B.shaftRad.push_back(0.5 * f.width);
    }
    // Refined key barbs (6.3.3: the default tip barb becomes a real key barb; more key barbs pack the
    // vane at a finer resolution without changing its shape). Breakpoints of a silhouette (barb length
    // profile) become key barbs too, so barb lengths between key barbs are linear as the generator's are.
    std::vector<glm::dvec3> shape;
    // Key barbs of one vane without a vector per key barb: the effective key barbs and the inserted shapes
    // (one flat buffer) are referenced by (rp, source) entries, sorted stably by rp as the key barbs
    // themselves were.
    struct Entry {
      double rp;
      bool inserted;
      uint32_t index;  // effective key barb, or offset into `shapes`
      uint32_t count;
    };
    thread_local std::vector<feather::KeyBarb> eff;
    thread_local std::vector<glm::dvec3> shapes;
    thread_local std::vector<Entry> entries;
    thread_local std::vector<double> rps;
    auto addKeys = [&](const feather::FeatherParams& fp, const dvec3& offset, int refine, bool silhouette) {
      for (int v = 0; v < 2; ++v) {
        eff = feather::effectiveKeyBarbs(fp, v);
        PTERYLA_CHECK(!eff.empty(), "barbShapeAt needs key barbs");
        entries.clear();
        shapes.clear();
        for (size_t e = 0; e < eff.size(); ++e)
          entries.push_back({eff[e].rp, false, static_cast<uint32_t>(e), static_cast<uint32_t>(eff[e].cvs.size())});
        rps.clear();
        for (int k = 0; k < refine; ++k) rps.push_back(static_cast<double>(k) / (refine - 1));
        const feather::LengthProfile& prof = v == 0 ? fp.silhouette.left : fp.silhouette.right;
        if (silhouette && prof.points.size() <= 16)
          for (const auto& pt : prof.points)
            if (pt.x > 0 && pt.x < 1) rps.push_back(pt.x);
        for (const double rp : rps) {
          bool present = false;
          for (const Entry& e : entries) present = present || std::abs(e.rp - rp) < 1e-6;
          if (present) continue;
          // feather::barbShapeAt(eff, rp, .): effective key barbs all have the same count.
          const auto it = std::upper_bound(eff.begin(), eff.end(), rp,
                                           [](double x, const feather::KeyBarb& k) { return x < k.rp; });
          const uint32_t off = static_cast<uint32_t>(shapes.size());
          if (it == eff.begin() || it == eff.end()) {
            const std::vector<glm::dvec3>& c = it == eff.begin() ? eff.front().cvs : eff.back().cvs;
            shapes.insert(shapes.end(), c.begin(), c.end());
          } else {
            const feather::KeyBarb& above = *it;
            const feather::KeyBarb& below = *(it - 1);
            const double t = (rp - below.rp) / (above.rp - below.rp);
            if (above.cvs.size() == below.cvs.size()) {
              for (size_t c = 0; c < above.cvs.size(); ++c) shapes.push_back((1 - t) * below.cvs[c] + t * above.cvs[c]);
            } else {
              feather::barbShapeAt(eff, rp, shape);
              shapes.insert(shapes.end(), shape.begin(), shape.end());
            }
          }
          entries.push_back({rp, true, off, static_cast<uint32_t>(shapes.size() - off)});
        }
        std::stable_sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.rp < b.rp; });
        const feather::VaneParams& vp = fp.vane(v);
        const double side = v == 0 ? 1.0 : -1.0;
        for (const Entry& kb : entries) {
          LocalKey k;
          k.rp = kb.rp;
          k.vane = static_cast<uint8_t>(v);
          const feather::RachisFrame f = feather::rachisFrame(fp, kb.rp);
          const double angle = std::clamp(vp.baseAngle * (1 - kb.rp) + vp.tipAngle * kb.rp, 0.01, kPi - 0.01);
          const double ca = std::cos(angle), sa = std::sin(angle);
          k.u = ca * f.tangent + (side * sa) * f.left;
          k.w = sa * f.tangent - (side * ca) * f.left;
          k.d = f.dorsal;
          k.left = f.left;
          k.root = offset + f.point + (side * 0.5 * f.width) * f.left;
          k.len = fp.barbLengthAt(v, kb.rp);
          k.cvOff = static_cast<uint32_t>(B.cvs.size());
          k.cvCount = static_cast<uint16_t>(kb.count);
          const glm::dvec3* src = kb.inserted ? &shapes[kb.index] : eff[kb.index].cvs.data();
          double xmax = 0;
          for (uint32_t c = 0; c < kb.count; ++c) {
            B.cvs.push_back(src[c]);
            xmax = std::max(xmax, src[c].x);
          }
          k.sExt = k.len * xmax;
          k.rootDist = glm::length(k.root);
          L.vaneHalf = std::max(L.vaneHalf, k.len * xmax * sa);
          B.keys.push_back(k);
        }
      }
    };
    addKeys(p, dvec3(0), std::max(2, o.keyBarbsPerVane), true);
    L.mainKeys = static_cast<uint32_t>(B.keys.size());
    for (const LocalKey& k : B.keys) L.leftKeys += k.vane == 0 ? 1 : 0;
    if (p.afterfeather) {
      // The afterfeather (5.2, at the superior umbilicus, as feather::generateBarbs places it) rides along
      // unpacked; its points still keep later feathers off it.
      const feather::FeatherParams& af = *p.afterfeather;
      const dvec3 umbilicus(p.calamusLength, 0, -0.5 * p.rachisWidth);
      const double vh = L.vaneHalf;
      addKeys(af, umbilicus, 3, false);
      L.vaneHalf = vh;
      for (int k = 0; k <= 4; ++k) {
        const feather::RachisFrame f = feather::rachisFrame(af, k / 4.0);
        B.after.push_back(umbilicus + f.point);
        B.afterRad.push_back(0.5 * f.width);
      }
    }
  }
  L.shaft = arena.copy(B.shaft);
  L.shaftRad = arena.copy(B.shaftRad);
  L.keys = arena.copy(B.keys);
  L.cvs = arena.copy(B.cvs);
  L.after = arena.copy(B.after);
  L.afterRad = arena.copy(B.afterRad);
  // Bounds over every packed state: elevation is a rotation about the follicle, flattening moves control
  // vertices toward the barb's plane and the lift rotates a barb about its root, so |p| <= |root| + len |cv|.
  double reach = 0, yMin = 0, yMax = 0;
  L.shaftYMin = L.shaftYMax = 0;
  for (size_t k = 0; k < L.shaft.size(); ++k) {
    L.shaftYMin = std::min(L.shaftYMin, L.shaft[k].y);
    L.shaftYMax = std::max(L.shaftYMax, L.shaft[k].y);
    reach = std::max(reach, glm::length(L.shaft[k]) + L.shaftRad[k]);
    yMin = std::min(yMin, L.shaft[k].y - L.shaftRad[k]);
    yMax = std::max(yMax, L.shaft[k].y + L.shaftRad[k]);
  }
  for (size_t k = 0; k < L.after.size(); ++k) {
    reach = std::max(reach, glm::length(L.after[k]) + L.afterRad[k]);
    yMin = std::min(yMin, L.after[k].y - L.afterRad[k]);
    yMax = std::max(yMax, L.after[k].y + L.afterRad[k]);
  }
  for (const LocalKey& k : L.keys) {
    double cm = 0;
    for (uint32_t c = 0; c < k.cvCount; ++c) cm = std::max(cm, glm::length(L.cvs[k.cvOff + c]));
    reach = std::max(reach, glm::length(k.root) + k.len * cm);
    yMin = std::min(yMin, k.root.y - k.len * cm);
    yMax = std::max(yMax, k.root.y + k.len * cm);
  }
  L.reach = reach;
  L.yMin = yMin - 1e-9 * (1 + reach);
  L.yMax = yMax + 1e-9 * (1 + reach);
  buildOutline(L, o);
  const uint32_t barbPts = static_cast<uint32_t>(std::max(1, o.barbSamples));
  L.pointCount = static_cast<uint32_t>(L.shaft.size() + L.after.size()) + static_cast<uint32_t>(L.keys.size()) * barbPts;
}

// ------------------------------------------------------------------ context

// Candidate points in the follicle frame (t along T, b along B, n along N). Points of packed feathers carry
// their thickness radius; skin samples stand for a patch of the surface (below): its radius, the unit
// normal (follicle frame) and the sine bound on how far the patch's faces turn away from that normal.
// The two kinds are kept apart (feather points first, then skin, as they are gathered).
struct FeatherCandidate {
  double t, b, n;
  double rad;  // thickness radius of the point
};

struct SkinCandidate {
  double t, b, n;
  double rho, cone;
  dvec3 normal;
  // Largest rise of the patch over its centre along unit direction a (follicle frame): rho times the sine
  // of the angle between a and the patch's faces' normals (a face tilted toward a rises along it).
  double rise(const dvec3& a) const {
    const double c = glm::dot(a, normal);
    return rho * std::min(1.0, std::sqrt(std::max(0.0, 1 - c * c)) + cone);
  }
};

struct Scratch {
  std::vector<FeatherCandidate> cand;
  std::vector<SkinCandidate> skinCand;
  std::vector<double> psiMin, shaftRadBin, yLo, yHi;
  std::vector<glm::dvec2> best;           // per shaft bin: direction of the largest angle so far
  std::vector<double> bh, bhRaw;          // barb fields, keys x bins
  std::vector<double> plane;              // per key: signed distance of the current candidate
  std::vector<double> keyRoot[3], keyW[3];  // per key: placed root and slicing-plane normal (arrays)
  std::vector<glm::dvec3> curve, tmp;     // barb samples and transformed control vertices
  std::vector<double> bern;               // Bernstein weights: samples x cvs
  std::vector<double> bernT, cx, cz;      // the weights cvs x samples; curve x and z being summed
  size_t bernCvs = 0, bernSamples = 0;
  PackStats stats;
  std::vector<BarbField> fields;
};

struct Context {
  Context(const SkinMesh& s, const CoatFeathers& c, const PackOptions& o) : skin(s), coat(c), opt(o) {}
  const SkinMesh& skin;
  const CoatFeathers& coat;
  const PackOptions& opt;
  double clearance = 0, skinClearance = 0, medianReach = 0;
  tbb::enumerable_thread_specific<detail::HugeArena> arenas;  // storage of local's arrays
  std::vector<LocalFeather> local;
  std::vector<uint32_t> order, pos;  // pos[i] = position in order, UINT32_MAX if not packed
  // dependency graph (CSR)
  std::vector<uint32_t> depOff, deps;
  // Origins of packed feathers in reach classes (class c holds reaches up to 2^(c+1) x the median), one
  // grid each with its own largest reach, so a small feather's neighbour search is not sized by the
  // longest flight feather. members[c][item] = position in `order`.
  struct ReachClass {
    detail::PointGrid grid;
    std::vector<uint32_t> members;
    double maxReach = 0;
  };
  std::vector<ReachClass> reachClasses;
  double maxReach = 0;
  // Calls f(position in order) for every packed feather whose origin lies within `range` + its class's
  // largest reach of `centre` (a superset; callers test the exact condition).
  template <class F>
  void forNearOrigins(const dvec3& centre, double range, F&& f) const {
    for (const ReachClass& rc : reachClasses) {
      const double q = range + rc.maxReach;
      rc.grid.query(centre - dvec3(q), centre + dvec3(q), [&](uint32_t item) { f(rc.members[item]); });
    }
  }
  // Skin samples (built by setup, or a base pack's for packOver); null without skin.
  std::shared_ptr<const detail::PackSkinSamples> skinData;
  std::vector<double> fixed;
  std::vector<double> minElevation;  // per feather from styling (NaN = none); empty = none
  std::vector<double> shaftBand;     // per feather from styling (NaN = PackOptions::shaftBand); empty = none
};

dvec3 toFrame(const FeatherFrame& F, const dvec3& q) {
  const dvec3 r = q - F.origin;
  return {glm::dot(r, F.tangent), glm::dot(r, F.binormal), glm::dot(r, F.normal)};
}

// Rotation by elevation e in the follicle frame (t, b, n): local (x, y, z) -> (x c - z s, y, x s + z c).
struct Rot {
  double c, s;
  dvec3 operator()(const dvec3& p) const { return {p.x * c - p.z * s, p.y, p.x * s + p.z * c}; }
};

// Monotone stand-in for the angle of (x, y) over (-pi/2, 3pi/2) ("diamond angle" of the vector turned by
// +pi/2): compares angles without atan2.
inline double pseudoAngle(double x, double y) {
  const double px = -y, py = x;  // turned by +pi/2: angles in (-pi/2, 3pi/2) -> (0, 2pi)
  const double s = std::abs(px) + std::abs(py);
  if (s == 0) return 0;
  if (py >= 0) return px >= 0 ? py / s : 1 + (-px) / s;
  return px < 0 ? 2 + (-py) / s : 3 + px / s;
}

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

// ---- barb fitting (6.3.3)

struct BarbFit {
  double mu = 0, alpha = 0;
  double stretch = 1;  // keepBarbArcLength: the flattened barb scaled about its root to its old arc length
  bool resolved = true;
};

// A key barb's control vertex after flattening mu, stretching about the root cv0 (flattened likewise) by
// `stretch` and lifting by alpha about the origin.
inline dvec3 flattenCv(const dvec3& cv, const dvec3& cv0, double mu, double stretch, double ca, double sa) {
  auto flat = [&](const dvec3& c) { return dvec3(c.x, c.y, c.z + mu * std::max(0.0, -c.z)); };
  dvec3 f = flat(cv);
  if (stretch != 1) {  // (exactly the plain flattening otherwise)
    const dvec3 f0 = flat(cv0);
    f = f0 + stretch * (f - f0);
  }
  return {f.x * ca - f.z * sa, f.y, f.x * sa + f.z * ca};
}

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
    if (clears(S, bh, nb, cell, sRoot)) hi = mid;
    else lo = mid;
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
    if (clipLo) xa = std::max(xa, clip);
    else if (clipHi) xb = std::min(xb, clip);
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


// Written once per chunk by closeChunks (packed or kept feather), so not zero-filled first.
using ChunkBounds = std::vector<glm::dvec4, UninitializedAllocator<glm::dvec4>>;

struct Output {
  std::vector<double>& elevation;
  PackedKeyBarbs& keys;
  std::vector<uint8_t>& barbsChanged;
  std::vector<uint32_t>& pointOffset;
  PackedPoints& points;
  std::vector<glm::dvec4>& bounds;
  const std::vector<uint32_t>& groupOffset;
  const std::vector<uint32_t>& groupPoint;
  PackedGroupBounds& groupBounds;
  // Internal culling level above the groups: chunk c of feather i (chunkOffset[i] <= c < [i+1]) holds
  // groups groupOffset[i] + kChunk (c - chunkOffset[i]) .. + kChunk, with a sphere around their spheres.
  const std::vector<uint32_t>& chunkOffset;
  ChunkBounds& chunkBounds;
};

constexpr uint32_t kChunk = 4;

std::vector<uint32_t> chunkOffsets(const std::vector<uint32_t>& groupOffset) {
  std::vector<uint32_t> off(groupOffset.size(), 0);
  for (size_t i = 0; i + 1 < groupOffset.size(); ++i)
    off[i + 1] = off[i] + (groupOffset[i + 1] - groupOffset[i] + kChunk - 1) / kChunk;
  return off;
}

// Chunk spheres of feather i from its stored group spheres. Each chunk sphere holds its groups' spheres
// with a margin far above the rounding of the footprint tests, so a group can only pass a test its chunk
// passes: skipping the groups of a failed chunk leaves the candidates unchanged.
void closeChunks(Output& out, uint32_t i) {
  const uint32_t g0 = out.groupOffset[i], g1 = out.groupOffset[i + 1];
  uint32_t c = out.chunkOffset[i];
  for (uint32_t a = g0; a < g1; a += kChunk, ++c) {
    const uint32_t b = std::min(g1, a + kChunk);
    dvec3 lo(kInf), hi(-kInf);
    for (uint32_t g = a; g < b; ++g) {
      const glm::vec4& s = out.groupBounds[g];
      const dvec3 p(s.x, s.y, s.z);
      lo = glm::min(lo, p - dvec3(s.w));
      hi = glm::max(hi, p + dvec3(s.w));
    }
    const dvec3 centre = 0.5 * (lo + hi);
    double r = 0;
    for (uint32_t g = a; g < b; ++g) {
      const glm::vec4& s = out.groupBounds[g];
      r = std::max(r, glm::length(dvec3(s.x, s.y, s.z) - centre) + s.w);
    }
    out.chunkBounds[c] = glm::dvec4(centre, r * (1 + 1e-9) + 1e-9 * (glm::length(centre) + r) + 1e-12);
  }
  PTERYLA_CHECK(c == out.chunkOffset[i + 1], "chunk count mismatch");
}

struct PlacedKey {
  dvec3 root, u, w, d, left;
};

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
          if (pad > 0 ? !L.nearOutline(b, std::sqrt(t * t + n * n), pad) : !L.inOutline(b, std::sqrt(t * t + n * n))) return;
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
            for (int b = b0; b <= b1; ++b) put(b, lineMax(q, g, wv, wl, rho, b * bcell - s, (b + 1) * bcell - s, baseR));
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

// Packs feather i against its dependencies' packed points (already in `out`) and the skin.
void packFeather(const Context& ctx, uint32_t i, Scratch& S, Output& out) {
  const LocalFeather& L = ctx.local[i];
  const FeatherFrame& F = ctx.coat.frames[i];
  const PackOptions& o = ctx.opt;
  PackStats& st = S.stats;
  ++st.recomputed;
  gatherCandidates(ctx, i, S, out);
  const double e = shaftElevation(ctx, i, S);
  if (L.unopened) ++st.unopened;
  out.elevation[i] = e;
  const Rot R{std::cos(e), std::sin(e)};

  // ---- 6.3.3 barb elevation: per key barb, a height field in its barb slicing plane from the candidates
  // on its side of the shaft between the neighbouring key barbs' slicing planes.
  const size_t nKeys = L.mainKeys;
  const int fb = std::max(2, o.barbFieldBins);
  bool anyChanged = false;
  // The packed key barbs are written to their slots in the flat output (layout: layoutKeys) and elevated
  // there; an unopened feather keeps its input key barbs (no slots).
  PackedKeyBarbs& K = out.keys;
  const uint32_t k0 = K.keyOffset[i];
  PTERYLA_CHECK((K.replaced[i] != 0) == !L.unopened && K.keyOffset[i + 1] - k0 == (L.unopened ? 0 : nKeys),
                "packed key barb layout mismatch");
  for (size_t kk = 0; kk < K.keyOffset[i + 1] - k0; ++kk) {
    const LocalKey& k = L.keys[kk];
    PTERYLA_CHECK(K.cvOffset[k0 + kk + 1] - K.cvOffset[k0 + kk] == k.cvCount, "packed key barb layout mismatch");
    K.rp[k0 + kk] = k.rp;
    std::copy(L.cvs.begin() + k.cvOff, L.cvs.begin() + k.cvOff + k.cvCount, K.cvs.begin() + K.cvOffset[k0 + kk]);
  }
  if (o.elevateBarbs && !L.unopened && nKeys > 0) {
    PlacedKey pk[256];
    const size_t nk = std::min<size_t>(nKeys, 256);
    for (size_t kk = 0; kk < nk; ++kk) {
      const LocalKey& k = L.keys[kk];
      pk[kk] = {R(k.root), R(k.u), R(k.w), R(k.d), R(k.left)};
    }
    S.bh.assign(nk * fb, -kInf);
    if (o.captureFields) S.bhRaw.assign(nk * fb, -kInf);
    S.plane.resize(nk);
    barbFields(ctx, i, S, pk, nk);
    for (size_t kk = 0; kk < nk; ++kk) {
      const LocalKey& k = L.keys[kk];
      if (k.sExt <= 0) continue;
      glm::dvec3* const cvs = K.cvs.data() + K.cvOffset[k0 + kk];  // k.cvCount of them (checked above)
      const BarbFit fit = fitBarb(cvs, k.cvCount, k.len, k.sExt, &S.bh[kk * fb], fb, o, S);
      if (fit.mu > 0 || fit.alpha > 0) {
        ++st.barbsElevated;
        anyChanged = true;
        const double ca = std::cos(fit.alpha), sa = std::sin(fit.alpha);
        const glm::dvec3 cv0 = cvs[0];
        for (size_t c = 0; c < k.cvCount; ++c) cvs[c] = flattenCv(cvs[c], cv0, fit.mu, fit.stretch, ca, sa);
      }
      if (fit.alpha > 0) ++st.barbsLifted;
      if (!fit.resolved) ++st.barbsUnresolved;
      if (o.captureFields) {
        BarbField bf;
        bf.feather = i;
        bf.vane = k.vane;
        bf.key = static_cast<uint16_t>(k.vane == 0 ? kk : kk - L.leftKeys);
        const PlacedKey& p = pk[kk];
        bf.root = F.origin + p.root.x * F.tangent + p.root.y * F.binormal + p.root.z * F.normal;
        bf.along = p.u.x * F.tangent + p.u.y * F.binormal + p.u.z * F.normal;
        bf.up = p.d.x * F.tangent + p.d.y * F.binormal + p.d.z * F.normal;
        bf.length = k.sExt;
        bf.field.origin = 0;
        bf.field.cell = k.sExt / fb;
        bf.field.h.resize(fb);
        for (int b = 0; b < fb; ++b) bf.field.h[b] = static_cast<float>(S.bhRaw[kk * fb + b]);
        S.fields.push_back(std::move(bf));
      }
    }
  }
  out.barbsChanged[i] = anyChanged ? 1 : 0;

  // ---- packed points handed to later feathers: shaft polyline and samples along every key barb.
  uint32_t q = out.pointOffset[i];
  // rad = the largest |f| + r; for r = 0 the largest |f|^2 is kept and its root taken once (sqrt is
  // monotone, so the same value).
  double rad = 0, rad2 = 0;
  auto emit = [&](const dvec3& local, double r) {
    const dvec3 f = R(local);
    const dvec3 w = F.origin + f.x * F.tangent + f.y * F.binormal + f.z * F.normal;
    out.points[q++] = glm::vec4(static_cast<float>(w.x), static_cast<float>(w.y), static_cast<float>(w.z),
                                static_cast<float>(r));
    if (r == 0) rad2 = std::max(rad2, glm::dot(f, f));
    else rad = std::max(rad, glm::length(f) + r);
  };
  uint32_t g = out.groupOffset[i];
  auto closeGroup = [&] {
    // Sphere around the group's stored (float) points: box centre, largest distance plus thickness.
    const uint32_t a = out.groupPoint[g], b = out.groupPoint[g + 1];
    PTERYLA_CHECK(b == q, "packed point group mismatch");
    dvec3 lo(kInf), hi(-kInf);
    for (uint32_t k = a; k < b; ++k) {
      const dvec3 p(out.points[k]);
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    const dvec3 c = 0.5 * (lo + hi);
    double r = 0, r2 = 0;
    for (uint32_t k = a; k < b; ++k) {
      const dvec3 d = dvec3(out.points[k]) - c;
      if (out.points[k].w == 0) r2 = std::max(r2, glm::dot(d, d));
      else r = std::max(r, glm::length(d) + out.points[k].w);
    }
    r = std::max(r, std::sqrt(r2));
    out.groupBounds[g] = glm::vec4(static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z),
                                   static_cast<float>(r * (1 + 1e-5) + 1e-6 * (glm::length(c) + r)));
    ++g;
  };
  for (size_t k = 0; k < L.shaft.size(); ++k) emit(L.shaft[k], L.shaftRad[k]);
  closeGroup();
  if (!L.after.empty()) {
    for (size_t k = 0; k < L.after.size(); ++k) emit(L.after[k], L.afterRad[k]);
    closeGroup();
  }
  const int bs = std::max(1, o.barbSamples);
  for (size_t kk = 0; kk < L.keys.size(); ++kk) {
    const LocalKey& k = L.keys[kk];
    // The packed (elevated) control vertices of an opened feather's main keys, else the local ones.
    const glm::dvec3* cv = kk < nKeys && !L.unopened ? K.cvs.data() + K.cvOffset[k0 + kk] : &L.cvs[k.cvOff];
    const size_t cn = k.cvCount;
    for (int s = 1; s <= bs; s += 2) {
      glm::dvec3 c[2];
      bezierPair(cv, cn, static_cast<double>(s) / bs, static_cast<double>(s + 1) / bs, c[0], c[1]);
      for (int m = 0; m < 2 && s + m <= bs; ++m) emit(k.root + k.len * (c[m].x * k.u + c[m].y * k.w + c[m].z * k.d), 0.0);
    }
    closeGroup();
  }
  PTERYLA_CHECK(q == out.pointOffset[i + 1] && g == out.groupOffset[i + 1], "packed point count mismatch");
  closeChunks(out, i);
  rad = std::max(rad, std::sqrt(rad2));
  // Pad the sphere for the float rounding of the stored points.
  out.bounds[i] = glm::dvec4(F.origin, rad * (1 + 1e-6) + 1e-9);
}

// ------------------------------------------------------------------ setup

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + m, v.end());
  return v[m];
}

void checkInput(const CoatFeathers& c, const PackOptions& o) {
  const size_t n = c.size();
  auto need = [&](size_t got, const char* what) {
    if (got != n)
      throw Error(std::string("CoatFeathers.") + what + " has " + std::to_string(got) + " entries, expected " +
                      std::to_string(n),
                  {}, what);
  };
  need(c.params.size(), "params");
  need(c.frames.size(), "frames");
  if (!c.tract.empty()) need(c.tract.size(), "tract");
  if (!c.age.empty()) need(c.age.size(), "age");
  if (!c.present.empty()) need(c.present.size(), "present");
  if (!o.fixedElevation.empty() && o.fixedElevation.size() != n)
    throw Error("fixedElevation has " + std::to_string(o.fixedElevation.size()) + " entries, expected " +
                    std::to_string(n),
                {}, "fixedElevation");
  std::vector<uint8_t> seen(n, 0);
  for (size_t k = 0; k < c.layerOrder.size(); ++k) {
    const uint32_t i = c.layerOrder[k];
    if (i >= n) throw Error("layer order names feather " + std::to_string(i) + " of " + std::to_string(n), {}, "layerOrder[" + std::to_string(k) + "]");
    if (seen[i]) throw Error("layer order lists feather " + std::to_string(i) + " twice", {}, "layerOrder[" + std::to_string(k) + "]");
    seen[i] = 1;
  }
  for (size_t i = 0; i < n; ++i) {
    const FeatherFrame& f = c.frames[i];
    for (const dvec3* v : {&f.origin, &f.normal, &f.tangent, &f.binormal})
      if (!std::isfinite(v->x) || !std::isfinite(v->y) || !std::isfinite(v->z))
        throw Error("feather frame is not finite", {}, "frames[" + std::to_string(i) + "]");
  }
  if (!(o.maxElevation >= o.minElevation)) throw Error("maxElevation below minElevation", {}, "maxElevation");
  if (!(o.maxFlatten >= 0 && o.maxFlatten <= 2)) throw Error("maxFlatten must be in [0, 2]", {}, "maxFlatten");
}

// Reach classes over the packed feathers' origins (Context::reachClasses): class c holds the feathers
// whose radius is up to 2^(c+1) x `med`; radius[i] bounds feather i's points around its origin.
void buildReachClasses(Context& ctx, const std::vector<double>& radius, double med) {
  std::vector<std::vector<uint32_t>> members;
  for (size_t k = 0; k < ctx.order.size(); ++k) {
    const double ratio = radius[ctx.order[k]] / (2 * med);
    const size_t c = ratio <= 1 ? 0 : std::min<size_t>(16, static_cast<size_t>(std::ceil(std::log2(ratio))));
    if (members.size() <= c) members.resize(c + 1);
    members[c].push_back(static_cast<uint32_t>(k));
  }
  ctx.reachClasses.clear();
  for (auto& m : members) {
    if (m.empty()) continue;
    Context::ReachClass rc;
    std::vector<glm::dvec3> origins(m.size());
    for (size_t q = 0; q < m.size(); ++q) {
      origins[q] = ctx.coat.frames[ctx.order[m[q]]].origin;
      rc.maxReach = std::max(rc.maxReach, radius[ctx.order[m[q]]]);
    }
    rc.grid.build(origins, std::max(rc.maxReach, 1e-9));
    rc.members = std::move(m);
    ctx.reachClasses.push_back(std::move(rc));
  }
}

// Dependencies (ctx.depOff / ctx.deps, CSR over every feather; empty but for `items`): for each feather
// in `items`, the feathers before it in layer order whose radius ball can touch its footprint, in index
// order. Needs the reach classes and the items' feather-local data.
void buildDependencies(Context& ctx, const std::vector<uint32_t>& items, const std::vector<double>& radius, size_t grain) {
  const size_t n = ctx.coat.size();
  std::vector<std::vector<uint32_t>> depLists(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, items.size(), grain), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t w = r.begin(); w < r.end(); ++w) {
      const uint32_t i = items[w];
      const LocalFeather& L = ctx.local[i];
      const FeatherFrame& F = ctx.coat.frames[i];
      std::vector<uint32_t>& d = depLists[i];
      ctx.forNearOrigins(F.origin, L.reach, [&](uint32_t kj) {
        if (kj >= ctx.pos[i]) return;
        const uint32_t j = ctx.order[kj];
        const double Rj = radius[j];
        const dvec3 c = toFrame(F, ctx.coat.frames[j].origin);
        if (glm::length(c) > L.reach + Rj) return;
        if (c.x < -Rj || c.y < L.yMin - Rj || c.y > L.yMax + Rj) return;
        d.push_back(j);
      });
      std::sort(d.begin(), d.end());
    }
  });
  ctx.depOff.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) ctx.depOff[i + 1] = ctx.depOff[i] + static_cast<uint32_t>(depLists[i].size());
  ctx.deps.resize(ctx.depOff[n]);
  for (size_t i = 0; i < n; ++i) std::copy(depLists[i].begin(), depLists[i].end(), ctx.deps.begin() + ctx.depOff[i]);
}

void setup(Context& ctx) {
  const CoatFeathers& coat = ctx.coat;
  const PackOptions& o = ctx.opt;
  const size_t n = coat.size();
  ctx.fixed = o.fixedElevation;
  ctx.minElevation = resolveMinElevation(coat, o.styling);
  ctx.shaftBand = resolveShaftBand(coat, o.styling);
  ctx.order.clear();
  if (coat.layerOrder.empty()) {
    for (uint32_t i = 0; i < n; ++i) ctx.order.push_back(i);
  } else {
    ctx.order = coat.layerOrder;
  }
  ctx.order.erase(std::remove_if(ctx.order.begin(), ctx.order.end(),
                                 [&](uint32_t i) { return !coat.present.empty() && coat.present[i] == 0; }),
                  ctx.order.end());
  ctx.pos.assign(n, UINT32_MAX);
  for (size_t k = 0; k < ctx.order.size(); ++k) ctx.pos[ctx.order[k]] = static_cast<uint32_t>(k);

  ctx.local.resize(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16), [&](const tbb::blocked_range<size_t>& r) {
    detail::HugeArena& arena = ctx.arenas.local();
    for (size_t i = r.begin(); i < r.end(); ++i) {
      ctx.local[i].packable = ctx.pos[i] != UINT32_MAX;
      if (ctx.local[i].packable) buildLocal(coat, static_cast<uint32_t>(i), o, arena, ctx.local[i]);
      else ctx.local[i].pointCount = 0;
    }
  });

  // Clearances.
  std::vector<double> widths, reaches;
  for (uint32_t i : ctx.order) {
    widths.push_back(coat.params[i].rachisWidth);
    reaches.push_back(ctx.local[i].reach);
  }
  ctx.clearance = o.clearance > 0 ? o.clearance : 0.25 * median(widths);
  ctx.skinClearance = o.skinClearance > 0 ? o.skinClearance : ctx.clearance;
  const double medReach = std::max(1e-12, median(reaches));
  ctx.medianReach = medReach;
  double maxReach = 0;
  for (double r : reaches) maxReach = std::max(maxReach, r);
  ctx.maxReach = maxReach;

  // Dependency graph: j before i whose reach ball can touch i's footprint.
  std::vector<double> radius(n, 0.0);
  for (uint32_t i : ctx.order) radius[i] = ctx.local[i].reach;
  buildReachClasses(ctx, radius, medReach);
  buildDependencies(ctx, ctx.order, radius, 16);

  // Skin samples (9.1.2: the surface under the feather, including neighbouring polygons).
  ctx.skinData.reset();
  if (o.skin && !ctx.skin.faces.empty()) {
    auto data = std::make_shared<detail::PackSkinSamples>();
    detail::PackSkinSamples& sd = *data;
    sd.skinPositions = ctx.skin.positions;
    const double h = o.skinSampleSpacing > 0 ? o.skinSampleSpacing : 0.1 * medReach;
    // Every used vertex once, points along each edge once (the face with the lower index, or the only
    // face, owns it), and interior points of each face; counts from the edge/face size and spacing h.
    const SkinMesh& sk = ctx.skin;
    const size_t nf = sk.faces.size();
    auto segs = [&](double len) { return std::clamp(static_cast<int>(std::ceil(len / h)), 1, 32); };
    std::vector<uint8_t> used(sk.positions.size(), 0);
    for (const auto& t : sk.faces) used[t[0]] = used[t[1]] = used[t[2]] = 1;
    size_t base = 0;
    for (size_t v = 0; v < sk.positions.size(); ++v) base += used[v];
    std::vector<uint32_t> faceOff(nf + 1, 0);
    std::vector<int> faceN(nf);
    for (size_t f = 0; f < nf; ++f) {
      const auto& t = sk.faces[f];
      uint32_t cnt = 0;
      double le = 0;
      for (int c = 0; c < 3; ++c) {
        const double l = glm::length(sk.positions[t[(c + 1) % 3]] - sk.positions[t[c]]);
        le = std::max(le, l);
        const int32_t nb = sk.faceNeighbors.empty() ? -1 : sk.faceNeighbors[f][c];
        if (nb < 0 || static_cast<size_t>(nb) > f) cnt += static_cast<uint32_t>(segs(l) - 1);
      }
      const int m = segs(le);
      faceN[f] = m;
      cnt += static_cast<uint32_t>(m >= 3 ? (m - 1) * (m - 2) / 2 : 0);
      faceOff[f + 1] = faceOff[f] + cnt;
    }
    sd.pts.resize(base + faceOff.back());
    {
      size_t q = 0;
      for (size_t v = 0; v < sk.positions.size(); ++v)
        if (used[v]) sd.pts[q++] = sk.positions[v];
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nf, 64), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t f = r.begin(); f < r.end(); ++f) {
        const auto& t = sk.faces[f];
        const dvec3 P[3] = {sk.positions[t[0]], sk.positions[t[1]], sk.positions[t[2]]};
        size_t q = base + faceOff[f];
        for (int c = 0; c < 3; ++c) {
          const int32_t nb = sk.faceNeighbors.empty() ? -1 : sk.faceNeighbors[f][c];
          if (!(nb < 0 || static_cast<size_t>(nb) > f)) continue;
          const dvec3 a = P[c], b = P[(c + 1) % 3];
          const int m = segs(glm::length(b - a));
          for (int k = 1; k < m; ++k) sd.pts[q++] = a + (static_cast<double>(k) / m) * (b - a);
        }
        const int m = faceN[f];
        for (int x = 1; x < m; ++x)
          for (int y = 1; x + y < m; ++y) {
            const double u = static_cast<double>(x) / m, v = static_cast<double>(y) / m;
            sd.pts[q++] = P[0] + u * (P[1] - P[0]) + v * (P[2] - P[0]);
          }
        PTERYLA_CHECK(q == base + faceOff[f + 1], "skin sample count mismatch");
      }
    });
    // The sample grid (serial, ~2.5 MB of fresh memory on the bird) is built beside the patches.
    auto patches = [&] {
      // Patches. A point of face f lies in the sub-triangle of f's m-subdivision (longest edge le / m,
      // covering radius <= le / (m sqrt 3)); a corner of that sub-triangle on an edge of f may be replaced by
      // the nearest sample of that edge, at most half an edge step away.
      std::vector<double> faceRho(nf);
      for (size_t f = 0; f < nf; ++f) {
        const auto& t = sk.faces[f];
        double le = 0, edgeHalf = 0;
        for (int c = 0; c < 3; ++c) {
          const double l = glm::length(sk.positions[t[(c + 1) % 3]] - sk.positions[t[c]]);
          le = std::max(le, l);
          edgeHalf = std::max(edgeHalf, 0.5 * l / segs(l));
        }
        faceRho[f] = (le / faceN[f] / std::sqrt(3.0) + edgeHalf) * (1 + 1e-9);
      }
      sd.normal.resize(sd.pts.size());
      sd.rho.resize(sd.pts.size());
      sd.cone.resize(sd.pts.size());
      auto setPatch = [&](size_t q, const uint32_t* faces, size_t count) {
        dvec3 nsum(0);
        double rho = 0;
        for (size_t k = 0; k < count; ++k) {
          nsum += sk.faceNormals[faces[k]];
          rho = std::max(rho, faceRho[faces[k]]);
        }
        const double l = glm::length(nsum);
        const dvec3 nrm = l > 1e-12 ? nsum / l : sk.faceNormals[faces[0]];
        double cone = 0;
        for (size_t k = 0; k < count; ++k) {
          const dvec3 x = glm::cross(nrm, sk.faceNormals[faces[k]]);
          // sine of the angle (or 1 past 90 degrees)
          cone = std::max(cone, glm::dot(nrm, sk.faceNormals[faces[k]]) < 0 ? 1.0 : glm::length(x));
        }
        sd.normal[q] = nrm;
        sd.rho[q] = static_cast<float>(rho * (1 + 1e-6));
        sd.cone[q] = static_cast<float>(std::min(1.0, cone * (1 + 1e-6) + 1e-9));
      };
      {
        size_t q = 0;
        std::vector<uint32_t> inc;
        for (size_t v = 0; v < sk.positions.size(); ++v) {
          if (!used[v]) continue;
          inc.clear();
          if (!sk.vertexFaceOffsets.empty()) {
            for (uint32_t k = sk.vertexFaceOffsets[v]; k < sk.vertexFaceOffsets[v + 1]; ++k) inc.push_back(sk.vertexFaces[k]);
          } else {
            for (uint32_t f = 0; f < nf; ++f)
              if (sk.faces[f][0] == v || sk.faces[f][1] == v || sk.faces[f][2] == v) inc.push_back(f);
          }
          setPatch(q++, inc.data(), inc.size());
        }
      }
      tbb::parallel_for(tbb::blocked_range<size_t>(0, nf, 64), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t f = r.begin(); f < r.end(); ++f) {
          size_t q = base + faceOff[f];
          const uint32_t self = static_cast<uint32_t>(f);
          for (int c = 0; c < 3; ++c) {
            const int32_t nb = sk.faceNeighbors.empty() ? -1 : sk.faceNeighbors[f][c];
            if (!(nb < 0 || static_cast<size_t>(nb) > f)) continue;
            const int m = segs(glm::length(sk.positions[sk.faces[f][(c + 1) % 3]] - sk.positions[sk.faces[f][c]]));
            const uint32_t two[2] = {self, static_cast<uint32_t>(nb < 0 ? self : static_cast<uint32_t>(nb))};
            for (int k = 1; k < m; ++k) setPatch(q++, two, 2);
          }
          for (; q < base + faceOff[f + 1]; ++q) setPatch(q, &self, 1);
        }
      });
    };
    tbb::parallel_invoke([&] { sd.grid.build(sd.pts.data(), sd.pts.size(), std::max(0.2 * medReach, 2 * h)); }, patches);
    for (float r : sd.rho) sd.maxRho = std::max(sd.maxRho, static_cast<double>(r));
    ctx.skinData = std::move(data);
  }
}

std::vector<uint32_t> pointOffsets(const Context& ctx) {
  const size_t n = ctx.coat.size();
  std::vector<uint32_t> off(n + 1, 0);
  for (size_t i = 0; i < n; ++i) off[i + 1] = off[i] + ctx.local[i].pointCount;
  return off;
}

// Runs task(i) for every feather of `items` (in layer order) after those of its dependencies that are
// items too (`member[j]` != 0; null = every feather is); deterministic results because each task reads
// only its dependencies' outputs.
template <class Task>
void schedule(const Context& ctx, const std::vector<uint32_t>& items, const uint8_t* member, int threads, Task&& task) {
  if (threads == 1 || items.size() < 64) {
    for (uint32_t i : items) task(i);
    return;
  }
  const size_t n = ctx.coat.size();
  auto in = [&](uint32_t j) { return member == nullptr || member[j] != 0; };
  // Successors (CSR) and pending dependency counts within the items.
  std::vector<uint32_t> succOff(n + 1, 0);
  std::vector<std::atomic<uint32_t>> pending(n);
  std::vector<uint32_t> ready;
  for (uint32_t i : items) {
    uint32_t c = 0;
    for (uint32_t k = ctx.depOff[i]; k < ctx.depOff[i + 1]; ++k)
      if (in(ctx.deps[k])) {
        ++c;
        ++succOff[ctx.deps[k] + 1];
      }
    pending[i].store(c, std::memory_order_relaxed);
    if (c == 0) ready.push_back(i);
  }
  for (size_t i = 0; i < n; ++i) succOff[i + 1] += succOff[i];
  std::vector<uint32_t, UninitializedAllocator<uint32_t>> succ(succOff[n]);  // every slot is filled below
  std::vector<uint32_t> fill(succOff.begin(), succOff.end() - 1);
  for (uint32_t i : items)
    for (uint32_t k = ctx.depOff[i]; k < ctx.depOff[i + 1]; ++k)
      if (in(ctx.deps[k])) succ[fill[ctx.deps[k]]++] = i;
  auto body = [&](uint32_t i, tbb::feeder<uint32_t>& feeder) {
    task(i);
    for (uint32_t k = succOff[i]; k < succOff[i + 1]; ++k)
      if (pending[succ[k]].fetch_sub(1, std::memory_order_acq_rel) == 1) feeder.add(succ[k]);
  };
  tbb::parallel_for_each(ready.begin(), ready.end(), body);
}

// Appends the point groups of a packed feather (its shaft, afterfeather shaft, then each key barb's
// samples) starting at point p to groupPoint; returns the point after its last group.
uint32_t appendGroups(const LocalFeather& L, int barbSamples, uint32_t p, std::vector<uint32_t>& groupPoint) {
  groupPoint.push_back(p);
  p += static_cast<uint32_t>(L.shaft.size());
  if (!L.after.empty()) {
    groupPoint.push_back(p);
    p += static_cast<uint32_t>(L.after.size());
  }
  for (size_t k = 0; k < L.keys.size(); ++k) {
    groupPoint.push_back(p);
    p += static_cast<uint32_t>(std::max(1, barbSamples));
  }
  return p;
}

// Sizes the flat packed key barbs: feather i gets `count(i)` = {keys, left keys, replaced} and its key k's
// control vertex count from cvCount(i, k). rp and cvs are left uninitialised: every slot is written once
// (packFeather, or a copy from an earlier result).
template <class Count, class CvCount>
void layoutKeys(size_t n, PackedKeyBarbs& K, Count&& count, CvCount&& cvCount) {
  K.keyOffset.assign(n + 1, 0);
  K.leftKeys.assign(n, 0);
  K.replaced.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const std::array<uint32_t, 3> c = count(i);
    K.keyOffset[i + 1] = K.keyOffset[i] + c[0];
    K.leftKeys[i] = c[1];
    K.replaced[i] = static_cast<uint8_t>(c[2]);
  }
  K.cvOffset.assign(K.keyOffset[n] + 1, 0);
  for (size_t i = 0; i < n; ++i)
    for (uint32_t k = K.keyOffset[i]; k < K.keyOffset[i + 1]; ++k)
      K.cvOffset[k + 1] = K.cvOffset[k] + cvCount(i, k - K.keyOffset[i]);
  K.rp.clear();
  K.rp.resize(K.keyOffset[n]);
  K.cvs.clear();
  K.cvs.resize(K.cvOffset.back());  // huge pages, uninitialised (UninitializedAllocator)
}

// The key barb layout of a feather packed from its local data: the main (packed) key barbs of an opened
// feather, left vane first.
std::array<uint32_t, 3> localKeyCount(const LocalFeather& L) {
  if (!L.packable || L.unopened) return {0, 0, 0};
  for (uint32_t k = 0; k < L.mainKeys; ++k)
    PTERYLA_CHECK((L.keys[k].vane == 0) == (k < L.leftKeys), "local key barbs are not left vane first");
  return {L.mainKeys, L.leftKeys, 1};
}

// Copies feather i's packed key barbs from `from` (the same layout for i).
void copyKeys(const PackedKeyBarbs& from, PackedKeyBarbs& to, uint32_t i) {
  const uint32_t a = from.keyOffset[i], b = from.keyOffset[i + 1], t = to.keyOffset[i];
  PTERYLA_CHECK(b - a == to.keyOffset[i + 1] - t && from.cvOffset[b] - from.cvOffset[a] == to.cvOffset[t + b - a] - to.cvOffset[t],
                "copied key barbs with a different layout");
  std::copy(from.rp.begin() + a, from.rp.begin() + b, to.rp.begin() + t);
  std::copy(from.cvs.begin() + from.cvOffset[a], from.cvs.begin() + from.cvOffset[b], to.cvs.begin() + to.cvOffset[t]);
}

// Whether feather i has the same key barb layout in two results.
bool sameKeyLayout(const PackedKeyBarbs& a, const PackedKeyBarbs& b, uint32_t i) {
  const uint32_t n = a.keyOffset[i + 1] - a.keyOffset[i];
  if (n != b.keyOffset[i + 1] - b.keyOffset[i] || a.replaced[i] != b.replaced[i] || a.leftKeys[i] != b.leftKeys[i]) return false;
  for (uint32_t k = 0; k < n; ++k)
    if (a.cvOffset[a.keyOffset[i] + k + 1] - a.cvOffset[a.keyOffset[i] + k] !=
        b.cvOffset[b.keyOffset[i] + k + 1] - b.cvOffset[b.keyOffset[i] + k])
      return false;
  return true;
}

void initResult(const Context& ctx, PackResult& res) {
  const size_t n = ctx.coat.size();
  res.order = ctx.order;
  res.elevation.assign(n, 0.0);
  layoutKeys(n, res.packedKeys, [&](size_t i) { return localKeyCount(ctx.local[i]); },
             [&](size_t i, uint32_t k) -> uint32_t { return ctx.local[i].keys[k].cvCount; });
  res.barbsChanged.assign(n, 0);
  res.recomputed.assign(n, 0);
  res.pointOffset = pointOffsets(ctx);
  res.points.clear();
  res.points.resize(res.pointOffset.back());  // uninitialised: every feather writes its own points
  res.bounds.assign(n, glm::dvec4(0));
  res.groupOffset.assign(n + 1, 0);
  res.groupPoint.clear();
  size_t groups = 1;
  for (const LocalFeather& L : ctx.local)
    if (L.packable) groups += 1 + (L.after.empty() ? 0 : 1) + L.keys.size();
  res.groupPoint.reserve(groups);
  for (size_t i = 0; i < n; ++i) {
    const LocalFeather& L = ctx.local[i];
    uint32_t p = res.pointOffset[i];
    if (L.packable) p = appendGroups(L, ctx.opt.barbSamples, p, res.groupPoint);
    PTERYLA_CHECK(p == res.pointOffset[i + 1], "point groups do not cover the points");
    res.groupOffset[i + 1] = static_cast<uint32_t>(res.groupPoint.size());
  }
  res.groupPoint.push_back(res.pointOffset[n]);
  res.groupBounds.clear();
  res.groupBounds.resize(res.groupOffset[n]);  // uninitialised: each group's sphere is written by its feather
  res.barbFields.clear();
  res.stats = {};
}

bool fieldBefore(const BarbField& a, const BarbField& b) {
  return a.feather != b.feather ? a.feather < b.feather : (a.vane != b.vane ? a.vane < b.vane : a.key < b.key);
}

void finish(const Context& ctx, tbb::enumerable_thread_specific<Scratch>& scratch, PackResult& res,
            std::chrono::steady_clock::time_point t0) {
  PackStats& st = res.stats;
  for (Scratch& s : scratch) {
    st.recomputed += s.stats.recomputed;
    st.fixed += s.stats.fixed;
    st.unopened += s.stats.unopened;
    st.free += s.stats.free;
    st.shaftClamped += s.stats.shaftClamped;
    st.conflicts += s.stats.conflicts;
    st.barbsElevated += s.stats.barbsElevated;
    st.barbsLifted += s.stats.barbsLifted;
    st.barbsUnresolved += s.stats.barbsUnresolved;
    st.candidatePoints += s.stats.candidatePoints;
    for (auto& f : s.fields) res.barbFields.push_back(std::move(f));
  }
  std::sort(res.barbFields.begin(), res.barbFields.end(), fieldBefore);
  st.packed = ctx.order.size();
  st.dependencies = ctx.deps.size();
  st.skinSamples = ctx.skinData ? ctx.skinData->pts.size() : 0;
  res.clearance = ctx.clearance;
  res.skinClearance = ctx.skinClearance;
  res.medianReach = ctx.medianReach;
  res.skinSamples = ctx.skinData;
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

PackResult pack(const SkinMesh& skin, const CoatFeathers& coat, const PackOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  checkInput(coat, options);
  Context ctx(skin, coat, options);
  auto run = [&](PackResult& res) {
    setup(ctx);
    initResult(ctx, res);
    tbb::enumerable_thread_specific<Scratch> scratch;
    const std::vector<uint32_t> chunkOffset = chunkOffsets(res.groupOffset);
    ChunkBounds chunkBounds(chunkOffset.back());
    Output out{res.elevation, res.packedKeys, res.barbsChanged, res.pointOffset, res.points, res.bounds, res.groupOffset, res.groupPoint, res.groupBounds, chunkOffset, chunkBounds};
    schedule(ctx, ctx.order, nullptr, options.threads, [&](uint32_t i) {
      packFeather(ctx, i, scratch.local(), out);
      res.recomputed[i] = 1;
    });
    finish(ctx, scratch, res, t0);
  };
  PackResult res;
  detail::inArena(options.threads, [&] { run(res); });
  return res;
}

PackResult repack(const SkinMesh& skin, const CoatFeathers& coat, const PackResult& prev,
                  const std::vector<uint32_t>& changed, const PackOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  checkInput(coat, options);
  const size_t n = coat.size();
  std::vector<uint32_t> order = coat.layerOrder;
  if (order.empty())
    for (uint32_t i = 0; i < n; ++i) order.push_back(i);
  order.erase(std::remove_if(order.begin(), order.end(), [&](uint32_t i) { return !coat.present.empty() && coat.present[i] == 0; }),
              order.end());
  // The previous result must describe the same feathers in the same order.
  if (prev.elevation.size() != n || prev.pointOffset.size() != n + 1 || prev.packedKeys.keyOffset.size() != n + 1 ||
      prev.order != order || changed.size() * 2 > n)
    return pack(skin, coat, options);
  std::vector<uint8_t> isChanged(n, 0);
  for (uint32_t c : changed) {
    if (c >= n) throw Error("changed feather " + std::to_string(c) + " out of range", {}, "changed");
    isChanged[c] = 1;
  }
  Context ctx(skin, coat, options);
  PackResult res;
  auto run = [&] {
    setup(ctx);
    initResult(ctx, res);
    // Feathers whose old packed points (previous bounds) touch i's footprint: a changed feather that
    // moved away must still dirty what it used to cover.
    std::vector<uint8_t> touched(n, 0);
    for (uint32_t j : changed) {
      if (prev.bounds[j].w <= 0) continue;
      const dvec3 c(prev.bounds[j]);
      const double rj = prev.bounds[j].w;
      const uint32_t pj = ctx.pos[j];
      ctx.forNearOrigins(c, rj, [&](uint32_t ki) {
        const uint32_t i = ctx.order[ki];
        if (pj != UINT32_MAX && ki <= pj) return;
        const LocalFeather& L = ctx.local[i];
        const dvec3 l = toFrame(coat.frames[i], c);
        if (glm::length(l) > L.reach + rj || l.x < -rj || l.y < L.yMin - rj || l.y > L.yMax + rj) return;
        touched[i] = 1;
      });
    }
    std::vector<uint8_t> outChanged(n, 0);
    tbb::enumerable_thread_specific<Scratch> scratch;
    const std::vector<uint32_t> chunkOffset = chunkOffsets(res.groupOffset);
    ChunkBounds chunkBounds(chunkOffset.back());
    Output out{res.elevation, res.packedKeys, res.barbsChanged, res.pointOffset, res.points, res.bounds, res.groupOffset, res.groupPoint, res.groupBounds, chunkOffset, chunkBounds};
    schedule(ctx, ctx.order, nullptr, options.threads, [&](uint32_t i) {
      bool dirty = isChanged[i] || touched[i];
      for (uint32_t k = ctx.depOff[i]; k < ctx.depOff[i + 1] && !dirty; ++k) dirty = outChanged[ctx.deps[k]] != 0;
      const uint32_t cnt = res.pointOffset[i + 1] - res.pointOffset[i];
      const bool sameShape = prev.pointOffset[i + 1] - prev.pointOffset[i] == cnt && sameKeyLayout(prev.packedKeys, res.packedKeys, i);
      if (!dirty && sameShape) {
        res.elevation[i] = prev.elevation[i];
        copyKeys(prev.packedKeys, res.packedKeys, i);
        res.barbsChanged[i] = prev.barbsChanged[i];
        std::copy(prev.points.begin() + prev.pointOffset[i], prev.points.begin() + prev.pointOffset[i + 1],
                  res.points.begin() + res.pointOffset[i]);
        res.bounds[i] = prev.bounds[i];
        PTERYLA_CHECK(prev.groupOffset[i + 1] - prev.groupOffset[i] == res.groupOffset[i + 1] - res.groupOffset[i],
                      "unchanged feather with a different point structure");
        std::copy(prev.groupBounds.begin() + prev.groupOffset[i], prev.groupBounds.begin() + prev.groupOffset[i + 1],
                  res.groupBounds.begin() + res.groupOffset[i]);
        closeChunks(out, i);
        return;
      }
      packFeather(ctx, i, scratch.local(), out);
      res.recomputed[i] = 1;
      bool diff = !sameShape || std::memcmp(&res.elevation[i], &prev.elevation[i], sizeof(double)) != 0 ||
                  res.bounds[i] != prev.bounds[i];
      if (!diff)
        diff = std::memcmp(res.points.data() + res.pointOffset[i], prev.points.data() + prev.pointOffset[i],
                           cnt * sizeof(glm::vec4)) != 0;
      outChanged[i] = diff ? 1 : 0;
    });
    finish(ctx, scratch, res, t0);
  };
  detail::inArena(options.threads, run);
  return res;
}

PackResult packOver(const SkinMesh& skin, const CoatFeathers& coat, const PackResult& base,
                    const std::vector<uint32_t>& changed, const PackOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  checkInput(coat, options);
  const size_t n = coat.size();
  auto present = [&](uint32_t i) { return coat.present.empty() || coat.present[i] != 0; };
  if (base.elevation.size() != n || base.pointOffset.size() != n + 1 || base.groupOffset.size() != n + 1 ||
      base.packedKeys.keyOffset.size() != n + 1 || base.bounds.size() != n)
    throw Error("packOver: the base pack is for " + std::to_string(base.elevation.size()) + " feathers, the coat has " +
                    std::to_string(n),
                {}, "base");
  // Every present feather must be packed in base, in the same relative order.
  std::vector<uint32_t> order;
  order.reserve(base.order.size());
  for (uint32_t i : base.order)
    if (i < n && present(i)) order.push_back(i);
  {
    std::vector<uint32_t> want = coat.layerOrder;
    if (want.empty())
      for (uint32_t i = 0; i < n; ++i) want.push_back(i);
    want.erase(std::remove_if(want.begin(), want.end(), [&](uint32_t i) { return !present(i); }), want.end());
    if (want != order)
      throw Error("packOver: the coat's present feathers are not packed in the base pack in the same layer order", {},
                  "base");
  }
  std::vector<uint8_t> isChanged(n, 0);
  for (uint32_t c : changed) {
    if (c >= n) throw Error("changed feather " + std::to_string(c) + " out of range", {}, "changed");
    isChanged[c] = 1;
  }
  if (options.skin && !skin.faces.empty()) {
    const auto& sd = base.skinSamples;
    if (!sd || sd->skinPositions.size() != skin.positions.size() ||
        std::memcmp(sd->skinPositions.data(), skin.positions.data(), skin.positions.size() * sizeof(dvec3)) != 0)
      throw Error("packOver: the skin differs from the one the base pack was packed on", {}, "base");
  }

  Context ctx(skin, coat, options);
  PackResult res;
  auto run = [&] {
    ctx.fixed = options.fixedElevation;
    ctx.minElevation = resolveMinElevation(coat, options.styling);
    ctx.shaftBand = resolveShaftBand(coat, options.styling);
    ctx.order = order;
    ctx.pos.assign(n, UINT32_MAX);
    for (size_t k = 0; k < order.size(); ++k) ctx.pos[order[k]] = static_cast<uint32_t>(k);
    ctx.clearance = base.clearance;
    ctx.skinClearance = base.skinClearance;
    ctx.medianReach = base.medianReach;
    ctx.skinData = base.skinSamples;
    // The feathers to pack, in layer order; only they get their feather-local data.
    std::vector<uint32_t> work;
    for (uint32_t i : order)
      if (isChanged[i]) work.push_back(i);
    ctx.local.resize(n);
    for (uint32_t i : order) ctx.local[i].packable = true;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, work.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
      detail::HugeArena& arena = ctx.arenas.local();
      for (size_t k = r.begin(); k < r.end(); ++k) buildLocal(coat, work[k], options, arena, ctx.local[work[k]]);
    });
    // Dependencies of the packed feathers: feathers before them whose points can touch their footprint
    // (a kept feather's packed bounds, a packed one's reach).
    std::vector<double> radius(n, 0.0);
    for (uint32_t j : order) radius[j] = isChanged[j] ? ctx.local[j].reach : base.bounds[j].w;
    {
      std::vector<double> rs;
      rs.reserve(order.size());
      for (uint32_t j : order) rs.push_back(radius[j]);
      buildReachClasses(ctx, radius, std::max(1e-12, median(rs)));
    }
    buildDependencies(ctx, work, radius, 4);

    // Result layout: kept feathers take base's point groups, packed ones their own, absent ones none.
    res.order = order;
    res.elevation.assign(n, 0.0);
    // Packed feathers' key barbs laid out from their local data, kept ones' from base.
    const PackedKeyBarbs& BK = base.packedKeys;
    layoutKeys(
        n, res.packedKeys,
        [&](size_t i) -> std::array<uint32_t, 3> {
          if (ctx.pos[i] == UINT32_MAX) return {0, 0, 0};
          if (isChanged[i]) return localKeyCount(ctx.local[i]);
          return {BK.keyOffset[i + 1] - BK.keyOffset[i], BK.leftKeys[i], BK.replaced[i]};
        },
        [&](size_t i, uint32_t k) -> uint32_t {
          if (isChanged[i]) return ctx.local[i].keys[k].cvCount;
          return BK.cvOffset[BK.keyOffset[i] + k + 1] - BK.cvOffset[BK.keyOffset[i] + k];
        });
    res.barbsChanged.assign(n, 0);
    res.recomputed.assign(n, 0);
    res.bounds.assign(n, glm::dvec4(0));
    res.pointOffset.assign(n + 1, 0);
    res.groupOffset.assign(n + 1, 0);
    res.groupPoint.clear();
    res.groupPoint.reserve(base.groupPoint.size());
    for (uint32_t i = 0; i < n; ++i) {
      uint32_t p = res.pointOffset[i];
      if (ctx.pos[i] != UINT32_MAX && isChanged[i]) {
        const LocalFeather& L = ctx.local[i];
        p = appendGroups(L, options.barbSamples, p, res.groupPoint);
        PTERYLA_CHECK(p - res.pointOffset[i] == L.pointCount, "point groups do not cover the points");
      } else if (ctx.pos[i] != UINT32_MAX) {
        for (uint32_t g = base.groupOffset[i]; g < base.groupOffset[i + 1]; ++g) {
          res.groupPoint.push_back(p);
          p += base.groupPoint[g + 1] - base.groupPoint[g];
        }
        PTERYLA_CHECK(p - res.pointOffset[i] == base.pointOffset[i + 1] - base.pointOffset[i],
                      "base point groups do not cover its points");
      }
      res.pointOffset[i + 1] = p;
      res.groupOffset[i + 1] = static_cast<uint32_t>(res.groupPoint.size());
    }
    res.groupPoint.push_back(res.pointOffset[n]);
    res.points.clear();
    res.points.resize(res.pointOffset[n]);
    res.groupBounds.clear();
    res.groupBounds.resize(res.groupOffset[n]);  // uninitialised: written by packed and kept feathers
    res.barbFields.clear();
    res.stats = {};
    const std::vector<uint32_t> chunkOffset = chunkOffsets(res.groupOffset);
    ChunkBounds chunkBounds(chunkOffset.back());
    Output out{res.elevation, res.packedKeys, res.barbsChanged, res.pointOffset, res.points, res.bounds, res.groupOffset, res.groupPoint, res.groupBounds, chunkOffset, chunkBounds};
    // Kept feathers: base's results as they are.
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, static_cast<uint32_t>(n), 32), [&](const tbb::blocked_range<uint32_t>& r) {
      for (uint32_t i = r.begin(); i < r.end(); ++i) {
        if (ctx.pos[i] == UINT32_MAX || isChanged[i]) continue;
        res.elevation[i] = base.elevation[i];
        copyKeys(base.packedKeys, res.packedKeys, i);
        res.barbsChanged[i] = base.barbsChanged[i];
        res.bounds[i] = base.bounds[i];
        std::copy(base.points.begin() + base.pointOffset[i], base.points.begin() + base.pointOffset[i + 1],
                  res.points.begin() + res.pointOffset[i]);
        std::copy(base.groupBounds.begin() + base.groupOffset[i], base.groupBounds.begin() + base.groupOffset[i + 1],
                  res.groupBounds.begin() + res.groupOffset[i]);
        closeChunks(out, i);
      }
    });
    // The packed feathers, each after the packed feathers it depends on.
    tbb::enumerable_thread_specific<Scratch> scratch;
    schedule(ctx, work, isChanged.data(), options.threads, [&](uint32_t i) {
      packFeather(ctx, i, scratch.local(), out);
      res.recomputed[i] = 1;
    });
    finish(ctx, scratch, res, t0);
    if (options.captureFields) {
      for (const BarbField& f : base.barbFields)
        if (f.feather < n && ctx.pos[f.feather] != UINT32_MAX && !isChanged[f.feather]) res.barbFields.push_back(f);
      std::sort(res.barbFields.begin(), res.barbFields.end(), fieldBefore);
    }
  };
  detail::inArena(options.threads, run);
  return res;
}

std::vector<uint32_t> changedFeathers(const CoatFeathers& a, const CoatFeathers& b, const std::vector<double>& fa,
                                      const std::vector<double>& fb) {
  PTERYLA_CHECK(a.size() == b.size(), "changedFeathers needs coats of equal size");
  std::vector<uint32_t> out;
  auto bitsEq = [](double x, double y) { return std::memcmp(&x, &y, sizeof(double)) == 0; };
  for (uint32_t i = 0; i < a.size(); ++i) {
    const FeatherFrame &x = a.frames[i], &y = b.frames[i];
    bool d = x.origin != y.origin || x.normal != y.normal || x.tangent != y.tangent || x.binormal != y.binormal;
    d = d || a.params[i] != b.params[i];
    const double ageA = a.age.empty() ? 1.0 : a.age[i], ageB = b.age.empty() ? 1.0 : b.age[i];
    d = d || !bitsEq(ageA, ageB);
    const uint8_t pa = a.present.empty() ? 1 : a.present[i], pb = b.present.empty() ? 1 : b.present[i];
    d = d || pa != pb;
    const double ea = fa.empty() ? kNaN : fa[i], eb = fb.empty() ? kNaN : fb[i];
    d = d || !(bitsEq(ea, eb) || (std::isnan(ea) && std::isnan(eb)));
    if (d) out.push_back(i);
  }
  return out;
}

namespace {
// Feather i's packed keys: checks that `result` is a pack of `coat`.
const PackedKeyBarbs& packedKeysOf(const CoatFeathers& coat, const PackResult& result, uint32_t i) {
  const PackedKeyBarbs& K = result.packedKeys;
  PTERYLA_CHECK(i < coat.size() && K.replaced.size() == coat.size() && K.keyOffset.size() == coat.size() + 1,
                "packedParams: the result is not a pack of this coat");
  return K;
}

// Keys [first, second) of feather i's vane v (0 left, 1 right) in K.
std::pair<uint32_t, uint32_t> vaneKeys(const PackedKeyBarbs& K, uint32_t i, int v) {
  const uint32_t m = K.keyOffset[i] + K.leftKeys[i];
  return v == 0 ? std::make_pair(K.keyOffset[i], m) : std::make_pair(m, K.keyOffset[i + 1]);
}
}  // namespace

void packedParamsInto(const CoatFeathers& coat, const PackResult& result, uint32_t i, feather::FeatherParams& out) {
  const PackedKeyBarbs& K = packedKeysOf(coat, result, i);
  out = coat.params[i];
  if (!K.replaced[i]) return;
  for (int v = 0; v < 2; ++v) {
    std::vector<feather::KeyBarb>& kb = out.vane(v).keyBarbs;
    const auto [k0, k1] = vaneKeys(K, i, v);
    kb.resize(k1 - k0);
    for (uint32_t k = k0; k < k1; ++k) {
      kb[k - k0].rp = K.rp[k];
      kb[k - k0].cvs.assign(K.cvs.begin() + K.cvOffset[k], K.cvs.begin() + K.cvOffset[k + 1]);
    }
  }
}

feather::FeatherParams packedParams(const CoatFeathers& coat, const PackResult& result, uint32_t i) {
  feather::FeatherParams p;
  packedParamsInto(coat, result, i, p);
  return p;
}

bool packedParamsEqual(const feather::FeatherParams& p, const CoatFeathers& coat, const PackResult& result, uint32_t i) {
  const PackedKeyBarbs& K = packedKeysOf(coat, result, i);
  if (!K.replaced[i]) return p == coat.params[i];
  for (int v = 0; v < 2; ++v) {
    const std::vector<feather::KeyBarb>& kb = p.vane(v).keyBarbs;
    const auto [k0, k1] = vaneKeys(K, i, v);
    if (kb.size() != k1 - k0) return false;
    for (uint32_t k = k0; k < k1; ++k)
      if (!(kb[k - k0].rp == K.rp[k]) || !std::equal(kb[k - k0].cvs.begin(), kb[k - k0].cvs.end(), K.cvs.begin() + K.cvOffset[k],
                                                      K.cvs.begin() + K.cvOffset[k + 1]))
        return false;
  }
  return p.equalExceptKeyBarbs(coat.params[i]);
}

std::vector<feather::FeatherParams> allPackedParams(const CoatFeathers& coat, const PackResult& result) {
  std::vector<feather::FeatherParams> out(coat.size());
  for (uint32_t i = 0; i < coat.size(); ++i) packedParamsInto(coat, result, i, out[i]);
  return out;
}

std::vector<PlacedKeyBarb> placedKeyBarbs(const CoatFeathers& coat, const PackResult& result, uint32_t i) {
  PTERYLA_CHECK(i < coat.size() && i < result.elevation.size(), "feather index out of range");
  const feather::FeatherParams p = packedParams(coat, result, i);
  const FeatherFrame& F = coat.frames[i];
  const double e = result.elevation[i];
  std::vector<PlacedKeyBarb> out;
  for (int v = 0; v < 2; ++v) {
    const double side = v == 0 ? 1.0 : -1.0;
    const feather::VaneParams& vp = p.vane(v);
    for (const feather::KeyBarb& kb : feather::effectiveKeyBarbs(p, v)) {
      const feather::RachisFrame f = feather::rachisFrame(p, kb.rp);
      const double angle = std::clamp(vp.baseAngle * (1 - kb.rp) + vp.tipAngle * kb.rp, 0.01, kPi - 0.01);
      const dvec3 u = std::cos(angle) * f.tangent + (side * std::sin(angle)) * f.left;
      const dvec3 w = std::sin(angle) * f.tangent - (side * std::cos(angle)) * f.left;
      const dvec3 root = f.point + (side * 0.5 * f.width) * f.left;
      const double len = p.barbLengthAt(v, kb.rp);
      PlacedKeyBarb pk;
      pk.vane = static_cast<uint8_t>(v);
      pk.rp = kb.rp;
      pk.length = len;
      pk.root = placePoint(F, e, root);
      pk.along = placeDirection(F, e, u);
      pk.up = placeDirection(F, e, f.dorsal);
      for (const auto& c : kb.cvs) pk.cvs.push_back(placePoint(F, e, root + len * (c.x * u + c.y * w + c.z * f.dorsal)));
      out.push_back(std::move(pk));
    }
  }
  return out;
}

}  // namespace pteryla::coat
