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
#include "pack_internal.hpp"

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

namespace packing {
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
}  // namespace packing

using namespace packing;

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

}  // namespace pteryla::coat
