#pragma once
// A pipeline frame as the pipeline tests compare it: elevations, ages, presence, every attribute of the
// coat mesh and its draw ranges, compared bit for bit.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/core/trimesh.hpp"
#include "pteryla/pipeline/pipeline.hpp"

namespace pteryla::pipeline_test {

struct Frame {
  std::vector<double> elevation, age;
  std::vector<uint8_t> present;
  TriMesh mesh;
  std::vector<pipeline::CoatDrawRange> ranges;
};

inline Frame grab(pipeline::Pipeline& p) {
  Frame f;
  f.elevation = p.elevations();
  f.age = p.feathers().age;
  f.present = p.feathers().present;
  f.mesh = p.coatMesh().mesh;
  f.ranges = p.coatMesh().ranges;
  return f;
}

template <class T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

// Every array of the two meshes holds the same bytes.
inline bool sameMesh(const TriMesh& a, const TriMesh& b) {
  return sameBytes(a.positions, b.positions) && sameBytes(a.normals, b.normals) && sameBytes(a.tangents, b.tangents) &&
         sameBytes(a.uvGlobal, b.uvGlobal) && sameBytes(a.uvBarb, b.uvBarb) && sameBytes(a.uvGrowth, b.uvGrowth) &&
         sameBytes(a.alpha, b.alpha) && sameBytes(a.sheath, b.sheath) && sameBytes(a.barbCount, b.barbCount) &&
         sameBytes(a.featherId, b.featherId) && sameBytes(a.indices, b.indices);
}

inline void expectIdentical(const Frame& a, const Frame& b, double t) {
  SCOPED_TRACE("t = " + std::to_string(t));
  EXPECT_TRUE(sameBytes(a.elevation, b.elevation));
  EXPECT_TRUE(sameBytes(a.age, b.age));
  EXPECT_EQ(a.present, b.present);
  EXPECT_EQ(a.mesh.vertexCount(), b.mesh.vertexCount());
  EXPECT_TRUE(sameBytes(a.mesh.positions, b.mesh.positions));
  EXPECT_TRUE(sameBytes(a.mesh.normals, b.mesh.normals));
  EXPECT_TRUE(sameBytes(a.mesh.tangents, b.mesh.tangents));
  EXPECT_TRUE(sameBytes(a.mesh.uvGlobal, b.mesh.uvGlobal));
  EXPECT_TRUE(sameBytes(a.mesh.uvBarb, b.mesh.uvBarb));
  EXPECT_TRUE(sameBytes(a.mesh.uvGrowth, b.mesh.uvGrowth));
  EXPECT_TRUE(sameBytes(a.mesh.alpha, b.mesh.alpha));
  EXPECT_TRUE(sameBytes(a.mesh.sheath, b.mesh.sheath));
  EXPECT_TRUE(sameBytes(a.mesh.barbCount, b.mesh.barbCount));
  EXPECT_TRUE(sameBytes(a.mesh.featherId, b.mesh.featherId));
  EXPECT_TRUE(sameBytes(a.mesh.indices, b.mesh.indices));
  ASSERT_EQ(a.ranges.size(), b.ranges.size());
  for (size_t k = 0; k < a.ranges.size(); ++k) {
    EXPECT_EQ(a.ranges[k].firstIndex, b.ranges[k].firstIndex) << k;
    EXPECT_EQ(a.ranges[k].indexCount, b.ranges[k].indexCount) << k;
    for (int q = 0; q < 4; ++q) EXPECT_EQ(a.ranges[k].partCount[q], b.ranges[k].partCount[q]) << k;
    EXPECT_EQ(a.ranges[k].origin, b.ranges[k].origin) << k;
    EXPECT_EQ(a.ranges[k].axisX, b.ranges[k].axisX) << k;
  }
}

}  // namespace pteryla::pipeline_test
