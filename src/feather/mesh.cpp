// Feather surface generation, Streit 2003: 5.3 (barb polylines connected per vane, boundary edges along
// splits, generalized-cylinder shaft, level of detail of Fig. 5.8), 7.1.1 (feather-global, barb and
// growth texture mappings), 7.1.2 (per-vertex alpha with the quadratic fall-off at barb tips, barb
// counts for lower detail) and 8.1 (texture coordinates fixed in the open pose while growing).
#include "pteryla/feather/mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pteryla/core/error.hpp"
#include "pteryla/core/frame.hpp"
#include "pteryla/feather/bezier.hpp"

namespace pteryla::feather {

namespace {

constexpr float kTwoPi = 6.28318530717958647692f;

// ---------------------------------------------------------------- output slice

struct Dst {
  glm::vec3 *pos, *nrm, *tan;
  glm::vec2 *uvG, *uvB, *uvGr;
  float *alpha, *sheath, *count;
  uint32_t* fid;
  uint32_t* idx;
  uint32_t vbase;  // absolute index of the feather's first vertex
  uint32_t ibase;  // absolute offset of the feather's first index
};

struct Xform {
  glm::mat3 m{1.0f}, nm{1.0f};
  glm::vec3 o{0.0f};
  bool raw = false;  // FeatherMeshInput::unplaced: pass local values through (placed later, same functions)
  explicit Xform(const FeatherPlacement& p, bool unplaced = false) : raw(unplaced) {
    const glm::dmat3 md(p.x, p.y, p.z);
    m = glm::mat3(md);
    o = glm::vec3(p.origin);
    const double det = glm::determinant(md);
    nm = std::abs(det) > 1e-300 ? glm::mat3(glm::transpose(glm::inverse(md))) : m;
  }
  glm::vec3 point(const glm::vec3& q) const { return raw ? q : place(q); }
  glm::vec3 place(const glm::vec3& q) const { return o + m * q; }
  static glm::vec3 unit(const glm::vec3& v, const glm::vec3& fallback) {
    const float l2 = glm::dot(v, v);
    return l2 > 1e-30f ? v / std::sqrt(l2) : fallback;
  }
  glm::vec3 normal(const glm::vec3& n) const { return raw ? n : placeNormal(n); }
  glm::vec3 tangent(const glm::vec3& t) const { return raw ? t : placeTangent(t); }
  glm::vec3 placeNormal(const glm::vec3& n) const { return unit(nm * n, n); }
  glm::vec3 placeTangent(const glm::vec3& t) const { return unit(m * t, t); }
};

glm::vec3 safeUnit(const glm::vec3& v, const glm::vec3& fallback) { return Xform::unit(v, fallback); }

// ---------------------------------------------------------------- shaft frames

struct Frame {
  glm::vec3 p{0.0f}, t{1, 0, 0}, l{0, 1, 0}, d{0, 0, 1};
  float s = 0;      // arc length from the follicle
  float width = 0;  // diameter
};

// Rotation-minimizing frames at every shaft polyline point (dorsal transported from the umbilicus).
struct ShaftFrames {
  std::vector<Frame> f;
  int rachisBegin = 0;
  void build(const ShaftCurve& sh) {
    const size_t n = sh.points.size();
    f.resize(n);
    rachisBegin = sh.calamusPoints;
    float s = 0;
    glm::vec3 d = sh.dorsal[0];
    for (size_t i = 0; i < n; ++i) {
      const glm::vec3 a = sh.points[i > 0 ? i - 1 : i], b = sh.points[i + 1 < n ? i + 1 : i];
      glm::vec3 t = safeUnit(b - a, i > 0 ? f[i - 1].t : glm::vec3(1, 0, 0));
      if (i > 0) s += glm::length(sh.points[i] - sh.points[i - 1]);
      d = safeUnit(d - glm::dot(d, t) * t, i > 0 ? f[i - 1].d : glm::vec3(0, 0, 1));
      Frame& fr = f[i];
      fr.p = sh.points[i];
      fr.t = t;
      fr.d = d;
      fr.l = glm::cross(d, t);
      fr.s = s;
      fr.width = sh.widths[i];
    }
  }
  float length() const { return f.empty() ? 0.0f : f.back().s; }
  // Frame at rachis position rp (< 0 on the calamus: -1 follicle .. 0 umbilicus), interpolated.
  Frame at(const ShaftCurve& sh, float rp) const {
    const size_t n = f.size();
    if (n == 0) return Frame{};
    if (n == 1) return f[0];
    const auto it = std::upper_bound(sh.rp.begin(), sh.rp.end(), rp);
    size_t hi = static_cast<size_t>(it - sh.rp.begin());
    if (hi == 0) return f[0];
    if (hi >= n) return f[n - 1];
    const size_t lo = hi - 1;
    const float span = sh.rp[hi] - sh.rp[lo];
    const float w = span > 0 ? (rp - sh.rp[lo]) / span : 0.0f;
    Frame r;
    r.p = (1 - w) * f[lo].p + w * f[hi].p;
    r.t = safeUnit((1 - w) * f[lo].t + w * f[hi].t, f[lo].t);
    r.d = safeUnit((1 - w) * f[lo].d + w * f[hi].d, f[lo].d);
    r.d = safeUnit(r.d - glm::dot(r.d, r.t) * r.t, f[lo].d);
    r.l = glm::cross(r.d, r.t);
    r.s = (1 - w) * f[lo].s + w * f[hi].s;
    r.width = (1 - w) * f[lo].width + w * f[hi].width;
    return r;
  }
};

// ---------------------------------------------------------------- texture space of the reference

struct RefBarb {
  Frame fr;          // rachis frame at the barb's rp
  float len = 0;     // chord from root to tip
  float u0 = 0;      // global |u - 0.5| of the root (rachis half width)
  float uTip = 0;    // global |u - 0.5| of the tip
};

struct UvSpace {
  float alongMin = 0, alongInv = 1, acrossInv = 1, vgInv = 1;
};

// Vane runs of one part: [begin, end) per vane (0 left, 1 right); empty when the vane has no barbs.
struct VaneRuns {
  uint32_t begin[2] = {0, 0}, end[2] = {0, 0};
};
VaneRuns vaneRuns(const FeatherCurves& c, size_t part) {
  VaneRuns r;
  const uint32_t b = c.barbBegin[part], e = c.barbEnd[part];
  uint32_t split = b;
  while (split < e && c.barbs[split].vane == 0) ++split;
  r.begin[0] = b;
  r.end[0] = split;
  r.begin[1] = split;
  r.end[1] = e;
  return r;
}

// ---------------------------------------------------------------- per-thread scratch

constexpr int kBelow = -2, kAbove = -3;  // Row::b markers for a vane of a single barb

struct Row {
  int a = 0, b = 0;         // sources (b < 0: kBelow / kAbove)
  float wa = 1, wb = 0;     // weights
  float count = 1;          // barbCount
  bool centre = false;
};

struct Scratch {
  LodOrder order;
  std::vector<ShaftFrames> frames, refFrames;
  std::vector<RefBarb> ref;            // per barb of the reference (valid where refDone)
  std::vector<uint8_t> refDone;
  std::vector<ShaftFrames>* geo = nullptr;  // frames of the curves being meshed (refFrames when same)
  std::vector<UvSpace> space;          // per part of the reference
  std::vector<uint32_t> kept;          // kept barbs of the current vane
  std::vector<int> keptSlot;           // source slot of each kept barb
  std::vector<float> keptCount;
  // Sources: evaluated barbs, (segments + 1) samples each.
  std::vector<glm::vec3> srcPos;
  std::vector<glm::vec2> srcUvG, srcUvB, srcUvGr;
  std::vector<float> srcRp;
  std::vector<Row> rows;
  std::vector<glm::vec3> rowPos;
  std::vector<int> shaftSel;
  std::vector<float> alphaC, alphaE;   // alpha per sample of centre / side rows
  std::vector<glm::vec2> ring;         // (cos, sin) per shaft side
};
Scratch& scratch() {
  static thread_local Scratch s;
  return s;
}

// ---------------------------------------------------------------- planning

struct Plan {
  const FeatherCurves* c = nullptr;
  const FeatherCurves* ref = nullptr;
  const LodOrder* order = nullptr;
  uint32_t keep = 0;
  int segs = 1;        // barb segments at this level
  int fullSegs = 1;
  double lod = 1;      // clamped level
  size_t parts = 0;
};

bool keptBarb(const Plan& pl, uint32_t i) { return pl.order->rank[i] < pl.keep; }

Plan makePlan(const FeatherMeshInput& in, const MeshOptions& opt, Scratch& s) {
  PTERYLA_CHECK(in.curves != nullptr, "FeatherMeshInput::curves is required");
  Plan pl;
  pl.c = in.curves;
  pl.ref = in.reference ? in.reference : in.curves;
  const FeatherCurves& c = *in.curves;
  PTERYLA_CHECK(c.barbBegin.size() == c.partCount() && c.barbEnd.size() == c.partCount(), "malformed FeatherCurves");
  if (in.order) {
    PTERYLA_CHECK(in.order->rank.size() == c.barbs.size(), "LodOrder was computed for different curves");
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
  for (int k = 0; k <= target; ++k) sel.push_back(rb + static_cast<int>(std::lround(static_cast<double>(k) * segs / target)));
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
  rb.uTip = b.cvCount ? std::clamp(std::abs(glm::dot(cv[b.cvCount - 1] - rb.fr.p, rb.fr.l)) * sp.acrossInv, rb.u0, 0.5f) : rb.u0;
  return rb;
}

// Reference barbs standing for barb i of the curves: same index when the vane layouts match, else the
// two reference barbs bracketing its rp.
struct RefLink {
  uint32_t a = 0, b = 0;
  float w = 0;
  size_t part = 0;
  bool valid = false;
};

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
    if (pl.ref->barbs[mid].rp <= rp) lo = mid + 1; else hi = mid;
  }
  if (lo == rb) { L.a = L.b = rb; return L; }
  if (lo == re) { L.a = L.b = re - 1; return L; }
  L.a = lo - 1;
  L.b = lo;
  const float ra = pl.ref->barbs[L.a].rp, rbp = pl.ref->barbs[L.b].rp;
  L.w = rbp > ra ? (rp - ra) / (rbp - ra) : 0.0f;
  return L;
}

glm::vec2 clamp01(glm::vec2 v) { return glm::clamp(v, glm::vec2(0.0f), glm::vec2(1.0f)); }

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

// ---------------------------------------------------------------- writers

float alphaAt(float t, float start, float tip) {
  if (t <= start) return 1.0f;
  const float x = (t - start) / (1.0f - start);
  return 1.0f - (1.0f - tip) * x * x;
}

struct Cursor {
  uint32_t v = 0;  // local vertex count written
  uint32_t i = 0;  // local index count written
};

void writeVane(const Plan& pl, const MeshOptions& opt, const FeatherMeshInput& in, const Xform& xf, Scratch& s,
               size_t part, int vane, const VaneRuns& runs, const VaneRuns& refRuns, Dst& d, Cursor& cur) {
  const FeatherCurves& c = *pl.c;
  const uint32_t vb = runs.begin[vane], ve = runs.end[vane];
  s.kept.clear();
  for (uint32_t i = vb; i < ve; ++i)
    if (keptBarb(pl, i)) s.kept.push_back(i);
  const size_t K = s.kept.size();
  if (K == 0) return;
  const float side = vane == 0 ? 1.0f : -1.0f;
  const size_t n = static_cast<size_t>(pl.segs + 1);

  s.srcPos.clear();
  s.srcUvG.clear();
  s.srcUvB.clear();
  s.srcUvGr.clear();
  s.srcRp.clear();
  s.keptSlot.resize(K);
  s.keptCount.resize(K);
  for (size_t q = 0; q < K; ++q)
    s.keptSlot[q] = addSource(pl, s, s.kept[q], refLink(pl, part, vane, runs, refRuns, s.kept[q]), side);

  auto splitBetween = [&](size_t q) { return c.barbs[s.kept[q]].splitAfter; };  // between kept q and q+1
  for (size_t q = 0; q < K; ++q) {
    const uint32_t j = s.kept[q];
    const float dPrev = (q > 0 && !splitBetween(q - 1)) ? static_cast<float>(j - s.kept[q - 1]) : 1.0f;
    const float dNext = (q + 1 < K && !splitBetween(q)) ? static_cast<float>(s.kept[q + 1] - j) : 1.0f;
    s.keptCount[q] = 0.5f * (dPrev + dNext);
  }

  // Source of original barb j (kept neighbour reused, others evaluated).
  auto sourceOf = [&](uint32_t j, size_t nearQ) -> int {
    for (size_t q = nearQ > 0 ? nearQ - 1 : 0; q < std::min(K, nearQ + 2); ++q)
      if (s.kept[q] == j) return s.keptSlot[q];
    return addSource(pl, s, j, refLink(pl, part, vane, runs, refRuns, j), side);
  };
  // Boundary row of kept barb q on side dir (-1 toward the base, +1 toward the tip).
  auto boundaryRow = [&](size_t q, int dir) {
    const uint32_t j = s.kept[q];
    Row r;
    r.count = s.keptCount[q];
    r.a = s.keptSlot[q];
    const bool hasOpp = dir < 0 ? j + 1 < ve : j > vb;
    const bool hasSame = dir < 0 ? j > vb : j + 1 < ve;
    if (hasOpp) {  // mirror the half gap to the neighbour on the other side
      r.b = sourceOf(dir < 0 ? j + 1 : j - 1, q);
      r.wa = 1.5f;
      r.wb = -0.5f;
    } else if (hasSame) {  // isolated barb: a quarter of the way to the neighbour across the split
      r.b = sourceOf(dir < 0 ? j - 1 : j + 1, q);
      r.wa = 0.75f;
      r.wb = 0.25f;
    } else {
      r.b = dir < 0 ? kBelow : kAbove;  // single barb: offset along the shaft (resolved below)
      r.wa = 1.0f;
      r.wb = 0.0f;
    }
    return r;
  };

  s.rows.clear();
  for (size_t q = 0; q < K; ++q) {
    if (q == 0) s.rows.push_back(boundaryRow(q, -1));
    else if (splitBetween(q - 1)) s.rows.push_back(boundaryRow(q, -1));
    Row cr;
    cr.a = cr.b = s.keptSlot[q];
    cr.wa = 1;
    cr.wb = 0;
    cr.count = s.keptCount[q];
    cr.centre = true;
    s.rows.push_back(cr);
    if (q + 1 == K || splitBetween(q)) {
      s.rows.push_back(boundaryRow(q, +1));
    } else {
      Row mr;
      mr.a = s.keptSlot[q];
      mr.b = s.keptSlot[q + 1];
      mr.wa = mr.wb = 0.5f;
      mr.count = 0.5f * (s.keptCount[q] + s.keptCount[q + 1]);
      s.rows.push_back(mr);
    }
  }
  const size_t R = s.rows.size();

  // Row positions (feather-local) for the normals.
  s.rowPos.resize(R * n);
  for (size_t r = 0; r < R; ++r) {
    const Row& row = s.rows[r];
    const glm::vec3* A = s.srcPos.data() + static_cast<size_t>(row.a) * n;
    if (row.b < 0) {  // single-barb vane: offset by a small fraction of the barb along the shaft
      const float dir = row.b == kBelow ? -1.0f : 1.0f;
      const glm::vec3 chord = A[n - 1] - A[0];
      const float off = 0.05f * glm::length(chord) + 1e-7f;
      const Frame fr = (*s.geo)[part].at(c.shafts[part], c.barbs[s.kept[0]].rp);
      for (size_t k = 0; k < n; ++k) s.rowPos[r * n + k] = A[k] + (dir * off) * fr.t;
      continue;
    }
    const glm::vec3* B = s.srcPos.data() + static_cast<size_t>(row.b) * n;
    for (size_t k = 0; k < n; ++k) s.rowPos[r * n + k] = row.wa * A[k] + row.wb * B[k];
  }

  const float startC = std::max(0.0f, 1.0f - 1.0f / pl.fullSegs);
  const float startE = std::max(0.0f, 1.0f - 2.0f / pl.fullSegs);
  const float tipAlpha = static_cast<float>(opt.alphaTip);
  s.alphaC.resize(n);
  s.alphaE.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const float t = static_cast<float>(static_cast<double>(k) / pl.segs);
    s.alphaC[k] = alphaAt(t, startC, tipAlpha);
    s.alphaE[k] = alphaAt(t, startE, tipAlpha);
  }
  const bool sheathed = in.sheathShed < 1.0;
  const float orient = vane == 0 ? -1.0f : 1.0f;  // cross(along, across) points ventral on the left vane
  const uint32_t v0 = cur.v;
  for (size_t r = 0; r < R; ++r) {
    const Row& row = s.rows[r];
    const size_t sa = static_cast<size_t>(row.a) * n;
    const size_t sb = row.b >= 0 ? static_cast<size_t>(row.b) * n : sa;
    const float wb = row.b >= 0 ? row.wb : 0.0f, wa = row.b >= 0 ? row.wa : 1.0f;
    const float rp = std::clamp(wa * s.srcRp[static_cast<size_t>(row.a)] + wb * s.srcRp[static_cast<size_t>(row.b >= 0 ? row.b : row.a)], 0.0f, 1.0f);
    const glm::vec3* P = s.rowPos.data() + r * n;
    const glm::vec3* Pp = s.rowPos.data() + (r > 0 ? r - 1 : r) * n;
    const glm::vec3* Pn = s.rowPos.data() + (r + 1 < R ? r + 1 : r) * n;
    // Rachis frame: only for degenerate normals / tangents (closed pin barbs, zero-length barbs).
    Frame fr;
    bool haveFrame = false;
    auto frame = [&]() -> const Frame& {
      if (!haveFrame) fr = (*s.geo)[part].at(c.shafts[part], rp);
      haveFrame = true;
      return fr;
    };
    const float* alphaRow = (row.centre ? s.alphaC : s.alphaE).data();
    for (size_t k = 0; k < n; ++k) {
      const size_t o = v0 + r * n + k;
      const glm::vec3 along = P[k + 1 < n ? k + 1 : k] - P[k > 0 ? k - 1 : k];
      const glm::vec3 across = Pn[k] - Pp[k];
      const glm::vec3 nrm = orient * glm::cross(along, across);
      const float l2 = glm::dot(nrm, nrm);
      const float along2 = glm::dot(along, along);
      const bool okN = l2 > 1e-10f * along2 * glm::dot(across, across) && l2 > 1e-36f;
      d.pos[o] = xf.point(P[k]);
      d.nrm[o] = xf.normal(okN ? nrm : frame().d);
      d.tan[o] = xf.tangent(along2 > 1e-36f ? along : frame().t);
      const glm::vec2 g = clamp01(wa * s.srcUvG[sa + k] + wb * s.srcUvG[sb + k]);
      const glm::vec2 bu = clamp01(glm::vec2(wa * s.srcUvB[sa + k].x + wb * s.srcUvB[sb + k].x, rp));
      const glm::vec2 gr = clamp01(wa * s.srcUvGr[sa + k] + wb * s.srcUvGr[sb + k]);
      d.uvG[o] = g;
      d.uvB[o] = bu;
      d.uvGr[o] = gr;
      d.alpha[o] = alphaRow[k];
      d.sheath[o] = sheathed ? static_cast<float>(sheathWeight(gr.y, in.sheathShed, in.sheathBand)) : 0.0f;
      d.count[o] = row.count;
      d.fid[o] = in.featherId;
    }
  }

