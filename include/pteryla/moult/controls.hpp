#pragma once
// Expressive feather controls after AnimFur (Grier 2019, 3.2 and 4.3) on top of Streit 2003, 8.3 fixed
// feather angles: control objects sit on the skin; each follicle is bound to its nearest control within
// the control's radius; keyframed control attributes turn and raise the bound feathers:
//   lift       raise toward the skin normal (1 = upright, elevation max_lift, default 90 degrees)
//   aim        point at the control's position
//   direction  follow the control's displacement (its keyframed offset)
//   random     turn each feather about its normal by a seeded per-feather multiplier (random twist)
//   dynamic    the shaft bends as a spring chain (chain.hpp) driven by the skin's and the control's
//              motion: the root follows the skin, the tip lags; blended by weight
// Raised feathers become fixed-angle feathers (PackConstraints::fixedElevation; NaN = free) and the rest
// of the coat packs against them, so raised crests and puffed chests stay free of interpenetration.
// A raise starts from the feather's natural (packed) elevation, so lift 0 leaves the coat unchanged and
// lift 1 stands the shafts up. The chain is integrated with a fixed step from the clip start, so every
// evaluation is a pure function of t. docs/controls.md has the details and the JSON.
#include <glm/vec3.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/moult/chain.hpp"
#include "pteryla/moult/keyframes.hpp"

namespace pteryla::moult {

struct ControlSpec {
  std::string name;
  glm::dvec3 at{0.0};                      // placement in rest coordinates; the control sits at the closest skin point
  double radius = 0;                       // scene units: follicles within this distance (at rest) can bind (> 0)
  double falloff = 0;                      // [0, 1]: outer fraction of the radius over which the weight fades to 0
  std::vector<std::string> tracts;         // bind only follicles of these tracts (empty = any tract)
  uint64_t seed = 1;                       // per-feather random twist multipliers
  double twistAngle = 0.7853981633974483;  // radians: largest twist at random = 1
  double maxLift = 1.5707963267948966;     // radians: elevation reached at lift = 1 (<= pi/2)
  double springFrequency = 1.5;            // cycles per time unit (natural frequency of the dynamic spring)
  double springDamping = 0.4;              // damping ratio (0 undamped, 1 critical)
  int chainSegments = kDefaultChainSegments;  // segments of the dynamic chain along the shaft (chain.hpp)
  // Keyframed attributes (scalars in x); lift, aim, direction, random, dynamic in [0, 1].
  Track lift, aim, direction, random, dynamic;
  Track offset;  // displacement of the control from its placement (world, scene units)
};

struct ControlValues {
  double lift = 0, aim = 0, direction = 0, random = 0, dynamic = 0;
  glm::dvec3 offset{0.0};
  // Rigid (one-segment) spring lag behind the offset alone, in closed form (springLag): what a one-segment
  // chain on a still skin gives; the pipeline bends the shaft with the chain (chain.hpp) instead.
  glm::dvec3 lag{0.0};
};
ControlValues controlValuesAt(const ControlSpec& c, double t);

// Damped spring x'' + 2 zeta w x' + w^2 x = w^2 u(t), w = 2 pi frequency, driven by the track u (any
// interpolation), at rest at u before the first key. Returns x(t) - u(t), exact (closed form per key
// segment, no time stepping).
glm::dvec3 springLag(const Track& u, double frequency, double damping, double t);

// Binding of follicles to controls, computed on the rest skin (AnimFur 4.3: each curve is linked to
// its nearest control).
struct ControlBinding {
  std::vector<coat::SurfacePoint> anchor;  // per control: its point on the skin
  std::vector<int32_t> control;            // per follicle: bound control, -1 = none
  std::vector<double> weight;              // per follicle: falloff weight in [0, 1]
  std::vector<size_t> bound;               // per control: follicles bound with weight > 0
};
// controlTracts[c]: tract indices control c may bind (empty or missing = any). Follicle positions are
// evaluated on `rest` from (face, bary), so posed follicles may be passed.
ControlBinding bindControls(const coat::SkinMesh& rest, const coat::Follicles& follicles,
                            const std::vector<ControlSpec>& controls,
                            const std::vector<std::vector<uint32_t>>& controlTracts = {});

struct ControlResult {
  size_t bound = 0;            // present feathers bound to a control with weight > 0
  size_t turned = 0;           // feathers whose direction (tangent) the controls changed
  size_t raised = 0;           // feathers given a fixed elevation by the controls
  double maxElevation = 0;     // radians, largest fixed elevation set
  bool naturalPacked = false;  // a pack without the raises ran to find the natural elevations
  coat::PackResult natural;    // that pack (when naturalPacked): repack() from it with `changed` gives the final pack
  std::vector<uint32_t> changed;  // feathers whose fixed elevation the controls set
};

// Evaluates the controls at time t on the posed coat: turns (coat.frames tangent/binormal about the
// normal) and raises (fixedElevation, one entry per feather, NaN = free; entries already fixed, e.g. by
// styling, are raised from their value). `pack` and `constraints` are the scene's packing options and
// its styling's minimum elevations and shaft bands (used for the natural elevations; the constraints'
// fixedElevation is ignored: `fixedElevation` stands for it).
ControlResult evaluateControls(const std::vector<ControlSpec>& controls, const ControlBinding& binding,
                               const coat::SkinMesh& posed, const coat::Follicles& follicles, double t,
                               const coat::PackOptions& pack, const coat::PackConstraints& constraints,
                               coat::CoatFeathers& coat, std::vector<double>& fixedElevation);

// The same with the natural pack supplied by the caller (e.g. an incremental repack from the previous
// frame's natural pack): naturalPack(posed, coat, options, constraints) must return what
// coat::pack(posed, coat, options, constraints) returns, valid until evaluateControls returns. It is
// called at most once, only when some bound feather rises from a free elevation;
// ControlResult::naturalPacked then says so, but ControlResult::natural stays empty (the caller owns that
// pack).
using NaturalPackFn =
    std::function<const coat::PackResult&(const coat::SkinMesh& posed, const coat::CoatFeathers& coat,
                                          const coat::PackOptions& options, const coat::PackConstraints& constraints)>;
ControlResult evaluateControls(const std::vector<ControlSpec>& controls, const ControlBinding& binding,
                               const coat::SkinMesh& posed, const coat::Follicles& follicles, double t,
                               const coat::PackOptions& pack, const coat::PackConstraints& constraints,
                               coat::CoatFeathers& coat, std::vector<double>& fixedElevation,
                               const NaturalPackFn& naturalPack);

// JSON (docs/controls.md): one control object; calls r.finish().
ControlSpec readControl(JsonReader& r);
// The scene's "controls" array.
std::vector<ControlSpec> readControls(const Json& array, const std::string& file, const std::string& path = "controls");

}  // namespace pteryla::moult
