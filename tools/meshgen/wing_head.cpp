// The stand-alone wing (Streit 2003, section 8.3 / Fig. 8.6: a wing with two tracts, coverts and
// flight feathers, bent at elbow and wrist by vertex blending) and the head for the crest scene.
#include "cage_build.hpp"

#include "pteryla/core/error.hpp"

namespace pteryla::meshgen {

namespace {

enum WingPart { kWing = 0, kWingRootCap = 1 };
enum HeadPart { kHead = 0, kNeck = 1, kNeckCap = 2 };

// Stand-alone wing: span along +X from the shoulder at the origin, dorsal side +Y, leading edge
// towards -Z, trailing edge towards +Z. x, leading z, trailing z, thickness.
struct Station {
  double x, zLead, zTrail, thick;
};
const std::vector<Station> kStations = {
    {0.00, -0.12, 0.38, 0.16},  {0.22, -0.14, 0.42, 0.14}, {0.45, -0.15, 0.43, 0.12}, {0.70, -0.15, 0.41, 0.11},
    {0.95, -0.14, 0.37, 0.095}, {1.20, -0.12, 0.31, 0.08}, {1.42, -0.08, 0.25, 0.07}, {1.62, -0.04, 0.19, 0.06},
    {1.78, 0.00, 0.14, 0.05},   {1.89, 0.03, 0.10, 0.04},
};
const glm::dvec3 kTip(1.97, 0.0, 0.07);
constexpr int kWristStation = 5;

}  // namespace

Generated makeWing() {
  QuadCage cage;
  std::vector<std::vector<glm::dvec3>> loops;
  for (const auto& s : kStations) {
    auto at = [&](double u, double h) { return glm::dvec3(s.x, h, s.zLead + u * (s.zTrail - s.zLead)); };
    const double t = s.thick;
    loops.push_back({at(0.0, 0.32 * t), at(0.45, 0.45 * t), at(1.0, 0.0), at(0.72, -0.18 * t), at(0.44, -0.30 * t),
                     at(0.15, -0.36 * t)});
  }
  std::vector<uint32_t> root;
  for (const auto& p : loops[0]) root.push_back(cage.addVertex(p));
  const auto ids = tube(cage, root, {loops.begin() + 1, loops.end()}, kWing);
  const uint32_t tip = capPole(cage, ids.back(), kTip, kWing, static_cast<double>(ids.size() - 1), 0.5);
  capPole(cage, root, glm::dvec3(-0.03, 0.0, 0.12), kWingRootCap, 0.0, -0.5);
  std::vector<uint32_t> chain;
  for (const auto& sec : ids) chain.push_back(sec[2]);
  chain.push_back(tip);
  cage.chains.push_back(chain);

  QuadCage fine = subdivide(cage, 2);
  const Classifier classify = [](const FaceTag& tag, const glm::dvec3&) -> std::string {
    if (tag.part == kWingRootCap) return "apteria";
    const double l = tag.center().y;
    if (l >= 1.5 && l <= 2.8) return "remiges_base";
    if (l < 1.5 || l > 5.5) return "coverts";
    return "coverts_ventral";
  };
  Generated g;
  g.name = "wing";
  g.mesh = triangulate(fine, classify, {"coverts", "remiges_base", "coverts_ventral", "apteria"});
  finishSurface(g.mesh, cage);

  Skeleton& sk = g.skeleton;
  sk.joints = {{"shoulder", -1, {0.0, 0.0, 0.0}},
               {"elbow", 0, {0.62, 0.0, -0.06}},
               {"wrist", 1, {1.22, 0.0, -0.05}},
               {"wingtip", 2, {1.97, 0.0, 0.06}}};
  for (uint32_t v = 0; v < g.mesh.positions.size(); ++v) {
    const auto ws = chainWeights(v, g.mesh.positions[v], 1.0, {0, 0, 1, 2, 3}, sk, 0.25);
    sk.weights.insert(sk.weights.end(), ws.begin(), ws.end());
  }
  g.hasSkeleton = true;

  Polyline te{"trailing_edge", {}}, sec{"secondaries", {}}, pri{"primaries", {}}, span{"span_axis", {}};
  const int wristAt = kWristStation * 4;
  const auto& fc = fine.chains[0];
  for (size_t i = 0; i < fc.size(); ++i) {
    const glm::dvec3 p = g.mesh.positions[fc[i]];
    te.points.push_back(p);
    if (static_cast<int>(i) <= wristAt) sec.points.push_back(p);
    if (static_cast<int>(i) >= wristAt) pri.points.push_back(p);
  }
  for (const auto& j : sk.joints) span.points.push_back(j.position);
  g.axes = {te, sec, pri, span};
  return g;
}

namespace {

// Head: skull loft along +X (back of the skull -> beak tip), neck extruded down from the skull's
// underside. Sized for close-ups: beak tip to back of skull about 1.1 units.
const std::vector<SpineKey> kHeadKeys = {
    {-0.40, 0.02, 0.12, 0.11, 0.11},     // 0 back of the skull
    {-0.31, 0.04, 0.24, 0.22, 0.22},     // 1
    {-0.15, 0.05, 0.30, 0.30, 0.27},     // 2 neck root (rings 1..3, bottom)
    {0.03, 0.05, 0.30, 0.28, 0.27},      // 3 eyes
    {0.19, 0.03, 0.24, 0.20, 0.21},      // 4
    {0.31, 0.00, 0.16, 0.13, 0.14},      // 5 beak base
    {0.44, -0.04, 0.095, 0.08, 0.085},   // 6 beak
    {0.55, -0.08, 0.05, 0.04, 0.045},    // 7
    {0.61, -0.105, 0.022, 0.018, 0.02},  // 8 beak tip
};
constexpr double kHeadBeakS = 5.3;

}  // namespace

Generated makeHead() {
  QuadCage cage;
  const auto rings = ringsAlongSpine(kHeadKeys, 0.6);
  const std::set<std::pair<int, int>> skip = {{1, 3}, {1, 4}, {2, 3}, {2, 4}};
  const auto ring = loft(cage, rings, kHead, skip);
  const int last = static_cast<int>(rings.size()) - 1;
  capPole(cage, std::vector<uint32_t>(ring[0].begin(), ring[0].end()), rings[0].center + glm::dvec3(-0.04, 0, 0), kHead,
          0.0, -0.5);
  capPole(cage, std::vector<uint32_t>(ring[last].begin(), ring[last].end()),
          rings[last].center + glm::dvec3(0.025, -0.01, 0), kHead, last, 0.5);

  // Neck: the boundary of the 2x2 patch under rings 1..3, extruded downwards and slightly back.
  const std::vector<uint32_t> root = {ring[1][3], ring[2][3], ring[3][3], ring[3][4],
                                      ring[3][5], ring[2][5], ring[1][5], ring[1][4]};
  glm::dvec3 rootCentre(0.0);
  for (uint32_t v : root) rootCentre += cage.positions[v];
  rootCentre /= double(root.size());
  struct NeckKey {
    double y, dx, rx, rz;
  };
  const std::vector<NeckKey> keys = {
      {-0.42, -0.06, 0.20, 0.19}, {-0.66, -0.10, 0.20, 0.19}, {-0.90, -0.12, 0.21, 0.20}, {-1.10, -0.13, 0.22, 0.21}};
  std::vector<std::vector<glm::dvec3>> sections;
  for (const auto& k : keys) {
    std::vector<glm::dvec3> loop;
    for (uint32_t v : root) {
      glm::dvec3 d = cage.positions[v] - rootCentre;
      d.y = 0;
      d = glm::normalize(d);
      loop.push_back({rootCentre.x + k.dx + d.x * k.rx, k.y, d.z * k.rz});
    }
    sections.push_back(loop);
  }
  const auto ids = tube(cage, root, sections, kNeck);
  glm::dvec3 base(0.0);
  for (const auto& p : sections.back()) base += p;
  base /= double(sections.back().size());
  capPole(cage, ids.back(), base + glm::dvec3(0, -0.03, 0), kNeckCap, double(keys.size()), 0.5);

  QuadCage fine = subdivide(cage, 2);
  const auto headParam = vertexParams(fine, kHead);
  auto nearest = [&](glm::dvec2 target) {
    size_t best = 0;
    double bestD = 1e30;
    for (size_t v = 0; v < headParam.size(); ++v) {
      if (std::isnan(headParam[v].x)) continue;
      const double d = glm::length(headParam[v] - target);
      if (d < bestD) {
        bestD = d;
        best = v;
      }
    }
    return fine.positions[best];
  };
  const glm::dvec3 eyeL = nearest({3.0, 1.75}), eyeR = nearest({3.0, 6.25});
  const double eyeRadius = 0.085;
  const Classifier classify = [&](const FaceTag& tag, const glm::dvec3& c) -> std::string {
    if (tag.part == kNeckCap) return "apteria";
    if (tag.part == kNeck) return "capital";
    const glm::dvec2 p = tag.center();
    if (p.x > kHeadBeakS) return "apteria";
    if (glm::length(c - eyeL) < eyeRadius || glm::length(c - eyeR) < eyeRadius) return "apteria";
    if (p.x > 0.3 && p.x < 4.6 && std::min(p.y, 8.0 - p.y) < 1.25) return "crest";
    return "capital";
  };
  Generated g;
  g.name = "head";
  g.mesh = triangulate(fine, classify, {"crest", "capital", "apteria"});
  finishSurface(g.mesh, cage);
  return g;
}

std::vector<Generated> makeAll() {
  std::vector<Generated> all;
  all.push_back(makeBird());
  all.push_back(makeWing());
  all.push_back(makeHead());
  all.push_back(makeSphere(127, "sphere_250"));
  all.push_back(makeSphere(802, "sphere_1600"));
  all.push_back(makePatch(20));
  return all;
}

}  // namespace pteryla::meshgen
