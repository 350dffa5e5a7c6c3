#pragma once
// Feather level of detail (Streit 2003, 5.3 and 7.1.3): a continuous fraction of geometry in (0, 1].
// Lowering the detail collapses barbs and merges their vane surface into the neighbouring kept barbs;
// the order is fixed once per feather definition so picking a level is a comparison per barb.
//
// Collapse order (computed by computeLodOrder, "rank" 0 = kept longest):
//  1. pinned, kept at every level: the first and last barb of every vane and the barbs bordering a split
//     (so split boundaries and the vane ends never move);
//  1b. then the key barbs (BarbCurve::isKey), ranked among themselves by the divide and conquer of step 2
//     over the key barbs between consecutive pinned ones: every level that keeps more barbs than pinned
//     + key barbs keeps all key barbs (the thesis' rule), and a feather with many key barbs (the packer
//     refines them, packing.md) still reaches low levels, keeping a dispersed subset of them;
//  2. then, across all vanes of all parts at once, divide and conquer: the interval (in barb count)
//     between consecutive pinned or key barbs that is widest is split at its middle barb. Equal widths go to
//     the interval whose middle barb is nearest a key barb, so barbs near key barbs are collapsed last;
//     remaining ties go base to tip, left vane first, main feather first. The result is a dispersed
//     order: removing barbs never opens a local hole and the silhouette (barb tips at vane ends, key
//     barbs) survives to the lowest level.
// A level f keeps keptBarbCount(order, f) = clamp(round(f * barbs), pinned, barbs) barbs: those with
// rank < that count. Kept sets are nested, so every mesh quantity is monotone in f.
//
// Barb polylines also get fewer segments at low detail (lodSegments): full segments down to
// `segmentLodStart`, then proportional to f, never below `minSegments`.
#include <cstdint>
#include <vector>

#include "pteryla/feather/barbs.hpp"

namespace pteryla::feather {

struct LodOrder {
  std::vector<uint32_t> rank;  // per barb of FeatherCurves::barbs; 0 = kept longest
  uint32_t pinned = 0;         // barbs with rank < pinned are kept at every level
  size_t barbCount() const { return rank.size(); }
};

// Collapse order of every barb of `c` (all parts). O(n log n); no allocation beyond `out`.
void computeLodOrder(const FeatherCurves& c, LodOrder& out);
LodOrder computeLodOrder(const FeatherCurves& c);

// Number of barbs kept at level `lod` (clamped to (0, 1]); at least `pinned`.
uint32_t keptBarbCount(const LodOrder& order, double lod);

// Segments per barb at level `lod`: fullSegments for lod >= segmentLodStart, else
// ceil(fullSegments * lod / segmentLodStart), clamped to [minSegments, fullSegments].
int lodSegments(int fullSegments, int minSegments, double segmentLodStart, double lod);

}  // namespace pteryla::feather
