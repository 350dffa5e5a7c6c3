// The dynamic blend's spring chain (moult/chain.hpp): the one-segment chain is the closed-form spring, a
// steady ramp gives the analytic trailing lag per joint, a root step bends the chain (lag and bend grow
// toward the tip) and it settles at the tip spring's analytic rate, any scrub order gives the same bits,
// and bad spring values are refused with their key path.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "pteryla/core/error.hpp"
#include "pteryla/moult/chain.hpp"
#include "pteryla/moult/controls.hpp"
#include "pteryla/moult/keyframes.hpp"

using namespace pteryla;
using namespace pteryla::moult;

namespace {

// A drive of `count` chains at `root + shift * i` following a track.
ChainDrive trackDrive(const Track& u, size_t count = 1) {
  ChainDrive d;
  d.count = count;
  d.start = u.t.front();
  d.end = u.t.back();
  d.at = [u, count](double t, std::vector<glm::dvec3>& out) {
    out.resize(count);
    for (size_t i = 0; i < count; ++i) out[i] = glm::dvec3(0.5 * static_cast<double>(i), 1.0, -0.25) + u.at(t);
  };
  return d;
}

// The root jumps by `jump` at t = 1 (a step key in the skeleton animation, as a drive).
ChainDrive stepDrive(const glm::dvec3& jump) {
  ChainDrive d;
  d.count = 1;
  d.start = 0;
  d.end = 1;
  d.at = [jump](double t, std::vector<glm::dvec3>& out) {
    out.assign(1, glm::dvec3(0.3, 0.2, 0.1) + (t >= 1 ? jump : glm::dvec3(0.0)));
  };
  return d;
}

bool sameBits(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::dvec3)) == 0;
}

Track offsetTrack(Interpolation in) {
  Track u;
  // Keys on the chain's grid (powers of two), so the linear drive is exact across every step.
  u.addKey(0.0, {0, 0, 0});
  u.addKey(1.0, {0.3, 0.1, 0});
  u.addKey(1.75, {0.3, -0.2, 0.4});
  u.addKey(3.0, {0, 0, 0});
  u.interpolation = in;
  return u;
}

}  // namespace

TEST(Chain, StepIsAPowerOfTwoAndStagesStiffenTowardTheRoot) {
  EXPECT_EQ(chainStep(1.5, 6), 1.0 / 256);  // 1 / (16 * 6 * 1.5) = 1 / 144
  EXPECT_EQ(chainStep(1.0, 1), 1.0 / 16);
  EXPECT_EQ(chainStep(1e6, 16), std::ldexp(1.0, -12));  // clamped
  EXPECT_EQ(chainStep(1e-4, 1), 1.0);
  EXPECT_DOUBLE_EQ(chainStageFrequency(1.5, 6, 6), 1.5);  // the tip rings at the spring's frequency
  EXPECT_DOUBLE_EQ(chainStageFrequency(1.5, 6, 1), 9.0);
}

TEST(Chain, OneSegmentIsTheClosedFormSpring) {
  for (Interpolation in : {Interpolation::Linear, Interpolation::Smooth}) {
    const Track u = offsetTrack(in);
    for (double zeta : {0.0, 0.3, 1.0, 2.5}) {
      ChainSim sim(1.2, zeta, 1, trackDrive(u));
      std::vector<glm::dvec3> lag;
      for (double t : {-1.0, 0.6, 1.7, 2.2, 4.5, 40.0}) {
        sim.lags(t, lag);
        ASSERT_EQ(lag.size(), 1u);
        const glm::dvec3 exact = springLag(u, 1.2, zeta, t);
        // Linear keys on the grid: exact steps (rounding only). Smooth keys: the cubic drive is taken
        // linear across each step (h = 1/32, 16 steps per cycle), a second-order error (< 0.3% of the
        // offset's 0.5 here).
        const double tol = in == Interpolation::Linear ? 1e-9 : 1.5e-3;
        EXPECT_LT(glm::length(lag[0] - exact), tol) << interpolationName(in) << " zeta " << zeta << " t " << t;
      }
    }
  }
}