  // Two strips per kept barb: (centre - 1, centre) and (centre, centre + 1), rachis to tip.
  uint32_t* idx = d.idx + cur.i;
  const uint32_t base = d.vbase + v0;
  size_t r = 0;
  for (size_t q = 0; q < K; ++q) {
    while (!s.rows[r].centre) ++r;
    for (size_t strip = 0; strip < 2; ++strip) {
      const uint32_t lo = base + static_cast<uint32_t>((r - 1 + strip) * n);
      const uint32_t hi = lo + static_cast<uint32_t>(n);
      for (uint32_t k = 0; k + 1 < n; ++k) {
        const uint32_t a = lo + k, b = lo + k + 1, e = hi + k, f = hi + k + 1;
        if (vane == 0) {  // (a, e, b), (b, e, f): faces point dorsal
          *idx++ = a; *idx++ = e; *idx++ = b;
          *idx++ = b; *idx++ = e; *idx++ = f;
        } else {
          *idx++ = a; *idx++ = b; *idx++ = e;
          *idx++ = b; *idx++ = f; *idx++ = e;
        }
      }
    }
    ++r;
  }
  cur.v += static_cast<uint32_t>(R * n);
  cur.i = static_cast<uint32_t>(idx - d.idx);
}

void writeShaft(const Plan& pl, const MeshOptions& opt, const FeatherMeshInput& in, const Xform& xf, Scratch& s,
                size_t part, Dst& d, Cursor& cur) {
  const ShaftCurve& sh = pl.c->shafts[part];
  shaftSelection(sh, pl, opt, s.shaftSel);
  if (s.shaftSel.size() < 2) return;
  const ShaftFrames& sf = (*s.geo)[part];
  const bool hasRef = part < pl.ref->partCount();
  const ShaftCurve& rsh = hasRef ? pl.ref->shafts[part] : sh;
  const ShaftFrames& rsf = hasRef ? s.refFrames[part] : sf;
  const UvSpace sp = hasRef ? s.space[part] : UvSpace{};
  const int sides = opt.shaftSides;
  const size_t rings = s.shaftSel.size() - 1;
  const bool sheathed = in.sheathShed < 1.0;
  const uint32_t v0 = cur.v;
  uint32_t o = v0;
  if (s.ring.size() != static_cast<size_t>(sides + 1)) {
    s.ring.resize(static_cast<size_t>(sides + 1));
    for (int j = 0; j <= sides; ++j) {
      const double th = -kPi + 2 * kPi * j / sides;
      s.ring[static_cast<size_t>(j)] = glm::vec2(static_cast<float>(std::cos(th)), static_cast<float>(std::sin(th)));
    }
  }
  // Reference arc length and half width at rachis position rp (calamus: rp in [-1, 0)).
  auto refAt = [&](float rp, float& sRef, float& halfW) {
    const Frame f = rsf.at(rsh, rp);
    sRef = f.s;
    halfW = 0.5f * f.width;
  };
  for (size_t ri = 0; ri < rings; ++ri) {
    const int pi = s.shaftSel[ri];
    const Frame& f = sf.f[static_cast<size_t>(pi)];
    const float rad = 0.5f * f.width;
    const float rp = sh.rp[static_cast<size_t>(pi)];
    float sRef, halfW;
    refAt(rp, sRef, halfW);
    const float vG = std::clamp((sRef - sp.alongMin) * sp.alongInv, 0.0f, 1.0f);
    const float vGr = std::clamp(sRef * sp.vgInv, 0.0f, 1.0f);
    const float sheath = sheathed ? static_cast<float>(sheathWeight(vGr, in.sheathShed, in.sheathBand)) : 0.0f;
    for (int j = 0; j <= sides; ++j, ++o) {
      const float th = -0.5f * kTwoPi + kTwoPi * static_cast<float>(j) / static_cast<float>(sides);
      const float cs = s.ring[static_cast<size_t>(j)].x, sn = s.ring[static_cast<size_t>(j)].y;
      const glm::vec3 dir = cs * f.d + sn * f.l;
      d.pos[o] = xf.point(f.p + rad * dir);
      d.nrm[o] = xf.normal(dir);
      d.tan[o] = xf.tangent(f.t);
      const float uG = std::clamp(0.5f - halfW * sn * sp.acrossInv, 0.0f, 1.0f);
      d.uvG[o] = glm::vec2(uG, vG);
      d.uvB[o] = glm::vec2(uG, std::clamp(rp, 0.0f, 1.0f));
      d.uvGr[o] = glm::vec2(std::clamp(0.5f - th / kTwoPi, 0.0f, 1.0f), vGr);
      d.alpha[o] = 1.0f;
      d.sheath[o] = sheath;
      d.count[o] = 1.0f;
      d.fid[o] = in.featherId;
    }
  }
  {  // apex: one vertex per side so every side keeps its own u
    const int pi = s.shaftSel.back();
    const Frame& f = sf.f[static_cast<size_t>(pi)];
    float sRef, halfW;
    refAt(sh.rp[static_cast<size_t>(pi)], sRef, halfW);
    const float vG = std::clamp((sRef - sp.alongMin) * sp.alongInv, 0.0f, 1.0f);
    const float vGr = std::clamp(sRef * sp.vgInv, 0.0f, 1.0f);
    const float sheath = sheathed ? static_cast<float>(sheathWeight(vGr, in.sheathShed, in.sheathBand)) : 0.0f;
    for (int j = 0; j < sides; ++j, ++o) {
      const float th = -0.5f * kTwoPi + kTwoPi * (static_cast<float>(j) + 0.5f) / static_cast<float>(sides);
      d.pos[o] = xf.point(f.p);
      d.nrm[o] = xf.normal(f.t);
      d.tan[o] = xf.tangent(f.t);
      d.uvG[o] = glm::vec2(0.5f, vG);
      d.uvB[o] = glm::vec2(0.5f, 1.0f);
      d.uvGr[o] = glm::vec2(std::clamp(0.5f - th / kTwoPi, 0.0f, 1.0f), vGr);
      d.alpha[o] = 1.0f;
      d.sheath[o] = sheath;
      d.count[o] = 1.0f;
      d.fid[o] = in.featherId;
    }
  }
  uint32_t* idx = d.idx + cur.i;
  const uint32_t base = d.vbase + v0;
  const uint32_t ringN = static_cast<uint32_t>(sides + 1);
  for (size_t ri = 0; ri + 1 < rings; ++ri) {
    const uint32_t a0 = base + static_cast<uint32_t>(ri) * ringN, b0 = a0 + ringN;
    for (uint32_t j = 0; j < static_cast<uint32_t>(sides); ++j) {
      *idx++ = a0 + j; *idx++ = b0 + j; *idx++ = a0 + j + 1;
      *idx++ = a0 + j + 1; *idx++ = b0 + j; *idx++ = b0 + j + 1;
    }
  }
  const uint32_t last = base + static_cast<uint32_t>(rings - 1) * ringN;
  const uint32_t apex = base + static_cast<uint32_t>(rings) * ringN;
  for (uint32_t j = 0; j < static_cast<uint32_t>(sides); ++j) {
    *idx++ = last + j; *idx++ = apex + j; *idx++ = last + j + 1;
  }
  cur.v = o;
  cur.i = static_cast<uint32_t>(idx - d.idx);
}

