// Camera navigation and picking math.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/geometric.hpp>

#include "camera_controller.hpp"
#include "picking.hpp"

using namespace pteryla;
using namespace pteryla::viewer;

namespace {
render::Camera startCamera() {
  render::Camera c;
  c.eye = {0, 0, 5};
  c.target = {0, 0, 0};
  c.up = {0, 1, 0};
  c.fovYDegrees = 40;
  return c;
}
}  // namespace

TEST(CameraController, OrbitKeepsDistanceTargetAndNeverFlips) {
  CameraController cc;
  cc.set(startCamera());
  cc.orbit(0.7f, 0.3f);
  EXPECT_NEAR(cc.distance(), 5.0f, 1e-4f);
  EXPECT_EQ(cc.camera().target, glm::vec3(0));
  // Yaw by a full turn returns to the start.
  CameraController c2;
  c2.set(startCamera());
  for (int i = 0; i < 8; ++i) c2.orbit(3.14159265f / 4, 0);
  EXPECT_NEAR(glm::length(c2.camera().eye - glm::vec3(0, 0, 5)), 0.0f, 1e-3f);
  // Pitching far past the pole stops one degree short of it.
  cc.orbit(0, 10.0f);
  const glm::vec3 dir = glm::normalize(cc.camera().eye - cc.camera().target);
  EXPECT_NEAR(std::acos(glm::dot(dir, glm::vec3(0, 1, 0))), 1.0f * 3.14159265f / 180.0f, 1e-3f);
  EXPECT_NEAR(cc.distance(), 5.0f, 1e-3f);
}

TEST(CameraController, PanMovesEyeAndTargetTogetherZoomScalesDistance) {
  CameraController cc;
  cc.set(startCamera());
  cc.panPixels({100, 0}, 500);
  EXPECT_NEAR(cc.distance(), 5.0f, 1e-4f);
  EXPECT_LT(cc.camera().target.x, 0.0f);  // dragging right moves the view's content right: target left
  EXPECT_NEAR(cc.camera().target.y, 0.0f, 1e-5f);
  cc.zoom(0.5f);
  EXPECT_NEAR(cc.distance(), 2.5f, 1e-4f);
}

TEST(CameraController, FrameAllShowsTheWholeBox) {
  CameraController cc;
  cc.set(startCamera());
  cc.orbit(0.4f, 0.2f);
  const glm::vec3 lo(-1, -0.5f, 3), hi(3, 1.5f, 4);
  const glm::ivec2 vp(800, 600);
  cc.frame(lo, hi, 800.0f / 600.0f);
  for (int k = 0; k < 8; ++k) {
    const glm::vec3 p((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
    glm::vec2 px;
    ASSERT_TRUE(projectToPixel(cc.camera(), p, vp, px));
    EXPECT_GE(px.x, 0.0f);
    EXPECT_LE(px.x, 800.0f);
    EXPECT_GE(px.y, 0.0f);
    EXPECT_LE(px.y, 600.0f);
    const float depth = glm::dot(p - cc.camera().eye, cc.camera().forward());
    EXPECT_GT(depth, cc.camera().zNear);
    EXPECT_LT(depth, cc.camera().zFar);
  }
}

TEST(Picking, RayThroughAPixelHitsWhatProjectsThere) {
  render::Camera c = startCamera();
  const glm::ivec2 vp(640, 480);
  // One triangle facing the camera at z = 0.
  TriMesh m;
  m.positions = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
  m.indices = {0, 1, 2};
  const glm::vec3 target(0.1f, 0.2f, 0.0f);
  glm::vec2 px;
  ASSERT_TRUE(projectToPixel(c, target, vp, px));
  const auto hit = raycast(m, pixelRay(c, px, vp));
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(glm::length(hit->point - target), 0.0f, 1e-4f);
  EXPECT_NEAR(hit->normal.z, 1.0f, 1e-6f);  // facing the ray origin
  EXPECT_FALSE(raycast(m, pixelRay(c, {2, 2}, vp)).has_value());
  // Nearest projected point, skipping points that face away.
  const std::vector<glm::vec3> pts = {{0.1f, 0.2f, 0.0f}, {0.1f, 0.2f, -0.1f}, {-0.8f, 0.0f, 0.0f}};
  const std::vector<glm::vec3> nrm = {{0, 0, -1}, {0, 0, 1}, {0, 0, 1}};
  EXPECT_EQ(pickPoint(pts, nrm, c, vp, px, 10.0f), 1);
  EXPECT_EQ(pickPoint(pts, {}, c, vp, px, 10.0f), 0);
  EXPECT_EQ(pickPoint(pts, nrm, c, vp, {5, 5}, 10.0f), -1);

  // Feathers: the nearest coat triangle's feather id, unless the skin is in front of it.
  TriMesh coat;
  coat.positions = {{-1, -1, 0.2f}, {1, -1, 0.2f}, {0, 1, 0.2f}, {-1, -1, 0.4f}, {1, -1, 0.4f}, {0, 1, 0.4f}};
  coat.indices = {0, 1, 2, 3, 4, 5};
  coat.featherId = {7, 7, 7, 9, 9, 9};
  const Ray ray = pixelRay(c, px, vp);
  const bool eyeAbove = c.eye.z > 0.4f;
  ASSERT_TRUE(eyeAbove) << "the test camera looks down the z axis from above";
  EXPECT_EQ(pickFeather(coat, TriMesh{}, ray), 9);  // the upper card is nearer the eye
  TriMesh lid = m;
  for (auto& p : lid.positions) p.z = 0.6f;  // skin in front of both
  EXPECT_EQ(pickFeather(coat, lid, ray), -1);
  EXPECT_EQ(pickFeather(coat, m, ray), 9);  // skin behind
  coat.featherId.clear();
  EXPECT_EQ(pickFeather(coat, m, ray), -1);
}
