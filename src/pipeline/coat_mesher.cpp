// The pipeline's mesh stage (coat_mesher.hpp): barb curves (Streit 2003, 5.2) generated from the packed
// feathers (6.3), tessellated per feather at its level of detail (7.1) and placed at its follicle.
#include "coat_mesher.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "pteryla/core/error.hpp"
#include "pteryla/core/trimesh_reuse.hpp"
#include "pteryla/feather/generator.hpp"
#include "pteryla/feather/instancing.hpp"

namespace pteryla::pipeline {

bool packedAsGrown(double age, const feather::GrowthSchedule& schedule, const feather::FeatherParams& p) {
  if (!(age < 1.0)) return false;
  if (p.generator != "streit") {
    const feather::FeatherGenerator* g = feather::findFeatherGenerator(p.generator);
    if (g && g->grow) return true;
  }
  return feather::growthStateAt(age, schedule)[feather::GrowthParam::ShaftLength] >= 1.0;
}

namespace {

void resizeAll(TriMesh& m, size_t verts, size_t indices) {
  m.positions.resize(verts);
  m.normals.resize(verts);
  m.tangents.resize(verts);
  m.uvGlobal.resize(verts);
  m.uvBarb.resize(verts);
  m.uvGrowth.resize(verts);
  m.alpha.resize(verts);
  m.sheath.resize(verts);
  m.barbCount.resize(verts);
  m.featherId.resize(verts);
  m.indices.resize(indices);
}

template <class T>
void copySlice(const std::vector<T>& from, size_t f0, std::vector<T>& to, size_t t0, size_t count) {
  if (count) std::memcpy(to.data() + t0, from.data() + f0, count * sizeof(T));
}

// Moves the part offsets of a feather's ranges from index position `from` to `to`. An afterfeather
// range that was never set (no afterfeather: afterFirst stays 0) stays 0.
feather::FeatherMeshRanges rebase(feather::FeatherMeshRanges r, uint32_t from, uint32_t to) {
  auto move = [&](uint32_t& first) { first = first - from + to; };
  move(r.shaftFirst);
  move(r.leftFirst);
  move(r.rightFirst);
  if (!(r.afterFirst == 0 && r.afterCount == 0)) move(r.afterFirst);
  return r;
}

// A hash of a feather's unplaced vertices (positions, normals, tangents), for finding identical ones.
uint64_t unplacedHash(const glm::vec3* p, const PackedDir* n, const PackedDir* t, size_t count) {
  uint64_t h = 0x9e3779b97f4a7c15ull ^ count;
  auto mix = [&](uint64_t v) {
    h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    h *= 0xff51afd7ed558ccdull;
  };
  for (size_t k = 0; k < count; ++k) {
    uint32_t x[3];
    std::memcpy(x, &p[k], sizeof(x));
    mix(uint64_t(x[0]) << 32 | x[1]);
    mix(uint64_t(x[2]) << 32 | uint32_t(uint16_t(n[k].q[0])) << 16 | uint16_t(n[k].q[1]));
    mix(uint64_t(uint16_t(n[k].q[2])) << 48 | uint64_t(uint16_t(t[k].q[0])) << 32 |
        uint64_t(uint16_t(t[k].q[1])) << 16 | uint16_t(t[k].q[2]));
  }
  return h;
}

}  // namespace

size_t InstancingStats::storedBytes() const { return storedVertices * (sizeof(glm::vec3) + 2 * sizeof(PackedDir)); }
size_t InstancingStats::unsharedBytes() const { return vertices * (sizeof(glm::vec3) + 2 * sizeof(PackedDir)); }

uint32_t indexEnd(const feather::FeatherMeshRanges& r) {
  return std::max({r.shaftFirst + r.shaftCount, r.leftFirst + r.leftCount, r.rightFirst + r.rightCount,
                   r.afterFirst + r.afterCount});
}

// Where each of `inputs`, meshed one after another into `mesh` from its start with `ranges`, sits in it.
std::vector<CoatMesher::Slice> CoatMesher::locate(const std::vector<feather::FeatherMeshInput>& inputs,
                                                  const std::vector<feather::FeatherMeshRanges>& ranges,
                                                  const TriMesh& mesh) {
  std::vector<Slice> out(inputs.size());
  uint32_t iEnd = 0, vEnd = 0;
  for (size_t k = 0; k < inputs.size(); ++k) {
    Slice& sl = out[k];
    const auto& r = ranges[k];
    sl.i0 = iEnd;
    iEnd = std::max(iEnd, indexEnd(r));
    sl.in = iEnd - sl.i0;
    sl.v0 = vEnd;
    while (vEnd < mesh.featherId.size() && mesh.featherId[vEnd] == inputs[k].featherId) ++vEnd;
    sl.vn = vEnd - sl.v0;
    sl.ranges = r;
  }
  return out;
}

void CoatMesher::clear() { *this = CoatMesher{}; }

void CoatMesher::keepIndices(const TriMesh& out) { keptIndices_ = out.indices; }

void CoatMesher::resize(size_t n) {
  if (meshParams_.size() == n) return;
  meshParams_.assign(n, feather::FeatherParams{});
  matureValid_.assign(n, 0);
  grownAge_.assign(n, std::nan(""));
  grownParams_.assign(n, feather::FeatherParams{});
  matureCurves_.assign(n, {});
  grownCurves_.assign(n, {});
  lodOrders_.assign(n, {});
  grownOrders_.assign(n, {});
  curvesVersion_.assign(n, 0);
  matureVersion_.assign(n, 0);
  slices_.assign(n, Slice{});
  rep_.clear();
  repKey_.clear();
}

bool CoatMesher::clustersEveryFeather(const CoatMeshInput& in) {
  return in.instanceTolerance > 0 && in.packed->packedKeys.keyOffset.empty();
}

// Representatives in feather index order (a pure function of the curves taken), computed again only
// when those curves or the tolerance changed. A coat meshed from its interpolated parameters (a draped
// one) takes every feather's mature curves, present or not, growing or not: they do not change over a
// moult, so neither does any mature feather's representative (no feather changes shape because another
// moults). A packed coat's packed curves exist for its present feathers only: it takes the present
// mature ones, so a feather may change representative when an earlier one moults or is packed again.
void CoatMesher::updateRepresentatives(const CoatMeshInput& in, const std::vector<uint8_t>& grown) {
  const coat::CoatFeathers& coat = *in.coat;
  const size_t n = coat.size();
  const double tol = in.instanceTolerance > 0 ? in.instanceTolerance : 0;
  const bool everyFeather = clustersEveryFeather(in);
  std::vector<uint64_t> key(n, 0);
  if (tol > 0)
    for (size_t i = 0; i < n; ++i)
      if (everyFeather ? matureValid_[i] != 0 : coat.present[i] && grown[i]) key[i] = matureVersion_[i];
  if (rep_.size() == n && key == repKey_ && std::memcmp(&tol, &tolerance_, sizeof(double)) == 0) return;
  tolerance_ = tol;
  repKey_ = std::move(key);
  std::vector<const feather::FeatherCurves*> curves(n, nullptr);
  for (size_t i = 0; i < n; ++i)
    if (repKey_[i]) curves[i] = &matureCurves_[i];
  rep_ = feather::shareCurves(curves, tol);
}

// Barb curves are a pure function of the packed parameters (and the age while growing), so a feather
// whose inputs equal those of its cached curves keeps them. A growing feather keeps the mature
// feather's LOD order (docs/growth.md), so its kept barbs do not change as it opens.
void CoatMesher::updateCurves(const CoatMeshInput& in, std::vector<uint8_t>& grown, std::vector<double>& shed) {
  const coat::CoatFeathers& coat = *in.coat;
  const coat::CoatFeathers& packedCoat = *in.packedCoat;
  const coat::PackResult& packed = *in.packed;
  const size_t n = coat.size();
  std::vector<uint8_t> regenerated(n, 0), matureRegenerated(n, 0);
  // Instancing a coat meshed from its interpolated parameters chooses representatives among every
  // feather, present or not (updateRepresentatives): absent feathers get their mature curves too.
  const bool everyFeather = clustersEveryFeather(in);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 8), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) {
      const bool present = coat.present[i] != 0;
      if (!present && !everyFeather) continue;
      const double age = coat.age[i];
      const feather::GrowthSchedule& schedule = feather::growthScheduleOf(coat.params[i]);
      // Growing (age < 1), or worn (age > 1 with a schedule that wears): meshed from the feather at its
      // age, with the mature feather as the reference for texture coordinates and LOD order. A worn
      // feather is packed mature; its shorter barbs lie within the packed ones.
      const bool growing = age < 1.0 || (age > 1.0 && schedule.wears());
      // A feather packed as grown (computePack) is meshed from its packed parameters as they are; the
      // mature feather (unpacked) gives its texture coordinates and LOD order. Any other growing feather
      // was packed mature and grows from its packed parameters.
      // The packed parameters are rebuilt from the pack's flat key barbs only when they differ from the
      // cached ones (coat::packedParamsEqual compares without building them).
      const bool havePacked = !packed.packedKeys.keyOffset.empty();
      const bool asGrown = growing && havePacked && packedAsGrown(age, schedule, coat.params[i]);
      const bool meshUnpacked = asGrown || !havePacked;  // mesh params = coat.params[i], else the packed ones
      const bool same =
          matureValid_[i] && (meshUnpacked ? meshParams_[i] == coat.params[i]
                                           : coat::packedParamsEqual(meshParams_[i], packedCoat, packed, i));
      if (!same) {
        if (meshUnpacked)
          meshParams_[i] = coat.params[i];
        else
          coat::packedParamsInto(packedCoat, packed, i, meshParams_[i]);
        const feather::FeatherParams& p = meshParams_[i];
        feather::generateBarbs(p, matureCurves_[i]);
        feather::computeLodOrder(matureCurves_[i], lodOrders_[i]);
        matureValid_[i] = 1;
        grownAge_[i] = std::nan("");
        regenerated[i] = 1;
        matureRegenerated[i] = 1;
      }
      if (growing && present) {
        const feather::GrowthState st = feather::growthStateAt(age, schedule);
        // Whether a feather is packed as grown depends on its age only, so equal ages mean the same path.
        if (std::memcmp(&grownAge_[i], &age, sizeof(double)) != 0 ||
            (asGrown && !coat::packedParamsEqual(grownParams_[i], packedCoat, packed, i))) {
          if (asGrown) coat::packedParamsInto(packedCoat, packed, i, grownParams_[i]);
          feather::generateBarbs(asGrown ? grownParams_[i] : feather::featherAtState(meshParams_[i], st, schedule),
                                 grownCurves_[i]);
          // Same barbs as the mature feather (the usual case): its LOD order (as buildFeatherMesh does).
          if (grownCurves_[i].barbs.size() != matureCurves_[i].barbs.size())
            feather::computeLodOrder(grownCurves_[i], grownOrders_[i]);
          grownAge_[i] = age;
          regenerated[i] = 1;
        }
        shed[i] = st[feather::GrowthParam::Sheath];
        grown[i] = 0;
      }
    }
  });
  regenerated_ = 0;
  for (size_t i = 0; i < n; ++i) {
    if (regenerated[i]) {
      ++regenerated_;
      ++curvesVersion_[i];
    }
    if (matureRegenerated[i]) ++matureVersion_[i];
  }
}