void writeFeather(const FeatherMeshInput& in, const MeshOptions& opt, Dst& d, FeatherMeshRanges* ranges) {
  Scratch& s = scratch();
  const Plan pl = makePlan(in, opt, s);
  const Xform xf(in.placement, in.unplaced);
  buildReference(pl, s);
  if (pl.ref == pl.c) {
    s.geo = &s.refFrames;
  } else {
    s.frames.resize(pl.c->partCount());
    for (size_t part = 0; part < pl.parts; ++part) s.frames[part].build(pl.c->shafts[part]);
    s.geo = &s.frames;
  }
  Cursor cur;
  FeatherMeshRanges rg;
  auto mark = [&](uint32_t& first) { first = d.ibase + cur.i; };
  for (size_t part = 0; part < pl.parts; ++part) {
    const VaneRuns runs = vaneRuns(*pl.c, part);
    const VaneRuns refRuns = part < pl.ref->partCount() ? vaneRuns(*pl.ref, part) : VaneRuns{};
    const uint32_t partStart = cur.i;
    if (part == 1) mark(rg.afterFirst);
    if (part == 0) mark(rg.shaftFirst);
    if (opt.shaft) writeShaft(pl, opt, in, xf, s, part, d, cur);
    if (part == 0) { rg.shaftCount = cur.i - partStart; mark(rg.leftFirst); }
    const uint32_t leftStart = cur.i;
    writeVane(pl, opt, in, xf, s, part, 0, runs, refRuns, d, cur);
    if (part == 0) { rg.leftCount = cur.i - leftStart; mark(rg.rightFirst); }
    const uint32_t rightStart = cur.i;
    writeVane(pl, opt, in, xf, s, part, 1, runs, refRuns, d, cur);
    if (part == 0) rg.rightCount = cur.i - rightStart;
    if (part == 1) rg.afterCount = cur.i - partStart;
  }
  if (ranges) *ranges = rg;
}

