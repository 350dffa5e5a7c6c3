// Expressive controls (AnimFur): keyframe tracks, the closed-form spring against a fine numerical
// integration, binding to the nearest control, lift/aim/twist on a small packed coat, strict JSON.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <limits>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/key_feathers.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/moult/controls.hpp"
#include "pteryla/moult/keyframes.hpp"

using namespace pteryla;
using namespace pteryla::moult;

namespace {

const std::string kData = PTERYLA_DATA_DIR;

// RK4 integration of x'' + 2 zeta w x' + w^2 x = w^2 u(t) from rest at the first key, stepping each key
// interval separately with u from its own segment (so kinks and steps at keys cost no accuracy).
glm::dvec3 integrateLag(const Track& u, double freq, double zeta, double t) {
  const double w = 2 * M_PI * freq;
  glm::dvec3 x = u.at(u.t.front()), v(0.0);
  for (const TrackSegment& sg : u.segments()) {
    if (!std::isfinite(sg.start)) continue;
    const double end = std::min(t, sg.end);
    if (end <= sg.start) break;
    auto uAt = [&](double s) { return sg.c[0] + s * (sg.c[1] + s * (sg.c[2] + s * sg.c[3])); };
    auto acc = [&](double s, const glm::dvec3& xx, const glm::dvec3& vv) {
      return w * w * (uAt(s) - xx) - 2 * zeta * w * vv;
    };
    const int steps = 4000;
    const double h = (end - sg.start) / steps;
    double s = 0;
    for (int k = 0; k < steps; ++k) {
      const glm::dvec3 a1 = acc(s, x, v);
      const glm::dvec3 x2 = x + 0.5 * h * v, v2 = v + 0.5 * h * a1;
      const glm::dvec3 a2 = acc(s + 0.5 * h, x2, v2);
      const glm::dvec3 x3 = x + 0.5 * h * v2, v3 = v + 0.5 * h * a2;
      const glm::dvec3 a3 = acc(s + 0.5 * h, x3, v3);
      const glm::dvec3 x4 = x + h * v3, v4 = v + h * a3;
      const glm::dvec3 a4 = acc(s + h, x4, v4);
      x += h / 6 * (v + 2.0 * v2 + 2.0 * v3 + v4);
      v += h / 6 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
      s += h;
    }
    if (end < sg.end) break;
  }
  return x - u.at(t);
}

// A flat square coat: a grid of follicles on the patch mesh, contour feathers pointing +X.
struct SmallCoat {
  coat::SkinMesh skin;
  coat::Follicles follicles;
  coat::CoatFeathers coat;
};

SmallCoat smallCoat() {
  SmallCoat s;
  s.skin = coat::loadSkinMesh(kData + "/meshes/patch.obj");
  feather::FeatherParams p = feather::loadFeather(kData + "/feathers/contour.json");
  coat::scaleFeather(p, 0.22 / p.totalLength());
  uint64_t id = 0;
  for (int i = 0; i < 12; ++i)
    for (int k = 0; k < 12; ++k) {
      const glm::dvec3 at(-0.6 + 0.1 * i, 0.5, -0.55 + 0.1 * k);
      const coat::SurfacePoint sp = coat::closestSurfacePoint(s.skin, at);
      s.follicles.push(s.skin, sp.face, sp.bary, 0, id++);
    }
  for (uint32_t f = 0; f < s.follicles.size(); ++f) {
    s.coat.follicle.push_back(f);
    s.coat.tract.push_back(0);
    s.coat.params.push_back(p);
    coat::FeatherFrame fr;
    fr.origin = s.follicles.position[f];
    fr.normal = s.follicles.normal[f];
    fr.tangent = glm::normalize(glm::dvec3(1, 0, 0) - glm::dot(glm::dvec3(1, 0, 0), fr.normal) * fr.normal);
    fr.binormal = glm::cross(fr.normal, fr.tangent);
    s.coat.frames.push_back(fr);
    s.coat.age.push_back(1);
    s.coat.present.push_back(1);
  }
  // Roof tiles: feathers further along +X (the direction they point) lie lower.
  std::vector<uint32_t> order(s.coat.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return s.coat.frames[a].origin.x > s.coat.frames[b].origin.x; });
  s.coat.layerOrder = order;
  return s;
}