void CoatMesher::update(const CoatMeshInput& in, TriMesh& out) {
  const coat::CoatFeathers& coat = *in.coat;
  const size_t n = coat.size();
  resize(n);
  std::vector<uint8_t> grown(n, 1);
  std::vector<double> shed(n, 1.0);
  updateCurves(in, grown, shed);
  updateRepresentatives(in, grown);
  std::vector<feather::FeatherMeshInput> inputs;
  which_.clear();
  inputs.reserve(n);
  for (uint32_t i : coat.layerOrder) {
    if (!coat.present[i]) continue;
    feather::FeatherMeshInput fi;
    const uint32_t r = rep_[i];  // i itself unless it is instanced (then mature, as r is)
    fi.curves = grown[i] ? &matureCurves_[r] : &grownCurves_[i];
    fi.reference = grown[i] ? nullptr : &matureCurves_[i];
    fi.order =
        !grown[i] && grownCurves_[i].barbs.size() != matureCurves_[i].barbs.size() ? &grownOrders_[i] : &lodOrders_[r];
    const coat::FeatherFrame& fr = coat.frames[i];
    fi.placement = feather::FeatherPlacement::fromFollicle(fr.origin, fr.tangent, fr.normal, in.packed->elevation[i]);
    fi.featherId = i;
    fi.lod = in.featherLods && in.featherLods->size() == n ? in.lod * (*in.featherLods)[i] : in.lod;
    fi.sheathShed = shed[i];
    inputs.push_back(fi);
    which_.push_back(i);
  }
  if (!keptIndices_.empty() && keptIndices_.size() == out.indices.size()) out.indices.swap(keptIndices_);
  keptIndices_.clear();
  // Not the mesh of the last update (or a first one): nothing can be copied from it.
  if (out.featherId.size() != meshVertices_)
    for (auto& sl : slices_) sl.valid = false;
  bends_ = in.bends && in.bends->size() == n ? in.bends : nullptr;
  assemble(inputs, shed, out);
  bends_ = nullptr;
}

