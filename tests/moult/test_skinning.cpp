// Skin deformation (Streit 2003, 8.3): identity poses change nothing, rigid parts move rigidly about
// their joints, rotations compose down the chain, keys interpolate, follicles ride the skin, bad rigs
// are errors with key paths.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cmath>

#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/moult/skinning.hpp"

using namespace pteryla;
using namespace pteryla::moult;

namespace {

const std::string kData = PTERYLA_DATA_DIR;

const coat::SkinMesh& wing() {
  static const coat::SkinMesh m = coat::loadSkinMesh(kData + "/meshes/wing.obj");
  return m;
}
const Skeleton& wingSkeleton() {
  static const Skeleton s = loadSkeleton(kData + "/meshes/wing.skeleton.json", wing().vertexCount());
  return s;
}

// Weight of joint j on vertex v.
double weightOf(const Skeleton& s, size_t v, uint32_t j) {
  for (uint32_t k = s.weightOffset[v]; k < s.weightOffset[v + 1]; ++k)
    if (s.weightJoint[k] == j) return s.weight[k];
  return 0;
}

}  // namespace

TEST(Skinning, LoadsTheBundledSkeletons) {
  const Skeleton& s = wingSkeleton();
  ASSERT_EQ(s.jointCount(), 4u);
  EXPECT_EQ(s.find("elbow"), 1);
  EXPECT_EQ(s.parent[2], 1);
  EXPECT_EQ(s.vertexCount(), wing().vertexCount());
  for (size_t v = 0; v < s.vertexCount(); ++v) {
    double sum = 0;
    for (uint32_t k = s.weightOffset[v]; k < s.weightOffset[v + 1]; ++k) sum += s.weight[k];
    EXPECT_NEAR(sum, 1.0, 1e-12);
  }
  const coat::SkinMesh bird = coat::loadSkinMesh(kData + "/meshes/bird.obj");
  const Skeleton b = loadSkeleton(kData + "/meshes/bird.skeleton.json", bird.vertexCount());
  EXPECT_EQ(b.jointCount(), 9u);
  EXPECT_EQ(b.find("wrist_right"), 7);
}

TEST(Skinning, IdentityPoseLeavesFolliclesInPlace) {
  const coat::SkinMesh& rest = wing();
  coat::SkinMesh posed = rest;
  EXPECT_FALSE(poseSkinMesh(wingSkeleton(), restPose(wingSkeleton()), rest, posed));
  EXPECT_EQ(posed.positions, rest.positions);
  EXPECT_EQ(posed.vertexNormals, rest.vertexNormals);
  // Also when the identity comes from zero-angle keys.
  SkeletonAnimation a;
  a.times.assign(4, {});
  a.rotations.assign(4, {});
  a.times[1] = {0.0, 2.0};
  a.rotations[1] = {rotationFromAxisAngle({0, 0, 1}, 0), rotationFromAxisAngle({1, 0, 0}, 0)};
  std::vector<glm::dvec3> out;
  skinPoints(wingSkeleton(), jointTransforms(wingSkeleton(), poseAt(a, 1.0)), rest.positions, out);
  EXPECT_EQ(out, rest.positions);

  const coat::Tract all = coat::wholeMeshTract(rest);
  coat::ScatterOptions so;
  so.count = 200;
  coat::Follicles f = coat::scatterFollicles(rest, all, so);
  coat::Follicles g = f;
  coat::updateFollicleGeometry(posed, g);
  EXPECT_EQ(g.position, f.position);
}

TEST(Skinning, RigidPartsTurnAboutTheirJoint) {
  const Skeleton& s = wingSkeleton();
  const coat::SkinMesh& rest = wing();
  SkeletonPose pose = restPose(s);
  pose.rotation[1] = rotationFromAxisAngle({0, 0, 1}, 40);  // elbow up
  std::vector<glm::dvec3> out;
  skinPoints(s, jointTransforms(s, pose), rest.positions, out);
  const glm::dvec3 elbow = s.position[1];
  const glm::dmat3 R = glm::mat3_cast(pose.rotation[1]);
  size_t forearm = 0, upper = 0;
  for (size_t v = 0; v < rest.vertexCount(); ++v) {
    const double w0 = weightOf(s, v, 0);
    const double wOut = weightOf(s, v, 1) + weightOf(s, v, 2);  // elbow and wrist follow the elbow turn
    if (w0 == 1.0) {
      EXPECT_EQ(out[v], rest.positions[v]);
      ++upper;
    } else if (wOut == 1.0) {
      EXPECT_LT(glm::length(out[v] - (elbow + R * (rest.positions[v] - elbow))), 1e-12);
      ++forearm;
    }
  }
  EXPECT_GT(upper, 50u);
  EXPECT_GT(forearm, 50u);
}