template <class T>
void padTo(std::vector<T>& v, size_t n, const T& def) {
  if (v.size() < n) v.resize(n, def);
}

// Grows every attribute of `out` by `verts` (existing arrays padded first) and indices by `indices`.
Dst reserveSlice(TriMesh& out, size_t verts, size_t indices) {
  const size_t n0 = out.positions.size();
  const size_t n1 = n0 + verts;
  PTERYLA_CHECK(n1 <= std::numeric_limits<uint32_t>::max(), "mesh exceeds 32-bit vertex indices");
  padTo(out.normals, n0, glm::vec3(0, 0, 1));
  padTo(out.tangents, n0, glm::vec3(1, 0, 0));
  padTo(out.uvGlobal, n0, glm::vec2(0));
  padTo(out.uvBarb, n0, glm::vec2(0));
  padTo(out.uvGrowth, n0, glm::vec2(0));
  padTo(out.alpha, n0, 1.0f);
  padTo(out.sheath, n0, 0.0f);
  padTo(out.barbCount, n0, 1.0f);
  padTo(out.featherId, n0, 0u);
  out.positions.resize(n1);
  out.normals.resize(n1);
  out.tangents.resize(n1);
  out.uvGlobal.resize(n1);
  out.uvBarb.resize(n1);
  out.uvGrowth.resize(n1);
  out.alpha.resize(n1);
  out.sheath.resize(n1);
  out.barbCount.resize(n1);
  out.featherId.resize(n1);
  const size_t i0 = out.indices.size();
  out.indices.resize(i0 + indices);
  Dst d{};
  d.vbase = static_cast<uint32_t>(n0);
  d.ibase = static_cast<uint32_t>(i0);
  return d;
}