ControlSpec control(const glm::dvec3& at, double radius) {
  ControlSpec c;
  c.at = at;
  c.radius = radius;
  return c;
}

}  // namespace

TEST(Controls, TracksInterpolateAndHoldEnds) {
  Track tr;
  EXPECT_TRUE(tr.addKey(2.0, {1, 0, 0}));
  EXPECT_TRUE(tr.addKey(0.0, {0, 0, 0}));
  EXPECT_FALSE(tr.addKey(2.0, {5, 0, 0}));
  EXPECT_EQ(tr.scalarAt(-1), 0.0);
  EXPECT_EQ(tr.scalarAt(1), 0.5);
  EXPECT_EQ(tr.scalarAt(9), 1.0);
  tr.interpolation = Interpolation::Smooth;
  EXPECT_NEAR(tr.scalarAt(0.5), 0.25 * 0.25 * (3 - 0.5), 1e-15);
  tr.interpolation = Interpolation::Step;
  EXPECT_EQ(tr.scalarAt(1.99), 0.0);
  // Segments reproduce at() everywhere.
  for (Interpolation in : {Interpolation::Linear, Interpolation::Smooth, Interpolation::Step}) {
    tr.interpolation = in;
    for (const auto& s : tr.segments()) {
      if (!std::isfinite(s.start) || !std::isfinite(s.end)) continue;
      const double mid = 0.5 * (s.start + s.end), d = mid - s.start;
      const glm::dvec3 v = s.c[0] + d * (s.c[1] + d * (s.c[2] + d * s.c[3]));
      EXPECT_NEAR(v.x, tr.scalarAt(mid), 1e-12);
    }
  }
}

TEST(Controls, ClosedFormSpringMatchesIntegration) {
  Track u;
  u.addKey(0.0, {0, 0, 0});
  u.addKey(1.0, {0.3, 0.1, 0});
  u.addKey(1.7, {0.3, -0.2, 0.4});
  u.addKey(3.0, {0, 0, 0});
  for (Interpolation in : {Interpolation::Linear, Interpolation::Smooth, Interpolation::Step}) {
    u.interpolation = in;
    for (double zeta : {0.0, 0.3, 1.0, 2.5}) {
      for (double t : {0.6, 1.7, 2.2, 4.5}) {
        const glm::dvec3 exact = springLag(u, 1.2, zeta, t);
        const glm::dvec3 numeric = integrateLag(u, 1.2, zeta, t);
        EXPECT_LT(glm::length(exact - numeric), 1e-6) << interpolationName(in) << " zeta " << zeta << " t " << t;
      }
    }
  }
  // No motion, no lag; before the first key, no lag.
  Track still;
  still.addKey(0.0, {1, 2, 3});
  EXPECT_EQ(springLag(still, 1, 0.5, 10), glm::dvec3(0));
  EXPECT_EQ(springLag(u, 1, 0.5, -1), glm::dvec3(0));
  // Steady ramp: the spring trails by 2 zeta / w times the speed.
  Track ramp;
  ramp.addKey(0, {0, 0, 0});
  ramp.addKey(100, {100, 0, 0});
  const double w = 2 * M_PI * 2.0;
  EXPECT_NEAR(springLag(ramp, 2.0, 0.7, 60).x, -2 * 0.7 / w, 1e-9);
}

TEST(Controls, FolliclesBindToTheirNearestControlWithinRadius) {
  SmallCoat s = smallCoat();
  std::vector<ControlSpec> cs = {control({-0.3, 0.5, 0}, 0.25), control({0.2, 0.5, 0}, 0.25)};
  cs[1].falloff = 0.5;
  const ControlBinding b = bindControls(s.skin, s.follicles, cs);
  size_t none = 0;
  for (size_t f = 0; f < s.follicles.size(); ++f) {
    const glm::dvec3 p = s.follicles.position[f];
    const double d0 = glm::length(p - coat::pointAt(s.skin, b.anchor[0]));
    const double d1 = glm::length(p - coat::pointAt(s.skin, b.anchor[1]));
    if (b.control[f] < 0) {
      ++none;
      EXPECT_TRUE(d0 > 0.25 || d1 > 0.25 * 0.99);
      continue;
    }
    const double mine = b.control[f] == 0 ? d0 : d1, other = b.control[f] == 0 ? d1 : d0;
    EXPECT_LE(mine, 0.25);
    EXPECT_LE(mine, other);
    if (b.control[f] == 0) {
      EXPECT_EQ(b.weight[f], 1.0);
    } else if (d1 < 0.125) {
      EXPECT_EQ(b.weight[f], 1.0);  // inside the unfaded core
    } else if (d1 > 0.13) {
      EXPECT_LT(b.weight[f], 1.0);  // in the falloff band
    }
  }
  EXPECT_GT(none, s.follicles.size() / 2);
  EXPECT_GT(b.bound[0], 5u);
  EXPECT_GT(b.bound[1], 5u);
  // A tract filter excludes everything else.
  const ControlBinding filtered = bindControls(s.skin, s.follicles, cs, {{3}, {}});
  EXPECT_EQ(filtered.bound[0], 0u);
}