TEST(Skinning, RotationsComposeDownTheChain) {
  const Skeleton& s = wingSkeleton();
  SkeletonPose pose = restPose(s);
  pose.rotation[1] = rotationFromAxisAngle({0, 0, 1}, 30);
  pose.rotation[2] = rotationFromAxisAngle({0, 1, 0}, -20);
  const auto m = jointTransforms(s, pose);
  // The wrist joint moves with the elbow turn; the wingtip point moves with both.
  const glm::dvec3 wrist = s.position[2], tip = s.position[3];
  EXPECT_LT(glm::length(m[2].apply(wrist) - m[1].apply(wrist)), 1e-12);
  const glm::dmat3 r1 = glm::mat3_cast(pose.rotation[1]), r2 = glm::mat3_cast(pose.rotation[2]);
  const glm::dvec3 wristPosed = s.position[1] + r1 * (wrist - s.position[1]);
  const glm::dvec3 tipPosed = wristPosed + r1 * (r2 * (tip - wrist));
  EXPECT_LT(glm::length(m[2].apply(tip) - tipPosed), 1e-12);
  // Bone lengths are kept.
  EXPECT_NEAR(glm::length(m[2].apply(tip) - m[1].apply(wrist)), glm::length(tip - wrist), 1e-12);
}

TEST(Skinning, KeysInterpolate) {
  SkeletonAnimation a;
  a.times = {{}, {0.0, 2.0}};
  a.rotations = {{}, {rotationFromAxisAngle({0, 0, 1}, 0), rotationFromAxisAngle({0, 0, 1}, 60)}};
  auto angle = [](const glm::dquat& q) { return glm::degrees(glm::angle(q)); };
  EXPECT_NEAR(angle(poseAt(a, 1.0).rotation[1]), 30.0, 1e-9);
  EXPECT_NEAR(angle(poseAt(a, 0.5).rotation[1]), 15.0, 1e-9);
  EXPECT_NEAR(angle(poseAt(a, -3.0).rotation[1]), 0.0, 1e-9);
  EXPECT_NEAR(angle(poseAt(a, 7.0).rotation[1]), 60.0, 1e-9);
  a.interpolation = Interpolation::Smooth;
  EXPECT_NEAR(angle(poseAt(a, 1.0).rotation[1]), 30.0, 1e-9);
  EXPECT_NEAR(angle(poseAt(a, 0.5).rotation[1]), 60.0 * (0.25 * 0.25 * (3 - 0.5)), 1e-9);
  a.interpolation = Interpolation::Step;
  EXPECT_NEAR(angle(poseAt(a, 1.9).rotation[1]), 0.0, 1e-9);
  EXPECT_EQ(poseAt(a, 1.0).rotation[0], glm::dquat(1, 0, 0, 0));
}

TEST(Skinning, FolliclesRideTheBentWing) {
  const coat::SkinMesh& rest = wing();
  const Skeleton& s = wingSkeleton();
  SkeletonPose pose = restPose(s);
  pose.rotation[1] = rotationFromAxisAngle({0, 0, 1}, 35);
  pose.rotation[2] = rotationFromAxisAngle({0, 0, 1}, -35);
  coat::SkinMesh posed = rest;
  ASSERT_TRUE(poseSkinMesh(s, pose, rest, posed));
  coat::ScatterOptions so;
  so.count = 300;
  coat::Follicles f = coat::scatterFollicles(rest, coat::wholeMeshTract(rest), so);
  coat::Follicles g = f;
  coat::updateFollicleGeometry(posed, g);
  size_t moved = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    EXPECT_LT(glm::length(g.position[i] - coat::pointAt(posed, f.face[i], f.bary[i])), 1e-12);
    EXPECT_NEAR(glm::length(g.normal[i]), 1.0, 1e-9);
    if (glm::length(g.position[i] - f.position[i]) > 0.05) ++moved;
  }
  EXPECT_GT(moved, f.size() / 4);
  // Normals follow the bend: a face on the fully rotated hand turns with it.
  for (size_t t = 0; t < rest.faceCount(); ++t) {
    bool hand = true;
    for (uint32_t v : rest.faces[t]) hand = hand && weightOf(s, v, 2) == 1.0;
    if (!hand) continue;
    // Elbow +35 then wrist -35 about parallel axes: the hand is translated, not turned.
    EXPECT_LT(glm::length(posed.faceNormals[t] - rest.faceNormals[t]), 1e-9);
  }
}

