// OBJ / PLY export of feather meshes.
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/mesh.hpp"
#include "pteryla/feather/mesh_io.hpp"
#include "test_mesh_fixtures.hpp"

using namespace pteryla;
using namespace pteryla::feather;

namespace {
std::string tmp(const std::string& name) { return std::string(PTERYLA_BUILD_DIR) + "/" + name; }
std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
}  // namespace

TEST(FeatherMeshIo, ObjHasVerticesTexcoordsNormalsFaces) {
  const TriMesh m = buildFeatherMesh(geomtest::contour(), 1.0, 0.3);
  const std::string path = tmp("test_mesh_io.obj");
  writeObj(path, m, UvSet::Barb);
  std::ifstream f(path);
  std::string line;
  size_t v = 0, vt = 0, vn = 0, faces = 0, vtIndex = 0;
  bool vtOk = true, faceOk = true;
  while (std::getline(f, line)) {
    if (line.rfind("v ", 0) == 0) ++v;
    if (line.rfind("vt ", 0) == 0) {
      float a, b;
      std::sscanf(line.c_str(), "vt %f %f", &a, &b);
      vtOk = vtOk && std::abs(a - m.uvBarb[vtIndex].x) < 1e-6f && std::abs(b - m.uvBarb[vtIndex].y) < 1e-6f;
      ++vt;
      ++vtIndex;
    }
    if (line.rfind("vn ", 0) == 0) ++vn;
    if (line.rfind("f ", 0) == 0) {
      unsigned a[9];
      faceOk = faceOk &&
               std::sscanf(line.c_str(), "f %u/%u/%u %u/%u/%u %u/%u/%u", a, a + 1, a + 2, a + 3, a + 4, a + 5, a + 6,
                           a + 7, a + 8) == 9 &&
               a[0] == m.indices[3 * faces] + 1 && a[3] == m.indices[3 * faces + 1] + 1 &&
               a[6] == m.indices[3 * faces + 2] + 1;
      ++faces;
    }
  }
  EXPECT_EQ(v, m.vertexCount());
  EXPECT_EQ(vt, m.vertexCount());
  EXPECT_EQ(vn, m.vertexCount());
  EXPECT_EQ(faces, m.triangleCount());
  EXPECT_TRUE(vtOk);
  EXPECT_TRUE(faceOk);
}

TEST(FeatherMeshIo, PlyBinaryAndAsciiCarryUvProperties) {
  const TriMesh m = buildFeatherMesh(geomtest::contour(), 0.7, 0.2);
  const std::string bin = tmp("test_mesh_io_bin.ply"), asc = tmp("test_mesh_io_ascii.ply");
  writePly(bin, m);
  PlyOptions o;
  o.binary = false;
  writePly(asc, m, o);
  const std::string b = slurp(bin), a = slurp(asc);
  for (const std::string* s : {&a, &b}) {
    EXPECT_NE(s->find("element vertex " + std::to_string(m.vertexCount()) + "\n"), std::string::npos);
    EXPECT_NE(s->find("element face " + std::to_string(m.triangleCount()) + "\n"), std::string::npos);
    EXPECT_NE(s->find("property float u\nproperty float v\n"), std::string::npos);
    EXPECT_NE(s->find("property float sheath\n"), std::string::npos);
  }
  const size_t headerEnd = b.find("end_header\n") + 11;
  const size_t props = 3 + 3 + 2 + 2 + 2 + 1 + 1 + 1 + 1;
  EXPECT_EQ(b.size(), headerEnd + m.vertexCount() * props * 4 + m.triangleCount() * 13);
  float x;
  std::memcpy(&x, b.data() + headerEnd, 4);
  EXPECT_EQ(x, m.positions[0].x);
  // ascii: header + one line per vertex + one per face
  size_t lines = 0;
  for (char ch : a.substr(a.find("end_header\n") + 11)) lines += ch == '\n';
  EXPECT_EQ(lines, m.vertexCount() + m.triangleCount());
}

TEST(FeatherMeshIo, UnwritablePathAndUnknownExtensionThrow) {
  const TriMesh m = buildFeatherMesh(geomtest::contour(), 1.0, 0.1);
  try {
    writeObj("/nonexistent-dir/x.obj", m);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "/nonexistent-dir/x.obj");
  }
  EXPECT_THROW(writePly("/nonexistent-dir/x.ply", m), Error);
  EXPECT_THROW(writeMesh(tmp("x.stl"), m), Error);
  writeMesh(tmp("test_mesh_io_ext.PLY"), m);
  EXPECT_FALSE(slurp(tmp("test_mesh_io_ext.PLY")).empty());
}
