#pragma once
// Feather-type interpolation (Streit 2003, 5.2.4): key barbs are matched base to tip by rp after the
// feather with fewer key barbs is inflated at the tip with key barbs that copy the local barb shape;
// each new key barb sits at the blended rp and its control vertices blend the barb shapes each feather
// has at that rp (the bilinear construction). Scalars (lengths, widths, curvatures, angles, spacing,
// silhouettes, split settings) blend linearly. The N-way version is a barycentric blend used by coats.
#include <vector>

#include "pteryla/feather/params.hpp"

namespace pteryla::feather {

// t = 0 gives a, t = 1 gives b (same barbs; key barbs appear with the defaults made explicit).
FeatherParams interpolateFeathers(const FeatherParams& a, const FeatherParams& b, double t);
// Barycentric blend; weights are normalized (must be >= 0 with a positive sum); zero-weight feathers are
// ignored. Feathers of one generator blend as that generator (its blend hook, else the heaviest
// feather's generator settings). When the feathers (zero weights included) have different generators,
// every one is blended in its Streit key-barb form (streitForm, generator.hpp): a helical feather as its
// converted key barbs, so weights 1/0 give exactly streitForm of that feather. Throws Error for bad
// weights.
FeatherParams blendFeathers(const std::vector<const FeatherParams*>& feathers, const std::vector<double>& weights);

// Inflates `keys` (sorted, as from effectiveKeyBarbs) to `count` key barbs by adding barbs between the
// last key barb below the tip and rp = 1 that copy the barb shape there: the barbs generated from the
// result are the same as before. No-op when keys.size() >= count.
void inflateKeyBarbs(std::vector<KeyBarb>& keys, size_t count);

}  // namespace pteryla::feather