// Meshes the present feathers (inputs, in layer order) into `out`. Feathers are meshed unplaced
// (feather-local positions, normals, tangents; feather/mesh.hpp) and kept that way in localPos_/Nrm_/Tan_:
// a feather whose curves, level of detail and sheath are unchanged is copied from the last mesh instead
// of meshed again, and every feather is then placed.
void CoatMesher::assemble(const std::vector<feather::FeatherMeshInput>& placed, const std::vector<double>& shed,
                          TriMesh& out) {
  const std::vector<uint32_t>& which = which_;
  const size_t count = placed.size();
  const feather::MeshOptions mo;
  std::vector<feather::FeatherMeshInput> inputs = placed;
  for (auto& in : inputs) in.unplaced = true;
  std::vector<uint8_t> reuse(count, 0);
  size_t reused = 0;
  for (size_t k = 0; k < count; ++k) {
    const uint32_t i = which[k];
    const Slice& sl = slices_[i];
    const bool growing = inputs[k].reference != nullptr;
    const uint32_t r = growing ? i : rep_[i];
    const uint64_t version = growing ? curvesVersion_[i] : matureVersion_[r];
    const bool same = sl.valid && sl.rep == r && sl.version == version && sl.growing == growing &&
                      sl.lod == inputs[k].lod && std::memcmp(&sl.shed, &shed[i], sizeof(double)) == 0 &&
                      sl.in > 0;  // empty feathers are re-meshed (nothing to copy; keeps range offsets exact)
    reuse[k] = same ? 1 : 0;
    reused += reuse[k];
  }
  reused_ = reused;
  std::vector<feather::FeatherMeshRanges>& ranges = ranges_;
  ranges.assign(count, feather::FeatherMeshRanges{});
  std::vector<Slice> next(count);
  if (reused * 10 < count && !(tolerance_ > 0)) {
    // Little to reuse: mesh everything straight into the output.
    clearKeepingCapacity(out);
    feather::appendFeatherMeshes(inputs.data(), count, mo, out, &ranges);
    next = locate(inputs, ranges, out);
    // Stored from the mesh's (unplaced) positions, which placing then overwrites.
    const std::vector<Slice> at = next;
    storeUnplaced(std::vector<uint8_t>(count, 0), at, out, next);
  } else {
    // Mesh the changed feathers into freshMesh_, then copy them into the mesh: in place when the layout is
    // unchanged, else into a new mesh with the reused slices.
    // With instancing, feathers meshed from the same curves at the same level of detail and sheath get
    // the same unplaced mesh (all but its feather id): each such mesh is made once.
    std::vector<size_t> changedAt;  // the feathers to mesh
    for (size_t k = 0; k < count; ++k)
      if (!reuse[k]) changedAt.push_back(k);
    std::vector<uint32_t> meshedAs(changedAt.size());  // per feather to mesh: its entry in `changed`
    std::vector<feather::FeatherMeshInput> changed;
    if (tolerance_ > 0) {
      std::vector<feather::FeatherMeshLevel> level(changedAt.size());
      tbb::parallel_for(tbb::blocked_range<size_t>(0, changedAt.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t c = r.begin(); c < r.end(); ++c) level[c] = feather::featherMeshLevel(inputs[changedAt[c]], mo);
      });
      auto same = [&](const feather::FeatherMeshInput& a, const feather::FeatherMeshInput& b) {
        return a.curves == b.curves && a.order == b.order && a.reference == b.reference &&
               std::memcmp(&a.sheathShed, &b.sheathShed, sizeof(double)) == 0 &&
               std::memcmp(&a.sheathBand, &b.sheathBand, sizeof(double)) == 0;
      };
      std::unordered_multimap<const void*, uint32_t> byCurves;  // curves -> entries of `changed`
      std::vector<size_t> levelOf;                              // per entry of `changed`: its c
      for (size_t c = 0; c < changedAt.size(); ++c) {
        const feather::FeatherMeshInput& fi = inputs[changedAt[c]];
        meshedAs[c] = static_cast<uint32_t>(changed.size());
        auto [lo, hi] = byCurves.equal_range(fi.curves);
        for (auto it = lo; it != hi; ++it)
          if (same(changed[it->second], fi) && level[levelOf[it->second]] == level[c]) {
            meshedAs[c] = it->second;
            break;
          }
        if (meshedAs[c] == changed.size()) {
          byCurves.emplace(fi.curves, meshedAs[c]);
          levelOf.push_back(c);
          changed.push_back(fi);
        }
      }
    } else {
      for (size_t c = 0; c < changedAt.size(); ++c) {
        meshedAs[c] = static_cast<uint32_t>(c);
        changed.push_back(inputs[changedAt[c]]);
      }
    }
    clearKeepingCapacity(freshMesh_);
    std::vector<feather::FeatherMeshRanges> freshRanges;
    feather::appendFeatherMeshes(changed.data(), changed.size(), mo, freshMesh_, &freshRanges);
    // Source slices: in the last mesh (reused) or in freshMesh_.
    std::vector<Slice> src(count);
    const std::vector<Slice> fresh = locate(changed, freshRanges, freshMesh_);
    for (size_t c = 0; c < changedAt.size(); ++c) src[changedAt[c]] = fresh[meshedAs[c]];
    for (size_t k = 0; k < count; ++k)
      if (reuse[k]) src[k] = slices_[which[k]];
    size_t vTotal = 0, iTotal = 0;
    for (size_t k = 0; k < count; ++k) {
      next[k].v0 = static_cast<uint32_t>(vTotal);
      next[k].i0 = static_cast<uint32_t>(iTotal);
      next[k].vn = src[k].vn;
      next[k].in = src[k].in;
      next[k].ranges = rebase(src[k].ranges, src[k].i0, next[k].i0);
      vTotal += src[k].vn;
      iTotal += src[k].in;
    }
    PTERYLA_CHECK(vTotal <= UINT32_MAX, "mesh exceeds 32-bit vertex indices");
    // Every feather where it was, with as many vertices and indices (a feather regrown, re-shed or
    // repacked at the same level of detail): the changed slices are written over their old places in the
    // mesh itself, and nothing else moves.
    bool inPlace = vTotal == meshVertices_ && vTotal == out.featherId.size() && iTotal == out.indices.size();
    for (size_t k = 0; k < count && inPlace; ++k) {
      const Slice& old = slices_[which[k]];
      inPlace =
          old.valid && old.v0 == next[k].v0 && old.vn == next[k].vn && old.i0 == next[k].i0 && old.in == next[k].in;
    }
    if (inPlace) {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, changedAt.size(), 16),
                        [&](const tbb::blocked_range<size_t>& range) {
                          for (size_t c = range.begin(); c < range.end(); ++c) {
                            const size_t k = changedAt[c];
                            const Slice& a = src[k];
                            const Slice& b = next[k];
                            copySlice(freshMesh_.uvGlobal, a.v0, out.uvGlobal, b.v0, a.vn);
                            copySlice(freshMesh_.uvBarb, a.v0, out.uvBarb, b.v0, a.vn);
                            copySlice(freshMesh_.uvGrowth, a.v0, out.uvGrowth, b.v0, a.vn);
                            copySlice(freshMesh_.alpha, a.v0, out.alpha, b.v0, a.vn);
                            copySlice(freshMesh_.sheath, a.v0, out.sheath, b.v0, a.vn);
                            copySlice(freshMesh_.barbCount, a.v0, out.barbCount, b.v0, a.vn);
                            std::fill_n(out.featherId.data() + b.v0, a.vn, which[k]);
                            const uint32_t shift = b.v0 - a.v0;
                            const uint32_t* fi = freshMesh_.indices.data() + a.i0;
                            uint32_t* ti = out.indices.data() + b.i0;
                            for (uint32_t q = 0; q < a.in; ++q) ti[q] = fi[q] + shift;
                          }
                        });
    } else {
      // The layout moved: assemble a new mesh from the last one and the fresh slices, then let the last
      // one go (no spare copy of the coat is kept between updates).
      TriMesh next_;
      resizeAll(next_, vTotal, iTotal);  // every element is overwritten (positions etc. when placed)
      const TriMesh& last = out;
      tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t k = range.begin(); k < range.end(); ++k) {
          const bool old = reuse[k] != 0;
          const TriMesh& from = old ? last : freshMesh_;
          const Slice& a = src[k];
          const Slice& b = next[k];
          copySlice(from.uvGlobal, a.v0, next_.uvGlobal, b.v0, a.vn);
          copySlice(from.uvBarb, a.v0, next_.uvBarb, b.v0, a.vn);
          copySlice(from.uvGrowth, a.v0, next_.uvGrowth, b.v0, a.vn);
          copySlice(from.alpha, a.v0, next_.alpha, b.v0, a.vn);
          copySlice(from.sheath, a.v0, next_.sheath, b.v0, a.vn);
          copySlice(from.barbCount, a.v0, next_.barbCount, b.v0, a.vn);
          std::fill_n(next_.featherId.data() + b.v0, a.vn, which[k]);
          const uint32_t shift = b.v0 - a.v0;  // modular: vertex indices move by the slice's shift
          const uint32_t* fi = from.indices.data() + a.i0;
          uint32_t* ti = next_.indices.data() + b.i0;
          for (uint32_t q = 0; q < a.in; ++q) ti[q] = fi[q] + shift;
        }
      });
      out = std::move(next_);
    }
    // The store: kept as it is when no feather was meshed and none left (a feather that came would have
    // been meshed); without instancing, with the layout unchanged and every remeshed feather the only
    // holder of its stored mesh, those meshes are written over in place (a moult or growth step); else
    // built again from the reused slices' stored meshes and the fresh ones.
    for (size_t k = 0; k < count; ++k)
      if (reuse[k]) {
        next[k].u0 = src[k].u0;
        next[k].hash = src[k].hash;
      }
    if (!(changedAt.empty() && count == stats_.feathers) &&
        !(inPlace && !(tolerance_ > 0) && writeStoreInPlace(changedAt, src, next)))
      storeUnplaced(reuse, src, freshMesh_, next);
    freshMesh_ = TriMesh{};  // the changed feathers' meshes are in `out` now
    for (size_t k = 0; k < count; ++k) ranges[k] = next[k].ranges;
  }
  // Place every feather.
  const size_t vertices = out.featherId.size();
  out.positions.resize(vertices);
  out.normals.resize(vertices);
  out.tangents.resize(vertices);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t k = range.begin(); k < range.end(); ++k) {
      const Slice& sl = next[k];
      if (bends_ && !(*bends_)[which[k]].rigid())
        feather::placeBentFeatherVertices(placed[k].placement, (*bends_)[which[k]], localPos_.data() + sl.u0,
                                          localNrm_.data() + sl.u0, localTan_.data() + sl.u0, sl.vn,
                                          out.positions.data() + sl.v0, out.normals.data() + sl.v0,
                                          out.tangents.data() + sl.v0);
      else
        feather::placeFeatherVertices(placed[k].placement, localPos_.data() + sl.u0, localNrm_.data() + sl.u0,
                                      localTan_.data() + sl.u0, sl.vn, out.positions.data() + sl.v0,
                                      out.normals.data() + sl.v0, out.tangents.data() + sl.v0);
    }
  });
  // Remember what each slice of the new mesh was made from.
  for (auto& sl : slices_) sl.valid = false;
  for (size_t k = 0; k < count; ++k) {
    Slice& sl = slices_[which[k]];
    sl = next[k];
    sl.valid = true;
    sl.growing = inputs[k].reference != nullptr;
    sl.rep = sl.growing ? which[k] : rep_[which[k]];
    sl.version = sl.growing ? curvesVersion_[sl.rep] : matureVersion_[sl.rep];
    sl.lod = inputs[k].lod;
    sl.shed = shed[which[k]];
  }
  meshVertices_ = vertices;
  stats_ = InstancingStats{};
  stats_.feathers = count;
  for (size_t k = 0; k < count; ++k) stats_.representatives += slices_[which[k]].rep == which[k];
  stats_.vertices = vertices;
  stats_.storedVertices = localPos_.size();
  {
    std::vector<uint32_t> starts;
    starts.reserve(count);
    for (size_t k = 0; k < count; ++k)
      if (next[k].vn) starts.push_back(next[k].u0);
    std::sort(starts.begin(), starts.end());
    stats_.meshes = static_cast<size_t>(std::unique(starts.begin(), starts.end()) - starts.begin());
  }
}

