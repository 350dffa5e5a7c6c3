#pragma once
// Layer order for packing (Streit 2003, 6.3: "The feathers are packed by traversing the feathers in layered
// order from bottom to top. The order is determined from the parameterization of the tract"; 9.2.1: across
// tracts "by ordering the tracts or the individual follicles using projection to a body axis vector").
//
// Feathers overlap like roof tiles: a feather lies over the feathers its direction points at, so the
// feathers furthest downstream (toward where the feathers point) are the bottom layer and packed first.
//  - Tracts: tract by tract (OrderOptions::tractOrder, bottom first; unlisted tracts follow in index
//    order); within a tract by s = dot(uv, flow) descending, where flow is the tract's mean feather
//    direction in (u,v) (each follicle's direction mapped through its face's parameterization; a
//    hand-made parameterization without corner (u,v) gives flow (1,0)).
//  - Axis: one global order by the arc length of the follicle's closest point on a body-axis polyline
//    (head to tail), tail-most first.
//  - Flow: one global order by a potential phi over all follicles whose gradient follows the feather
//    directions (least squares over each follicle's nearest neighbours: phi_j - phi_i ~ (x_j - x_i) . T),
//    largest phi (furthest downstream) first. Unlike Axis it follows directions that leave the body axis
//    (wings, legs, flanks), and unlike Tracts it is one order across tract borders, so two neighbouring
//    feathers of different tracts are layered like two of the same tract.
// With Axis or Flow, OrderOptions::tractOrder lists tracts packed first, as bottom layers, in that order
// (e.g. the flight feathers, which the coverts overlap); each is ordered by the key and all other tracts
// follow as one group in the global order.
// Ties are broken by follicle id (Follicles::id), then by feather index, so the order is total and
// deterministic.
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <string>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/directions.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/parameterize.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/json.hpp"

namespace pteryla::coat {

enum class OrderMethod { Tracts, Axis, Flow };

struct OrderOptions {
  OrderMethod method = OrderMethod::Tracts;
  std::vector<std::string> tractOrder;  // names, bottom layer first (Axis, Flow: only these go first)
  std::vector<glm::dvec3> axis;         // Axis: polyline head to tail, >= 2 distinct points
  int neighbours = 8;                   // Flow: nearest follicles each follicle is compared with
};

struct OrderResult {
  std::vector<double> key;            // per feather: s (Tracts), axis arc length (Axis) or phi (Flow); larger = lower
  std::vector<glm::dvec2> tractFlow;  // per tract: unit mean direction in (u,v) (Tracts)
  std::vector<uint32_t> tractRank;    // per tract: its group in the order (unlisted tracts share one with Axis, Flow)
};

// Arc length along `axis` of the point of the polyline closest to p (ties: the earliest segment).
double axisArcLength(const std::vector<glm::dvec3>& axis, const glm::dvec3& p);

// Fills coat.layerOrder (a permutation of the feather indices, bottom first). `params[t]` is tract t's
// parameterization (Tracts only; may be empty for Axis); directions as from computeSurfaceDirections on
// `restSkin`. Throws Error for unknown tract names or a missing axis.
OrderResult orderLayers(const SkinMesh& restSkin, const std::vector<Tract>& tracts,
                        const std::vector<TractParameterization>& params, const Follicles& follicles,
                        const SurfaceDirections& directions, const OrderOptions& options, CoatFeathers& coat);

// Flow potential (OrderMethod::Flow) of points with unit directions: phi with grad phi ~ direction,
// least squares over each point's `neighbours` nearest points; mean 0. Deterministic.
std::vector<double> flowPotential(const std::vector<glm::dvec3>& position, const std::vector<glm::dvec3>& direction,
                                  int neighbours = 8);

// JSON (docs/coat.md): {"method": "tracts"|"axis"|"flow", "tracts": [names], "axis": [[x,y,z], ...],
// "neighbours": k}.
// Calls r.finish().
OrderOptions parseOrdering(JsonReader& r);

}  // namespace pteryla::coat