TEST(Chain, SteadyRampTrailsByTheSumOfStageLags) {
  // b = v t: stage j trails its parent by 2 zeta v / w_j, w_j = 2 pi f N / j, so joint k trails the root
  // by 2 zeta v k (k + 1) / (2 w N): growing toward the tip, the tip at (N + 1) / 2 rigid springs' lag.
  Track ramp;
  ramp.addKey(0, {0, 0, 0});
  ramp.addKey(100, {100, 0, 0});
  const int n = 4;
  const double f = 2.0, zeta = 0.7, w = 2 * M_PI * f;
  ChainSim sim(f, zeta, n, trackDrive(ramp, 3));
  std::vector<glm::dvec3> lag;
  sim.lags(60.3, lag);
  ASSERT_EQ(lag.size(), 3u * n);
  for (size_t c = 0; c < 3; ++c)
    for (int k = 1; k <= n; ++k) {
      const double expected = -2 * zeta * k * (k + 1) / (2.0 * w * n);
      EXPECT_NEAR(lag[c * n + static_cast<size_t>(k) - 1].x, expected, 1e-9) << "chain " << c << " joint " << k;
      EXPECT_NEAR(lag[c * n + static_cast<size_t>(k) - 1].y, 0.0, 1e-12);
    }
}

TEST(Chain, RootStepBendsTheShaftThenSettlesAtTheTipSpringRate) {
  const glm::dvec3 jump(0.0, 0.08, 0.02);
  const int n = 6;
  const double f = 1.5, w = 2 * M_PI * f;
  std::vector<glm::dvec3> lag;
  {
    // Critically damped: right after the step no joint has caught up (lag = -jump everywhere); the
    // stiff root segment follows first and the catching up travels to the tip, so every joint trails
    // (opposite the motion), the lag grows strictly from root to tip, and the shaft is bent, not turned:
    // joints are off the straight line from the root to the lagging tip.
    ChainSim sim(f, 1.0, n, stepDrive(jump));
    sim.lags(0.999, lag);
    for (const glm::dvec3& l : lag) EXPECT_EQ(l, glm::dvec3(0.0));  // at rest before the step
    for (double dt : {0.05, 0.1, 0.2, 0.3, 0.4, 0.6}) {
      sim.lags(1 + dt, lag);
      ASSERT_EQ(lag.size(), static_cast<size_t>(n));
      double prevLen = 0;
      for (int k = 0; k < n; ++k) {
        const glm::dvec3& l = lag[static_cast<size_t>(k)];
        EXPECT_GT(glm::length(l), prevLen) << "dt " << dt << " joint " << k + 1;
        EXPECT_LT(glm::dot(l, jump), 0.0) << "dt " << dt << " joint " << k + 1;
        EXPECT_LE(glm::length(l), glm::length(jump) * (1 + 1e-12));
        prevLen = glm::length(l);
      }
      // A rigidly turned shaft would put joint k at k / N of the tip's lag.
      double offLine = 0;
      for (int k = 1; k <= n; ++k)
        offLine = std::max(offLine, glm::length(lag[static_cast<size_t>(k) - 1] - (double(k) / n) * lag.back()));
      EXPECT_GT(offLine, 0.1 * glm::length(lag.back())) << "dt " << dt;
    }
    EXPECT_LT(glm::length(lag[0]), 1e-3 * glm::length(jump));  // the root segment is back on the rig
  }
  {
    // The default spring (underdamped): the tip still trails most while the others swing through, and
    // it settles on the tip spring's time scale 1 / (zeta w): after one of them it has not, within 12 of
    // them its lag is below 0.1% of the step.
    const double zeta = 0.4;
    ChainSim sim(f, zeta, n, stepDrive(jump));
    for (double dt : {0.05, 0.1, 0.2, 0.3}) {
      sim.lags(1 + dt, lag);
      for (int k = 0; k + 1 < n; ++k) EXPECT_GT(glm::length(lag.back()), glm::length(lag[static_cast<size_t>(k)]));
      EXPECT_LT(glm::dot(lag.back(), jump), 0.0);
    }
    sim.lags(1 + 1 / (zeta * w), lag);
    EXPECT_GT(glm::length(lag.back()), 0.01 * glm::length(jump));
    sim.lags(1 + 12 / (zeta * w), lag);
    EXPECT_LT(glm::length(lag.back()), 1e-3 * glm::length(jump));
  }
  // Overdamped: late in the settling the tip's lag decays at the slowest stage's analytic rate,
  // w (zeta - sqrt(zeta^2 - 1)) (the tip's; the stiffer stages toward the root decay faster).
  const double zo = 1.5, rate = w * (zo - std::sqrt(zo * zo - 1));
  ChainSim over(f, zo, 4, stepDrive(jump));
  std::vector<glm::dvec3> a, b;
  over.lags(9.0, a);
  over.lags(10.0, b);
  const double measured = std::log(glm::length(a.back()) / glm::length(b.back()));
  EXPECT_NEAR(measured, rate, 0.02 * rate);
}