bool CoatMesher::writeStoreInPlace(const std::vector<size_t>& changedAt, const std::vector<Slice>& src,
                                   std::vector<Slice>& next) {
  // Stored meshes held by more than one feather (identical meshes) cannot be written over.
  std::vector<uint32_t> held;
  held.reserve(next.size());
  for (const uint32_t i : which_)
    if (slices_[i].vn) held.push_back(slices_[i].u0);
  std::sort(held.begin(), held.end());
  for (size_t k : changedAt) {
    const Slice& old = slices_[which_[k]];
    const auto [lo, hi] = std::equal_range(held.begin(), held.end(), old.u0);
    if (old.vn && hi - lo != 1) return false;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, changedAt.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t c = r.begin(); c < r.end(); ++c) {
      const size_t k = changedAt[c];
      const Slice& a = src[k];
      const uint32_t u0 = slices_[which_[k]].u0;
      copySlice(freshMesh_.positions, a.v0, localPos_, u0, a.vn);
      copySlice(freshMesh_.normals, a.v0, localNrm_, u0, a.vn);
      copySlice(freshMesh_.tangents, a.v0, localTan_, u0, a.vn);
      next[k].u0 = u0;
      next[k].hash = unplacedHash(localPos_.data() + u0, localNrm_.data() + u0, localTan_.data() + u0, a.vn);
    }
  });
  return true;
}

