#include <gtest/gtest.h>

#include "pteryla/core/trimesh.hpp"

using pteryla::TriMesh;

TEST(TriMesh, AppendOffsetsIndicesAndPadsMissingAttributes) {
  TriMesh a, b;
  a.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  a.indices = {0, 1, 2};
  b.positions = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  b.indices = {0, 2, 1};
  b.alpha = {0.5f, 0.5f, 0.5f};
  a.append(b);
  ASSERT_EQ(a.vertexCount(), 6u);
  EXPECT_EQ(a.indices, (std::vector<uint32_t>{0, 1, 2, 3, 5, 4}));
  ASSERT_EQ(a.alpha.size(), 6u);  // a had no alpha: padded with the default 1
  EXPECT_EQ(a.alpha[0], 1.0f);
  EXPECT_EQ(a.alpha[3], 0.5f);
  EXPECT_TRUE(a.normals.empty());  // absent on both sides stays absent
}
