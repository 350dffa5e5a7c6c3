// Internals of the feather mesher (mesh.cpp and mesh_plan.cpp): output slices, shaft frames, the
// reference texture space, per-thread scratch and the plan of one feather's mesh. Not installed.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include "pteryla/feather/mesh.hpp"

namespace pteryla::feather::meshing {

constexpr float kTwoPi = 6.28318530717958647692f;

// ---------------------------------------------------------------- output slice

struct Dst {
  glm::vec3* pos;
  PackedDir *nrm, *tan;
  glm::vec2 *uvG, *uvB, *uvGr;
  Half *alpha, *sheath, *count;
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
  // A local normal or tangent is made unit and rounded to the 16 bits a mesh stores (core/packed.hpp):
  // unplaced, that is what is written; placed meshing places the rounded vector, as placeFeatherVertices
  // does with an unplaced mesh, so both give the same bits.
  PackedDir normal(const glm::vec3& n) const {
    const PackedDir local(unit(n, n));
    return raw ? local : PackedDir(placeNormal(local.get()));
  }
  PackedDir tangent(const glm::vec3& t) const {
    const PackedDir local(unit(t, t));
    return raw ? local : PackedDir(placeTangent(local.get()));
  }
  glm::vec3 placeNormal(const glm::vec3& n) const { return unit(nm * n, n); }
  glm::vec3 placeTangent(const glm::vec3& t) const { return unit(m * t, t); }
};

inline glm::vec3 safeUnit(const glm::vec3& v, const glm::vec3& fallback) { return Xform::unit(v, fallback); }

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
  Frame fr;        // rachis frame at the barb's rp
  float len = 0;   // chord from root to tip
  float u0 = 0;    // global |u - 0.5| of the root (rachis half width)
  float uTip = 0;  // global |u - 0.5| of the tip
};

struct UvSpace {
  float alongMin = 0, alongInv = 1, acrossInv = 1, vgInv = 1;
};

// Vane runs of one part: [begin, end) per vane (0 left, 1 right); empty when the vane has no barbs.
struct VaneRuns {
  uint32_t begin[2] = {0, 0}, end[2] = {0, 0};
};
inline VaneRuns vaneRuns(const FeatherCurves& c, size_t part) {
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
  int a = 0, b = 0;      // sources (b < 0: kBelow / kAbove)
  float wa = 1, wb = 0;  // weights
  float count = 1;       // barbCount
  bool centre = false;
};

struct Scratch {
  LodOrder order;
  std::vector<ShaftFrames> frames, refFrames;
  std::vector<RefBarb> ref;  // per barb of the reference (valid where refDone)
  std::vector<uint8_t> refDone;
  std::vector<ShaftFrames>* geo = nullptr;  // frames of the curves being meshed (refFrames when same)
  std::vector<UvSpace> space;               // per part of the reference
  std::vector<uint32_t> kept;               // kept barbs of the current vane
  std::vector<int> keptSlot;                // source slot of each kept barb
  std::vector<float> keptCount;
  // Sources: evaluated barbs, (segments + 1) samples each.
  std::vector<glm::vec3> srcPos;
  std::vector<glm::vec2> srcUvG, srcUvB, srcUvGr;
  std::vector<float> srcRp;
  std::vector<Row> rows;
  std::vector<glm::vec3> rowPos;
  std::vector<int> shaftSel;
  std::vector<float> alphaC, alphaE;  // alpha per sample of centre / side rows
  std::vector<glm::vec2> ring;        // (cos, sin) per shaft side
};
inline Scratch& scratch() {
  static thread_local Scratch s;
  return s;
}

// ---------------------------------------------------------------- planning

struct Plan {
  const FeatherCurves* c = nullptr;
  const FeatherCurves* ref = nullptr;
  const LodOrder* order = nullptr;
  uint32_t keep = 0;
  int segs = 1;  // barb segments at this level
  int fullSegs = 1;
  double lod = 1;  // clamped level
  size_t parts = 0;
};

inline bool keptBarb(const Plan& pl, uint32_t i) { return pl.order->rank[i] < pl.keep; }

// Reference barbs standing for barb i of the curves: same index when the vane layouts match, else the
// two reference barbs bracketing its rp.
struct RefLink {
  uint32_t a = 0, b = 0;
  float w = 0;
  size_t part = 0;
  bool valid = false;
};

inline glm::vec2 clamp01(glm::vec2 v) { return glm::clamp(v, glm::vec2(0.0f), glm::vec2(1.0f)); }

// ---- mesh_plan.cpp: planning, the reference texture space and evaluated barbs
Plan makePlan(const FeatherMeshInput& in, const MeshOptions& opt, Scratch& s);
void shaftSelection(const ShaftCurve& sh, const Plan& pl, const MeshOptions& opt, std::vector<int>& sel);
FeatherMeshSize planSize(const Plan& pl, const MeshOptions& opt, Scratch& s);
void buildReference(const Plan& pl, Scratch& s);
RefLink refLink(const Plan& pl, size_t part, int vane, const VaneRuns& runs, const VaneRuns& refRuns, uint32_t i);
// Evaluates barb i of the curves into a new source slot; texture coordinates from the reference.
int addSource(const Plan& pl, Scratch& s, uint32_t i, const RefLink& link, float side);

}  // namespace pteryla::feather::meshing