Dst sliceAt(TriMesh& out, size_t v, size_t i) {
  Dst d{};
  d.pos = out.positions.data() + v;
  d.nrm = out.normals.data() + v;
  d.tan = out.tangents.data() + v;
  d.uvG = out.uvGlobal.data() + v;
  d.uvB = out.uvBarb.data() + v;
  d.uvGr = out.uvGrowth.data() + v;
  d.alpha = out.alpha.data() + v;
  d.sheath = out.sheath.data() + v;
  d.count = out.barbCount.data() + v;
  d.fid = out.featherId.data() + v;
  d.idx = out.indices.data() + i;
  d.vbase = static_cast<uint32_t>(v);
  d.ibase = static_cast<uint32_t>(i);
  return d;
}

}  // namespace

// ---------------------------------------------------------------- public API

void validateMeshOptions(const MeshOptions& o) {
  if (o.barbSegments < 1 || o.barbSegments > 64) throw Error("expected 1..64 segments per barb", "", "mesh.barb_segments");
  if (o.minBarbSegments < 1 || o.minBarbSegments > o.barbSegments)
    throw Error("expected 1 <= min_barb_segments <= barb_segments", "", "mesh.min_barb_segments");
  if (!std::isfinite(o.segmentLodStart) || o.segmentLodStart < 0 || o.segmentLodStart > 1)
    throw Error("expected a level in [0, 1]", "", "mesh.segment_lod_start");
  if (o.shaftSides < 3 || o.shaftSides > 64) throw Error("expected 3..64 shaft sides", "", "mesh.shaft_sides");
  if (o.minShaftSegments < 1 || o.minShaftSegments > 1024) throw Error("expected 1..1024 shaft segments", "", "mesh.min_shaft_segments");
  if (!std::isfinite(o.alphaTip) || o.alphaTip < 0 || o.alphaTip > 1) throw Error("expected alpha in [0, 1]", "", "mesh.alpha_tip");
}