TEST(Controls, LiftStandsShaftsUpAndTheRestRepacksFreeOfThem) {
  SmallCoat s = smallCoat();
  coat::PackOptions po;
  po.threads = 1;
  const coat::PackResult before = coat::pack(s.skin, s.coat, po);
  std::vector<ControlSpec> cs = {control({0.0, 0.5, 0.0}, 0.2)};
  cs[0].lift.addKey(0, {0, 0, 0});
  cs[0].lift.addKey(1, {1, 0, 0});
  const ControlBinding b = bindControls(s.skin, s.follicles, cs);

  // lift 0: nothing fixed, frames unchanged.
  {
    coat::CoatFeathers c = s.coat;
    std::vector<double> fixed;
    const ControlResult r = evaluateControls(cs, b, s.skin, s.follicles, 0.0, po, {}, c, fixed);
    EXPECT_EQ(r.raised, 0u);
    EXPECT_EQ(r.turned, 0u);
    for (double e : fixed) EXPECT_TRUE(std::isnan(e));
  }
  // Half lift: halfway from the natural elevation to upright.
  {
    coat::CoatFeathers c = s.coat;
    std::vector<double> fixed;
    const ControlResult r = evaluateControls(cs, b, s.skin, s.follicles, 0.5, po, {}, c, fixed);
    ASSERT_TRUE(r.naturalPacked);
    for (uint32_t i : r.changed) EXPECT_NEAR(fixed[i], 0.5 * (before.elevation[i] + M_PI / 2), 1e-9);
  }
  coat::CoatFeathers c = s.coat;
  std::vector<double> fixed;
  const ControlResult r = evaluateControls(cs, b, s.skin, s.follicles, 2.0, po, {}, c, fixed);
  EXPECT_GT(r.raised, 5u);
  size_t below = 0;  // bound feathers not already upright
  for (size_t i = 0; i < c.size(); ++i)
    if (b.control[c.follicle[i]] == 0 && r.natural.elevation[i] < M_PI / 2) ++below;
  EXPECT_EQ(r.raised, below);
  coat::PackConstraints raised;
  raised.fixedElevation = fixed;
  const coat::PackResult after = coat::pack(s.skin, c, po, raised);
  // Repacking from the natural pack gives the same result.
  const coat::PackResult again = coat::repack(s.skin, c, r.natural, r.changed, po, raised);
  EXPECT_EQ(again.elevation, after.elevation);
  size_t pushed = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    const glm::dvec3 shaft = coat::placeDirection(c.frames[i], after.elevation[i], {1, 0, 0});
    const double angle = std::acos(std::clamp(glm::dot(shaft, c.frames[i].normal), -1.0, 1.0)) * 180 / M_PI;
    if (b.control[c.follicle[i]] == 0) {
      EXPECT_LT(angle, 10.0);
    } else if (after.elevation[i] > before.elevation[i] + 1e-9) {
      ++pushed;
    }
  }
  // Feathers resting on the raised ones were repacked higher.
  EXPECT_GT(pushed, 0u);
}

