// Cross-tract layer order (flow potential, ordering.hpp) and packing across a tract border; the
// min_elevation_deg styling bound (style.hpp, 8.3).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>

#include "pack_fixtures.hpp"
#include "pteryla/coat/check.hpp"
#include "pteryla/coat/ordering.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/primitives.hpp"
#include "pteryla/coat/style.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"

using namespace pteryla;
using namespace pteryla::coat;
using glm::dvec3;

namespace {

constexpr double kC = 1.2;  // centre of the patch [0, 2.4]^2

// A flat patch (normal +z) with two tracts meeting at x = kC: feathers of the left tract point along +x,
// those of the right tract turn by `turnDeg` toward +y, as at a border between body and wing coverts.
struct BorderScene {
  SkinMesh skin;
  CoatFeathers coat;
  double spacing = 0;
};

BorderScene borderScene(double turnDeg, double spacing = 0.1, double lengthInSpacings = 2.2) {
  BorderScene s;
  s.spacing = spacing;
  s.skin = makeGridPatch(24, 24, 2 * kC, 2 * kC);
  const double turn = turnDeg * 3.14159265358979323846 / 180;
  const double scale = lengthInSpacings * spacing / 0.42;  // contourFeather is ~0.42 * scale long
  const feather::FeatherParams p = packtest::contourFeather(scale);
  const double rowH = spacing * std::sqrt(3.0) / 2;
  uint32_t id = 0;
  for (int row = 0; row * rowH <= 1.4; ++row)
    for (double x = -0.7 + ((row % 2) ? 0.5 * spacing : 0.0); x <= 0.7; x += spacing) {
      const double y = -0.7 + row * rowH;
      if (y > 0.7) continue;
      FeatherFrame f;
      // Small seeded jitter so no two rows are exactly aligned.
      f.origin = {kC + x + 0.1 * spacing * (hashUniform(7, id, 0) - 0.5),
                  kC + y + 0.1 * spacing * (hashUniform(7, id, 1) - 0.5), 0};
      f.normal = {0, 0, 1};
      const bool right = f.origin.x > kC;
      f.tangent = right ? dvec3(std::cos(turn), std::sin(turn), 0) : dvec3(1, 0, 0);
      f.binormal = glm::cross(f.normal, f.tangent);
      s.coat.follicle.push_back(id);
      s.coat.tract.push_back(right ? 1 : 0);
      s.coat.params.push_back(p);
      s.coat.frames.push_back(f);
      s.coat.age.push_back(1.0);
      s.coat.present.push_back(1);
      ++id;
    }
  return s;
}

std::vector<uint32_t> orderByKey(const std::vector<double>& key) {
  std::vector<uint32_t> o(key.size());
  std::iota(o.begin(), o.end(), 0u);
  std::stable_sort(o.begin(), o.end(), [&](uint32_t a, uint32_t b) { return key[a] > key[b]; });
  return o;
}

std::vector<double> flowKey(const CoatFeathers& c) {
  std::vector<dvec3> x, d;
  for (const auto& f : c.frames) {
    x.push_back(f.origin);
    d.push_back(f.tangent);
  }
  return flowPotential(x, d);
}

}  // namespace

TEST(FlowOrder, PotentialIncreasesDownstreamOnBothSidesOfATractBorder) {
  const BorderScene s = borderScene(35);
  const std::vector<double> phi = flowKey(s.coat);
  // For every pair of neighbouring feathers, the one downstream of the other (along their mean
  // direction, by more than a third of a spacing) has the larger potential, on either side of the border
  // and across it.
  size_t checked = 0, across = 0;
  for (size_t i = 0; i < s.coat.size(); ++i)
    for (size_t j = 0; j < s.coat.size(); ++j) {
      const dvec3 d = s.coat.frames[j].origin - s.coat.frames[i].origin;
      if (i == j || glm::length(d) > 1.2 * s.spacing) continue;
      const dvec3 t = glm::normalize(s.coat.frames[i].tangent + s.coat.frames[j].tangent);
      if (glm::dot(d, t) < s.spacing / 3) continue;
      ++checked;
      across += s.coat.tract[i] != s.coat.tract[j] ? 1 : 0;
      EXPECT_GT(phi[j], phi[i]) << "feather " << j << " lies downstream of " << i;
    }
  EXPECT_GT(checked, 500u);
  EXPECT_GT(across, 20u);
}

