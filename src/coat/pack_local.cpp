// Feather-local geometry for packing: the shaft, key barbs and vane outline of a feather in its follicle
// frame at elevation 0, with reach and footprint bounds over every packed state.
#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "pteryla/core/error.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat::packing {

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
    const int k0 = static_cast<int>(std::floor((p.y - rad - L.yMin) / w)),
              k1 = static_cast<int>(std::floor((p.y + rad - L.yMin) / w));
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
    if (k > 0) {
      a = std::min(a, lo[k - 1]);
      b = std::max(b, hi[k - 1]);
    }
    if (k + 1 < nb) {
      a = std::min(a, lo[k + 1]);
      b = std::max(b, hi[k + 1]);
    }
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
  L.pointCount =
      static_cast<uint32_t>(L.shaft.size() + L.after.size()) + static_cast<uint32_t>(L.keys.size()) * barbPts;
}

}  // namespace pteryla::coat::packing