void CoatMesher::storeUnplaced(const std::vector<uint8_t>& reused, const std::vector<Slice>& src, TriMesh& fresh,
                               std::vector<Slice>& next) {
  const size_t count = next.size();
  // Each slice's data and hash (the fresh ones hashed in parallel).
  std::vector<const glm::vec3*> pos(count);
  std::vector<const PackedDir*> nrm(count), tan(count);
  std::vector<uint64_t> hash(count);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t k = range.begin(); k < range.end(); ++k) {
      const bool old = reused[k] != 0;
      const size_t at = old ? src[k].u0 : src[k].v0;
      pos[k] = (old ? localPos_ : fresh.positions).data() + at;
      nrm[k] = (old ? localNrm_ : fresh.normals).data() + at;
      tan[k] = (old ? localTan_ : fresh.tangents).data() + at;
      hash[k] = old ? src[k].hash : unplacedHash(pos[k], nrm[k], tan[k], src[k].vn);
    }
  });
  // Identical meshes once: the first slice (in layer order) with a mesh is where it is stored.
  std::unordered_multimap<uint64_t, uint32_t> firstOf;  // hash -> slice that stores it
  firstOf.reserve(count);
  std::vector<uint32_t> storedBy(count);
  size_t total = 0;
  for (size_t k = 0; k < count; ++k) {
    const uint32_t vn = src[k].vn;
    storedBy[k] = static_cast<uint32_t>(k);
    auto [lo, hi] = firstOf.equal_range(hash[k]);
    for (auto it = lo; it != hi; ++it) {
      const uint32_t j = it->second;
      if (src[j].vn == vn && std::memcmp(pos[j], pos[k], vn * sizeof(glm::vec3)) == 0 &&
          std::memcmp(nrm[j], nrm[k], vn * sizeof(PackedDir)) == 0 &&
          std::memcmp(tan[j], tan[k], vn * sizeof(PackedDir)) == 0) {
        storedBy[k] = j;
        break;
      }
    }
    if (storedBy[k] == k) {
      firstOf.emplace(hash[k], static_cast<uint32_t>(k));
      next[k].u0 = static_cast<uint32_t>(total);
      total += vn;
    } else {
      next[k].u0 = next[storedBy[k]].u0;
    }
    next[k].hash = hash[k];
  }
  PTERYLA_CHECK(total <= UINT32_MAX, "unplaced store exceeds 32-bit offsets");
  // Every feather fresh, none shared, in the order meshed: the fresh arrays are the store as they are.
  bool whole = total == fresh.positions.size();
  for (size_t k = 0; k < count && whole; ++k) whole = !reused[k] && storedBy[k] == k && src[k].v0 == next[k].u0;
  if (whole) {
    std::swap(localPos_, fresh.positions);
    std::swap(localNrm_, fresh.normals);
    std::swap(localTan_, fresh.tangents);
    return;
  }
  std::vector<glm::vec3> p(total);
  std::vector<PackedDir> nn(total), tt(total);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t k = range.begin(); k < range.end(); ++k) {
      if (storedBy[k] != k) continue;
      const size_t vn = src[k].vn, u0 = next[k].u0;
      if (!vn) continue;
      std::memcpy(p.data() + u0, pos[k], vn * sizeof(glm::vec3));
      std::memcpy(nn.data() + u0, nrm[k], vn * sizeof(PackedDir));
      std::memcpy(tt.data() + u0, tan[k], vn * sizeof(PackedDir));
    }
  });
  localPos_ = std::move(p);
  localNrm_ = std::move(nn);
  localTan_ = std::move(tt);
}

}  // namespace pteryla::pipeline