FeatherPlacement FeatherPlacement::fromFollicle(const glm::dvec3& origin, const glm::dvec3& T, const glm::dvec3& N,
                                                double elevation, double scale) {
  FeatherPlacement p;
  const ElevatedAxes<glm::dvec3> a = elevatedAxes(T, glm::cross(N, T), N, elevation);
  p.origin = origin;
  p.x = scale * a.x;
  p.y = scale * a.y;
  p.z = scale * a.z;
  return p;
}

FeatherMeshSize featherMeshSize(const FeatherMeshInput& in, const MeshOptions& opt) {
  validateMeshOptions(opt);
  Scratch& s = scratch();
  const Plan pl = makePlan(in, opt, s);
  return planSize(pl, opt, s);
}

void appendFeatherMesh(const FeatherMeshInput& in, const MeshOptions& opt, TriMesh& out, FeatherMeshRanges* ranges) {
  const FeatherMeshSize sz = featherMeshSize(in, opt);
  const Dst d0 = reserveSlice(out, sz.vertices, sz.indices);
  Dst d = sliceAt(out, d0.vbase, d0.ibase);
  writeFeather(in, opt, d, ranges);
}

void appendFeatherMesh(const FeatherCurves& curves, const MeshOptions& opt, const FeatherPlacement& placement,
                       uint32_t featherId, TriMesh& out, FeatherMeshRanges* ranges) {
  FeatherMeshInput in;
  in.curves = &curves;
  in.placement = placement;
  in.featherId = featherId;
  appendFeatherMesh(in, opt, out, ranges);
}

