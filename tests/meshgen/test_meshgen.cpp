// Checks the committed meshes in data/meshes/: topology (closed 2-manifold, oriented outwards),
// triangle quality, groups, frames and sizes, the skeleton and axes side files, and that the
// generator still reproduces exactly what is committed.
#include "meshgen.hpp"

#include "pteryla/core/error.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/trigonometric.hpp>

#include <algorithm>
#include <utility>
#include <cmath>
#include <fstream>
#include <map>
#include <set>

namespace mg = pteryla::meshgen;

namespace {

const std::string kDir = std::string(PTERYLA_DATA_DIR) + "/meshes/";

const mg::GroupedMesh& loaded(const std::string& name) {
  static std::map<std::string, mg::GroupedMesh> cache;
  auto it = cache.find(name);
  if (it == cache.end()) it = cache.emplace(name, mg::readObj(kDir + name + ".obj")).first;
  return it->second;
}

nlohmann::json loadJson(const std::string& file) {
  std::ifstream in(kDir + file);
  EXPECT_TRUE(in.good()) << file;
  return nlohmann::json::parse(in);
}

bool hasGroup(const mg::GroupedMesh& m, const std::string& g) {
  return std::find(m.groupNames.begin(), m.groupNames.end(), g) != m.groupNames.end();
}

glm::dvec3 groupCentroid(const mg::GroupedMesh& m, const std::string& g) {
  const auto gi = static_cast<uint32_t>(std::find(m.groupNames.begin(), m.groupNames.end(), g) - m.groupNames.begin());
  glm::dvec3 sum(0.0);
  double n = 0;
  for (size_t t = 0; t < m.triangles.size(); ++t)
    if (m.faceGroup[t] == gi) {
      for (uint32_t v : m.triangles[t]) sum += m.positions[v];
      n += 3;
    }
  return sum / std::max(n, 1.0);
}

void bounds(const mg::GroupedMesh& m, glm::dvec3& lo, glm::dvec3& hi) {
  lo = glm::dvec3(1e30);
  hi = glm::dvec3(-1e30);
  for (const auto& p : m.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
}

struct Expect {
  std::string name;
  bool closed;
  size_t minFaces, maxFaces;
  std::vector<std::string> groups;
};

const std::vector<Expect> kExpected = {
    {"bird",
     true,
     3000,
     8000,
     {"capital", "spinal", "humeral_left", "humeral_right", "alar_left", "alar_right", "remiges_left", "remiges_right",
      "caudal", "ventral", "femoral_left", "femoral_right", "crural_left", "crural_right", "apteria_beak",
      "apteria_eye", "apteria_cervical_lateral"}},
    {"wing", true, 1000, 4000, {"coverts", "remiges_base"}},
    {"head", true, 1500, 6000, {"crest", "capital", "apteria"}},
    {"sphere_250", true, 240, 260, {}},
    {"sphere_1600", true, 1550, 1650, {}},
    {"patch", false, 750, 850, {}},
};

}  // namespace

TEST(MeshgenFiles, ValidTopologyQualityAndGroups) {
  for (const auto& e : kExpected) {
    SCOPED_TRACE(e.name);
    const auto& m = loaded(e.name);
    const mg::MeshCheck c = mg::checkMesh(m, e.closed);
    EXPECT_TRUE(c.ok()) << mg::formatCheck(e.name, c);
    EXPECT_GE(c.faces, e.minFaces);
    EXPECT_LE(c.faces, e.maxFaces);
    EXPECT_EQ(c.boundaryEdges == 0, e.closed);
    EXPECT_GT(c.minAngleDeg, 12.0) << "sliver triangles";
    EXPECT_GT(c.meanMinAngleDeg, 33.0);
    for (const auto& g : e.groups) EXPECT_TRUE(hasGroup(m, g)) << "missing group " << g;
    EXPECT_FALSE(hasGroup(m, "default")) << "faces outside any group";
    ASSERT_EQ(m.faceGroup.size(), m.triangles.size());
  }
}

TEST(MeshgenFiles, BirdHasEighteenTractsAndTheAgreedFrame) {
  const auto& m = loaded("bird");
  size_t tracts = 0;
  for (const auto& g : m.groupNames) tracts += g.rfind("apteria", 0) != 0;
  EXPECT_EQ(tracts, 18u);
  glm::dvec3 lo, hi;
  bounds(m, lo, hi);
  EXPECT_NEAR(hi.x - lo.x, 2.0, 0.15) << "beak tip to tail end about 2 units";
  EXPECT_GT(groupCentroid(m, "apteria_beak").x, 0.8) << "faces +X";
  EXPECT_GT(groupCentroid(m, "spinal").y, groupCentroid(m, "ventral").y) << "+Y is up";
  EXPECT_GT(groupCentroid(m, "alar_left").z, 0.4) << "left wing at +Z";
  EXPECT_LT(groupCentroid(m, "alar_right").z, -0.4);
  EXPECT_LT(groupCentroid(m, "caudal").x, -0.8);
  // Mirror symmetry: left and right tracts match in size.
  const mg::MeshCheck c = mg::checkMesh(m, true);
  std::map<std::string, size_t> faces;
  for (const auto& g : c.groups) faces[g.name] = g.faces;
  for (const char* t : {"humeral", "alar", "remiges", "femoral", "crural", "capital"})
    EXPECT_EQ(faces[std::string(t) + "_left"], faces[std::string(t) + "_right"]) << t;
}

TEST(MeshgenFiles, SpheresAreUnitAndPatchIsTwoByTwo) {
  for (const char* s : {"sphere_250", "sphere_1600"}) {
    for (const auto& p : loaded(s).positions) EXPECT_NEAR(glm::length(p), 1.0, 1e-5) << s;
  }
  glm::dvec3 lo, hi;
  bounds(loaded("patch"), lo, hi);
  EXPECT_NEAR(hi.x - lo.x, 2.0, 1e-6);
  EXPECT_NEAR(hi.z - lo.z, 2.0, 1e-6);
  EXPECT_GT(hi.y - lo.y, 0.05) << "curved";
  EXPECT_LT(hi.y - lo.y, 0.3) << "gently";
  EXPECT_EQ(mg::checkMesh(loaded("patch"), false).boundaryLoops, 1u);
}

namespace {

void checkSkeleton(const std::string& name, const std::vector<std::string>& jointNames) {
  SCOPED_TRACE(name);
  const auto& m = loaded(name);
  const auto j = loadJson(name + ".skeleton.json");
  const auto& joints = j.at("joints");
  ASSERT_EQ(joints.size(), jointNames.size());
  for (size_t i = 0; i < joints.size(); ++i) {
    EXPECT_EQ(joints[i].at("name").get<std::string>(), jointNames[i]);
    const int parent = joints[i].at("parent").get<int>();
    EXPECT_LT(parent, static_cast<int>(i));
    EXPECT_EQ(parent < 0, i == 0) << "exactly one root, listed first";
    EXPECT_EQ(joints[i].at("position").size(), 3u);
  }
  std::vector<double> sum(m.positions.size(), 0.0);
  std::vector<int> count(m.positions.size(), 0);
  size_t blended = 0;
  for (const auto& w : j.at("weights")) {
    const auto v = w.at(0).get<size_t>(), ji = w.at(1).get<size_t>();
    const double wt = w.at(2).get<double>();
    ASSERT_LT(v, m.positions.size());
    ASSERT_LT(ji, joints.size());
    EXPECT_GT(wt, 0.0);
    sum[v] += wt;
    ++count[v];
  }
  for (size_t v = 0; v < sum.size(); ++v) {
    EXPECT_EQ(count[v] > 0, true) << "vertex " << v << " has no weights";
    if (count[v]) {
      EXPECT_NEAR(sum[v], 1.0, 1e-4) << "vertex " << v;
    }
    blended += count[v] >= 2;
  }
  EXPECT_GT(blended, 50u) << "vertex blending near joints";
}

// Weight of joint `joint` for the vertex nearest to p.
double weightNear(const std::string& name, const glm::dvec3& p, size_t joint) {
  const auto& m = loaded(name);
  size_t best = 0;
  for (size_t v = 1; v < m.positions.size(); ++v)
    if (glm::length(m.positions[v] - p) < glm::length(m.positions[best] - p)) best = v;
  double w = 0;
  const auto j = loadJson(name + ".skeleton.json");
  for (const auto& e : j.at("weights"))
    if (e.at(0).get<size_t>() == best && e.at(1).get<size_t>() == joint) w += e.at(2).get<double>();
  return w;
}

}  // namespace

TEST(MeshgenFiles, SkeletonsBindWingsToTheirBones) {
  checkSkeleton("bird", {"root", "shoulder_left", "elbow_left", "wrist_left", "wingtip_left", "shoulder_right",
                         "elbow_right", "wrist_right", "wingtip_right"});
  checkSkeleton("wing", {"shoulder", "elbow", "wrist", "wingtip"});
  // Wing tip follows the wrist, the back follows the root, the middle of the forearm the elbow.
  EXPECT_GT(weightNear("bird", {0.0, 0.2, 1.15}, 3), 0.95);
  EXPECT_GT(weightNear("bird", {0.0, 0.2, -1.15}, 7), 0.95);
  EXPECT_GT(weightNear("bird", {-0.3, 0.3, 0.0}, 0), 0.999);
  EXPECT_GT(weightNear("wing", {0.9, 0.05, 0.1}, 1), 0.95);
  EXPECT_GT(weightNear("wing", {0.2, 0.05, 0.1}, 0), 0.95);
}

TEST(MeshgenFiles, AxesLieOnTheSurface) {
  auto onSurface = [](const std::string& mesh, const nlohmann::json& line) {
    const auto& m = loaded(mesh);
    for (const auto& p : line) {
      const glm::dvec3 q(p.at(0).get<double>(), p.at(1).get<double>(), p.at(2).get<double>());
      double best = 1e30;
      for (const auto& v : m.positions) best = std::min(best, glm::length(v - q));
      EXPECT_LT(best, 1e-5) << mesh << " polyline point off the mesh";
    }
  };
  const auto bird = loadJson("bird.axes.json");
  for (const char* k :
       {"trailing_edge_left", "trailing_edge_right", "primaries_left", "secondaries_left", "tail_edge"}) {
    ASSERT_TRUE(bird.contains(k)) << k;
    EXPECT_GE(bird.at(k).size(), 5u);
    onSurface("bird", bird.at(k));
  }
  const auto& axis = bird.at("body_axis");
  ASSERT_GE(axis.size(), 5u);
  EXPECT_GT(axis.front().at(0).get<double>(), axis.back().at(0).get<double>() + 1.5) << "head -> tail";
  EXPECT_GT(bird.at("trailing_edge_left").back().at(2).get<double>(), 1.0) << "runs shoulder -> tip";
  const auto wing = loadJson("wing.axes.json");
  ASSERT_TRUE(wing.contains("trailing_edge"));
  onSurface("wing", wing.at("trailing_edge"));
  EXPECT_GT(wing.at("trailing_edge").back().at(0).get<double>(), 1.8);
}

TEST(MeshgenGenerator, ReproducesTheCommittedFiles) {
  for (const auto& g : mg::makeAll()) {
    SCOPED_TRACE(g.name);
    const auto& m = loaded(g.name);
    ASSERT_EQ(g.mesh.positions.size(), m.positions.size()) << "re-run pteryla_meshgen and commit data/meshes";
    ASSERT_EQ(g.mesh.triangles.size(), m.triangles.size());
    ASSERT_EQ(g.mesh.groupNames, m.groupNames);
    for (size_t v = 0; v < m.positions.size(); ++v)
      ASSERT_LT(glm::length(g.mesh.positions[v] - m.positions[v]), 2e-6) << "vertex " << v;
    // The file lists faces group by group; compare as sets of (group, triangle).
    std::multiset<std::array<uint32_t, 4>> a, b;
    for (size_t t = 0; t < m.triangles.size(); ++t) {
      a.insert({g.mesh.faceGroup[t], g.mesh.triangles[t][0], g.mesh.triangles[t][1], g.mesh.triangles[t][2]});
      b.insert({m.faceGroup[t], m.triangles[t][0], m.triangles[t][1], m.triangles[t][2]});
    }
    EXPECT_TRUE(a == b);
  }
}

TEST(MeshgenChecker, CatchesHolesFlipsAndBadFiles) {
  mg::GroupedMesh m = loaded("sphere_250");
  ASSERT_TRUE(mg::checkMesh(m, true).ok());
  mg::GroupedMesh flipped = m;
  std::swap(flipped.triangles[7][1], flipped.triangles[7][2]);
  EXPECT_GT(mg::checkMesh(flipped, true).misorientedEdges, 0u);
  mg::GroupedMesh holed = m;
  holed.triangles.pop_back();
  holed.faceGroup.pop_back();
  const auto c = mg::checkMesh(holed, true);
  EXPECT_FALSE(c.ok());
  EXPECT_EQ(c.boundaryEdges, 3u);
  mg::GroupedMesh inward = m;
  for (auto& t : inward.triangles) std::swap(t[1], t[2]);
  EXPECT_FALSE(mg::checkMesh(inward, true).ok()) << "inward normals";
  mg::GroupedMesh crossing = m;
  crossing.positions[0] *= -1.0;  // drags a vertex through the sphere
  EXPECT_GT(mg::checkMesh(crossing, true).selfIntersections, 0u);

  const std::string bad = std::string(PTERYLA_BUILD_DIR) + "/meshgen_bad.obj";
  {
    std::ofstream o(bad);
    o << "v 0 0 0\nv 1 0 0\nv 0 1 0\ng a\nf 1 2 3\nf 1 2 9\n";
  }
  try {
    mg::readObj(bad);
    FAIL() << "out-of-range index accepted";
  } catch (const pteryla::Error& e) {
    EXPECT_EQ(e.file(), bad);
    EXPECT_EQ(e.element(), "line 6");
  }
  EXPECT_THROW(mg::readObj(std::string(PTERYLA_BUILD_DIR) + "/does_not_exist.obj"), pteryla::Error);
}

namespace {

// Linear blend skinning with per-joint rotations about the joints' rest positions (docs/skeleton-format.md).
mg::GroupedMesh pose(const std::string& name, const std::map<std::string, glm::dvec3>& rotationsDeg) {
  const auto& m = loaded(name);
  const auto j = loadJson(name + ".skeleton.json");
  const auto& joints = j.at("joints");
  std::vector<glm::dmat4> world(joints.size());
  for (size_t i = 0; i < joints.size(); ++i) {
    const auto& p = joints[i].at("position");
    const glm::dvec3 pos(p.at(0).get<double>(), p.at(1).get<double>(), p.at(2).get<double>());
    glm::dmat4 local(1.0);
    const auto it = rotationsDeg.find(joints[i].at("name").get<std::string>());
    if (it != rotationsDeg.end()) {
      const glm::dvec3 r = glm::radians(it->second);
      glm::dmat4 rot = glm::rotate(glm::dmat4(1.0), r.z, glm::dvec3(0, 0, 1));
      rot = rot * glm::rotate(glm::dmat4(1.0), r.y, glm::dvec3(0, 1, 0));
      rot = rot * glm::rotate(glm::dmat4(1.0), r.x, glm::dvec3(1, 0, 0));
      local = glm::translate(glm::dmat4(1.0), pos) * rot * glm::translate(glm::dmat4(1.0), -pos);
    }
    const int parent = joints[i].at("parent").get<int>();
    world[i] = parent < 0 ? local : world[static_cast<size_t>(parent)] * local;
  }
  mg::GroupedMesh out = m;
  std::vector<glm::dvec3> acc(m.positions.size(), glm::dvec3(0.0));
  for (const auto& w : j.at("weights")) {
    const auto v = w.at(0).get<size_t>(), ji = w.at(1).get<size_t>();
    acc[v] += w.at(2).get<double>() * glm::dvec3(world[ji] * glm::dvec4(m.positions[v], 1.0));
  }
  out.positions = acc;
  return out;
}

// Largest change of the angle between the normals of two faces sharing an edge (degrees): a
// deformation concentrated in one ring of faces (rigid skinning) shows up as a big jump.
double maxCreaseChange(const mg::GroupedMesh& rest, const mg::GroupedMesh& bent) {
  auto normal = [](const mg::GroupedMesh& m, size_t t) {
    const auto& tri = m.triangles[t];
    return glm::normalize(
        glm::cross(m.positions[tri[1]] - m.positions[tri[0]], m.positions[tri[2]] - m.positions[tri[0]]));
  };
  std::map<std::pair<uint32_t, uint32_t>, size_t> firstFace;
  double worst = 0;
  for (size_t t = 0; t < rest.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = rest.triangles[t][k], b = rest.triangles[t][(k + 1) % 3];
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = firstFace.find(key);
      if (it == firstFace.end()) {
        firstFace[key] = t;
        continue;
      }
      auto angle = [&](const mg::GroupedMesh& m) {
        return glm::degrees(std::acos(std::clamp(glm::dot(normal(m, it->second), normal(m, t)), -1.0, 1.0)));
      };
      worst = std::max(worst, std::abs(angle(bent) - angle(rest)));
    }
  return worst;
}

}  // namespace

TEST(MeshgenFiles, BendingJointsDeformsSmoothly) {
  // Fig. 8.6: the wing bent down and up at elbow and wrist (rotation about the chord axis, Z).
  for (double deg : {-35.0, 35.0}) {
    const auto bent = pose("wing", {{"elbow", {0, 0, deg}}, {"wrist", {0, 0, deg * 0.8}}});
    const auto c = mg::checkMesh(bent, true);
    EXPECT_TRUE(c.ok()) << mg::formatCheck("bent wing", c);
    EXPECT_GT(c.minAngleDeg, 8.0);
    // A 35 deg bend spread over about five rings of faces; rigid binding puts it all on one.
    EXPECT_LT(maxCreaseChange(loaded("wing"), bent), 18.0) << "bend not spread over several rings of faces";
    glm::dvec3 lo, hi;
    bounds(bent, lo, hi);
    EXPECT_GT(deg > 0 ? hi.y : -lo.y, 0.5) << "the tip actually moved";
  }
  // Wings raised and lowered at the shoulders (rotation about the body axis, X), elbows flexed.
  for (double deg : {-30.0, 30.0}) {
    const auto flap = pose("bird", {{"shoulder_left", {deg, 0, 0}},
                                    {"shoulder_right", {-deg, 0, 0}},
                                    {"elbow_left", {0, 20, 0}},
                                    {"elbow_right", {0, -20, 0}}});
    const auto c = mg::checkMesh(flap, true);
    EXPECT_TRUE(c.ok()) << mg::formatCheck("flapping bird", c);
    EXPECT_GT(c.minAngleDeg, 5.0);
    EXPECT_LT(maxCreaseChange(loaded("bird"), flap), 22.0);
  }
}
