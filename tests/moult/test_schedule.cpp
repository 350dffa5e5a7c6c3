// Moult replacement (Streit 2003, 8.2): ages stay in range, the window holds the declared number of
// feathers, sequences visit feathers in their declared order, randomness is seeded.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/moult/schedule.hpp"

using namespace pteryla;
using namespace pteryla::moult;

namespace {

struct Tract {
  std::vector<glm::dvec2> uv;
  std::vector<double> size;
  std::vector<uint64_t> id;
};

// n follicles scattered over a 1 x 0.6 (u,v) rectangle, sizes varying along u.
Tract randomTract(size_t n, uint64_t seed = 7) {
  Tract t;
  Rng rng(seed);
  for (size_t i = 0; i < n; ++i) {
    t.uv.push_back({rng.uniform(), 0.6 * rng.uniform()});
    t.size.push_back(0.5 + t.uv.back().x);
    t.id.push_back(1000 + 3 * i);
  }
  return t;
}

const MoultSequence kAll[] = {MoultSequence::CentreOut,   MoultSequence::BoundaryIn,  MoultSequence::CentreOutU,
                              MoultSequence::BoundaryInU, MoultSequence::CentreOutV,  MoultSequence::BoundaryInV,
                              MoultSequence::IncreasingU, MoultSequence::DecreasingU, MoultSequence::IncreasingV,
                              MoultSequence::DecreasingV, MoultSequence::Radial,      MoultSequence::Random};

// The time at which feather i leaves the Old phase.
double dropTime(const MoultPlan& p, size_t i) { return p.options.start + p.options.duration * p.order[i] / p.sweep; }

}  // namespace

TEST(MoultSchedule, AgesStayInRangeOrFeatherIsAbsent) {
  const Tract t = randomTract(300);
  for (MoultSequence s : kAll) {
    for (MoultPace pace : {MoultPace::Order, MoultPace::Distance}) {
      MoultOptions o;
      o.sequence = s;
      o.pace = pace;
      o.start = 2;
      o.duration = 8;
      o.window = 0.3;
      o.gap = 0.15;
      o.random = 0.3;
      o.sizeExponent = 1.5;
      o.boundarySlowdown = 0.8;
      const MoultPlan p = planMoult(t.uv, t.size, t.id, o);
      for (size_t i = 0; i < p.size(); ++i) {
        EXPECT_GE(p.distance[i], 0.0);
        EXPECT_LE(p.distance[i], 1.0);
        EXPECT_GE(p.order[i], 0.0);
        EXPECT_LE(p.order[i], 1.0);
      }
      for (int k = -5; k <= 125; ++k) {
        const double time = k * 0.1;
        for (size_t i = 0; i < p.size(); ++i) {
          const MoultState st = moultStateAt(p, i, time);
          if (!st.present) {
            EXPECT_EQ(st.phase, MoultPhase::Lost);
            continue;
          }
          ASSERT_GE(st.age, 0.0);
          ASSERT_LE(st.age, 1.0);
          if (time <= 2.0 || time >= 10.0) {
            ASSERT_EQ(st.age, 1.0) << "outside the moult interval every feather is mature";
          }
        }
      }
    }
  }
}

TEST(MoultSchedule, WindowHoldsTheDeclaredNumberOfFeathers) {
  const size_t n = 401;
  const Tract t = randomTract(n);
  for (double w : {0.05, 0.1, 0.25}) {
    MoultOptions o;
    o.window = w;
    o.gap = 0.2;
    o.duration = 10;
    o.sequence = MoultSequence::IncreasingU;
    const MoultPlan p = planMoult(t.uv, t.size, t.id, o);
    // While the window is entirely inside the order (front in [w, 1]), it holds w (n - 1) feathers:
    // (1 - gap) of them growing and gap of them absent.
    for (double front = w + 0.01; front <= 1.0; front += 0.037) {
      const double time = o.start + o.duration * front / p.sweep;
      size_t lost = 0, growing = 0;
      for (size_t i = 0; i < n; ++i) {
        const MoultState st = moultStateAt(p, i, time);
        lost += st.phase == MoultPhase::Lost;
        growing += st.phase == MoultPhase::Growing;
      }
      const double expected = w * (n - 1);
      EXPECT_NEAR(double(lost + growing), expected, 1.01) << "w " << w << " front " << front;
      EXPECT_NEAR(double(growing), (1 - o.gap) * expected, 1.01);
      EXPECT_NEAR(double(lost), o.gap * expected, 1.01);
    }
  }
}

