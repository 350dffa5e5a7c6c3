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
#include "mesh_internal.hpp"

namespace pteryla::feather {

namespace meshing {

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
    if (q == 0)
      s.rows.push_back(boundaryRow(q, -1));
    else if (splitBetween(q - 1))
      s.rows.push_back(boundaryRow(q, -1));
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
    const float rp = std::clamp(
        wa * s.srcRp[static_cast<size_t>(row.a)] + wb * s.srcRp[static_cast<size_t>(row.b >= 0 ? row.b : row.a)], 0.0f,
        1.0f);
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
          *idx++ = a;
          *idx++ = e;
          *idx++ = b;
          *idx++ = b;
          *idx++ = e;
          *idx++ = f;
        } else {
          *idx++ = a;
          *idx++ = b;
          *idx++ = e;
          *idx++ = b;
          *idx++ = f;
          *idx++ = e;
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
      *idx++ = a0 + j;
      *idx++ = b0 + j;
      *idx++ = a0 + j + 1;
      *idx++ = a0 + j + 1;
      *idx++ = b0 + j;
      *idx++ = b0 + j + 1;
    }
  }
  const uint32_t last = base + static_cast<uint32_t>(rings - 1) * ringN;
  const uint32_t apex = base + static_cast<uint32_t>(rings) * ringN;
  for (uint32_t j = 0; j < static_cast<uint32_t>(sides); ++j) {
    *idx++ = last + j;
    *idx++ = apex + j;
    *idx++ = last + j + 1;
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
    if (part == 0) {
      rg.shaftCount = cur.i - partStart;
      mark(rg.leftFirst);
    }
    const uint32_t leftStart = cur.i;
    writeVane(pl, opt, in, xf, s, part, 0, runs, refRuns, d, cur);
    if (part == 0) {
      rg.leftCount = cur.i - leftStart;
      mark(rg.rightFirst);
    }
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
  PTERYLA_CHECK_LE(n1, std::numeric_limits<uint32_t>::max(), "mesh exceeds 32-bit vertex indices");
  padTo(out.normals, n0, PackedDir(glm::vec3(0, 0, 1)));
  padTo(out.tangents, n0, PackedDir(glm::vec3(1, 0, 0)));
  padTo(out.uvGlobal, n0, glm::vec2(0));
  padTo(out.uvBarb, n0, glm::vec2(0));
  padTo(out.uvGrowth, n0, glm::vec2(0));
  padTo(out.alpha, n0, Half(1.0f));
  padTo(out.sheath, n0, Half(0.0f));
  padTo(out.barbCount, n0, Half(1.0f));
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

}  // namespace meshing

using namespace meshing;

// ---------------------------------------------------------------- public API

void validateMeshOptions(const MeshOptions& o) {
  if (o.barbSegments < 1 || o.barbSegments > 64)
    throw Error("expected 1..64 segments per barb", "", "mesh.barb_segments");
  if (o.minBarbSegments < 1 || o.minBarbSegments > o.barbSegments)
    throw Error("expected 1 <= min_barb_segments <= barb_segments", "", "mesh.min_barb_segments");
  if (!std::isfinite(o.segmentLodStart) || o.segmentLodStart < 0 || o.segmentLodStart > 1)
    throw Error("expected a level in [0, 1]", "", "mesh.segment_lod_start");
  if (o.shaftSides < 3 || o.shaftSides > 64) throw Error("expected 3..64 shaft sides", "", "mesh.shaft_sides");
  if (o.minShaftSegments < 1 || o.minShaftSegments > 1024)
    throw Error("expected 1..1024 shaft segments", "", "mesh.min_shaft_segments");
  if (!std::isfinite(o.alphaTip) || o.alphaTip < 0 || o.alphaTip > 1)
    throw Error("expected alpha in [0, 1]", "", "mesh.alpha_tip");
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

FeatherMeshLevel featherMeshLevel(const FeatherMeshInput& in, const MeshOptions& opt) {
  validateMeshOptions(opt);
  Scratch& s = scratch();
  const Plan pl = makePlan(in, opt, s);
  FeatherMeshLevel l;
  l.keep = pl.keep;
  l.segs = pl.segs;
  for (size_t part = 0; part < pl.parts; ++part) {
    if (opt.shaft) {
      shaftSelection(pl.c->shafts[part], pl, opt, s.shaftSel);
      l.shaft.insert(l.shaft.end(), s.shaftSel.begin(), s.shaftSel.end());
    }
    l.shaft.push_back(-1);
  }
  return l;
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

void placeFeatherVertices(const FeatherPlacement& placement, const glm::vec3* positions, const PackedDir* normals,
                          const PackedDir* tangents, size_t count, glm::vec3* outPositions, PackedDir* outNormals,
                          PackedDir* outTangents) {
  const Xform xf(placement);
  for (size_t k = 0; k < count; ++k) {
    outPositions[k] = xf.place(positions[k]);
    outNormals[k] = xf.placeNormal(normals[k].get());
    outTangents[k] = xf.placeTangent(tangents[k].get());
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