void appendFeatherMeshes(const FeatherMeshInput* inputs, size_t count, const MeshOptions& opt, TriMesh& out,
                         std::vector<FeatherMeshRanges>* ranges) {
  validateMeshOptions(opt);
  std::vector<FeatherMeshSize> sizes(count);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count), [&](const tbb::blocked_range<size_t>& r) {
    Scratch& s = scratch();
    for (size_t i = r.begin(); i != r.end(); ++i) sizes[i] = planSize(makePlan(inputs[i], opt, s), opt, s);
  });
  std::vector<size_t> vOff(count + 1, 0), iOff(count + 1, 0);
  for (size_t i = 0; i < count; ++i) {
    vOff[i + 1] = vOff[i] + sizes[i].vertices;
    iOff[i + 1] = iOff[i] + sizes[i].indices;
  }
  const Dst d0 = reserveSlice(out, vOff[count], iOff[count]);
  if (ranges) ranges->assign(count, FeatherMeshRanges{});
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      Dst d = sliceAt(out, d0.vbase + vOff[i], d0.ibase + iOff[i]);
      writeFeather(inputs[i], opt, d, ranges ? &(*ranges)[i] : nullptr);
    }
  });
}

void placeFeatherVertices(const FeatherPlacement& placement, const glm::vec3* positions, const glm::vec3* normals,
                          const glm::vec3* tangents, size_t count, glm::vec3* outPositions, glm::vec3* outNormals,
                          glm::vec3* outTangents) {
  const Xform xf(placement);
  for (size_t k = 0; k < count; ++k) {
    outPositions[k] = xf.place(positions[k]);
    outNormals[k] = xf.placeNormal(normals[k]);
    outTangents[k] = xf.placeTangent(tangents[k]);
  }
}

