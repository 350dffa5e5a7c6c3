// Tracts: groups, label files, JSON descriptions with set operations, and their errors.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include "pteryla/coat/primitives.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/error.hpp"

using namespace pteryla;
using namespace pteryla::coat;

namespace {

std::string data(const std::string& name) { return std::string(PTERYLA_TEST_DIR) + "/data/" + name; }

std::vector<uint32_t> sources(const SkinMesh& m, const Tract& t) {
  std::vector<uint32_t> s;
  for (uint32_t f : t.faces)
    if (s.empty() || s.back() != m.sourceFace[f]) s.push_back(m.sourceFace[f]);
  return s;
}

void expectFileRejected(const std::string& file, const SkinMesh& m, const std::string& elementFile,
                        const std::string& element, const std::string& message) {
  try {
    loadTractFile(data(file), m);
    FAIL() << file << " was accepted";
  } catch (const Error& e) {
    EXPECT_NE(e.file().find(elementFile), std::string::npos) << e.what();
    EXPECT_NE(e.element().find(element), std::string::npos) << "element '" << e.element() << "': " << e.what();
    EXPECT_NE(e.detail().find(message), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(Tracts, WholeMeshGroupsAndSetOperations) {
  const SkinMesh m = loadSkinMesh(data("groups.obj"));
  const Tract all = wholeMeshTract(m);
  EXPECT_EQ(all.size(), m.faceCount());
  const Tract back = tractFromGroups(m, "back", {"back"});
  const Tract front = tractFromGroups(m, "front", {"belly", "left"});
  EXPECT_EQ(sources(m, back), (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(sources(m, front), (std::vector<uint32_t>{3, 4, 5}));
  EXPECT_EQ(tractUnion(back, front).size(), m.faceCount());
  EXPECT_TRUE(tractIntersection(back, front).faces.empty());
  EXPECT_EQ(tractDifference(all, back).faces, front.faces);
  EXPECT_TRUE(back.contains(back.faces[0]));
  EXPECT_FALSE(back.contains(front.faces[0]));
  EXPECT_THROW(tractFromGroups(m, "x", {"tail"}), Error);
  const Tract picked = tractFromSourceFaces(m, "p", {5, 0, 5});
  EXPECT_EQ(sources(m, picked), (std::vector<uint32_t>{0, 5}));
  EXPECT_EQ(picked.size(), 4u);  // two quads -> four triangles
  EXPECT_NEAR(tractArea(m, back), 3.0, 1e-12);
}

TEST(Tracts, LabelFiles) {
  const SkinMesh m = loadSkinMesh(data("groups.obj"));
  const auto labels = readFaceLabels(data("labels.txt"), m.sourceFaceCount);
  EXPECT_EQ(labels, (std::vector<int64_t>{0, 0, 1, 2, 2, -1}));
  EXPECT_EQ(sources(m, tractFromLabels(m, "t", labels, {1, 2})), (std::vector<uint32_t>{2, 3, 4}));
  try {
    readFaceLabels(data("labels_bad.txt"), m.sourceFaceCount);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "line 3");
    EXPECT_NE(e.detail().find("'three'"), std::string::npos);
  }
  try {
    readFaceLabels(data("labels_short.txt"), m.sourceFaceCount);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(e.detail().find("4 labels but the mesh has 6 faces"), std::string::npos) << e.what();
  }
}

TEST(Tracts, JsonFileWithSetOperations) {
  const SkinMesh m = loadSkinMesh(data("groups.obj"));
  const auto t = loadTractFile(data("tracts.json"), m);
  ASSERT_EQ(t.size(), 6u);
  EXPECT_EQ(t[0].name, "back");
  EXPECT_EQ(sources(m, t[0]), (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(sources(m, t[1]), (std::vector<uint32_t>{3, 4, 5}));
  EXPECT_EQ(sources(m, t[2]), (std::vector<uint32_t>{2, 3, 4}));  // labels_file relative to the JSON
  EXPECT_EQ(sources(m, t[3]), (std::vector<uint32_t>{3, 4, 5}));  // whole mesh minus back
  EXPECT_EQ(sources(m, t[4]), (std::vector<uint32_t>{2, 3, 4}));
  EXPECT_EQ(sources(m, t[5]), (std::vector<uint32_t>{0, 5}));
}

TEST(Tracts, JsonErrorsNameFileAndKeyPath) {
  const SkinMesh m = loadSkinMesh(data("groups.obj"));
  expectFileRejected("tracts_unknown_group.json", m, "tracts_unknown_group.json", "tracts[0].groups[1]",
                     "unknown face group 'tail'");
  expectFileRejected("tracts_unknown_key.json", m, "tracts_unknown_key.json", "tracts[0].densty", "unknown key");
  expectFileRejected("tracts_empty.json", m, "tracts_empty.json", "tracts[0]", "selects no faces");
  expectFileRejected("tracts_bad_labels.json", m, "labels_bad.txt", "line 3", "not an integer");
}

TEST(Tracts, ReadTractLeavesOtherKeysToTheCaller) {
  const SkinMesh m = makeGridPatch(4, 4);
  const Json j = Json::parse(R"({"name": "strip", "faces": [0, 1, 2], "density": 40, "union": ["all"]})");
  JsonReader r(j, "scene.json", "tracts[0]");
  const std::vector<Tract> earlier = {wholeMeshTract(m, "all")};
  const Tract t = readTract(r, m, earlier);
  EXPECT_EQ(t.size(), m.faceCount());
  EXPECT_THROW(r.finish(), Error);  // "density" is the caller's to read
  EXPECT_EQ(r.number("density"), 40);
  EXPECT_NO_THROW(r.finish());

  const Json bad = Json::parse(R"([{"name": "a", "faces": [3, 99]}, {"name": "a"}, {"name": "b", "union": ["zz"]}])");
  {
    JsonReader r0(bad[0], "scene.json", "tracts[0]");
    try {
      readTract(r0, m, {});
      FAIL();
    } catch (const Error& e) {
      EXPECT_EQ(e.element(), "tracts[0].faces[1]");
    }
  }
  {
    const Json two = Json::parse(R"([{"name": "a"}, {"name": "a"}])");
    std::vector<JsonReader> items = {JsonReader(two[0], "s.json", "tracts[0]"),
                                     JsonReader(two[1], "s.json", "tracts[1]")};
    try {
      readTracts(items, m);
      FAIL();
    } catch (const Error& e) {
      EXPECT_EQ(e.element(), "tracts[1].name");
    }
  }
  {
    JsonReader r2(bad[2], "scene.json", "tracts[2]");
    try {
      readTract(r2, m, {});
      FAIL();
    } catch (const Error& e) {
      EXPECT_EQ(e.element(), "tracts[2].union[0]");
    }
  }
}

TEST(Tracts, BoundaryOfATractInsideAMesh) {
  const SkinMesh m = makeGridPatch(4, 4, 4.0, 4.0);
  Tract all = wholeMeshTract(m);
  double perimeter = 0;
  for (const auto& s : tractBoundarySegments(m, all)) perimeter += glm::length(s[1] - s[0]);
  EXPECT_NEAR(perimeter, 16.0, 1e-12);
  // Left half: its boundary includes the interior cut at x = 2.
  Tract left;
  for (uint32_t f = 0; f < m.faceCount(); ++f)
    if (pointAt(m, f, glm::dvec3(1.0 / 3)).x < 2.0) left.faces.push_back(f);
  perimeter = 0;
  for (const auto& s : tractBoundarySegments(m, left)) perimeter += glm::length(s[1] - s[0]);
  EXPECT_NEAR(perimeter, 12.0, 1e-12);
  // Closed surfaces have no tract boundary.
  EXPECT_TRUE(tractBoundarySegments(makeIcosphere(1), wholeMeshTract(makeIcosphere(1))).empty());
}
