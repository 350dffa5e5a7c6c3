// Packing one feather: shaft elevation, barb elevation, and its packed points, groups and bounds.
#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "pteryla/core/error.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat::packing {

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
  PTERYLA_CHECK_EQ(c, out.chunkOffset[i + 1], "chunk count mismatch");
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
    PTERYLA_DCHECK_EQ(K.cvOffset[k0 + kk + 1] - K.cvOffset[k0 + kk], k.cvCount, "packed key barb layout mismatch");
    K.rp[k0 + kk] = k.rp;
    std::copy(L.cvs.begin() + k.cvOff, L.cvs.begin() + k.cvOff + k.cvCount, K.cvs.begin() + K.cvOffset[k0 + kk]);
  }
  if (o.elevateBarbs && !L.unopened && nKeys > 0) {
    const size_t nk = nKeys;
    S.placed.resize(nk);
    PlacedKey* const pk = S.placed.data();
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
    out.points[q++] =
        glm::vec4(static_cast<float>(w.x), static_cast<float>(w.y), static_cast<float>(w.z), static_cast<float>(r));
    if (r == 0)
      rad2 = std::max(rad2, glm::dot(f, f));
    else
      rad = std::max(rad, glm::length(f) + r);
  };
  uint32_t g = out.groupOffset[i];
  auto closeGroup = [&] {
    // Sphere around the group's stored (float) points: box centre, largest distance plus thickness.
    const uint32_t a = out.groupPoint[g], b = out.groupPoint[g + 1];
    PTERYLA_DCHECK_EQ(b, q, "packed point group mismatch");
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
      if (out.points[k].w == 0)
        r2 = std::max(r2, glm::dot(d, d));
      else
        r = std::max(r, glm::length(d) + out.points[k].w);
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
      for (int m = 0; m < 2 && s + m <= bs; ++m)
        emit(k.root + k.len * (c[m].x * k.u + c[m].y * k.w + c[m].z * k.d), 0.0);
    }
    closeGroup();
  }
  PTERYLA_CHECK(q == out.pointOffset[i + 1] && g == out.groupOffset[i + 1], "packed point count mismatch");
  closeChunks(out, i);
  rad = std::max(rad, std::sqrt(rad2));
  // Pad the sphere for the float rounding of the stored points.
  out.bounds[i] = glm::dvec4(F.origin, rad * (1 + 1e-6) + 1e-9);
}

}  // namespace pteryla::coat::packing
