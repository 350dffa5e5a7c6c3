// Internals of the packer (pack.cpp and its pack_*.cpp parts): feather-local geometry, the per-pack
// context and scratch, and the output layout. Not installed; the public interface is pteryla/coat/pack.hpp.
#pragma once

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include <glm/geometric.hpp>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for_each.h>
#include <atomic>

#include "pteryla/coat/pack.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/bezier.hpp"
#include "arena.hpp"
#include "spatial.hpp"

namespace pteryla::coat {

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
  double maxRho = 0;  // largest patch radius
  // What they were built from (packing::samplesFitSkin): the skin's positions, faces and face normals,
  // the sample spacing and the grid cell.
  std::vector<glm::dvec3> skinPositions, skinFaceNormals;
  std::vector<std::array<uint32_t, 3>> skinFaces;
  double spacing = 0, cell = 0;
};
}  // namespace detail

namespace packing {

using feather::kPi;
using glm::dvec3;

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// ------------------------------------------------------------------ feather-local geometry

struct LocalKey {
  double rp = 0;
  uint8_t vane = 0;
  dvec3 root{0}, u{1, 0, 0}, w{0, 1, 0}, d{0, 0, 1}, left{0, 1, 0};
  double len = 0;
  double sExt = 0;      // extent along u (len * max cv.x)
  double rootDist = 0;  // |root|
  uint32_t cvOff = 0;
  uint16_t cvCount = 0;
};

struct LocalFeather {
  bool packable = false;
  bool unopened = false;
  double reach = 0;           // bound on |p| for every point in any packed state
  double yMin = 0, yMax = 0;  // lateral footprint (bound over packed states)
  double vaneHalf = 0;        // largest lateral reach of a barb from its root (unpacked)
  double shaftYMin = 0, shaftYMax = 0;
  double totalLength = 0;
  // Arrays live in the pack's per-thread arenas (detail::HugeArena).
  detail::ArenaArray<dvec3> shaft;  // polyline from the follicle to the tip, feather-local
  detail::ArenaArray<double> shaftRad;
  detail::ArenaArray<LocalKey> keys;  // left vane first, ascending rp within a vane; afterfeather keys last
  uint32_t leftKeys = 0;
  uint32_t mainKeys = 0;            // keys of the main feather (the packed ones); the rest are the afterfeather's
  detail::ArenaArray<dvec3> after;  // afterfeather shaft polyline (not packed, but handed to later feathers)
  detail::ArenaArray<double> afterRad;
  detail::ArenaArray<dvec3> cvs;  // key barb control vertices, barb-local unit frame
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

// A key barb's frame placed at the feather's elevation (feather-local coordinates).
struct PlacedKey {
  dvec3 root, u, w, d, left;
};

struct Scratch {
  std::vector<PlacedKey> placed;  // per main key barb of the feather being packed
  std::vector<FeatherCandidate> cand;
  std::vector<SkinCandidate> skinCand;
  std::vector<double> psiMin, shaftRadBin, yLo, yHi;
  std::vector<glm::dvec2> best;             // per shaft bin: direction of the largest angle so far
  std::vector<double> bh, bhRaw;            // barb fields, keys x bins
  std::vector<double> plane;                // per key: signed distance of the current candidate
  std::vector<double> keyRoot[3], keyW[3];  // per key: placed root and slicing-plane normal (arrays)
  std::vector<glm::dvec3> curve, tmp;       // barb samples and transformed control vertices
  std::vector<double> bern;                 // Bernstein weights: samples x cvs
  std::vector<double> bernT, cx, cz;        // the weights cvs x samples; curve x and z being summed
  size_t bernCvs = 0, bernSamples = 0;
  PackStats stats;
  std::vector<BarbField> fields;
};

struct Context {
  Context(const SkinMesh& s, const CoatFeathers& c, const PackOptions& o, const PackConstraints& k)
      : skin(s), coat(c), opt(o), constraints(k) {}
  const SkinMesh& skin;
  const CoatFeathers& coat;
  const PackOptions& opt;
  const PackConstraints& constraints;
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
  // Samples setup may take instead of building them, when they fit (coat::Packer's cache, a seed's).
  std::array<std::shared_ptr<const detail::PackSkinSamples>, 2> reusable;
  std::vector<double> fixed;
  std::vector<double> minElevation;  // per feather (PackConstraints; NaN = none); empty = none
  std::vector<double> shaftBand;     // per feather (PackConstraints; NaN = PackOptions::shaftBand); empty = none
};

inline dvec3 toFrame(const FeatherFrame& F, const dvec3& q) {
  const dvec3 r = q - F.origin;
  return {glm::dot(r, F.tangent), glm::dot(r, F.binormal), glm::dot(r, F.normal)};
}

// Rotation by elevation e in the follicle frame (t, b, n): local (x, y, z) -> (x c - z s, y, x s + z c).
// The placement of pteryla/core/frame.hpp written in follicle-frame coordinates (the packer's hot loops).
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

struct BarbFit {
  double mu = 0, alpha = 0;
  double stretch = 1;  // keepBarbArcLength: the flattened barb scaled about its root to its old arc length
  bool resolved = true;
};
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

// ---- pack_local.cpp: feather-local geometry
void buildLocal(const CoatFeathers& coat, uint32_t i, const PackOptions& o, detail::HugeArena& arena, LocalFeather& L);

// ---- pack_shaft.cpp: candidates and the shaft field (6.3.2)
void gatherCandidates(const Context& ctx, uint32_t i, Scratch& S, const Output& out);
double shaftElevation(const Context& ctx, uint32_t i, Scratch& S);

// ---- pack_barbs.cpp: barb fields and barb fitting (6.3.3)
double curveLength(const std::vector<dvec3>& c);
BarbFit fitBarb(const dvec3* cvs, size_t n, double len, double sExt, const double* bh, int nb, const PackOptions& o,
                Scratch& S);
void barbFields(const Context& ctx, uint32_t i, Scratch& S, const PlacedKey* pk, size_t nk);

// ---- pack_feather.cpp: one feather
std::vector<uint32_t> chunkOffsets(const std::vector<uint32_t>& groupOffset);
void closeChunks(Output& out, uint32_t i);
void packFeather(const Context& ctx, uint32_t i, Scratch& S, Output& out);

// ---- pack_setup.cpp: input checks, feather-local data, reach classes, dependencies, skin samples
double median(std::vector<double> v);
void checkInput(const CoatFeathers& c, const PackOptions& o, const PackConstraints& k);
void buildReachClasses(Context& ctx, const std::vector<double>& radius, double med);
void buildDependencies(Context& ctx, const std::vector<uint32_t>& items, const std::vector<double>& radius,
                       size_t grain);
// ctx.skinData: one of ctx.reusable when it fits the skin and the spacing, else built.
void buildSkinSamples(Context& ctx, double medReach);
// The samples were built from this skin's positions, faces and face normals (bit for bit).
bool samplesFitSkin(const detail::PackSkinSamples& sd, const SkinMesh& skin);
// `r` was packed against this skin with these options' use of it: with samples of this skin when the
// options pack against the skin, without samples when they do not.
bool packedOnSkin(const PackResult& r, const SkinMesh& skin, const PackOptions& o);
// PackOptions equal field for field, threads aside (the results are the same bits at any thread count).
bool sameKnobs(const PackOptions& a, const PackOptions& b);
// The styling constraints and the layer order (ctx.order, ctx.pos) of a pack.
void beginContext(Context& ctx, std::vector<uint32_t> order);
// Everything a full pack needs before its feathers: beginContext over the present feathers, feather-local
// data, clearances, reach classes, dependencies and skin samples.
void setup(Context& ctx);
std::vector<uint32_t> presentInLayerOrder(const CoatFeathers& coat);
std::vector<uint8_t> changedMask(const std::vector<uint32_t>& changed, size_t n);

// ---- pack_result.cpp: the result's layout and the end of a pack
uint32_t appendGroups(const LocalFeather& L, int barbSamples, uint32_t p, std::vector<uint32_t>& groupPoint);
std::array<uint32_t, 3> localKeyCount(const LocalFeather& L);
void copyKeys(const PackedKeyBarbs& from, PackedKeyBarbs& to, uint32_t i);
bool sameKeyLayout(const PackedKeyBarbs& a, const PackedKeyBarbs& b, uint32_t i);
// Where a feather's packed data comes from in a result being laid out.
enum class Source : uint8_t {
  None,   // not packed (absent): no points, groups or key barbs
  Local,  // packed now, from its feather-local data
  Kept,   // copied from an earlier result (its shape there)
};
// Sizes every array of `res` for ctx.order with each feather's shape from `source` (`kept` for Kept
// feathers, may be null without them). Points, spheres and key barbs are left to be written once.
void layoutResult(const Context& ctx, const std::vector<Source>& source, const PackResult* kept, PackResult& res);
// Copies feather i from `from` into `res` (laid out with the same shape for i) and closes its chunks.
void keepFeather(const PackResult& from, PackResult& res, Output& out, uint32_t i);
bool fieldBefore(const BarbField& a, const BarbField& b);
void finish(const Context& ctx, tbb::enumerable_thread_specific<Scratch>& scratch, PackResult& res,
            std::chrono::steady_clock::time_point t0);

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

// ---- pack.cpp, pack_deformed.cpp: the packs over a Context made by coat::Packer (packer.cpp), which
// sets its reusable samples; each checks its input and throws Error as the free function does.
PackResult packAll(Context& ctx);
PackResult repackFrom(Context& ctx, const PackResult& prev, const std::vector<uint32_t>& changed);
PackResult packOverBase(Context& ctx, const PackResult& base, const std::vector<uint32_t>& changed);
PackResult packDeformedFrom(Context& ctx, const SkinMesh& refSkin, const std::vector<FeatherFrame>& refFrames,
                            const PackResult& ref, double tolerance, DeformedPackStats* stats);

// ------------------------------------------------------------------ scheduling (pack.cpp, pack_deformed.cpp)

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

// What one pack's feathers share while they are packed: per-thread scratch and the output's views with the
// chunk spheres above the groups.
struct Run {
  explicit Run(PackResult& res)
      : chunkOffset(chunkOffsets(res.groupOffset)),
        chunkBounds(chunkOffset.back()),
        out{res.elevation,   res.packedKeys, res.barbsChanged, res.pointOffset, res.points, res.bounds,
            res.groupOffset, res.groupPoint, res.groupBounds,  chunkOffset,     chunkBounds} {}
  tbb::enumerable_thread_specific<Scratch> scratch;
  const std::vector<uint32_t> chunkOffset;
  ChunkBounds chunkBounds;
  Output out;

  void packOne(const Context& ctx, PackResult& res, uint32_t i) {
    packFeather(ctx, i, scratch.local(), out);
    res.recomputed[i] = 1;
  }
};

// Every feather in ctx.order is packed from its local data (pack and repack; absent ones have none).
inline std::vector<Source> localSources(const Context& ctx) {
  std::vector<Source> s(ctx.coat.size());
  for (size_t i = 0; i < s.size(); ++i) s[i] = ctx.local[i].packable ? Source::Local : Source::None;
  return s;
}

}  // namespace packing
}  // namespace pteryla::coat
