#pragma once
// Styling a packed coat (Streit 2003, 8.3 "Feather Rearrangement"): the user fixes the elevation angle of
// selected feathers (by id, with a spherical brush on the skin, or with a comb line), and/or edits their
// surface direction; every other feather then packs against them. Selections are plain data that a scene
// file's "packing.styling" array describes (docs/packing.md).
#include <glm/vec3.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/core/json.hpp"

namespace pteryla::coat {

enum class StyleKind {
  Ids,     // explicit feather indices
  Sphere,  // follicles within `radius` of `center` (a brush on the skin)
  Comb,    // follicles within `radius` of the segment from -> to (a comb pulled along a line)
};

struct StyleSelection {
  StyleKind kind = StyleKind::Ids;
  std::vector<uint32_t> ids;            // Ids
  glm::dvec3 center{0};                 // Sphere
  glm::dvec3 from{0}, to{0};            // Comb
  double radius = 0;                    // Sphere / Comb, scene units
  std::optional<double> elevation;      // radians: fixed elevation of the selected feathers
  std::optional<double> minElevation;   // radians: the selected feathers pack freely but never below this
                                        // (e.g. flight feathers kept in the wing plane, packing above it)
  std::optional<glm::dvec3> direction;  // world direction: new surface direction (projected to each tangent plane)
  std::optional<double> shaftBand;      // [0,1]: the selected feathers' shaft packs against candidates within this
                                        // fraction of the vane half-width (overrides packing.shaft_band; e.g.
                                        // flight feathers, whose stiff vanes overlap and lift their barbs instead)
};

struct StyleApplied {
  std::vector<double> fixedElevation;   // per feather, NaN = free (for PackConstraints::fixedElevation)
  std::vector<uint32_t> changed;        // feathers whose frame or fixed elevation the selections changed
  std::vector<uint32_t> selectedCount;  // feathers selected by each selection
};

// Feathers selected by one selection, ascending. Ids out of range are an Error naming `where`.
std::vector<uint32_t> selectFeathers(const CoatFeathers& coat, const StyleSelection& s, const std::string& where = {});

// Applies selections in order (later ones win): direction edits rewrite coat.frames (tangent and
// binormal, the normal is kept); elevations go into the returned fixedElevation, which starts from
// `baseFixed` (may be empty). Pass `changed` to repack() for an incremental update.
StyleApplied applyStyling(CoatFeathers& coat, const std::vector<StyleSelection>& selections,
                          const std::vector<double>& baseFixed = {});

// Only the fixed elevations of the selections (no frame edits).
std::vector<double> resolveStyling(const CoatFeathers& coat, const std::vector<StyleSelection>& selections);
// Per feather the minimum elevation of the selections (later ones win; NaN = none); empty when no
// selection has one: PackConstraints::minElevation.
std::vector<double> resolveMinElevation(const CoatFeathers& coat, const std::vector<StyleSelection>& selections);

// Per feather the shaft band of the selections (later ones win; NaN = packing.shaft_band); empty when no
// selection has one: PackConstraints::shaftBand.
std::vector<double> resolveShaftBand(const CoatFeathers& coat, const std::vector<StyleSelection>& selections);
// One selection object of "packing.styling" (docs/packing.md).
StyleSelection parseStyleSelection(JsonReader& r);
Json styleSelectionToJson(const StyleSelection& s);

}  // namespace pteryla::coat