TEST(Controls, AimTurnsTowardTheControlAndTwistIsSeeded) {
  SmallCoat s = smallCoat();
  coat::PackOptions po;
  po.threads = 1;
  std::vector<ControlSpec> cs = {control({0.0, 0.5, 0.0}, 0.3)};
  cs[0].aim.addKey(0, {1, 0, 0});
  const ControlBinding b = bindControls(s.skin, s.follicles, cs);
  coat::CoatFeathers c = s.coat;
  std::vector<double> fixed;
  const ControlResult r = evaluateControls(cs, b, s.skin, s.follicles, 0.0, po, {}, c, fixed);
  EXPECT_GT(r.turned, 5u);
  const glm::dvec3 at = coat::pointAt(s.skin, b.anchor[0]);
  for (size_t i = 0; i < c.size(); ++i) {
    if (b.control[c.follicle[i]] != 0) {
      EXPECT_EQ(c.frames[i].tangent, s.coat.frames[i].tangent);
      continue;
    }
    const glm::dvec3 to = at - c.frames[i].origin;
    const glm::dvec3 N = c.frames[i].normal;
    const glm::dvec3 tp = to - glm::dot(to, N) * N;
    if (glm::length(tp) < 1e-6) continue;
    EXPECT_GT(glm::dot(c.frames[i].tangent, glm::normalize(tp)), 1 - 1e-9);
    EXPECT_NEAR(glm::dot(c.frames[i].binormal, glm::cross(N, c.frames[i].tangent)), 1.0, 1e-12);
  }
  // Random twist: per-feather, bounded by twist_angle, reproducible and seed-dependent.
  auto twisted = [&](uint64_t seed) {
    std::vector<ControlSpec> t = {control({0.0, 0.5, 0.0}, 0.3)};
    t[0].random.addKey(0, {1, 0, 0});
    t[0].seed = seed;
    t[0].twistAngle = 0.5;
    coat::CoatFeathers cc = s.coat;
    std::vector<double> fx;
    evaluateControls(t, b, s.skin, s.follicles, 0.0, po, {}, cc, fx);
    std::vector<double> ang;
    for (size_t i = 0; i < cc.size(); ++i)
      ang.push_back(std::acos(std::clamp(glm::dot(cc.frames[i].tangent, s.coat.frames[i].tangent), -1.0, 1.0)));
    return ang;
  };
  const auto a1 = twisted(1), a2 = twisted(1), a3 = twisted(2);
  EXPECT_EQ(a1, a2);
  EXPECT_NE(a1, a3);
  double maxAng = 0;
  for (double a : a1) maxAng = std::max(maxAng, a);
  EXPECT_LE(maxAng, 0.5 + 1e-9);
  EXPECT_GT(maxAng, 0.2);
  // Feathers absent at t (moulted) turn as when present: a moult frame's mature coat takes its frames from
  // the frame, and must not change as feathers come and go. Only present feathers are counted.
  std::vector<ControlSpec> both = {control({0.0, 0.5, 0.0}, 0.3)};
  both[0].aim.addKey(0, {0.5, 0, 0});
  both[0].random.addKey(0, {1, 0, 0});
  coat::CoatFeathers all = s.coat, some = s.coat;
  some.present.assign(some.size(), 1);
  for (size_t i = 0; i < some.size(); i += 3) some.present[i] = 0;
  std::vector<double> fa, fs;
  const ControlResult ra = evaluateControls(both, b, s.skin, s.follicles, 0.0, po, {}, all, fa);
  const ControlResult rs = evaluateControls(both, b, s.skin, s.follicles, 0.0, po, {}, some, fs);
  for (size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all.frames[i].tangent, some.frames[i].tangent) << i;
    EXPECT_EQ(all.frames[i].binormal, some.frames[i].binormal) << i;
  }
  EXPECT_LT(rs.turned, ra.turned);
}