TEST(FlowOrder, DeterministicAndParsed) {
  const BorderScene s = borderScene(35);
  const std::vector<double> a = flowKey(s.coat), b = flowKey(s.coat);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]);
  Json j = Json::parse(R"({"method": "flow", "neighbours": 6})");
  JsonReader r(j, "scene.json", "ordering");
  const OrderOptions o = parseOrdering(r);
  EXPECT_EQ(o.method, OrderMethod::Flow);
  EXPECT_EQ(o.neighbours, 6);
  Json bad = Json::parse(R"({"method": "flow", "neighbours": 0.5})");
  JsonReader rb(bad, "scene.json", "ordering");
  EXPECT_THROW(parseOrdering(rb), Error);
}

TEST(FlowOrder, TwoTractBorderPacksWithFewerIntersectionsThanTractOrder) {
  BorderScene s = borderScene(35);
  s.coat.layerOrder = orderByKey(flowKey(s.coat));
  const PackResult r = pack(s.skin, s.coat);
  // The same coat packed tract by tract (left tract first, each in its own flow order): the border is
  // where the tract order stacks feathers on the wrong neighbours.
  CoatFeathers byTract = s.coat;
  std::stable_sort(byTract.layerOrder.begin(), byTract.layerOrder.end(),
                   [&](uint32_t a, uint32_t b) { return byTract.tract[a] < byTract.tract[b]; });
  const PackResult rt = pack(s.skin, byTract);

  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const std::vector<double> flat(s.coat.size(), median(r.elevation));
  const TriMesh unpacked = proxyCoatMesh(s.coat, flat, s.coat.params);
  const TriMesh packed = proxyCoatMesh(s.coat, r.elevation, allPackedParams(s.coat, r));
  const TriMesh packedByTract = proxyCoatMesh(byTract, rt.elevation, allPackedParams(byTract, rt));
  CheckOptions co;
  co.coverage = false;
  setFeatherBases(co, s.coat, PackOptions{}.baseAllowance);
  const CheckResult before = check(s.skin, {}, unpacked, co);
  const CheckResult after = check(s.skin, {}, packed, co);
  const size_t afterByTract = countIntersectingPairs(packedByTract);
  // Measured: 390 packed vs 2371 unpacked pairs. Not yet met here: issue #8's 95% and 0 skin penetrations
  // (drooping barb tips of feathers lying almost flat dip between the skin samples: 31 vertices).
  EXPECT_EQ(before.skinPenetrations, 0u);
  EXPECT_EQ(after.skinPenetrations, 0u) << "packed vertices below the flat skin";
  EXPECT_GT(before.intersectingPairs, 1000u);
  EXPECT_LE(after.intersectingPairs * 5, before.intersectingPairs)  // >= 80% fewer
      << after.intersectingPairs << " vs " << before.intersectingPairs;
  EXPECT_LT(after.intersectingPairs, afterByTract);
  // Feathers 2.2 spacings long lie low on a flat patch.
  EXPECT_LT(median(r.elevation), 0.5);
}

TEST(StyleMinElevation, SelectedFeathersPackAtOrAboveTheBoundOthersUnchangedBelowThem) {
  BorderScene s = borderScene(0);
  s.coat.layerOrder = orderByKey(flowKey(s.coat));
  PackOptions o;
  const PackResult free = pack(s.skin, s.coat, o);
  StyleSelection sel;
  sel.kind = StyleKind::Sphere;
  sel.center = {kC, kC, 0.0};
  sel.radius = 0.25;
  sel.minElevation = 0.6;
  PackConstraints bound;
  bound.minElevation = resolveMinElevation(s.coat, {sel});
  const PackResult r = pack(s.skin, s.coat, o, bound);
  const std::vector<uint32_t> chosen = selectFeathers(s.coat, sel);
  ASSERT_GT(chosen.size(), 5u);
  std::vector<uint8_t> isChosen(s.coat.size(), 0);
  for (uint32_t i : chosen) {
    isChosen[i] = 1;
    EXPECT_GE(r.elevation[i], 0.6);
    EXPECT_GE(r.elevation[i], free.elevation[i]);  // a lower bound, never a lowering
  }
  EXPECT_EQ(r.stats.fixed, 0u);  // packed, not fixed
  // Feathers packed before the first selected one (under them) are untouched.
  size_t before = 0;
  for (uint32_t i : s.coat.layerOrder) {
    if (isChosen[i]) break;
    EXPECT_EQ(r.elevation[i], free.elevation[i]);
    ++before;
  }
  EXPECT_GT(before, 10u);
  // JSON round trip.
  Json j = Json::parse(R"({"select": "sphere", "center": [0, 0, 0], "radius": 0.25, "min_elevation_deg": 30})");
  JsonReader rd(j, "scene.json", "packing.styling[0]");
  const StyleSelection p = parseStyleSelection(rd);
  ASSERT_TRUE(p.minElevation.has_value());
  EXPECT_NEAR(*p.minElevation, 30 * 3.14159265358979323846 / 180, 1e-12);
  EXPECT_NEAR(styleSelectionToJson(p)["min_elevation_deg"].get<double>(), 30.0, 1e-9);
}

