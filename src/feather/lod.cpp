// Barb collapse order for feather level of detail, Streit 2003, 5.3 (Fig. 5.8): vane ends and split
// borders kept at every level, key barbs kept to the end after them, barbs between them collapsed in a
// dispersed, divide-and-conquer order, those nearest key barbs last. Key barbs rank among themselves by
// the same divide and conquer, so a feather with many key barbs (e.g. the packer's refined ones) still
// reaches low levels with a dispersed subset of them.
#include "pteryla/feather/lod.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pteryla/core/error.hpp"

namespace pteryla::feather {

namespace {

struct Interval {
  uint32_t gap;      // b - a
  uint32_t keyDist;  // distance (barbs) from the middle barb to the nearest key barb of its vane
  uint32_t a, b;     // kept barbs bounding the interval (global barb indices)
  uint32_t mid() const { return a + gap / 2; }
};

// True when x should be split before y.
struct Before {
  bool operator()(const Interval& x, const Interval& y) const {
    if (x.gap != y.gap) return x.gap > y.gap;
    if (x.keyDist != y.keyDist) return x.keyDist < y.keyDist;
    return x.mid() < y.mid();
  }
};
// std heap keeps the "largest" on top: invert.
struct HeapLess {
  bool operator()(const Interval& x, const Interval& y) const { return Before()(y, x); }
};

struct Scratch {
  std::vector<uint32_t> keyDist;
  std::vector<uint8_t> pinned;
  std::vector<Interval> heap;
  std::vector<uint32_t> seq;  // per vane: anchors and key barbs in barb order (global barb indices)
};

// Pops the widest interval first and ranks its middle element, pushing both halves, until the heap is
// empty. `at(i)` maps an interval position to the barb index it ranks.
template <class At>
void divideAndConquer(std::vector<Interval>& heap, std::vector<uint32_t>& rank, uint32_t& next, const At& at,
                      const std::vector<uint32_t>& keyDist) {
  std::make_heap(heap.begin(), heap.end(), HeapLess());
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), HeapLess());
    const Interval iv = heap.back();
    heap.pop_back();
    const uint32_t m = iv.mid();
    rank[at(m)] = next++;
    for (const auto& [a, b] : {std::pair<uint32_t, uint32_t>{iv.a, m}, std::pair<uint32_t, uint32_t>{m, iv.b}}) {
      if (b - a < 2) continue;
      Interval sub{b - a, 0, a, b};
      sub.keyDist = keyDist.empty() ? 0 : keyDist[at(sub.mid())];
      heap.push_back(sub);
      std::push_heap(heap.begin(), heap.end(), HeapLess());
    }
  }
}

}  // namespace

