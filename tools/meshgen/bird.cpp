// The bird skin mesh (data/meshes/bird.obj) with its feather tracts, wing skeleton and axes.
// Tract layout after Streit 2003, section 2.7 (eight main pterylae: capital, spinal, humeral,
// ventral, caudal, alar, femoral, crural) and the 18-tract model of section 9.2 (5 head, 3 neck,
// 3 per wing, 4 body); skinning by vertex blending around joints as in section 8.3 / Fig. 8.6.
//
// Frame: the bird faces +X, +Y is up, the wing at +Z is named "left" (project convention, see
// data/meshes/README.md). Length beak tip to tail end is about 2 units.
#include "cage_build.hpp"

#include "pteryla/core/error.hpp"

namespace pteryla::meshgen {

namespace {

enum Part { kBody = 0, kWingL, kWingR, kLegL, kLegR };

const std::vector<std::string> kBirdGroupOrder = {"capital",         "capital_left",    "capital_right",
                                                  "capital_throat",  "cervical_dorsal", "spinal",
                                                  "ventral",         "caudal",          "humeral_left",
                                                  "humeral_right",   "alar_left",       "alar_right",
                                                  "remiges_left",    "remiges_right",   "femoral_left",
                                                  "femoral_right",   "crural_left",     "crural_right",
                                                  "apteria_beak",    "apteria_eye",     "apteria_cervical_lateral",
                                                  "apteria_ventral", "apteria_lateral", "apteria_axillary",
                                                  "apteria_leg"};

// Body spine, tail end (ring 0) to beak tip (ring 14).
const std::vector<SpineKey> kBodyKeys = {
    {-1.00, 0.07, 0.045, 0.04, 0.10},    // 0 tail end (rectrices root here)
    {-0.90, 0.07, 0.065, 0.055, 0.11},   // 1 tail base
    {-0.76, 0.06, 0.11, 0.10, 0.14},     // 2 uropygium
    {-0.56, 0.03, 0.19, 0.19, 0.195},    // 3 hips (legs)
    {-0.32, 0.01, 0.25, 0.26, 0.25},     // 4
    {-0.08, 0.00, 0.28, 0.29, 0.28},     // 5 wing root, rear
    {0.12, 0.02, 0.28, 0.29, 0.27},      // 6
    {0.30, 0.06, 0.23, 0.25, 0.23},      // 7 wing root, front; breast
    {0.44, 0.14, 0.16, 0.17, 0.15},      // 8 neck base
    {0.54, 0.24, 0.11, 0.11, 0.10},      // 9 neck
    {0.63, 0.33, 0.12, 0.11, 0.11},      // 10 back of the head
    {0.74, 0.37, 0.12, 0.10, 0.11},      // 11 eyes
    {0.84, 0.36, 0.075, 0.065, 0.07},    // 12 forehead, beak base
    {0.905, 0.34, 0.036, 0.03, 0.032},   // 13 beak
    {0.95, 0.327, 0.016, 0.013, 0.014},  // 14 beak tip
};
constexpr int kWingRing = 5;  // wing root spans rings 5..7, angles 1..2 (mirrored 6..7)
constexpr int kLegRing = 3;   // leg root: rings 3..4, angles 3..4 (mirrored 4..5)
constexpr double kBeakS = 12.45;
constexpr int kWristSection = 4;
constexpr double kBirdBlendWidth = 0.14;  // elbow and wrist blend half-width, units

// Left wing sections (z-planes): span z, leading/trailing edge x, centre height, thickness.
struct WingSection {
  double z, xLead, xTrail, y, thick;
};
const std::vector<WingSection> kWing = {
    {0.38, 0.33, -0.12, 0.16, 0.13},   {0.50, 0.35, -0.11, 0.17, 0.10},   {0.62, 0.36, -0.08, 0.18, 0.085},
    {0.74, 0.35, -0.05, 0.19, 0.075},  {0.86, 0.29, -0.05, 0.195, 0.065}, {0.98, 0.21, -0.06, 0.20, 0.055},
    {1.09, 0.12, -0.08, 0.205, 0.047}, {1.18, 0.03, -0.10, 0.21, 0.04},
};
const glm::dvec3 kWingTip(-0.05, 0.21, 1.245);
const glm::dvec3 kShoulder(0.18, 0.15, 0.20), kElbow(0.10, 0.17, 0.47), kWrist(0.28, 0.19, 0.74),
    kTipJoint(-0.03, 0.21, 1.21);

// Cross-section loop of a flat wing: [0] leading edge top, [1] mid top, [2] trailing edge,
// [3] rear bottom, [4] front bottom, [5] leading edge bottom. chordPoint(u, h) maps chord
// fraction u (0 leading, 1 trailing) and height h to space.
template <class F>
std::vector<glm::dvec3> wingLoop(F chordPoint, double t) {
  return {chordPoint(0.0, 0.32 * t),   chordPoint(0.45, 0.45 * t),  chordPoint(1.0, 0.0),
          chordPoint(0.72, -0.18 * t), chordPoint(0.44, -0.30 * t), chordPoint(0.15, -0.36 * t)};
}

glm::dvec3 mirror(glm::dvec3 p) { return {p.x, p.y, -p.z}; }

// Angle index a in [0,8) measured from the top towards +Z; distance from the top ridge.
double fromTop(double a) { return std::min(a, 8.0 - a); }

}  // namespace

Generated makeBird() {
  QuadCage cage;
  const auto rings = ringsAlongSpine(kBodyKeys, 0.8);
  std::set<std::pair<int, int>> skip = {{kWingRing, 1},     {kWingRing + 1, 1}, {kWingRing, 6},
                                        {kWingRing + 1, 6}, {kLegRing, 3},      {kLegRing, 4}};
  const auto ring = loft(cage, rings, kBody, skip);
  const int last = static_cast<int>(rings.size()) - 1;
  auto loopOf = [&](int r) { return std::vector<uint32_t>(ring[r].begin(), ring[r].end()); };
  const uint32_t tailPole = capPole(cage, loopOf(0), rings[0].center + glm::dvec3(-0.045, 0, 0), kBody, 0.0, -0.5);
  capPole(cage, loopOf(last), rings[last].center + glm::dvec3(0.018, -0.004, 0), kBody, last, 0.5);

  std::vector<std::vector<uint32_t>> wingIds[2];
  uint32_t wingTip[2] = {0, 0};
  for (int side = 0; side < 2; ++side) {
    const int kUp = side == 0 ? 1 : 7, kLow = side == 0 ? 2 : 6;
    const int r = kWingRing;
    const std::vector<uint32_t> root = {ring[r + 2][kUp], ring[r + 1][kUp],  ring[r][kUp],
                                        ring[r][kLow],    ring[r + 1][kLow], ring[r + 2][kLow]};
    std::vector<std::vector<glm::dvec3>> sections;
    for (const auto& s : kWing) {
      auto loop = wingLoop(
          [&](double u, double h) { return glm::dvec3(s.xLead + u * (s.xTrail - s.xLead), s.y + h, s.z); }, s.thick);
      if (side == 1)
        for (auto& p : loop) p = mirror(p);
      sections.push_back(loop);
    }
    const int part = side == 0 ? kWingL : kWingR;
    wingIds[side] = tube(cage, root, sections, part);
    wingTip[side] = capPole(cage, wingIds[side].back(), side == 0 ? kWingTip : mirror(kWingTip), part,
                            static_cast<double>(kWing.size()), 0.5);
  }
  for (int side = 0; side < 2; ++side) {
    const int kOut = side == 0 ? 3 : 5, kMid = 4;
    const int r = kLegRing;
    const std::vector<uint32_t> root = {ring[r][kOut], ring[r][kMid], ring[r + 1][kMid], ring[r + 1][kOut]};
    // Tucked leg: drumstick down and back, then a thin tarsus stub pointing back.
    struct LegKey {
      glm::dvec3 c;
      double r;
      glm::dvec3 dir;
    };
    const std::vector<LegKey> keys = {
        {{-0.47, -0.27, 0.11}, 0.07, {-0.5, -1, 0}},
        {{-0.56, -0.33, 0.10}, 0.05, {-1, -0.6, 0}},
        {{-0.67, -0.36, 0.09}, 0.03, {-1, -0.2, 0}},
    };
    std::vector<std::vector<glm::dvec3>> sections;
    for (const auto& k : keys) {
      const glm::dvec3 d = glm::normalize(k.dir);
      const glm::dvec3 front = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), d));
      const glm::dvec3 lat(0, 0, 1);
      std::vector<glm::dvec3> loop = {k.c - front * k.r + lat * k.r, k.c - front * k.r - lat * k.r,
                                      k.c + front * k.r - lat * k.r, k.c + front * k.r + lat * k.r};
      if (side == 1)
        for (auto& p : loop) p = mirror(p);
      sections.push_back(loop);
    }
    const int part = side == 0 ? kLegL : kLegR;
    const auto ids = tube(cage, root, sections, part);
    const auto& end = ids.back();
    const double w = static_cast<double>(keys.size());
    cage.addQuad({end[0], end[1], end[2], end[3]}, part,
                 {glm::dvec2(w, 0), glm::dvec2(w, 1), glm::dvec2(w, 2), glm::dvec2(w, 3)});
  }

  // Chains refined with the mesh: wing trailing edges (root -> tip), tail edge (left -> right).
  for (int side = 0; side < 2; ++side) {
    std::vector<uint32_t> chain;
    for (const auto& sec : wingIds[side]) chain.push_back(sec[2]);
    chain.push_back(wingTip[side]);
    cage.chains.push_back(chain);
  }
  cage.chains.push_back({ring[0][2], tailPole, ring[0][6]});

  QuadCage fine = subdivide(cage, 2);
  const auto bodyParam = vertexParams(fine, kBody);

  // Eye centres: the surface vertex nearest to the (s, a) position of each eye.
  auto nearestBodyVertex = [&](glm::dvec2 target) {
    size_t best = 0;
    double bestD = 1e30;
    for (size_t v = 0; v < bodyParam.size(); ++v) {
      if (std::isnan(bodyParam[v].x)) continue;
      const double d = glm::length(bodyParam[v] - target);
      if (d < bestD) {
        bestD = d;
        best = v;
      }
    }
    return fine.positions[best];
  };
  const glm::dvec3 eyeL = nearestBodyVertex({11.0, 1.6}), eyeR = nearestBodyVertex({11.0, 6.4});
  const double eyeRadius = 0.042;

  const Classifier classify = [&](const FaceTag& tag, const glm::dvec3& c) -> std::string {
    const glm::dvec2 p = tag.center();
    if (tag.part == kWingL || tag.part == kWingR) {
      const std::string sfx = tag.part == kWingL ? "_left" : "_right";
      const double w = p.x, l = p.y;
      const bool top = l < 1.5 || l > 5.5, trailing = l >= 1.5 && l <= 2.8;
      if (w < 0.5) return top || trailing ? "humeral" + sfx : "apteria_axillary";
      if (trailing) return "remiges" + sfx;
      if (top) return w < 2.0 ? "humeral" + sfx : "alar" + sfx;
      return w < 1.0 ? "apteria_axillary" : "alar" + sfx;
    }
    if (tag.part == kLegL || tag.part == kLegR) {
      if (p.x < 1.6) return tag.part == kLegL ? "crural_left" : "crural_right";
      return "apteria_leg";
    }
    const double s = p.x, a = p.y, top = fromTop(a);
    const std::string sfx = a < 4 ? "_left" : "_right";
    if (s > kBeakS) return "apteria_beak";
    if (glm::length(c - eyeL) < eyeRadius || glm::length(c - eyeR) < eyeRadius) return "apteria_eye";
    if (s >= 10.0) {
      if (top < 1.3) return "capital";
      if (top > 2.8) return "capital_throat";
      return "capital" + sfx;
    }
    if (s >= 8.3) {
      if (top < 1.4) return "cervical_dorsal";
      if (top > 2.9) return "capital_throat";
      return "apteria_cervical_lateral";
    }
    if (s < 1.5) return "caudal";
    if (top < 1.3) return "spinal";
    if (top > 3.75 && s < 6.0 && s > 2.5) return "apteria_ventral";
    if (top > 2.7) return "ventral";
    if (s < 5.0) return "femoral" + sfx;
    if (s < 7.0) return "apteria_lateral";
    return "ventral";
  };

  Generated g;
  g.name = "bird";
  g.mesh = triangulate(fine, classify, kBirdGroupOrder);
  finishSurface(g.mesh, cage);

  // Skeleton: root at the body centre, shoulder -> elbow -> wrist -> wing tip on each side.
  Skeleton& sk = g.skeleton;
  sk.joints.push_back({"root", -1, {0.0, 0.05, 0.0}});
  const char* names[2] = {"left", "right"};
  for (int side = 0; side < 2; ++side) {
    auto m = [&](glm::dvec3 p) { return side == 0 ? p : mirror(p); };
    const int base = static_cast<int>(sk.joints.size());
    sk.joints.push_back({std::string("shoulder_") + names[side], 0, m(kShoulder)});
    sk.joints.push_back({std::string("elbow_") + names[side], base, m(kElbow)});
    sk.joints.push_back({std::string("wrist_") + names[side], base + 1, m(kWrist)});
    sk.joints.push_back({std::string("wingtip_") + names[side], base + 2, m(kTipJoint)});
  }
  // The shoulder blend runs along the wing's root tube (section param w in [0, 2]) and reaches into
  // the body around the wing root, so raising a wing stretches the flank instead of creasing it.
  constexpr double kRootShare = 0.3, kBodyReach = 0.14;  // shoulder weight at the root ring; units
  const auto wingParamL = vertexParams(fine, kWingL), wingParamR = vertexParams(fine, kWingR);
  std::vector<glm::dvec3> rootRing[2];
  for (uint32_t v = 0; v < g.mesh.positions.size(); ++v)
    for (int side = 0; side < 2; ++side)
      if (!std::isnan((side == 0 ? wingParamL : wingParamR)[v].x) && !std::isnan(bodyParam[v].x))
        rootRing[side].push_back(g.mesh.positions[v]);
  for (uint32_t v = 0; v < g.mesh.positions.size(); ++v) {
    std::vector<SkinWeight> ws;
    const glm::dvec3 p = g.mesh.positions[v];
    for (int side = 0; side < 2; ++side) {
      const auto& wp = side == 0 ? wingParamL : wingParamR;
      double beta0 = 0;
      if (!std::isnan(wp[v].x)) {
        beta0 = kRootShare + (1 - kRootShare) * smoothstep(0.0, 2.0, wp[v].x);
      } else if (!std::isnan(bodyParam[v].x) && (side == 0 ? p.z > 0 : p.z < 0)) {
        double d = 1e30;
        for (const auto& q : rootRing[side]) d = std::min(d, glm::length(p - q));
        beta0 = kRootShare * (1 - smoothstep(0.0, kBodyReach, d));
      }
      if (beta0 <= 0) continue;
      const uint32_t b = 1 + 4 * side;
      ws = chainWeights(v, p, beta0, {0, b, b + 1, b + 2, b + 3}, sk, kBirdBlendWidth);
    }
    if (ws.empty()) ws.push_back({v, 0, 1.0});
    sk.weights.insert(sk.weights.end(), ws.begin(), ws.end());
  }
  g.hasSkeleton = true;

  // Axes: body axis head -> tail through the ring centres; trailing edges; tail edge.
  Polyline body{"body_axis", {}};
  body.points.push_back(rings[last].center + glm::dvec3(0.02, 0, 0));
  for (int r = last; r >= 0; --r) body.points.push_back(rings[r].center);
  body.points.push_back(rings[0].center + glm::dvec3(-0.02, 0, 0));
  g.axes.push_back(body);
  const int wristAt = kWristSection * 4;  // two subdivision levels
  for (int side = 0; side < 2; ++side) {
    const auto& chain = fine.chains[side];
    Polyline te{std::string("trailing_edge_") + names[side], {}}, sec{std::string("secondaries_") + names[side], {}},
        pri{std::string("primaries_") + names[side], {}};
    for (size_t i = 0; i < chain.size(); ++i) {
      const glm::dvec3 p = g.mesh.positions[chain[i]];
      te.points.push_back(p);
      if (static_cast<int>(i) <= wristAt) sec.points.push_back(p);
      if (static_cast<int>(i) >= wristAt) pri.points.push_back(p);
    }
    g.axes.push_back(te);
    g.axes.push_back(sec);
    g.axes.push_back(pri);
  }
  Polyline tail{"tail_edge", {}};
  for (uint32_t v : fine.chains[2]) tail.points.push_back(g.mesh.positions[v]);
  g.axes.push_back(tail);
  return g;
}

}  // namespace pteryla::meshgen