TEST(MoultSchedule, SequencesVisitFeathersInDeclaredOrder) {
  const Tract t = randomTract(250);
  const glm::dvec2 centre(0.4, 0.25);
  // The quantity each sequence must be non-decreasing in (ties allowed).
  auto measure = [&](MoultSequence s, const glm::dvec2& q) -> double {
    glm::dvec2 lo(1e9), hi(-1e9);
    for (const auto& p : t.uv) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    const glm::dvec2 half = glm::max(centre - lo, hi - centre);
    const glm::dvec2 e = (q - centre) / half;
    switch (s) {
      case MoultSequence::CentreOut:
        return glm::length(e);
      case MoultSequence::BoundaryIn:
        return -glm::length(e);
      case MoultSequence::CentreOutU:
        return std::abs(q.x - centre.x);
      case MoultSequence::BoundaryInU:
        return -std::abs(q.x - centre.x);
      case MoultSequence::CentreOutV:
        return std::abs(q.y - centre.y);
      case MoultSequence::BoundaryInV:
        return -std::abs(q.y - centre.y);
      case MoultSequence::IncreasingU:
        return q.x;
      case MoultSequence::DecreasingU:
        return -q.x;
      case MoultSequence::IncreasingV:
        return q.y;
      case MoultSequence::DecreasingV:
        return -q.y;
      case MoultSequence::Radial:
        return glm::length(q - centre);
      case MoultSequence::Random:
        return 0;
    }
    return 0;
  };
  for (MoultSequence s : kAll) {
    if (s == MoultSequence::Random) continue;
    MoultOptions o;
    o.sequence = s;
    o.center = centre;
    o.window = 0.1;
    const MoultPlan p = planMoult(t.uv, t.size, t.id, o);
    std::vector<size_t> idx(p.size());
    std::iota(idx.begin(), idx.end(), size_t(0));
    std::sort(idx.begin(), idx.end(), [&](size_t a, size_t b) { return p.order[a] < p.order[b]; });
    for (size_t k = 1; k < idx.size(); ++k) {
      const double m0 = measure(s, t.uv[idx[k - 1]]), m1 = measure(s, t.uv[idx[k]]);
      EXPECT_LE(m0, m1 + 1e-12) << moultSequenceName(s) << " at rank " << k;
      EXPECT_LE(p.distance[idx[k - 1]], p.distance[idx[k]]) << moultSequenceName(s) << ": d non-decreasing";
      // Feathers drop in that order.
      EXPECT_LE(dropTime(p, idx[k - 1]), dropTime(p, idx[k]));
    }
    // The first feather to go is the one the sequence names, and it really drops at its time.
    const size_t first = idx.front();
    EXPECT_EQ(moultStateAt(p, first, dropTime(p, first) - 1e-9).phase, MoultPhase::Old);
    EXPECT_EQ(moultStateAt(p, first, dropTime(p, first) + 1e-6).phase, MoultPhase::Lost);
  }
}

TEST(MoultSchedule, RandomnessIsSeededAndOptional) {
  const Tract t = randomTract(200);
  MoultOptions o;
  o.sequence = MoultSequence::Random;
  o.seed = 11;
  const MoultPlan a = planMoult(t.uv, t.size, t.id, o), b = planMoult(t.uv, t.size, t.id, o);
  EXPECT_EQ(a.order, b.order);
  o.seed = 12;
  const MoultPlan c = planMoult(t.uv, t.size, t.id, o);
  EXPECT_NE(a.order, c.order);

  // Jitter: 0 keeps the sequence strict, > 0 breaks it (but stays deterministic).
  MoultOptions r;
  r.sequence = MoultSequence::Radial;
  const MoultPlan strict = planMoult(t.uv, t.size, t.id, r);
  r.random = 0.5;
  const MoultPlan j1 = planMoult(t.uv, t.size, t.id, r), j2 = planMoult(t.uv, t.size, t.id, r);
  EXPECT_EQ(j1.order, j2.order);
  EXPECT_NE(j1.order, strict.order);
  EXPECT_EQ(j1.distance, strict.distance);
  size_t inversions = 0;
  for (size_t i = 0; i < t.uv.size(); ++i)
    for (size_t k = 0; k < t.uv.size(); ++k)
      if (strict.distance[i] < strict.distance[k] && j1.order[i] > j1.order[k]) ++inversions;
  EXPECT_GT(inversions, 0u);
}

TEST(MoultSchedule, LargerFeathersAndBoundaryFeathersGrowSlower) {
  const Tract t = randomTract(150);
  MoultOptions o;
  o.sizeExponent = 1.0;
  const MoultPlan p = planMoult(t.uv, t.size, t.id, o);
  for (size_t i = 0; i < t.uv.size(); ++i)
    for (size_t k = 0; k < t.uv.size(); ++k)
      if (t.size[i] > t.size[k]) {
        EXPECT_GT(p.window[i], p.window[k]);
      }
  MoultOptions b;
  b.boundarySlowdown = 2.0;
  const MoultPlan q = planMoult(t.uv, t.size, t.id, b);
  const size_t centreMost = std::min_element(q.distance.begin(), q.distance.end()) - q.distance.begin();
  const size_t outerMost = std::max_element(q.distance.begin(), q.distance.end()) - q.distance.begin();
  EXPECT_NEAR(q.window[centreMost] / b.window, 1.0, 0.2);
  EXPECT_NEAR(q.window[outerMost] / b.window, 3.0, 1e-9);
  // A wider window is still fully swept by the end of the moult.
  for (size_t i = 0; i < t.uv.size(); ++i)
    EXPECT_EQ(moultStateAt(q, i, b.start + b.duration).phase, MoultPhase::Renewed);
}