// A styling selection's shaft_band overrides packing.shaft_band for its feathers (flight feathers: the shaft
// ignores the neighbours' overlapping vanes, the barbs lift over them instead).
TEST(StyleShaftBand, OverridesTheGlobalBandForTheSelectedFeathersOnly) {
  BorderScene s = borderScene(0);
  s.coat.layerOrder = orderByKey(flowKey(s.coat));
  PackOptions wide;
  wide.shaftBand = 1.0;
  PackOptions narrow;
  narrow.shaftBand = 0.0;
  const PackResult rWide = pack(s.skin, s.coat, wide), rNarrow = pack(s.skin, s.coat, narrow);
  // Selecting every feather with band 0 under a global band of 1 is exactly the global band 0.
  StyleSelection all;
  all.kind = StyleKind::Sphere;
  all.center = {kC, kC, 0.0};
  all.radius = 100;
  all.shaftBand = 0.0;
  PackConstraints band;
  band.shaftBand = resolveShaftBand(s.coat, {all});
  const PackResult rAll = pack(s.skin, s.coat, wide, band);
  EXPECT_EQ(rAll.elevation, rNarrow.elevation);
  ASSERT_NE(rWide.elevation, rNarrow.elevation) << "the band must matter on this scene for the test to mean anything";
  // A subset: feathers under the first selected one are untouched; the first selected one sees the same
  // feathers under it with a narrower band, so it can only lie lower or equal.
  StyleSelection some = all;
  some.radius = 0.25;
  band.shaftBand = resolveShaftBand(s.coat, {some});
  const PackResult r = pack(s.skin, s.coat, wide, band);
  const std::vector<uint32_t> chosen = selectFeathers(s.coat, some);
  ASSERT_GT(chosen.size(), 5u);
  std::vector<uint8_t> isChosen(s.coat.size(), 0);
  for (uint32_t i : chosen) isChosen[i] = 1;
  for (uint32_t i : s.coat.layerOrder) {
    if (isChosen[i]) {
      EXPECT_LE(r.elevation[i], rWide.elevation[i]);
      break;
    }
    EXPECT_EQ(r.elevation[i], rWide.elevation[i]);
  }
  size_t differ = 0;
  for (uint32_t i : chosen) differ += r.elevation[i] != rWide.elevation[i] ? 1 : 0;
  EXPECT_GT(differ, 0u);
  // JSON: round trip, a selection with only a shaft band is valid, out of range is an error.
  Json j = Json::parse(R"({"select": "ids", "ids": [1, 2], "shaft_band": 0.3})");
  JsonReader rd(j, "scene.json", "packing.styling[0]");
  const StyleSelection p = parseStyleSelection(rd);
  ASSERT_TRUE(p.shaftBand.has_value());
  EXPECT_EQ(*p.shaftBand, 0.3);
  EXPECT_EQ(styleSelectionToJson(p)["shaft_band"].get<double>(), 0.3);
  Json bad = Json::parse(R"({"select": "ids", "ids": [1], "shaft_band": 1.5})");
  JsonReader rb(bad, "scene.json", "packing.styling[0]");
  EXPECT_THROW(parseStyleSelection(rb), Error);
}

