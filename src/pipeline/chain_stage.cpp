// The dynamic blend's chains in the controls stage (moult/chain.hpp): which follicles are simulated, the
// drive (the skeleton's skinning of their roots plus the control's offset) and the bends of the frame.
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "pteryla/moult/skinning.hpp"
#include "time_stages.hpp"

namespace pteryla::pipeline {

namespace {

// A control is dynamic when some key of its dynamic track is above 0.
bool dynamicControl(const moult::ControlSpec& c) {
  return std::any_of(c.dynamic.v.begin(), c.dynamic.v.end(), [](const glm::dvec3& v) { return v.x > 0; });
}

// The times over which a track moves: its first and last key (a single key holds still).
void widen(const std::vector<double>& keys, double& start, double& end) {
  if (keys.size() < 2) return;
  start = std::min(start, keys.front());
  end = std::max(end, keys.back());
}

// One control's drive: the roots of `chosen` skinned by `rig` (null: the rest roots, still) plus the
// control's offset. Only these roots are skinned, three vertices each, per step.
moult::ChainDrive makeDrive(const moult::ControlSpec& control, const moult::SkinRig* rig, const coat::SkinMesh& rest,
                            const coat::Follicles& follicles, const std::vector<uint32_t>& chosen) {
  struct Root {
    std::array<uint32_t, 3> vertex;
    std::array<glm::dvec3, 3> rest;
    glm::dvec3 bary;
  };
  std::vector<Root> roots;
  roots.reserve(chosen.size());
  for (uint32_t f : chosen) {
    Root r;
    r.vertex = rest.faces[follicles.face[f]];
    for (int c = 0; c < 3; ++c) r.rest[static_cast<size_t>(c)] = rest.positions[r.vertex[static_cast<size_t>(c)]];
    r.bary = follicles.bary[f];
    roots.push_back(r);
  }
  moult::ChainDrive d;
  d.count = roots.size();
  widen(control.offset.t, d.start, d.end);
  if (rig)
    for (const auto& times : rig->animation.times) widen(times, d.start, d.end);
  const moult::Track offset = control.offset;
  d.at = [rig, roots = std::move(roots), offset](double t, std::vector<glm::dvec3>& out) {
    out.resize(roots.size());
    const glm::dvec3 u = offset.at(t);
    if (!rig) {
      for (size_t i = 0; i < roots.size(); ++i) {
        const Root& r = roots[i];
        out[i] = r.bary.x * r.rest[0] + r.bary.y * r.rest[1] + r.bary.z * r.rest[2] + u;
      }
      return;
    }
    const std::vector<moult::RigidTransform> joints =
        moult::jointTransforms(rig->skeleton, moult::poseAt(rig->animation, t));
    for (size_t i = 0; i < roots.size(); ++i) {
      const Root& r = roots[i];
      glm::dvec3 p(0.0);
      for (size_t c = 0; c < 3; ++c)
        p += r.bary[static_cast<int>(c)] * moult::skinPoint(rig->skeleton, joints, r.rest[c], r.vertex[c]);
      out[i] = p + u;
    }
  };
  return d;
}

}  // namespace

void applyChains(const ControlSettings& settings, const InputKey& controlsKey, double t,
                 const coat::Follicles& follicles, const moult::ControlBinding& binding, TimeState& state,
                 const coat::CoatFeathers& coat) {
  const std::vector<moult::ControlSpec>& controls = settings.controls;
  state.bends.clear();
  state.chainSteps = 0;
  state.chainCount = 0;
  const coat::SkinMesh* rest = state.rest;
  const bool anyDynamic = std::any_of(controls.begin(), controls.end(), dynamicControl);
  if (!anyDynamic || !rest) {
    state.chains.clear();
    state.chainFollicles.clear();
    state.chainsKey = InputKey{};
    return;
  }
  // The simulators (and their checkpoints) stay valid while their inputs do: the controls and the tract
  // names they resolve, the skeleton driving them (none: 0, 0), the rest state and the follicles.
  InputKey key = controlsKey;
  key.add(state.drivingRig ? state.drivingRigKey : InputKey{0, 0}).add({state.generation, follicles.size()});
  if (key != state.chainsKey || state.chains.size() != controls.size()) {
    state.chains.clear();
    state.chains.resize(controls.size());
    state.chainFollicles.assign(controls.size(), {});
    for (size_t f = 0; f < binding.control.size(); ++f)
      if (binding.control[f] >= 0 && binding.weight[f] > 0)
        state.chainFollicles[static_cast<size_t>(binding.control[f])].push_back(static_cast<uint32_t>(f));
    for (size_t c = 0; c < controls.size(); ++c) {
      const moult::ControlSpec& cs = controls[c];
      if (!dynamicControl(cs) || state.chainFollicles[c].empty()) continue;
      state.chains[c] =
          std::make_unique<moult::ChainSim>(cs.springFrequency, cs.springDamping, cs.chainSegments,
                                            makeDrive(cs, state.drivingRig, *rest, follicles, state.chainFollicles[c]));
    }
    state.chainsKey = key;
  }
  // Per follicle: its control's chain and its index there.
  std::vector<std::pair<int32_t, uint32_t>> slot(follicles.size(), {-1, 0});
  std::vector<std::vector<glm::dvec3>> lags(controls.size());
  std::vector<double> dynamic(controls.size(), 0.0);
  for (size_t c = 0; c < controls.size(); ++c) {
    if (!state.chains[c]) continue;
    dynamic[c] = std::clamp(controls[c].dynamic.scalarAt(t), 0.0, 1.0);
    if (!(dynamic[c] > 0)) continue;
    state.chains[c]->lags(t, lags[c]);
    state.chainSteps += state.chains[c]->lastSteps();
    state.chainCount += state.chains[c]->count();
    for (size_t k = 0; k < state.chainFollicles[c].size(); ++k)
      slot[state.chainFollicles[c][k]] = {static_cast<int32_t>(c), static_cast<uint32_t>(k)};
  }
  state.bends.assign(coat.size(), feather::ShaftBend{});
  for (size_t i = 0; i < coat.size(); ++i) {
    if (!coat.present.empty() && !coat.present[i]) continue;
    const uint32_t f = coat.follicle[i];
    const auto [c, k] = slot[f];
    if (c < 0) continue;
    const size_t ci = static_cast<size_t>(c);
    const double s = dynamic[ci] * binding.weight[f];
    const size_t n = static_cast<size_t>(controls[ci].chainSegments);
    feather::ShaftBend& b = state.bends[i];
    b.length = coat.params[i].totalLength();
    b.offset.resize(n);
    for (size_t j = 0; j < n; ++j) b.offset[j] = s * lags[ci][k * n + j];
  }
}

}  // namespace pteryla::pipeline