TEST(Chain, AnyScrubOrderGivesTheBitsOfAFreshEvaluation) {
  Track u = offsetTrack(Interpolation::Smooth);
  std::vector<double> times = {-0.5, 0.0, 0.001, 0.37, 1.0, 1.2345, 2.0, 2.99, 3.0, 3.0001, 7.5, 150.25};
  auto make = [&] { return ChainSim(1.5, 0.4, 6, trackDrive(u, 4)); };
  std::vector<std::vector<glm::dvec3>> fresh(times.size());
  for (size_t i = 0; i < times.size(); ++i) {
    ChainSim sim = make();
    sim.lags(times[i], fresh[i]);
  }
  EXPECT_GT(glm::length(fresh[5][5]), 1e-3);  // the chain really moves
  std::vector<size_t> order(times.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  ChainSim forward = make(), backward = make(), shuffled = make();
  std::vector<glm::dvec3> lag;
  for (size_t i : order) {
    forward.lags(times[i], lag);
    EXPECT_TRUE(sameBits(lag, fresh[i])) << "forward t " << times[i];
  }
  std::reverse(order.begin(), order.end());
  for (size_t i : order) {
    backward.lags(times[i], lag);
    EXPECT_TRUE(sameBits(lag, fresh[i])) << "backward t " << times[i];
  }
  std::mt19937 rng(7);
  for (int round = 0; round < 3; ++round) {
    std::shuffle(order.begin(), order.end(), rng);
    for (size_t i : order) {
      shuffled.lags(times[i], lag);
      EXPECT_TRUE(sameBits(lag, fresh[i])) << "shuffled t " << times[i];
    }
  }
  // Scrubbing back re-integrates from a checkpoint, not from the start; forward continues.
  ChainSim sim = make();
  sim.lags(2.9, lag);
  const size_t first = sim.lastSteps();
  sim.lags(2.95, lag);
  EXPECT_LT(sim.lastSteps(), first / 10);
  sim.lags(2.5, lag);
  EXPECT_LT(sim.lastSteps(), first / 2);
  EXPECT_GT(sim.checkpoints(), 1u);
  // Late times past the last key cost no stepping beyond it.
  sim.lags(1e6, lag);
  EXPECT_LT(sim.lastSteps(), first);
}

TEST(Chain, BadSpringValuesAreRefusedWithTheirKeyPath) {
  struct Case {
    const char* spring;
    const char* element;
  };
  const Case cases[] = {{R"({"frequency": 0})", "controls[0].spring.frequency"},
                        {R"({"frequency": -1})", "controls[0].spring.frequency"},
                        {R"({"damping": -0.1})", "controls[0].spring.damping"},
                        {R"({"segments": 0})", "controls[0].spring.segments"},
                        {R"({"segments": 17})", "controls[0].spring.segments"},
                        {R"({"segments": 2.5})", "controls[0].spring.segments"},
                        {R"({"segments": "six"})", "controls[0].spring.segments"},
                        {R"({"segmnets": 4})", "controls[0].spring.segmnets"}};
  for (const Case& c : cases) {
    Json j = Json::parse(R"([{"at": [0, 0, 0], "radius": 0.1, "dynamic": 1}])");
    j[0]["spring"] = Json::parse(c.spring);
    try {
      readControls(j, "scene.json");
      ADD_FAILURE() << "accepted " << c.spring;
    } catch (const Error& e) {
      EXPECT_EQ(e.element(), c.element) << c.spring << ": " << e.what();
      EXPECT_EQ(e.file(), "scene.json");
    }
  }
  Json ok = Json::parse(R"([{"at": [0, 0, 0], "radius": 0.1, "dynamic": 1,
                             "spring": {"frequency": 2, "damping": 0.5, "segments": 8}}])");
  const std::vector<ControlSpec> cs = readControls(ok, "scene.json");
  EXPECT_EQ(cs[0].chainSegments, 8);
  EXPECT_EQ(readControls(Json::parse(R"([{"at": [0, 0, 0], "radius": 0.1}])"), "s.json")[0].chainSegments,
            kDefaultChainSegments);
}