TEST(Skinning, RigJsonIsStrict) {
  const size_t nv = wing().vertexCount();
  const std::string scene = kData + "/scenes/rig_test.json";
  auto err = [&](const Json& j) -> std::string {
    JsonReader r(j, scene, "skeleton");
    try {
      readSkinRig(r, nv);
    } catch (const Error& e) {
      return e.element();
    }
    return "no error";
  };
  Json ok = Json::parse(R"({"file": "../meshes/wing.skeleton.json", "interpolation": "smooth",
      "keys": [{"joint": "elbow", "t": 1, "rotation": [0, 0, 1, 20]}, {"joint": 2, "t": 0, "rotation": [0, 1, 0, -5]}]})");
  {
    JsonReader r(ok, scene, "skeleton");
    const SkinRig rig = readSkinRig(r, nv);
    EXPECT_EQ(rig.animation.times[1].size(), 1u);
    EXPECT_EQ(rig.animation.interpolation, Interpolation::Smooth);
  }
  Json j = ok;
  j["keys"][0]["joint"] = "knee";
  EXPECT_EQ(err(j), "skeleton.keys[0].joint");
  j = ok;
  j["keys"][1]["joint"] = 9;
  EXPECT_EQ(err(j), "skeleton.keys[1].joint");
  j = ok;
  j["keys"][0]["rotation"] = {0, 0, 1};
  EXPECT_EQ(err(j), "skeleton.keys[0].rotation");
  j = ok;
  j["keys"][0]["rotation"] = {0, 0, 0, 10};
  EXPECT_EQ(err(j), "skeleton.keys[0].rotation");
  j = ok;
  j["keys"][1] = {{"joint", "elbow"}, {"t", 1}, {"rotation", {1, 0, 0, 3}}};
  EXPECT_EQ(err(j), "skeleton.keys[1].t");
  j = ok;
  j["keys"][0]["angle"] = 3;
  EXPECT_EQ(err(j), "skeleton.keys[0].angle");
  j = ok;
  j["speed"] = 3;
  EXPECT_EQ(err(j), "skeleton.speed");
  j = ok;
  j["file"] = "../meshes/missing.skeleton.json";
  EXPECT_EQ(err(j), "skeleton.file");
  // Inline skeletons: bad weights name their entry.
  Json inl = Json::parse(R"({"joints": [{"name": "root", "parent": -1, "position": [0, 0, 0]},
                                        {"name": "tip", "parent": 0, "position": [1, 0, 0]}],
                             "weights": [[0, 0, 1.0], [1, 1, 0.5], [1, 0, 0.5]]})");
  {
    JsonReader r(inl, scene, "skeleton");
    const SkinRig rig = readSkinRig(r, nv);
    EXPECT_EQ(rig.skeleton.vertexCount(), nv);
    EXPECT_EQ(rig.skeleton.weightOffset[2] - rig.skeleton.weightOffset[1], 2u);
  }
  j = inl;
  j["weights"][1] = {static_cast<int64_t>(nv), 1, 0.5};
  EXPECT_EQ(err(j), "skeleton.weights[1][0]");
  j = inl;
  j["weights"][1] = {1, 2, 0.5};
  EXPECT_EQ(err(j), "skeleton.weights[1][1]");
  j = inl;
  j["joints"][1]["parent"] = 1;
  EXPECT_EQ(err(j), "skeleton.joints[1].parent");
  j = inl;
  j["joints"][1]["name"] = "root";
  EXPECT_EQ(err(j), "skeleton.joints[1].name");
}
