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
    PTERYLA_DCHECK((L.keys[k].vane == 0) == (k < L.leftKeys), "local key barbs are not left vane first");
  return {L.mainKeys, L.leftKeys, 1};
}

// Copies feather i's packed key barbs from `from` (the same layout for i).
void copyKeys(const PackedKeyBarbs& from, PackedKeyBarbs& to, uint32_t i) {
  const uint32_t a = from.keyOffset[i], b = from.keyOffset[i + 1], t = to.keyOffset[i];
  PTERYLA_CHECK(b - a == to.keyOffset[i + 1] - t &&
                    from.cvOffset[b] - from.cvOffset[a] == to.cvOffset[t + b - a] - to.cvOffset[t],
                "copied key barbs with a different layout");
  std::copy(from.rp.begin() + a, from.rp.begin() + b, to.rp.begin() + t);
  std::copy(from.cvs.begin() + from.cvOffset[a], from.cvs.begin() + from.cvOffset[b], to.cvs.begin() + to.cvOffset[t]);
}

// Whether feather i has the same key barb layout in two results.
bool sameKeyLayout(const PackedKeyBarbs& a, const PackedKeyBarbs& b, uint32_t i) {
  const uint32_t n = a.keyOffset[i + 1] - a.keyOffset[i];
  if (n != b.keyOffset[i + 1] - b.keyOffset[i] || a.replaced[i] != b.replaced[i] || a.leftKeys[i] != b.leftKeys[i])
    return false;
  for (uint32_t k = 0; k < n; ++k)
    if (a.cvOffset[a.keyOffset[i] + k + 1] - a.cvOffset[a.keyOffset[i] + k] !=
        b.cvOffset[b.keyOffset[i] + k + 1] - b.cvOffset[b.keyOffset[i] + k])
      return false;
  return true;
}

void layoutResult(const Context& ctx, const std::vector<Source>& source, const PackResult* kept, PackResult& res) {
  const size_t n = ctx.coat.size();
  PTERYLA_CHECK_EQ(source.size(), n, "layoutResult needs a source per feather");
  if (std::find(source.begin(), source.end(), Source::Kept) != source.end())
    PTERYLA_CHECK(kept && kept->groupOffset.size() == n + 1 && kept->packedKeys.keyOffset.size() == n + 1,
                  "a kept feather needs a result of the same coat");
  res.order = ctx.order;
  res.elevation.assign(n, 0.0);
  layoutKeys(
      n, res.packedKeys,
      [&](size_t i) -> std::array<uint32_t, 3> {
        if (source[i] == Source::Local) return localKeyCount(ctx.local[i]);
        if (source[i] == Source::None) return {0, 0, 0};
        const PackedKeyBarbs& K = kept->packedKeys;
        return {K.keyOffset[i + 1] - K.keyOffset[i], K.leftKeys[i], K.replaced[i]};
      },
      [&](size_t i, uint32_t k) -> uint32_t {
        if (source[i] == Source::Local) return ctx.local[i].keys[k].cvCount;
        const PackedKeyBarbs& K = kept->packedKeys;
        return K.cvOffset[K.keyOffset[i] + k + 1] - K.cvOffset[K.keyOffset[i] + k];
      });
  res.barbsChanged.assign(n, 0);
  res.recomputed.assign(n, 0);
  res.bounds.assign(n, glm::dvec4(0));
  res.pointOffset.assign(n + 1, 0);
  res.groupOffset.assign(n + 1, 0);
  res.groupPoint.clear();
  size_t groups = 1;
  for (uint32_t i = 0; i < n; ++i) {
    const LocalFeather& L = ctx.local[i];
    if (source[i] == Source::Local) groups += 1 + (L.after.empty() ? 0 : 1) + L.keys.size();
    if (source[i] == Source::Kept) groups += kept->groupOffset[i + 1] - kept->groupOffset[i];
  }
  res.groupPoint.reserve(groups);
  for (uint32_t i = 0; i < n; ++i) {
    uint32_t p = res.pointOffset[i];
    if (source[i] == Source::Local) {
      const LocalFeather& L = ctx.local[i];
      p = appendGroups(L, ctx.opt.barbSamples, p, res.groupPoint);
      PTERYLA_CHECK_EQ(p - res.pointOffset[i], L.pointCount, "point groups do not cover the points");
    } else if (source[i] == Source::Kept) {
      for (uint32_t g = kept->groupOffset[i]; g < kept->groupOffset[i + 1]; ++g) {
        res.groupPoint.push_back(p);
        p += kept->groupPoint[g + 1] - kept->groupPoint[g];
      }
      PTERYLA_CHECK_EQ(p - res.pointOffset[i], kept->pointOffset[i + 1] - kept->pointOffset[i],
                       "kept point groups do not cover its points");
    }
    res.pointOffset[i + 1] = p;
    res.groupOffset[i + 1] = static_cast<uint32_t>(res.groupPoint.size());
  }
  res.groupPoint.push_back(res.pointOffset[n]);
  res.points.clear();
  res.points.resize(res.pointOffset[n]);  // uninitialised: every feather writes its own points
  res.groupBounds.clear();
  res.groupBounds.resize(res.groupOffset[n]);  // uninitialised: each group's sphere is written by its feather
  res.barbFields.clear();
  res.stats = {};
}

void keepFeather(const PackResult& from, PackResult& res, Output& out, uint32_t i) {
  res.elevation[i] = from.elevation[i];
  copyKeys(from.packedKeys, res.packedKeys, i);
  res.barbsChanged[i] = from.barbsChanged[i];
  res.bounds[i] = from.bounds[i];
  PTERYLA_CHECK(from.pointOffset[i + 1] - from.pointOffset[i] == res.pointOffset[i + 1] - res.pointOffset[i] &&
                    from.groupOffset[i + 1] - from.groupOffset[i] == res.groupOffset[i + 1] - res.groupOffset[i],
                "kept feather with a different point structure");
  std::copy(from.points.begin() + from.pointOffset[i], from.points.begin() + from.pointOffset[i + 1],
            res.points.begin() + res.pointOffset[i]);
  std::copy(from.groupBounds.begin() + from.groupOffset[i], from.groupBounds.begin() + from.groupOffset[i + 1],
            res.groupBounds.begin() + res.groupOffset[i]);
  closeChunks(out, i);
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
