// Feather meshing, planning (5.3): which barbs and shaft points a level of detail keeps and the mesh's
// size; the reference's texture space (7.1.1, 8.1); barbs evaluated into sources for the writers.
#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/bezier.hpp"
#include "mesh_internal.hpp"

namespace pteryla::feather::meshing {

Plan makePlan(const FeatherMeshInput& in, const MeshOptions& opt, Scratch& s) {
  PTERYLA_CHECK_NE(in.curves, nullptr, "FeatherMeshInput::curves is required");
  Plan pl;
  pl.c = in.curves;
  pl.ref = in.reference ? in.reference : in.curves;
  const FeatherCurves& c = *in.curves;
  PTERYLA_CHECK(c.barbBegin.size() == c.partCount() && c.barbEnd.size() == c.partCount(), "malformed FeatherCurves");
  if (in.order) {
    PTERYLA_CHECK_EQ(in.order->rank.size(), c.barbs.size(), "LodOrder was computed for different curves");
    pl.order = in.order;
  } else {
    computeLodOrder(c, s.order);
    pl.order = &s.order;
  }
  double lod = in.lod;
  if (!(lod > 0)) lod = 0;
  lod = std::min(lod, 1.0);
  pl.lod = lod;
  pl.keep = keptBarbCount(*pl.order, lod);
  pl.fullSegs = opt.barbSegments;
  pl.segs = lodSegments(opt.barbSegments, opt.minBarbSegments, opt.segmentLodStart, lod);
  pl.parts = opt.afterfeather ? c.partCount() : std::min<size_t>(1, c.partCount());
  return pl;
}

// Interior calamus point i carries no shape: on the line between its neighbours, width linear.
bool redundantCalamusPoint(const ShaftCurve& sh, int i) {
  const glm::vec3 a = sh.points[i - 1], p = sh.points[i], b = sh.points[i + 1];
  const glm::vec3 ab = b - a;
  const float len2 = glm::dot(ab, ab);
  if (len2 <= 0) return true;
  const float t = glm::dot(p - a, ab) / len2;
  const float tol = 1e-5f * std::sqrt(len2);
  const float w = sh.widths[i - 1] + t * (sh.widths[i + 1] - sh.widths[i - 1]);
  return glm::length(a + t * ab - p) <= tol && std::abs(w - sh.widths[i]) <= 1e-5f * std::max(sh.widths[i], 1e-30f);
}

// Shaft points (indices into the shaft polyline) used at this level, tip included: the follicle,
// calamus points that bend or change the taper, and ceil(lod * rachis segments) rachis segments (at
// least minShaftSegments).
void shaftSelection(const ShaftCurve& sh, const Plan& pl, const MeshOptions& opt, std::vector<int>& sel) {
  sel.clear();
  const int n = static_cast<int>(sh.points.size());
  if (n < 2) return;
  const int rb = std::min(sh.calamusPoints, n - 1);
  for (int i = 0; i < rb; ++i)
    if (i == 0 || !redundantCalamusPoint(sh, i)) sel.push_back(i);
  const int segs = n - 1 - rb;
  if (segs <= 0) {
    if (sel.empty() || sel.back() != n - 1) sel.push_back(n - 1);
    return;
  }
  const int lo = std::min(std::max(1, opt.minShaftSegments), segs);
  const int target = std::clamp(static_cast<int>(std::ceil(segs * pl.lod - 1e-9)), lo, segs);
  for (int k = 0; k <= target; ++k)
    sel.push_back(rb + static_cast<int>(std::lround(static_cast<double>(k) * segs / target)));
}

struct PartSize {
  size_t verts = 0, tris = 0;
};

PartSize shaftSize(const std::vector<int>& sel, int sides) {
  PartSize z;
  if (sel.size() < 2) return z;
  const size_t rings = sel.size() - 1;
  z.verts = rings * static_cast<size_t>(sides + 1) + static_cast<size_t>(sides);
  z.tris = (rings - 1) * static_cast<size_t>(sides) * 2 + static_cast<size_t>(sides);
  return z;
}

PartSize vaneSize(const Plan& pl, uint32_t begin, uint32_t end) {
  PartSize z;
  size_t k = 0, splits = 0;
  uint32_t prev = std::numeric_limits<uint32_t>::max();
  for (uint32_t i = begin; i < end; ++i) {
    if (!keptBarb(pl, i)) continue;
    if (prev != std::numeric_limits<uint32_t>::max() && pl.c->barbs[prev].splitAfter) ++splits;
    prev = i;
    ++k;
  }
  if (k == 0) return z;
  z.verts = (2 * k + 1 + splits) * static_cast<size_t>(pl.segs + 1);
  z.tris = k * 4 * static_cast<size_t>(pl.segs);
  return z;
}

FeatherMeshSize planSize(const Plan& pl, const MeshOptions& opt, Scratch& s) {
  FeatherMeshSize sz;
  for (size_t part = 0; part < pl.parts; ++part) {
    if (opt.shaft) {
      shaftSelection(pl.c->shafts[part], pl, opt, s.shaftSel);
      const PartSize z = shaftSize(s.shaftSel, opt.shaftSides);
      sz.vertices += z.verts;
      sz.indices += 3 * z.tris;
    }
    const VaneRuns runs = vaneRuns(*pl.c, part);
    for (int v = 0; v < 2; ++v) {
      const PartSize z = vaneSize(pl, runs.begin[v], runs.end[v]);
      sz.vertices += z.verts;
      sz.indices += 3 * z.tris;
    }
  }
  return sz;
}

// ---------------------------------------------------------------- reference texture space

// Texture space of every part of the reference: extents of along / across over all control vertices
// (a curve lies in the hull of its control vertices, so normalized coordinates stay in [0, 1]). Frames
// at barb attachments are walked (barbs ascend in rp per vane) and not renormalized: the extents are
// normalization constants only. Per-barb data is filled lazily by refBarb().
void buildReference(const Plan& pl, Scratch& s) {
  const FeatherCurves& r = *pl.ref;
  s.refFrames.resize(r.partCount());
  s.ref.resize(r.barbs.size());
  s.refDone.assign(r.barbs.size(), 0);
  s.space.assign(r.partCount(), UvSpace{});
  for (size_t part = 0; part < r.partCount(); ++part) {
    const ShaftCurve& sh = r.shafts[part];
    ShaftFrames& sf = s.refFrames[part];
    sf.build(sh);
    float alongMin = 0, alongMax = sf.length(), acrossMax = 0, vgMax = sf.length();
    for (const Frame& f : sf.f) acrossMax = std::max(acrossMax, 0.5f * f.width);
    const size_t nf = sf.f.size();
    size_t hi = 0;
    float prevRp = -2;
    for (uint32_t i = r.barbBegin[part]; i < r.barbEnd[part]; ++i) {
      const BarbCurve& b = r.barbs[i];
      if (b.rp < prevRp) hi = 0;  // next vane
      prevRp = b.rp;
      while (hi < nf && sh.rp[hi] <= b.rp) ++hi;
      const size_t h = std::min(std::max<size_t>(hi, 1), nf - 1), lo = h - 1;
      const float span = sh.rp[h] - sh.rp[lo];
      const float w = span > 0 ? std::clamp((b.rp - sh.rp[lo]) / span, 0.0f, 1.0f) : 0.0f;
      const Frame& f0 = sf.f[lo];
      const Frame& f1 = sf.f[h];
      const glm::vec3 p = f0.p + w * (f1.p - f0.p), t = f0.t + w * (f1.t - f0.t), l = f0.l + w * (f1.l - f0.l);
      const float s0 = f0.s + w * (f1.s - f0.s);
      const glm::vec3* cv = r.cvs.data() + b.cvOffset;
      for (uint16_t k = 0; k < b.cvCount; ++k) {
        const glm::vec3 d = cv[k] - p;
        const float along = s0 + glm::dot(d, t);
        const float across = std::abs(glm::dot(d, l));
        alongMin = std::min(alongMin, along);
        alongMax = std::max(alongMax, along);
        acrossMax = std::max(acrossMax, across);
      }
      if (b.cvCount) vgMax = std::max(vgMax, s0 + glm::length(cv[b.cvCount - 1] - cv[0]));
    }
    UvSpace& sp = s.space[part];
    sp.alongMin = alongMin;
    sp.alongInv = alongMax - alongMin > 1e-30f ? 1.0f / (alongMax - alongMin) : 0.0f;
    sp.acrossInv = acrossMax > 1e-30f ? 0.5f / acrossMax : 0.0f;
    sp.vgInv = vgMax > 1e-30f ? 1.0f / vgMax : 0.0f;
  }
}

const RefBarb& refBarb(const Plan& pl, Scratch& s, uint32_t i) {
  RefBarb& rb = s.ref[i];
  if (s.refDone[i]) return rb;
  s.refDone[i] = 1;
  const FeatherCurves& r = *pl.ref;
  const BarbCurve& b = r.barbs[i];
  const size_t part = b.part < r.partCount() ? b.part : 0;
  const UvSpace& sp = s.space[part];
  rb.fr = s.refFrames[part].at(r.shafts[part], b.rp);
  const glm::vec3* cv = r.cvs.data() + b.cvOffset;
  rb.len = b.cvCount ? glm::length(cv[b.cvCount - 1] - cv[0]) : 0.0f;
  rb.u0 = b.cvCount ? std::min(0.5f, std::abs(glm::dot(cv[0] - rb.fr.p, rb.fr.l)) * sp.acrossInv) : 0.0f;
  rb.uTip = b.cvCount ? std::clamp(std::abs(glm::dot(cv[b.cvCount - 1] - rb.fr.p, rb.fr.l)) * sp.acrossInv, rb.u0, 0.5f)
                      : rb.u0;
  return rb;
}

RefLink refLink(const Plan& pl, size_t part, int vane, const VaneRuns& runs, const VaneRuns& refRuns, uint32_t i) {
  RefLink L;
  if (part >= pl.ref->partCount()) return L;
  const uint32_t rb = refRuns.begin[vane], re = refRuns.end[vane];
  if (rb == re) return L;
  L.valid = true;
  L.part = part;
  if (pl.ref == pl.c || re - rb == runs.end[vane] - runs.begin[vane]) {
    L.a = L.b = rb + (i - runs.begin[vane]);
    return L;
  }
  const float rp = pl.c->barbs[i].rp;
  uint32_t lo = rb, hi = re;  // first reference barb with rp > rp
  while (lo < hi) {
    const uint32_t mid = (lo + hi) / 2;
    if (pl.ref->barbs[mid].rp <= rp)
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo == rb) {
    L.a = L.b = rb;
    return L;
  }
  if (lo == re) {
    L.a = L.b = re - 1;
    return L;
  }
  L.a = lo - 1;
  L.b = lo;
  const float ra = pl.ref->barbs[L.a].rp, rbp = pl.ref->barbs[L.b].rp;
  L.w = rbp > ra ? (rp - ra) / (rbp - ra) : 0.0f;
  return L;
}

// ---------------------------------------------------------------- sources (evaluated barbs)

// Evaluates barb i of the curves into a new source slot; texture coordinates from the reference.
int addSource(const Plan& pl, Scratch& s, uint32_t i, const RefLink& link, float side) {
  const int slot = static_cast<int>(s.srcRp.size());
  const size_t n = static_cast<size_t>(pl.segs + 1);
  const size_t base = static_cast<size_t>(slot) * n;
  s.srcPos.resize(base + n);
  s.srcUvG.resize(base + n);
  s.srcUvB.resize(base + n);
  s.srcUvGr.resize(base + n);
  const BarbCurve& b = pl.c->barbs[i];
  s.srcRp.push_back(b.rp);
  const glm::vec3* cv = pl.c->cvs.data() + b.cvOffset;
  const double inv = 1.0 / pl.segs;
  // Same parameters as barbPolyline(): t = k / segments.
  for (size_t k = 0; k < n; ++k) s.srcPos[base + k] = bezierPoint(cv, b.cvCount, static_cast<double>(k) / pl.segs);
  if (!link.valid) {
    for (size_t k = 0; k < n; ++k) {
      const float t = static_cast<float>(k * inv);
      s.srcUvG[base + k] = glm::vec2(0.5f, 0.5f);
      s.srcUvB[base + k] = glm::vec2(0.5f - 0.5f * side * t, b.rp);
      s.srcUvGr[base + k] = glm::vec2(0.5f - 0.5f * side * t, 0.5f);
    }
    return slot;
  }
  const UvSpace& sp = s.space[link.part];
  const RefBarb& ra = refBarb(pl, s, link.a);
  const RefBarb& rb = refBarb(pl, s, link.b);
  const float w = link.w;
  const bool same = pl.ref == pl.c;
  const BarbCurve& ba = pl.ref->barbs[link.a];
  const BarbCurve& bb = pl.ref->barbs[link.b];
  const glm::vec3* cva = pl.ref->cvs.data() + ba.cvOffset;
  const glm::vec3* cvb = pl.ref->cvs.data() + bb.cvOffset;
  auto globalUv = [&](const RefBarb& r, const glm::vec3& q) {
    const glm::vec3 d = q - r.fr.p;
    const float along = r.fr.s + glm::dot(d, r.fr.t);
    const float across = glm::dot(d, r.fr.l);
    return glm::vec2(0.5f - across * sp.acrossInv, (along - sp.alongMin) * sp.alongInv);
  };
  const float u0 = (1 - w) * ra.u0 + w * rb.u0;
  const float uTip = (1 - w) * ra.uTip + w * rb.uTip;
  const float s0 = (1 - w) * ra.fr.s + w * rb.fr.s;
  const float len = (1 - w) * ra.len + w * rb.len;
  for (size_t k = 0; k < n; ++k) {
    const double tt = static_cast<double>(k) / pl.segs;
    const float t = static_cast<float>(tt);
    glm::vec2 g;
    if (same) {
      g = globalUv(ra, s.srcPos[base + k]);
    } else {
      g = globalUv(ra, bezierPoint(cva, ba.cvCount, tt));
      if (w > 0) g = (1 - w) * g + w * globalUv(rb, bezierPoint(cvb, bb.cvCount, tt));
    }
    s.srcUvG[base + k] = clamp01(g);
    s.srcUvB[base + k] = clamp01(glm::vec2(0.5f - side * (u0 + t * (uTip - u0)), b.rp));
    s.srcUvGr[base + k] = clamp01(glm::vec2(0.5f - 0.5f * side * t, (s0 + t * len) * sp.vgInv));
  }
  return slot;
}

}  // namespace pteryla::feather::meshing
