// CoatMesher (src/pipeline/coat_mesher.hpp): an incremental update after some feathers changed (moved,
// grown, hidden, given another level of detail) gives byte-identical mesh arrays and ranges to a new
// mesher meshing the same input from scratch, and really reuses the unchanged feathers.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "coat_mesher.hpp"
#include "frames.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

using namespace pteryla;
using pipeline::CoatMesher;
using pipeline::CoatMeshInput;

namespace {

const std::string kSceneFile = std::string(PTERYLA_DATA_DIR) + "/scenes/coat_mesher_test_in_memory.json";

struct Coat {
  coat::CoatFeathers feathers;
  coat::PackResult packed;
  std::vector<double> lods;
};

// The patch's coat (220 feathers) packed by the height field, as the mesh stage receives it.
Coat patchCoat() {
  const pipeline::Scene scene = pipeline::sceneFromJson(Json::parse(R"({
    "pteryla": 1, "seed": 9, "mesh": "../meshes/patch.obj", "feathers": {"contour": "../feathers/contour.json"},
    "tracts": [{"name": "patch", "groups": ["patch"], "count": 220, "feather_scale": "auto",
                "feather_spacings": 1.5, "relax": {"iterations": 10}}],
    "directions": {"vectors": [{"at": [0, 0, 0], "direction": [1, 0, 0]}]},
    "packing": {"method": "height_field", "clearance": 0.0004, "skin_sample_spacing": 0.01}})"),
                                                        kSceneFile);
  pipeline::Pipeline p(scene);
  Coat c;
  c.feathers = p.feathers();
  coat::PackOptions o;
  o.clearance = 0.0004;
  c.packed = coat::pack(p.posedSkin(), c.feathers, o);
  return c;
}

CoatMeshInput input(const Coat& c) {
  CoatMeshInput in;
  in.coat = &c.feathers;
  in.packedCoat = &c.feathers;
  in.packed = &c.packed;
  in.lod = 0.3;
  in.featherLods = &c.lods;
  return in;
}

void expectSameResult(const CoatMesher& a, const TriMesh& ma, const CoatMesher& b, const TriMesh& mb) {
  EXPECT_TRUE(pipeline_test::sameMesh(ma, mb));
  EXPECT_EQ(a.feathers(), b.feathers());
  ASSERT_EQ(a.ranges().size(), b.ranges().size());
  for (size_t k = 0; k < a.ranges().size(); ++k) {
    const auto& x = a.ranges()[k];
    const auto& y = b.ranges()[k];
    EXPECT_TRUE(x.shaftFirst == y.shaftFirst && x.shaftCount == y.shaftCount && x.leftFirst == y.leftFirst &&
                x.leftCount == y.leftCount && x.rightFirst == y.rightFirst && x.rightCount == y.rightCount &&
                x.afterFirst == y.afterFirst && x.afterCount == y.afterCount)
        << k;
  }
}

}  // namespace

TEST(CoatMesher, IncrementalUpdateEqualsFullMesh) {
  Coat c = patchCoat();
  const size_t n = c.feathers.size();
  ASSERT_GT(n, 100u);
  CoatMesher incremental;
  TriMesh mesh;
  incremental.update(input(c), mesh);
  EXPECT_EQ(incremental.regenerated(), n);
  EXPECT_EQ(incremental.reused(), 0u);

  // Change a few feathers, each in another way: raised (placement only), growing (new curves), hidden,
  // a lower level of detail (re-meshed from the same curves).
  c.packed.elevation[3] += 0.1;
  c.packed.elevation[40] += 0.2;
  c.feathers.age[7] = 0.6;
  c.feathers.age[90] = 0.95;
  c.feathers.present[12] = 0;
  c.lods.assign(n, 1.0);
  c.lods[25] = 0.5;
  incremental.update(input(c), mesh);
  EXPECT_EQ(incremental.regenerated(), 2u);    // the growing feathers
  EXPECT_EQ(incremental.reused(), n - 1 - 3);  // all present but the growing and the lowered one
  CoatMesher full;
  TriMesh fresh;
  full.update(input(c), fresh);
  expectSameResult(incremental, mesh, full, fresh);

  // A feather regrown with as many vertices and triangles is written over its old place: the mesh keeps
  // its buffers (no second copy of the coat is made) and still equals a fresh one.
  {
    const void* uvs = mesh.uvGlobal.data();
    const void* indices = mesh.indices.data();
    c.feathers.age[90] = 0.9500001;
    incremental.update(input(c), mesh);
    EXPECT_EQ(incremental.regenerated(), 1u);
    EXPECT_EQ(incremental.reused(), n - 1 - 1);  // all present but the regrown one
    EXPECT_EQ(mesh.uvGlobal.data(), uvs);
    EXPECT_EQ(mesh.indices.data(), indices);
    CoatMesher full2;
    TriMesh fresh3;
    full2.update(input(c), fresh3);
    expectSameResult(incremental, mesh, full2, fresh3);
  }

  // A draped coat trims the indices of the mesh it was given; the next update starts from the kept ones.
  incremental.keepIndices(mesh);
  std::fill(mesh.indices.begin(), mesh.indices.begin() + 30, 0u);
  c.feathers.age[7] = 1.0;
  c.packed.elevation[3] -= 0.1;
  incremental.update(input(c), mesh);
  CoatMesher again;
  TriMesh fresh2;
  again.update(input(c), fresh2);
  expectSameResult(incremental, mesh, again, fresh2);

  // Any other mesh than its last result is not copied from.
  TriMesh other;
  incremental.update(input(c), other);
  EXPECT_EQ(incremental.reused(), 0u);
  expectSameResult(incremental, other, again, fresh2);
}