TEST(Controls, JsonIsStrict) {
  const Json ok = Json::parse(R"([{"name": "crest", "at": [0, 1, 0], "radius": 0.3, "falloff": 0.2,
      "tracts": ["crest"], "seed": 4, "twist_angle": 30, "max_lift": 80, "interpolation": "smooth",
      "spring": {"frequency": 2, "damping": 0.5}, "random": 0.5,
      "keys": [{"t": 0, "lift": 0, "offset": [0, 0, 0]}, {"t": 1, "lift": 1, "aim": 0.5}, {"t": 2, "dynamic": 1}]}])");
  const auto cs = readControls(ok, "scene.json");
  ASSERT_EQ(cs.size(), 1u);
  EXPECT_EQ(cs[0].lift.t.size(), 2u);
  EXPECT_EQ(cs[0].lift.interpolation, Interpolation::Smooth);
  EXPECT_NEAR(cs[0].maxLift, 80 * M_PI / 180, 1e-15);
  EXPECT_EQ(controlValuesAt(cs[0], 5).random, 0.5);
  EXPECT_EQ(controlValuesAt(cs[0], 0.5).lift, 0.5);

  auto err = [](Json j) -> std::string {
    try {
      readControls(j, "scene.json");
    } catch (const Error& e) {
      return e.element();
    }
    return "no error";
  };
  Json j = ok;
  j[0]["lfit"] = 1;
  EXPECT_EQ(err(j), "controls[0].lfit");
  j = ok;
  j[0]["keys"][1]["lift"] = 1.5;
  EXPECT_EQ(err(j), "controls[0].keys[1].lift");
  j = ok;
  j[0]["keys"][1]["random"] = 0.2;  // also a constant
  EXPECT_EQ(err(j), "controls[0].keys[1].random");
  j = ok;
  j[0]["keys"][2] = {{"t", 1}, {"lift", 0.3}};
  EXPECT_EQ(err(j), "controls[0].keys[2].t");
  j = ok;
  j[0]["keys"][2] = {{"t", 3}};
  EXPECT_EQ(err(j), "controls[0].keys[2]");
  j = ok;
  j[0].erase("radius");
  EXPECT_EQ(err(j), "controls[0].radius");
  j = ok;
  j[0]["spring"]["mass"] = 1;
  EXPECT_EQ(err(j), "controls[0].spring.mass");
  j = ok;
  j[0]["max_lift"] = 120;
  EXPECT_EQ(err(j), "controls[0].max_lift");
  EXPECT_EQ(err(Json::object()), "controls");
}

// The caller may supply the natural pack (the pipeline repacks it from the last frame's): the raises are
// the same as with the controls' own pack, the callback runs only when a feather rises, and the result
// then carries no copy of the pack.
TEST(Controls, CallerSuppliedNaturalPackGivesTheSameRaises) {
  SmallCoat s = smallCoat();
  coat::PackOptions po;
  po.threads = 1;
  std::vector<ControlSpec> cs = {control({0.0, 0.5, 0.0}, 0.2)};
  cs[0].lift.addKey(0, {0, 0, 0});
  cs[0].lift.addKey(1, {1, 0, 0});
  const ControlBinding b = bindControls(s.skin, s.follicles, cs);
  coat::PackResult supplied;
  int calls = 0;
  const NaturalPackFn natural = [&](const coat::SkinMesh& skin, const coat::CoatFeathers& c, const coat::PackOptions& o,
                                    const coat::PackConstraints& k) -> const coat::PackResult& {
    ++calls;
    EXPECT_EQ(o.threads, 1);
    supplied = coat::pack(skin, c, o, k);
    return supplied;
  };
  {
    coat::CoatFeathers c = s.coat;
    std::vector<double> fixed;
    const ControlResult r = evaluateControls(cs, b, s.skin, s.follicles, 0.0, po, {}, c, fixed, natural);
    EXPECT_EQ(calls, 0);  // lift 0: nothing rises, no pack needed
    EXPECT_FALSE(r.naturalPacked);
  }
  coat::CoatFeathers own = s.coat, viaFn = s.coat;
  std::vector<double> fixedOwn, fixedFn;
  const ControlResult a = evaluateControls(cs, b, s.skin, s.follicles, 0.6, po, {}, own, fixedOwn);
  const ControlResult r = evaluateControls(cs, b, s.skin, s.follicles, 0.6, po, {}, viaFn, fixedFn, natural);
  EXPECT_EQ(calls, 1);
  EXPECT_TRUE(r.naturalPacked);
  EXPECT_TRUE(r.natural.elevation.empty());
  EXPECT_EQ(r.changed, a.changed);
  EXPECT_GT(r.raised, 0u);
  ASSERT_EQ(fixedFn.size(), fixedOwn.size());
  for (size_t i = 0; i < fixedFn.size(); ++i)
    EXPECT_TRUE((std::isnan(fixedFn[i]) && std::isnan(fixedOwn[i])) || fixedFn[i] == fixedOwn[i]) << i;
  EXPECT_EQ(supplied.elevation, a.natural.elevation);
}
