// The packed result's layout (points, groups, key barbs) and the end of a pack (statistics, fields).
#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "pteryla/core/error.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat::packing {

// Appends the point groups of a packed feather (its shaft, afterfeather shaft, then each key barb's
// samples) starting at point p to groupPoint; returns the point after its last group.
uint32_t appendGroups(const LocalFeather& L, int barbSamples, uint32_t p, std::vector<uint32_t>& groupPoint) {
  groupPoint.push_back(p);
  p += static_cast<uint32_t>(L.shaft.size());
  if (!L.after.empty()) {
    groupPoint.push_back(p);
    p += static_cast<uint32_t>(L.after.size());
  }
  for (size_t k = 0; k < L.keys.size(); ++k) {
    groupPoint.push_back(p);
    p += static_cast<uint32_t>(std::max(1, barbSamples));
  }
  return p;
}

// The key barb layout of a feather packed from its local data: the main (packed) key barbs of an opened
// feather, left vane first.
std::array<uint32_t, 3> localKeyCount(const LocalFeather& L) {
  if (!L.packable || L.unopened) return {0, 0, 0};
  for (uint32_t k = 0; k < L.mainKeys; ++k)
    PTERYLA_CHECK((L.keys[k].vane == 0) == (k < L.leftKeys), "local key barbs are not left vane first");
  return {L.mainKeys, L.leftKeys, 1};
}

// Copies feather i's packed key barbs from `from` (the same layout for i).
void copyKeys(const PackedKeyBarbs& from, PackedKeyBarbs& to, uint32_t i) {
  const uint32_t a = from.keyOffset[i], b = from.keyOffset[i + 1], t = to.keyOffset[i];
  PTERYLA_CHECK(b - a == to.keyOffset[i + 1] - t && from.cvOffset[b] - from.cvOffset[a] == to.cvOffset[t + b - a] - to.cvOffset[t],
                "copied key barbs with a different layout");
  std::copy(from.rp.begin() + a, from.rp.begin() + b, to.rp.begin() + t);
  std::copy(from.cvs.begin() + from.cvOffset[a], from.cvs.begin() + from.cvOffset[b], to.cvs.begin() + to.cvOffset[t]);
}

// Whether feather i has the same key barb layout in two results.
bool sameKeyLayout(const PackedKeyBarbs& a, const PackedKeyBarbs& b, uint32_t i) {
  const uint32_t n = a.keyOffset[i + 1] - a.keyOffset[i];
  if (n != b.keyOffset[i + 1] - b.keyOffset[i] || a.replaced[i] != b.replaced[i] || a.leftKeys[i] != b.leftKeys[i]) return false;
  for (uint32_t k = 0; k < n; ++k)
    if (a.cvOffset[a.keyOffset[i] + k + 1] - a.cvOffset[a.keyOffset[i] + k] !=
        b.cvOffset[b.keyOffset[i] + k + 1] - b.cvOffset[b.keyOffset[i] + k])
      return false;
  return true;
}

void initResult(const Context& ctx, PackResult& res) {
  const size_t n = ctx.coat.size();
  res.order = ctx.order;
  res.elevation.assign(n, 0.0);
  layoutKeys(n, res.packedKeys, [&](size_t i) { return localKeyCount(ctx.local[i]); },
             [&](size_t i, uint32_t k) -> uint32_t { return ctx.local[i].keys[k].cvCount; });
  res.barbsChanged.assign(n, 0);
  res.recomputed.assign(n, 0);
  res.pointOffset = pointOffsets(ctx);
  res.points.clear();
  res.points.resize(res.pointOffset.back());  // uninitialised: every feather writes its own points
  res.bounds.assign(n, glm::dvec4(0));
  res.groupOffset.assign(n + 1, 0);
  res.groupPoint.clear();
  size_t groups = 1;
  for (const LocalFeather& L : ctx.local)
    if (L.packable) groups += 1 + (L.after.empty() ? 0 : 1) + L.keys.size();
  res.groupPoint.reserve(groups);
  for (size_t i = 0; i < n; ++i) {
    const LocalFeather& L = ctx.local[i];
    uint32_t p = res.pointOffset[i];
    if (L.packable) p = appendGroups(L, ctx.opt.barbSamples, p, res.groupPoint);
    PTERYLA_CHECK(p == res.pointOffset[i + 1], "point groups do not cover the points");
    res.groupOffset[i + 1] = static_cast<uint32_t>(res.groupPoint.size());
  }
  res.groupPoint.push_back(res.pointOffset[n]);
  res.groupBounds.clear();
  res.groupBounds.resize(res.groupOffset[n]);  // uninitialised: each group's sphere is written by its feather
  res.barbFields.clear();
  res.stats = {};
}

bool fieldBefore(const BarbField& a, const BarbField& b) {
  return a.feather != b.feather ? a.feather < b.feather : (a.vane != b.vane ? a.vane < b.vane : a.key < b.key);
}

void finish(const Context& ctx, tbb::enumerable_thread_specific<Scratch>& scratch, PackResult& res,
            std::chrono::steady_clock::time_point t0) {
  PackStats& st = res.stats;
  for (Scratch& s : scratch) {
    st.recomputed += s.stats.recomputed;
    st.fixed += s.stats.fixed;
    st.unopened += s.stats.unopened;
    st.free += s.stats.free;
    st.shaftClamped += s.stats.shaftClamped;
    st.conflicts += s.stats.conflicts;
    st.barbsElevated += s.stats.barbsElevated;
    st.barbsLifted += s.stats.barbsLifted;
    st.barbsUnresolved += s.stats.barbsUnresolved;
    st.candidatePoints += s.stats.candidatePoints;
    for (auto& f : s.fields) res.barbFields.push_back(std::move(f));
  }
  std::sort(res.barbFields.begin(), res.barbFields.end(), fieldBefore);
  st.packed = ctx.order.size();
  st.dependencies = ctx.deps.size();
  st.skinSamples = ctx.skinData ? ctx.skinData->pts.size() : 0;
  res.clearance = ctx.clearance;
  res.skinClearance = ctx.skinClearance;
  res.medianReach = ctx.medianReach;
  res.skinSamples = ctx.skinData;
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace pteryla::coat::packing
