// A feather bent along its shaft (feather/bend.hpp): no bend gives the rigid placement's bits; a bend
// keeps the shaft's length, leaves the root along the follicle frame, carries the vertices with the shaft
// (the shaft and barbs near the root stay put, the tip follows the displaced tip joint).
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>
#include <vector>

#include "pteryla/feather/bend.hpp"
#include "pteryla/feather/mesh.hpp"
#include "test_mesh_fixtures.hpp"

using namespace pteryla;
using namespace pteryla::feather;

namespace {

struct Placed {
  std::vector<glm::vec3> p;
  std::vector<PackedDir> n, t;
};

Placed place(const TriMesh& local, const FeatherPlacement& pl, const ShaftBend* bend) {
  Placed out;
  const size_t count = local.positions.size();
  out.p.resize(count);
  out.n.resize(count);
  out.t.resize(count);
  if (bend)
    placeBentFeatherVertices(pl, *bend, local.positions.data(), local.normals.data(), local.tangents.data(), count,
                             out.p.data(), out.n.data(), out.t.data());
  else
    placeFeatherVertices(pl, local.positions.data(), local.normals.data(), local.tangents.data(), count, out.p.data(),
                         out.n.data(), out.t.data());
  return out;
}

template <class T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

}  // namespace

TEST(Bend, RigidBendIsThePlacementBitForBit) {
  const FeatherParams p = geomtest::contour(false);
  const TriMesh local = buildFeatherMesh(p, 1.0, 1.0);
  const FeatherPlacement pl =
      FeatherPlacement::fromFollicle({0.2, -0.1, 0.4}, glm::normalize(glm::dvec3(1, 0.2, 0)), {0, 0, 1}, 0.3);
  const Placed rigid = place(local, pl, nullptr);
  ShaftBend none;
  none.length = p.totalLength();
  ShaftBend zero = none;
  zero.offset.assign(6, glm::dvec3(0.0));
  for (const ShaftBend* b : {&none, &zero}) {
    const Placed bent = place(local, pl, b);
    EXPECT_TRUE(sameBits(bent.p, rigid.p));
    EXPECT_TRUE(sameBits(bent.n, rigid.n));
    EXPECT_TRUE(sameBits(bent.t, rigid.t));
  }
}

TEST(Bend, BentShaftKeepsItsLengthAndLeavesTheRootAlongTheFrame) {
  const FeatherParams p = geomtest::contour(false);
  const TriMesh local = buildFeatherMesh(p, 1.0, 1.0);
  const glm::dvec3 T = glm::normalize(glm::dvec3(1, 0.2, 0)), N(0, 0, 1);
  const FeatherPlacement pl = FeatherPlacement::fromFollicle({0.2, -0.1, 0.4}, T, N, 0.3);
  ShaftBend b;
  b.length = p.totalLength();
  const int n = 6;
  // A lag growing toward the tip, across the shaft (as a chain trailing a sideways jolt).
  const glm::dvec3 side = glm::normalize(glm::cross(N, T));
  for (int k = 1; k <= n; ++k) b.offset.push_back(-0.5 * std::pow(k / double(n), 2.0) * side);
  const std::vector<glm::dvec3> shaft = bentShaft(pl, b);
  ASSERT_EQ(shaft.size(), 4u * n + 1);
  double length = 0;
  for (size_t i = 1; i < shaft.size(); ++i) length += glm::length(shaft[i] - shaft[i - 1]);
  EXPECT_NEAR(length, b.length, 1e-12);
  EXPECT_EQ(shaft.front(), pl.origin);
  const glm::dvec3 axis = glm::normalize(pl.x);
  EXPECT_GT(glm::dot(glm::normalize(shaft[1] - shaft[0]), axis), std::cos(0.02));  // root along the frame
  // The tip swings toward its displaced joint (the chain is inextensible, so it also comes back a little).
  const glm::dvec3 rigidTip = pl.origin + axis * b.length;
  EXPECT_LT(glm::dot(shaft.back() - rigidTip, side), -0.3);
  // Smooth: consecutive samples turn by a few degrees at most.
  for (size_t i = 1; i + 1 < shaft.size(); ++i) {
    const double c = glm::dot(glm::normalize(shaft[i] - shaft[i - 1]), glm::normalize(shaft[i + 1] - shaft[i]));
    EXPECT_GT(c, std::cos(0.1)) << i;
  }

  const Placed rigid = place(local, pl, nullptr);
  const Placed bent = place(local, pl, &b);
  // Vertices near the follicle stay (within the bend of the first sample); the far ones follow the tip.
  double nearMove = 0, farMove = 0;
  for (size_t v = 0; v < local.positions.size(); ++v) {
    const double x = local.positions[v].x;
    const double move = glm::length(glm::dvec3(bent.p[v] - rigid.p[v]));
    if (x < 0.05 * b.length) nearMove = std::max(nearMove, move);
    if (x > 0.9 * b.length) farMove = std::max(farMove, move);
    EXPECT_NEAR(glm::length(bent.n[v].get()), 1.0f, 5e-5f);  // unit, in 16-bit components
    EXPECT_NEAR(glm::length(bent.t[v].get()), 1.0f, 5e-5f);
  }
  EXPECT_LT(nearMove, 0.01);
  EXPECT_GT(farMove, 0.3);
}