// Property: on a curved skin (a torus: convex outside, saddle-shaped inside), no packed vertex lies below
// the skin outside the exempt base zone, whatever the skin sample spacing: the packer keeps feathers off
// the skin between its samples (each sample stands for the patch of skin around it), so coarse samples
// cost tightness, never penetrations. The unpacked coat (lying flat) does go through the skin.
TEST(PackSkin, NoVertexBelowACurvedSkinAtAnySampleSpacing) {
  const double R = 1.0, r = 0.4;
  const SkinMesh skin = makeTorus(40, 20, R, r);
  CoatFeathers coat;
  const feather::FeatherParams p = packtest::contourFeather(0.3 / 0.42);
  const int nu = 36, nv = 14;
  std::vector<double> key;
  for (int a = 0; a < nu; ++a)
    for (int b = 0; b < nv; ++b) {
      const uint32_t id = static_cast<uint32_t>(coat.size());
      const double u = 2 * 3.14159265358979323846 * (a + 0.5 * (b % 2) + 0.2 * hashUniform(11, id, 0)) / nu;
      const double v = 2 * 3.14159265358979323846 * (b + 0.2 * hashUniform(11, id, 1)) / nv;
      const dvec3 q((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v));
      const SurfacePoint sp = closestSurfacePoint(skin, q);
      FeatherFrame f;
      f.origin = pointAt(skin, sp);
      f.normal = normalAt(skin, sp.face, sp.bary);
      const dvec3 along(-std::sin(u), std::cos(u), 0.0);  // around the ring
      f.tangent = glm::normalize(along - glm::dot(along, f.normal) * f.normal);
      f.binormal = glm::cross(f.normal, f.tangent);
      coat.follicle.push_back(id);
      coat.tract.push_back(0);
      coat.params.push_back(p);
      coat.frames.push_back(f);
      coat.age.push_back(1.0);
      coat.present.push_back(1);
      key.push_back(-u);  // upstream first: feathers point toward growing u
    }
  coat.layerOrder = orderByKey(key);
  CheckOptions co;
  co.coverage = false;
  setFeatherBases(co, coat, PackOptions{}.baseAllowance);
  const TriMesh flat = proxyCoatMesh(coat, std::vector<double>(coat.size(), 0.0), coat.params);
  EXPECT_GT(check(skin, {}, flat, co).skinPenetrations, 100u);
  for (double spacing : {0.0, 0.03, 0.1}) {
    PackOptions o;
    o.skinSampleSpacing = spacing;
    const PackResult res = pack(skin, coat, o);
    const TriMesh packed = proxyCoatMesh(coat, res.elevation, allPackedParams(coat, res));
    const CheckResult c = check(skin, {}, packed, co);
    EXPECT_EQ(c.skinPenetrations, 0u) << "skin sample spacing " << spacing;
    EXPECT_GT(c.samplePoints, 10000u);
  }
}

// Property: packing commutes with a mirror. The mirror image of a coat (positions and frames reflected,
// each feather replaced by its mirror image: vanes swapped, lateral curvature negated) on the mirrored skin
// packs to the same elevations. A packer that prefers one side of the shaft would lay a bird's right wing
// differently from its left.
TEST(PackSymmetry, TheMirrorImageOfACoatPacksToTheSameElevations) {
  const SkinMesh skin = makeIcosphere(3);
  feather::FeatherParams p = packtest::contourFeather(0.9);
  p.left.baseAngle = 1.1;  // an asymmetric feather: a wide left vane, a narrow right one, a bent rachis
  p.right.baseAngle = 0.5;
  p.right.keyBarbs = {{0.5, {{0, 0, 0}, {0.3, 0.01, 0.01}, {0.6, 0.02, 0.0}, {0.9, 0.02, -0.05}}}};
  p.rachisLateralCurvature = 0.3;
  CoatFeathers coat = packtest::sphereCoat(skin, 260, 0.9);
  for (auto& q : coat.params) q = p;

  feather::FeatherParams pm = p;
  std::swap(pm.left, pm.right);
  std::swap(pm.silhouette.left, pm.silhouette.right);
  pm.rachisLateralCurvature = -p.rachisLateralCurvature;
  auto flip = [](glm::dvec3 v) { return glm::dvec3(-v.x, v.y, v.z); };
  std::vector<glm::dvec3> pos = skin.positions;
  for (auto& v : pos) v = flip(v);
  std::vector<std::array<uint32_t, 3>> faces = skin.faces;
  for (auto& f : faces) std::swap(f[1], f[2]);  // a reflection turns the winding
  const SkinMesh mirrorSkin = makeSkinMesh(pos, faces);
  CoatFeathers mirror = coat;
  for (size_t i = 0; i < coat.size(); ++i) {
    FeatherFrame& f = mirror.frames[i];
    f.origin = flip(f.origin);
    f.normal = flip(f.normal);
    f.tangent = flip(f.tangent);
    f.binormal = glm::cross(f.normal, f.tangent);  // = -flip(binormal): the frame stays right-handed
    mirror.params[i] = pm;
  }
  const PackResult a = pack(skin, coat), b = pack(mirrorSkin, mirror);
  double worst = 0;
  size_t worstAt = 0;
  for (size_t i = 0; i < coat.size(); ++i)
    if (std::abs(a.elevation[i] - b.elevation[i]) > worst) {
      worst = std::abs(a.elevation[i] - b.elevation[i]);
      worstAt = i;
    }
  EXPECT_LT(worst, 1e-6) << "feather " << worstAt << ": " << a.elevation[worstAt] << " vs its mirror image "
                         << b.elevation[worstAt];
}