void computeLodOrder(const FeatherCurves& c, LodOrder& out) {
  static thread_local Scratch s;
  const size_t n = c.barbs.size();
  PTERYLA_CHECK(n < std::numeric_limits<uint32_t>::max() / 2, "too many barbs");
  out.rank.assign(n, std::numeric_limits<uint32_t>::max());
  out.pinned = 0;
  s.keyDist.assign(n, std::numeric_limits<uint32_t>::max());
  s.pinned.assign(n, 0);
  s.heap.clear();
  s.seq.clear();

  // Vane runs: maximal ranges of barbs with the same part and vane (parts are contiguous, vanes too).
  auto sameVane = [&](size_t i, size_t j) {
    return c.barbs[i].part == c.barbs[j].part && c.barbs[i].vane == c.barbs[j].vane;
  };
  for (size_t begin = 0; begin < n;) {
    size_t end = begin + 1;
    while (end < n && sameVane(begin, end)) ++end;
    // Distance to the nearest key barb (two sweeps).
    uint32_t d = std::numeric_limits<uint32_t>::max();
    for (size_t i = begin; i < end; ++i) {
      d = c.barbs[i].isKey ? 0 : (d == std::numeric_limits<uint32_t>::max() ? d : d + 1);
      s.keyDist[i] = d;
    }
    d = std::numeric_limits<uint32_t>::max();
    for (size_t i = end; i-- > begin;) {
      d = c.barbs[i].isKey ? 0 : (d == std::numeric_limits<uint32_t>::max() ? d : d + 1);
      s.keyDist[i] = std::min(s.keyDist[i], d);
    }
    // Anchors (vane ends, split borders) are pinned; key barbs are kept before every other barb.
    for (size_t i = begin; i < end; ++i) {
      const BarbCurve& b = c.barbs[i];
      const bool before = i > begin && c.barbs[i - 1].splitAfter;
      if (i == begin || i + 1 == end || b.isSplitEdge || b.splitAfter || before)
        s.pinned[i] = 1;
      else if (b.isKey)
        s.pinned[i] = 2;
    }
    // The widest barb between consecutive anchors is pinned too when it is longer than both: with the
    // vane ends alone, the lowest levels of a feather whose end barbs are short (any contour feather)
    // collapse its vane into a sliver between them, and a body coat seen from afar shows bare skin.
    for (size_t a = begin; a < end;) {
      size_t b = a + 1;
      while (b < end && s.pinned[b] != 1) ++b;
      if (b >= end) break;
      size_t widest = a;
      for (size_t i = a + 1; i < b; ++i)
        if (c.barbs[i].length > c.barbs[widest].length) widest = i;
      if (widest != a && c.barbs[widest].length > c.barbs[b].length) s.pinned[widest] = 1;
      a = b;
    }
    for (size_t i = begin; i < end; ++i)
      if (s.pinned[i]) s.seq.push_back(static_cast<uint32_t>(i));
    begin = end;
  }

  uint32_t next = 0;
  for (size_t i = 0; i < n; ++i)
    if (s.pinned[i] == 1) out.rank[i] = next++;
  out.pinned = next;

  // Key barbs: intervals (in key-barb count) between consecutive anchors of the same vane.
  size_t prev = 0;
  for (size_t j = 1; j < s.seq.size(); ++j) {
    if (s.pinned[s.seq[j]] != 1) continue;
    if (j - prev >= 2)
      s.heap.push_back(
          Interval{static_cast<uint32_t>(j - prev), 0, static_cast<uint32_t>(prev), static_cast<uint32_t>(j)});
    prev = j;
  }
  static const std::vector<uint32_t> kNoKeyDist;
  divideAndConquer(
      s.heap, out.rank, next, [&](uint32_t j) { return s.seq[j]; }, kNoKeyDist);

  // The other barbs: intervals (in barbs) between consecutive anchors or key barbs of the same vane.
  for (size_t j = 1; j < s.seq.size(); ++j) {
    const uint32_t a = s.seq[j - 1], b = s.seq[j];
    if (b - a < 2 || !sameVane(a, b)) continue;
    Interval iv{b - a, 0, a, b};
    iv.keyDist = s.keyDist[iv.mid()];
    s.heap.push_back(iv);
  }
  divideAndConquer(
      s.heap, out.rank, next, [](uint32_t i) { return i; }, s.keyDist);
  PTERYLA_CHECK_EQ(next, n, "every barb gets a collapse rank");
}

LodOrder computeLodOrder(const FeatherCurves& c) {
  LodOrder o;
  computeLodOrder(c, o);
  return o;
}

uint32_t keptBarbCount(const LodOrder& order, double lod) {
  const double n = static_cast<double>(order.rank.size());
  if (!(lod > 0)) lod = 0;  // also maps NaN to the lowest level
  lod = std::min(lod, 1.0);
  const double k = std::round(lod * n);
  return std::max(order.pinned, static_cast<uint32_t>(std::min(k, n)));
}

int lodSegments(int fullSegments, int minSegments, double segmentLodStart, double lod) {
  fullSegments = std::max(1, fullSegments);
  minSegments = std::clamp(minSegments, 1, fullSegments);
  if (!(lod > 0)) lod = 0;
  if (!(segmentLodStart > 0) || lod >= segmentLodStart) return fullSegments;
  const int s = static_cast<int>(std::ceil(fullSegments * lod / segmentLodStart - 1e-9));
  return std::clamp(s, minSegments, fullSegments);
}

}  // namespace pteryla::feather
