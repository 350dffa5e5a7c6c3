// Dynamic blend as a spring chain along the shaft (AnimFur, Grier 2019, 3.2: the base follows the rig, the
// tip a dynamic simulation), integrated with a fixed step from the clip start so every time is a pure
// function of t (chain.hpp).
#include "pteryla/moult/chain.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "pteryla/core/error.hpp"
#include "spring_internal.hpp"

namespace pteryla::moult {

namespace {

// Advances x'' + c x' + k x = k g(tau) by s, g linear from g0 to g1 over the step: particular solution
// g0 + m tau - c m / k (m the slope), homogeneous part by the exact map.
template <class V>
void springStep(const double* map, double c, double k, double s, const V& g0, const V& g1, V& x, V& v) {
  const V slope = (g1 - g0) / s;
  const V shift = slope * (c / k);
  const V h0 = x - (g0 - shift), hd0 = v - slope;
  x = g1 - shift + map[0] * h0 + map[1] * hd0;
  v = slope + map[2] * h0 + map[3] * hd0;
}

// One step of one chain: joint k driven by joint k-1 (joint 0 by the drive), root to tip, each stage's
// drive linear from its parent's old to new position.
template <class V>
void stepChain(const double* maps, const double* c, const double* k, int n, double s, V g0, V g1, V* x, V* v) {
  for (int j = 0; j < n; ++j) {
    const V old = x[j];
    springStep(maps + 4 * j, c[j], k[j], s, g0, g1, x[j], v[j]);
    g0 = old;
    g1 = x[j];
  }
}

using Matrix = std::vector<double>;  // row-major, d x d

Matrix multiply(const Matrix& a, const Matrix& b, size_t d) {
  Matrix r(d * d, 0.0);
  for (size_t i = 0; i < d; ++i)
    for (size_t k = 0; k < d; ++k) {
      const double aik = a[i * d + k];
      if (aik == 0) continue;
      for (size_t j = 0; j < d; ++j) r[i * d + j] += aik * b[k * d + j];
    }
  return r;
}

}  // namespace

double chainStageFrequency(double frequency, int segments, int k) {
  return frequency * static_cast<double>(segments) / static_cast<double>(k);
}

double chainStep(double frequency, int segments) {
  const double x = 1.0 / (16.0 * static_cast<double>(segments) * frequency);
  int e = 0;
  std::frexp(x, &e);  // x = m 2^e, m in [0.5, 1): the largest power of two <= x is 2^(e - 1)
  return std::ldexp(1.0, std::clamp(e - 1, -12, 0));
}

ChainSim::ChainSim(double frequency, double damping, int segments, ChainDrive drive)
    : n_(segments), zeta_(damping), drive_(std::move(drive)) {
  PTERYLA_CHECK(frequency > 0 && std::isfinite(frequency), "chain frequency must be positive");
  PTERYLA_CHECK(damping >= 0 && std::isfinite(damping), "chain damping must be >= 0");
  PTERYLA_CHECK(segments >= 1 && segments <= kMaxChainSegments, "chain segments out of range");
  h_ = chainStep(frequency, segments);
  for (int k = 1; k <= n_; ++k) {
    const double w = 2 * spring::kPi * chainStageFrequency(frequency, segments, k);
    stages_.push_back({w, 2 * damping * w, w * w});
    const spring::SpringMap m = spring::springMap(w, damping, h_);
    stepMap_.insert(stepMap_.end(), {m.a, m.b, m.c, m.d});
  }
  if (drive_.start <= drive_.end) {
    const double q = std::ceil((drive_.end - drive_.start) / h_);
    last_ = static_cast<int64_t>(std::min(q, 4.0e15));
    every_ = std::max<int64_t>(64, last_ / 64 + 1);
  }
}

void ChainSim::initial(State& s) const {
  s.n = 0;
  drive_.at(drive_.start, s.b);
  PTERYLA_CHECK_EQ(s.b.size(), drive_.count, "chain drive returned the wrong number of positions");
  s.x.assign(drive_.count * static_cast<size_t>(n_), glm::dvec3(0.0));
  s.v.assign(s.x.size(), glm::dvec3(0.0));
  for (size_t c = 0; c < drive_.count; ++c)
    for (int k = 0; k < n_; ++k) s.x[c * static_cast<size_t>(n_) + static_cast<size_t>(k)] = s.b[c];
}

void ChainSim::advance(State& s) {
  drive_.at(gridTime(s.n + 1), scratch_);
  PTERYLA_CHECK_EQ(scratch_.size(), drive_.count, "chain drive returned the wrong number of positions");
  std::vector<double> c(static_cast<size_t>(n_)), k(static_cast<size_t>(n_));
  for (int j = 0; j < n_; ++j) {
    c[static_cast<size_t>(j)] = stages_[static_cast<size_t>(j)].c;
    k[static_cast<size_t>(j)] = stages_[static_cast<size_t>(j)].k;
  }
  const size_t N = static_cast<size_t>(n_);
  for (size_t ch = 0; ch < drive_.count; ++ch)
    stepChain(stepMap_.data(), c.data(), k.data(), n_, h_, s.b[ch], scratch_[ch], s.x.data() + ch * N,
              s.v.data() + ch * N);
  std::swap(s.b, scratch_);
  ++s.n;
}

// The state at grid step n (0 <= n <= last_): from the cursor when it is at or before n and after every
// earlier checkpoint, else from the nearest earlier checkpoint. Every path steps the same grid from the
// same start state, so the bits do not depend on which one is taken.
const ChainSim::State& ChainSim::stateAt(int64_t n) {
  if (checkpoints_.empty()) {
    initial(cursor_);
    checkpoints_[0] = cursor_;
  }
  auto it = checkpoints_.upper_bound(n);
  --it;  // checkpoint 0 exists
  if (!(cursor_.n <= n && cursor_.n >= it->first)) cursor_ = it->second;
  while (cursor_.n < n) {
    advance(cursor_);
    ++lastSteps_;
    if (cursor_.n % every_ == 0) checkpoints_.emplace(cursor_.n, cursor_);
  }
  return cursor_;
}

void ChainSim::lags(double t, std::vector<glm::dvec3>& out) {
  const size_t N = static_cast<size_t>(n_);
  out.assign(drive_.count * N, glm::dvec3(0.0));
  lastSteps_ = 0;
  if (drive_.count == 0 || !(drive_.start <= drive_.end) || !(t > drive_.start)) return;
  const double q = std::floor(std::min((t - drive_.start) / h_, 4.0e15));
  const int64_t n = static_cast<int64_t>(q);
  std::vector<double> c(N), k(N), partial(4 * N);
  for (size_t j = 0; j < N; ++j) {
    c[j] = stages_[j].c;
    k[j] = stages_[j].k;
  }
  const double s = std::max(0.0, t - gridTime(n));
  if (s > 0)
    for (size_t j = 0; j < N; ++j) {
      const spring::SpringMap m = spring::springMap(stages_[j].w, zeta_, s);
      partial[4 * j] = m.a;
      partial[4 * j + 1] = m.b;
      partial[4 * j + 2] = m.c;
      partial[4 * j + 3] = m.d;
    }
  if (n <= last_) {
    const State& st = stateAt(n);
    std::vector<glm::dvec3> bt;
    if (s > 0) drive_.at(t, bt);
    for (size_t ch = 0; ch < drive_.count; ++ch) {
      glm::dvec3* o = out.data() + ch * N;
      const glm::dvec3* x = st.x.data() + ch * N;
      if (!(s > 0)) {
        for (size_t j = 0; j < N; ++j) o[j] = x[j] - st.b[ch];
        continue;
      }
      std::vector<glm::dvec3> xx(x, x + N), vv(st.v.data() + ch * N, st.v.data() + (ch + 1) * N);
      stepChain(partial.data(), c.data(), k.data(), n_, s, st.b[ch], bt[ch], xx.data(), vv.data());
      for (size_t j = 0; j < N; ++j) o[j] = xx[j] - bt[ch];
    }
    return;
  }
  // After the drive's last key: the drive stays at its final value, and in coordinates relative to it
  // the step is the same linear map M for every chain and axis: the state is M^(n - last) applied to the
  // state at the last grid step, then the partial step.
  const State& st = stateAt(last_);
  const size_t d = 2 * N;
  Matrix m(d * d, 0.0);
  for (size_t col = 0; col < d; ++col) {
    std::vector<double> x(N, 0.0), v(N, 0.0);
    (col < N ? x[col] : v[col - N]) = 1.0;
    stepChain(stepMap_.data(), c.data(), k.data(), n_, h_, 0.0, 0.0, x.data(), v.data());
    for (size_t row = 0; row < N; ++row) {
      m[row * d + col] = x[row];
      m[(row + N) * d + col] = v[row];
    }
  }
  Matrix power(d * d, 0.0);
  for (size_t i = 0; i < d; ++i) power[i * d + i] = 1.0;
  for (uint64_t e = static_cast<uint64_t>(n - last_); e > 0; e >>= 1) {
    if (e & 1) power = multiply(m, power, d);
    if (e > 1) m = multiply(m, m, d);
  }
  for (size_t ch = 0; ch < drive_.count; ++ch) {
    std::vector<glm::dvec3> z(d), x(N), v(N);
    for (size_t j = 0; j < N; ++j) {
      z[j] = st.x[ch * N + j] - st.b[ch];
      z[N + j] = st.v[ch * N + j];
    }
    for (size_t row = 0; row < d; ++row) {
      glm::dvec3 acc(0.0);
      for (size_t col = 0; col < d; ++col) acc += power[row * d + col] * z[col];
      (row < N ? x[row] : v[row - N]) = acc;
    }
    if (s > 0)
      stepChain(partial.data(), c.data(), k.data(), n_, s, glm::dvec3(0.0), glm::dvec3(0.0), x.data(), v.data());
    for (size_t j = 0; j < N; ++j) out[ch * N + j] = x[j];
  }
}

}  // namespace pteryla::moult
