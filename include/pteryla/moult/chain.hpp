#pragma once
// Dynamic blend as a chain along the shaft (AnimFur, Grier 2019, 3.2 Fig. 3.2 d: "the base of the hair
// follows the rig, the tip a dynamic simulation"; a spring-bone chain as in animation rigs).
//
// A feather under a dynamic control is a chain of N segments (ControlSpec::chainSegments) from the root
// (joint 0, on the follicle) to the tip (joint N). Joint 0 follows the drive b(t) exactly; joint k >= 1
// is a damped spring pulled toward where its parent holds it:
//   x_k'' + 2 zeta w_k x_k' + w_k^2 x_k = w_k^2 (x_{k-1} + s_k),   w_k = 2 pi f N / k,
// s_k the rest segment (constant: it cancels from the lag). The drive is the root's world position on the
// skinned skin plus the control's keyed offset, b(t) = root(t) + offset(t), so both skin motion and the
// offset track make the chain lag. The lag of joint k is x_k(t) - b(t) (joint minus its rigid place).
// Stiffness falls toward the tip (w_k ~ 1 / k, a tapering rachis): the tip stage rings at the spring's
// frequency f and the lag grows from root to tip, so the shaft bends. N = 1 is the rigid feather of the
// closed-form springLag (controls.hpp): the same equation.
//
// Integration: a fixed step h (chainStep) from the clip start (the drive's first key; the chain is at rest
// there), each stage advanced by the exact solution of its spring over the step with its drive taken
// linear across the step (unconditionally stable for any frequency and damping), stages root to tip.
// The state at grid step n is the n-fold step from the start, so the lag at t is a pure function of t:
// ChainSim keeps the current grid state and checkpoints, scrubbing forward continues and scrubbing back
// restarts from the nearest earlier checkpoint, with the same bits as integrating afresh. A time between
// grid points is reached by one partial step (not stored). After the drive's last key the drive is
// constant and the (linear) step is applied by binary powers of its matrix, so late times cost
// O(log t), not O(t).
#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <vector>

namespace pteryla::moult {

constexpr int kMaxChainSegments = 16;
constexpr int kDefaultChainSegments = 6;

// Natural frequency of joint k (1 = next to the root .. N = the tip): f N / k.
double chainStageFrequency(double frequency, int segments, int k);
// The fixed step: the largest power of two <= 1 / (16 N f) (16 steps per cycle of the stiffest stage),
// clamped to [2^-12, 1] time units.
double chainStep(double frequency, int segments);

// The motion driving one control's chains.
struct ChainDrive {
  // The drive is constant before `start` and after `end` (its first and last key); start > end: still.
  double start = std::numeric_limits<double>::infinity();
  double end = -std::numeric_limits<double>::infinity();
  size_t count = 0;  // chains (follicles)
  // Drive positions b(t) of every chain at time t (out gets `count` entries). Must be a pure function of t.
  std::function<void(double t, std::vector<glm::dvec3>& out)> at;
};

class ChainSim {
 public:
  // frequency > 0, damping >= 0, 1 <= segments <= kMaxChainSegments (checked: PTERYLA_CHECK).
  ChainSim(double frequency, double damping, int segments, ChainDrive drive);

  int segments() const { return n_; }
  size_t count() const { return drive_.count; }
  double step() const { return h_; }
  double start() const { return drive_.start; }

  // Lag of every joint at t: out[c * N + k - 1] = x_k(t) - b(t) for chain c, joint k = 1..N. Zero at and
  // before the start (and always for a still drive).
  void lags(double t, std::vector<glm::dvec3>& out);

  // Diagnostics: grid steps integrated by the last lags() call, checkpoints held.
  size_t lastSteps() const { return lastSteps_; }
  size_t checkpoints() const { return checkpoints_.size(); }

 private:
  struct State {
    int64_t n = 0;
    std::vector<glm::dvec3> b;     // drive at grid step n, per chain
    std::vector<glm::dvec3> x, v;  // per chain and joint
  };
  struct Stage {
    double w, c, k;  // w, 2 zeta w, w^2
  };
  double gridTime(int64_t n) const { return drive_.start + static_cast<double>(n) * h_; }
  void initial(State& s) const;
  void advance(State& s);  // one grid step
  const State& stateAt(int64_t n);

  int n_;
  double zeta_, h_;
  ChainDrive drive_;
  std::vector<Stage> stages_;
  std::vector<double> stepMap_;  // per stage: a, b, c, d of the exact map over h
  int64_t last_ = 0;             // grid step at or after the drive's end
  int64_t every_ = 64;           // checkpoint spacing (grid steps)
  State cursor_;
  std::map<int64_t, State> checkpoints_;
  std::vector<glm::dvec3> scratch_;
  size_t lastSteps_ = 0;
};

}  // namespace pteryla::moult