TEST(MoultSchedule, CoatPlanFollowsTractsAndOverrides) {
  // Two tracts: the first moults centre-out, the second (e.g. primaries) on its own sequence, a third not.
  coat::CoatFeathers c;
  coat::Follicles f;
  std::vector<coat::TractParameterization> params(3);
  for (uint32_t i = 0; i < 30; ++i) {
    const uint32_t tract = i % 3;
    f.face.push_back(0);
    f.bary.push_back(glm::dvec3(1.0 / 3));
    f.position.push_back(glm::dvec3(0));
    f.normal.push_back(glm::dvec3(0, 0, 1));
    f.tract.push_back(tract);
    f.pinned.push_back(0);
    f.id.push_back(100 + i);
    params[tract].follicles.push_back(i);
    params[tract].follicleUv.push_back({0.03 * i, 0.5});
    c.follicle.push_back(i);
    c.tract.push_back(tract);
    feather::FeatherParams fp;
    c.params.push_back(fp);
  }
  c.frames.resize(c.size());
  MoultOptions a;
  a.window = 0.3;
  MoultOptions b = a;
  b.sequence = MoultSequence::DecreasingU;
  b.start = 5;
  const CoatMoultPlan plan = planCoatMoult(params, f, c, {a, b, std::nullopt});
  ASSERT_EQ(plan.plans.size(), 2u);
  EXPECT_EQ(plan.tractPlan[2], -1);
  // Mid-moult of tract 0 (before tract 1 starts): only tract 0 changes.
  MoultStats st = applyMoult(plan, 0.5, c);
  for (size_t i = 0; i < c.size(); ++i) {
    if (c.tract[i] != 0) {
      EXPECT_EQ(c.age[i], 1.0);
      EXPECT_EQ(c.present[i], 1);
    }
  }
  EXPECT_GT(st.lost + st.growing, 0u);
  EXPECT_EQ(st.old + st.lost + st.growing + st.renewed, c.size());
  // Tract 1 decreasing u: its largest-u feather goes first.
  st = applyMoult(plan, 5.05, c);
  uint32_t firstOut = 0;
  double bestU = -1;
  for (size_t k = 0; k < params[1].follicles.size(); ++k)
    if (params[1].follicleUv[k].x > bestU) {
      bestU = params[1].follicleUv[k].x;
      firstOut = params[1].follicles[k];
    }
  EXPECT_TRUE(c.present[firstOut] == 0 || c.age[firstOut] < 1);
}

TEST(MoultSchedule, JsonIsStrict) {
  const Json j = Json::parse(R"({"start": 1, "duration": 4, "window": 0.2, "sequence": "center_out_v", "gap": 0.1,
                                 "random": 0.25, "seed": 3, "center": [0.2, 0.3], "pace": "distance",
                                 "size_exponent": 1, "boundary_slowdown": 0.5})");
  JsonReader r(j, "scene.json", "moult");
  const MoultOptions o = readMoultOptions(r);
  EXPECT_EQ(o.sequence, MoultSequence::CentreOutV);
  EXPECT_EQ(o.pace, MoultPace::Distance);
  ASSERT_TRUE(o.center.has_value());
  EXPECT_EQ(o.center->y, 0.3);
  // Round trip.
  const Json back = moultOptionsToJson(o);
  JsonReader r2(back, "x", "moult");
  const MoultOptions o2 = readMoultOptions(r2);
  EXPECT_EQ(moultOptionsToJson(o2), back);
  // Overrides keep the defaults they do not name.
  const Json over = Json::parse(R"({"sequence": "random"})");
  JsonReader r3(over, "scene.json", "tracts[2].moult");
  const MoultOptions o3 = readMoultOptions(r3, o);
  EXPECT_EQ(o3.sequence, MoultSequence::Random);
  EXPECT_EQ(o3.duration, 4.0);

  auto err = [](const char* text) -> std::string {
    const Json bad = Json::parse(text);
    JsonReader rr(bad, "scene.json", "moult");
    try {
      readMoultOptions(rr);
    } catch (const Error& e) {
      return e.element();
    }
    return "no error";
  };
  EXPECT_EQ(err(R"({"windw": 0.2})"), "moult.windw");
  EXPECT_EQ(err(R"({"window": 0})"), "moult.window");
  EXPECT_EQ(err(R"({"gap": 1})"), "moult.gap");
  EXPECT_EQ(err(R"({"duration": -1})"), "moult.duration");
  EXPECT_EQ(err(R"({"sequence": "spiral"})"), "moult.sequence");
  EXPECT_EQ(err(R"({"center": [1]})"), "moult.center");
}