TriMesh buildFeatherMesh(const FeatherParams& p, double age, double lod, const MeshOptions& opt,
                         const GrowthSchedule& schedule, FeatherMeshRanges* ranges) {
  if (!std::isfinite(lod) || lod <= 0 || lod > 1) throw Error("level of detail must be in (0, 1]", p.sourceFile, "lod");
  if (!std::isfinite(age) || age < 0) throw Error("feather age must be a finite number >= 0", p.sourceFile, "age");
  validateMeshOptions(opt);
  const FeatherCurves mature = generateBarbs(p);
  const GrowthState st = growthStateAt(age, schedule);
  FeatherCurves grown;
  const bool isMature = st.mature(schedule);
  if (!isMature) generateBarbs(featherAtState(p, st, schedule), grown);
  const FeatherCurves& curves = isMature ? mature : grown;
  // While growing, the barb layout (count, splits) is the mature one: collapse in the mature order so
  // the kept barbs do not change as the pin key barbs migrate. Worn feathers have new splits.
  const bool reuse = st.grown() || grown.barbs.size() != mature.barbs.size() ? false : true;
  const LodOrder order = computeLodOrder(reuse ? mature : curves);
  FeatherMeshInput in;
  in.curves = &curves;
  in.reference = &mature;
  in.order = &order;
  in.lod = lod;
  in.sheathShed = st[GrowthParam::Sheath];
  in.sheathBand = schedule.sheathBand;
  TriMesh mesh;
  appendFeatherMesh(in, opt, mesh, ranges);
  return mesh;
}

}  // namespace pteryla::feather
