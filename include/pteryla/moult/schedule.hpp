#pragma once
// Moult: feather replacement over time (Streit 2003, 8.2). Per tract, a replacement sequence
// (centre-out, boundary-in, along u or v, radial, random) gives every feather a distance d in [0,1] from
// the moult start in the tract's (u,v) parameterization; d orders the feathers. An overlapping window of
// width w moves along that order: a feather is lost when the window's leading edge reaches it, stays
// absent for a gap, then regrows through the growth schedule (feather/growth.hpp, 8.1) until the window's
// trailing edge passes it. w sets how long a feather takes to grow and how many grow at once; it may
// depend on the feather's size (larger feathers grow slower) and on its distance from the tract centre.
//
// Everything is a pure function of (plan, t): a timeline can be scrubbed in any order. docs/moult.md
// describes the model and the scene JSON.
#include <glm/vec2.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/parameterize.hpp"
#include "pteryla/core/json.hpp"

namespace pteryla::moult {

enum class MoultSequence {
  CentreOut,    // elliptic distance from the centre (reaches the tract boundary at the same time everywhere)
  BoundaryIn,   // reverse of CentreOut
  CentreOutU,   // |u - centre.u|
  BoundaryInU,  // reverse of CentreOutU
  CentreOutV,
  BoundaryInV,
  IncreasingU,  // u from the tract's smallest u
  DecreasingU,
  IncreasingV,
  DecreasingV,
  Radial,  // Euclidean (u,v) distance from the centre: a circular wave
  Random,  // a seeded random order
};
const char* moultSequenceName(MoultSequence s);  // JSON names: "centre_out", "boundary_in", "centre_out_u", ...
bool parseMoultSequence(const std::string& name, MoultSequence& out);  // also accepts "center_*"

// How the window advances: over the rank of each feather in the order (a constant number of feathers
// in the window, the thesis' "number of feathers found within the window") or over the distance d
// itself (a wave front moving at constant speed in (u,v)).
enum class MoultPace { Order, Distance };

struct MoultOptions {
  bool enabled = true;
  double start = 0;     // time units: the leading edge of the window enters the order
  double duration = 1;  // time units until the last feather is mature again (> 0)
  double window = 0.2;  // (0, 1]: window width in units of the order (fraction of the tract)
  MoultSequence sequence = MoultSequence::CentreOut;
  MoultPace pace = MoultPace::Order;
  double gap = 0.05;                 // [0, 1): fraction of a feather's window with no feather (lost, not regrowing)
  double random = 0;                 // [0, 1]: jitter of the order (0 = strictly sequential)
  uint64_t seed = 1;                 // Random sequence and jitter
  std::optional<glm::dvec2> center;  // moult start in the tract's (u,v); default: centre of its (u,v) box
  double sizeExponent = 0;           // w_i = window * (L_i / median L)^sizeExponent, L = feather length
  double boundarySlowdown = 0;  // w_i *= 1 + boundarySlowdown * r_i, r_i in [0,1]: elliptic distance from the centre
  // Wear (Streit 2003, 5.2.5; growth ages above 1, docs/growth.md): the old plumage's age, in [1, 2]
  // (1 = as fresh as a new feather), and the time a renewed feather takes to wear from age 1 to 2
  // (0 = it stays fresh). With both, a moulting coat shows worn old and fresh new feathers side by side.
  double oldAge = 1;
  double wearTime = 0;
};

// One feather's state in the moult at a time t.
enum class MoultPhase : uint8_t {
  Old,      // the window has not reached it: the old, mature feather
  Lost,     // dropped out, regrowth not started (a gap in the coat)
  Growing,  // regrowing, age in [0, 1)
  Renewed,  // the window has passed: the new, mature feather
};
struct MoultState {
  MoultPhase phase = MoultPhase::Old;
  double age = 1;       // growth age: [0, 1) Growing; Old: options.oldAge; Renewed: 1 + wear, up to 2
  bool present = true;  // false while Lost
};

// The time-independent part of one tract's moult: the order and window of every feather.
struct MoultPlan {
  MoultOptions options;
  std::vector<double> distance;  // d in [0, 1] from the moult start (normalised over the tract)
  std::vector<double> order;     // position in the moult order, [0, 1] (after jitter; pace Order: rank)
  std::vector<double> window;    // window width per feather, units of `order`
  double sweep = 1;              // 1 + largest window: the leading edge runs from 0 to sweep over `duration`
  size_t size() const { return order.size(); }
};

// Plans one tract: uv[i], size[i] (feather length, scene units) and id[i] (stable follicle id, drives
// the seeded randomness) for each of its feathers. Throws Error for invalid options.
MoultPlan planMoult(const std::vector<glm::dvec2>& uv, const std::vector<double>& size, const std::vector<uint64_t>& id,
                    const MoultOptions& options);

// Leading edge of the window at time t, in units of the order: < 0 before the moult, sweep after it.
double moultFront(const MoultPlan& plan, double t);
MoultState moultStateAt(const MoultPlan& plan, size_t i, double t);

// The whole coat: one plan per moulting tract.
struct CoatMoultPlan {
  std::vector<int32_t> tractPlan;  // per tract: index into plans, -1 = the tract does not moult
  std::vector<MoultPlan> plans;
  std::vector<std::vector<uint32_t>> feathers;  // per plan: coat feather of each plan entry
};

// perTract[k]: the options of tract k (nullopt or enabled = false: no moult). Feather (u,v) comes from
// params[coat.tract[i]] at its follicle; ids from follicles.id. Throws Error when a feather's follicle
// is missing from its tract's parameterization.
CoatMoultPlan planCoatMoult(const std::vector<coat::TractParameterization>& params, const coat::Follicles& follicles,
                            const coat::CoatFeathers& coat, const std::vector<std::optional<MoultOptions>>& perTract);

struct MoultStats {
  size_t old = 0, lost = 0, growing = 0, renewed = 0;
};
// Sets coat.age and coat.present at time t (feathers of non-moulting tracts: age 1, present).
MoultStats applyMoult(const CoatMoultPlan& plan, double t, coat::CoatFeathers& coat);

// JSON (docs/moult.md): keys "enabled", "start", "duration", "window", "sequence", "pace", "gap",
// "random", "seed", "center", "size_exponent", "boundary_slowdown", read on top of `defaults` (per-tract
// objects override the scene-level one). Calls r.finish().
MoultOptions readMoultOptions(JsonReader& r, const MoultOptions& defaults = {});
Json moultOptionsToJson(const MoultOptions& o);

}  // namespace pteryla::moult
