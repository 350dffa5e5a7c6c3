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
#include "pteryla/core/frame.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/bezier.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat {

using feather::kPi;
using glm::dvec3;

double HeightField1D::at(double s) const {
  const double b = std::floor((s - origin) / cell);
  if (!(b >= 0) || b >= static_cast<double>(h.size())) return -std::numeric_limits<double>::infinity();
  return h[static_cast<size_t>(b)];
}

glm::dvec3 placeDirection(const FeatherFrame& f, double e, const glm::dvec3& d) {
  const ElevatedAxes<dvec3> a = elevatedAxes(f.tangent, f.binormal, f.normal, e);
  return d.x * a.x + d.y * a.y + d.z * a.z;
}

glm::dvec3 placePoint(const FeatherFrame& f, double e, const glm::dvec3& p) {
  return f.origin + placeDirection(f, e, p);
}

namespace packing {

PackResult packAll(Context& ctx) {
  const auto t0 = std::chrono::steady_clock::now();
  const PackOptions& options = ctx.opt;
  checkInput(ctx.coat, options, ctx.constraints);
  PackResult res;
  detail::inArena(options.threads, [&] {
    setup(ctx);
    layoutResult(ctx, localSources(ctx), nullptr, res);
    Run run(res);
    schedule(ctx, ctx.order, nullptr, options.threads, [&](uint32_t i) { run.packOne(ctx, res, i); });
    finish(ctx, run.scratch, res, t0);
  });
  return res;
}

PackResult repackFrom(Context& ctx, const PackResult& prev, const std::vector<uint32_t>& changed) {
  const auto t0 = std::chrono::steady_clock::now();
  const CoatFeathers& coat = ctx.coat;
  const PackOptions& options = ctx.opt;
  checkInput(coat, options, ctx.constraints);
  const size_t n = coat.size();
  // The previous result must describe the same feathers in the same order.
  if (prev.elevation.size() != n || prev.pointOffset.size() != n + 1 || prev.packedKeys.keyOffset.size() != n + 1 ||
      prev.order != presentInLayerOrder(coat) || changed.size() * 2 > n)
    return packAll(ctx);
  const std::vector<uint8_t> isChanged = changedMask(changed, n);
  PackResult res;
  detail::inArena(options.threads, [&] {
    setup(ctx);
    layoutResult(ctx, localSources(ctx), nullptr, res);
    // Clearances and the median reach (which sizes the skin samples) are resolved over the whole coat: when
    // the changes moved them, every feather packs against other values than it did in `prev`.
    auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; };
    const bool resolvedAlike = same(ctx.clearance, prev.clearance) && same(ctx.skinClearance, prev.skinClearance) &&
                               same(ctx.medianReach, prev.medianReach);
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
    Run run(res);
    schedule(ctx, ctx.order, nullptr, options.threads, [&](uint32_t i) {
      bool dirty = !resolvedAlike || isChanged[i] || touched[i];
      for (uint32_t k = ctx.depOff[i]; k < ctx.depOff[i + 1] && !dirty; ++k) dirty = outChanged[ctx.deps[k]] != 0;
      const uint32_t cnt = res.pointOffset[i + 1] - res.pointOffset[i];
      const bool sameShape =
          prev.pointOffset[i + 1] - prev.pointOffset[i] == cnt && sameKeyLayout(prev.packedKeys, res.packedKeys, i);
      if (!dirty && sameShape) {
        keepFeather(prev, res, run.out, i);
        return;
      }
      run.packOne(ctx, res, i);
      bool diff = !sameShape || std::memcmp(&res.elevation[i], &prev.elevation[i], sizeof(double)) != 0 ||
                  res.bounds[i] != prev.bounds[i];
      if (!diff)
        diff = std::memcmp(res.points.data() + res.pointOffset[i], prev.points.data() + prev.pointOffset[i],
                           cnt * sizeof(glm::vec4)) != 0;
      outChanged[i] = diff ? 1 : 0;
    });
    finish(ctx, run.scratch, res, t0);
  });
  return res;
}

PackResult packOverBase(Context& ctx, const PackResult& base, const std::vector<uint32_t>& changed) {
  const auto t0 = std::chrono::steady_clock::now();
  const SkinMesh& skin = ctx.skin;
  const CoatFeathers& coat = ctx.coat;
  const PackOptions& options = ctx.opt;
  checkInput(coat, options, ctx.constraints);
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
  if (presentInLayerOrder(coat) != order)
    throw Error("packOver: the coat's present feathers are not packed in the base pack in the same layer order", {},
                "base");
  const std::vector<uint8_t> isChanged = changedMask(changed, n);
  if (options.skin && !skin.faces.empty() && !packedOnSkin(base, skin, options))
    throw Error("packOver: the skin differs from the one the base pack was packed on", {}, "base");

  PackResult res;
  detail::inArena(options.threads, [&] {
    beginContext(ctx, order);
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

    // Kept feathers take base's shape and values, packed ones their own, absent ones none.
    std::vector<Source> source(n, Source::None);
    for (uint32_t i : order) source[i] = isChanged[i] ? Source::Local : Source::Kept;
    layoutResult(ctx, source, &base, res);
    Run run(res);
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, static_cast<uint32_t>(n), 32),
                      [&](const tbb::blocked_range<uint32_t>& r) {
                        for (uint32_t i = r.begin(); i < r.end(); ++i)
                          if (source[i] == Source::Kept) keepFeather(base, res, run.out, i);
                      });
    // The packed feathers, each after the packed feathers it depends on.
    schedule(ctx, work, isChanged.data(), options.threads, [&](uint32_t i) { run.packOne(ctx, res, i); });
    finish(ctx, run.scratch, res, t0);
    if (options.captureFields) {
      for (const BarbField& f : base.barbFields)
        if (f.feather < n && source[f.feather] == Source::Kept) res.barbFields.push_back(f);
      std::sort(res.barbFields.begin(), res.barbFields.end(), fieldBefore);
    }
  });
  return res;
}

}  // namespace packing

std::vector<uint32_t> changedFeathers(const CoatFeathers& a, const CoatFeathers& b, const std::vector<double>& fa,
                                      const std::vector<double>& fb) {
  PTERYLA_CHECK_EQ(a.size(), b.size(), "changedFeathers needs coats of equal size");
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
    const double ea = fa.empty() ? packing::kNaN : fa[i], eb = fb.empty() ? packing::kNaN : fb[i];
    d = d || !(bitsEq(ea, eb) || (std::isnan(ea) && std::isnan(eb)));
    if (d) out.push_back(i);
  }
  return out;
}

}  // namespace pteryla::coat
