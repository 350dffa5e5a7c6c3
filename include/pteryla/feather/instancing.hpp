#pragma once
// Instancing: feathers whose barb curves differ by less than a tolerance are meshed from one of them (the
// representative), as Houdini's feather instance pool shares one template among near-identical feathers.
// A coat's feathers are interpolated from a few key feathers (Streit 2003, 6.3), so neighbours in a tract
// differ little; sharing their curves makes their unplaced meshes identical at equal levels of detail, and
// one copy of such a mesh then serves all of them (pipeline::CoatMesher). Placement stays per feather.
#include <cstdint>
#include <vector>

#include "pteryla/feather/barbs.hpp"

namespace pteryla::feather {

// A feather's extent: the largest distance of a shaft point or control vertex from the follicle (the
// feather-local origin). Tolerances are fractions of it.
double curveExtent(const FeatherCurves& c);

// Whether b could stand in for a: the same parts, shaft points, barbs (vane, part, key, split flags,
// control vertex counts) and control vertices, so both mesh to the same topology at any level of detail.
bool sameCurveStructure(const FeatherCurves& a, const FeatherCurves& b);

// For curves of the same structure: the largest difference between corresponding shaft points and widths,
// rachis and barb control vertices and barb roots (scene units), and between barb positions along the
// rachis and the dorsal directions (times `extent`, so both count as a displacement of that feather).
// Stops early and returns a value above `limit` once any difference exceeds it; curves whose arrays differ
// in size are infinitely far apart.
double curveDistance(const FeatherCurves& a, const FeatherCurves& b, double extent, double limit);

// Representatives for feathers in the order given (null entries stand alone: rep[k] = k): every feather
// takes the first earlier representative of the same structure within tolerance x its own extent
// (curveDistance), or becomes one. rep[k] <= k, and rep[rep[k]] == rep[k]. tolerance <= 0 (or NaN) is
// off: every feather stands alone. Deterministic: the result depends only on the curves and their order.
std::vector<uint32_t> shareCurves(const std::vector<const FeatherCurves*>& curves, double tolerance);

}  // namespace pteryla::feather
