// CoatMesher (src/pipeline/coat_mesher.hpp): an incremental update after some feathers changed (moved,
// grown, hidden, given another level of detail) gives byte-identical mesh arrays and ranges to a new
// mesher meshing the same input from scratch, and really reuses the unchanged feathers.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

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

// The present feathers of `c` in layer order, each meshed on its own at `lod` from the packed curves of
// feather rep[i] and placed at its own follicle (feather::appendFeatherMeshes, no mesher involved).
TriMesh meshedFrom(const Coat& c, const std::vector<uint32_t>& rep, double lod) {
  const size_t n = c.feathers.size();
  std::vector<feather::FeatherCurves> curves(n);
  std::vector<feather::LodOrder> orders(n);
  std::vector<feather::FeatherMeshInput> inputs;
  for (uint32_t i : c.feathers.layerOrder) {
    if (!c.feathers.present[i]) continue;
    const uint32_t r = rep[i];
    if (curves[r].barbs.empty()) {
      feather::FeatherParams p;
      coat::packedParamsInto(c.feathers, c.packed, r, p);
      feather::generateBarbs(p, curves[r]);
      feather::computeLodOrder(curves[r], orders[r]);
    }
    feather::FeatherMeshInput fi;
    fi.curves = &curves[r];
    fi.order = &orders[r];
    const coat::FeatherFrame& fr = c.feathers.frames[i];
    fi.placement = feather::FeatherPlacement::fromFollicle(fr.origin, fr.tangent, fr.normal, c.packed.elevation[i]);
    fi.featherId = i;
    fi.lod = lod;
    inputs.push_back(fi);
  }
  TriMesh direct;
  feather::appendFeatherMeshes(inputs.data(), inputs.size(), feather::MeshOptions{}, direct);
  return direct;
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

// Instancing (CoatMeshInput::instanceTolerance): feathers meshed from an earlier feather's curves keep
// their own topology and lie within the tolerance of their own mesh (a barb vertex is a convex combination
// of control vertices, each within tolerance x extent; the shaft's rings add its width's turn, hence the
// factor 2), representatives are meshed exactly, and the store holds fewer vertices than the coat.
TEST(CoatMesher, InstancedFeathersStayWithinTheTolerance) {
  const Coat c = patchCoat();
  const size_t n = c.feathers.size();
  const double tol = 0.02;
  CoatMesher exact, shared;
  TriMesh a, b;
  CoatMeshInput in = input(c);
  exact.update(in, a);
  in.instanceTolerance = tol;
  shared.update(in, b);
  const pipeline::InstancingStats& s = shared.instancing();
  EXPECT_EQ(s.feathers, n);
  EXPECT_LT(s.representatives, n / 2) << "neighbours in a patch share curves at 2%";
  EXPECT_GE(s.meshes, s.representatives);
  EXPECT_EQ(s.vertices, b.positions.size());
  EXPECT_LT(s.storedVertices, s.vertices / 2);
  EXPECT_LT(s.storedBytes(), s.unsharedBytes() / 2);
  EXPECT_EQ(exact.instancing().representatives, n);
  EXPECT_LE(exact.instancing().storedVertices, a.positions.size());  // identical feathers are stored once

  // Without a tolerance the coat is what meshing every feather placed, on its own, gives: identical
  // meshes stored once are placed as their own.
  std::vector<uint32_t> itself(n);
  for (uint32_t i = 0; i < n; ++i) itself[i] = i;
  EXPECT_TRUE(pipeline_test::sameMesh(a, meshedFrom(c, itself, in.lod)));

  ASSERT_EQ(a.positions.size(), b.positions.size());
  ASSERT_EQ(a.indices, b.indices);
  ASSERT_EQ(a.featherId, b.featherId);
  std::vector<double> extent(n, 0.0), moved(n, 0.0);
  for (size_t v = 0; v < a.positions.size(); ++v) {
    const uint32_t i = a.featherId[v];
    extent[i] = std::max(extent[i], glm::length(glm::dvec3(a.positions[v]) - c.feathers.frames[i].origin));
    moved[i] = std::max(moved[i], glm::length(glm::dvec3(a.positions[v]) - glm::dvec3(b.positions[v])));
  }
  size_t changed = 0;
  for (size_t i = 0; i < n; ++i) {
    EXPECT_LE(moved[i], 2 * tol * extent[i]) << "feather " << i;
    changed += moved[i] > 0;
  }
  EXPECT_GT(changed, 0u);
  EXPECT_LE(changed, n - s.representatives);  // a representative is meshed from its own curves

  // The instanced coat is exactly what meshing every feather from its representative's curves, placed
  // at its own follicle, gives: meshes made once and copied, and stored once, come out as their own.
  const std::vector<uint32_t>& rep = shared.representatives();
  ASSERT_EQ(rep.size(), n);
  for (uint32_t i = 0; i < n; ++i) ASSERT_LE(rep[i], i);
  EXPECT_TRUE(pipeline_test::sameMesh(b, meshedFrom(c, rep, in.lod)));
}

// Instancing is a function of the frame's coat alone: after feathers changed (raised, growing, hidden,
// another level) or the tolerance changed, an update equals a new mesher's at that tolerance.
TEST(CoatMesher, InstancedUpdateEqualsFreshInstancedMesh) {
  Coat c = patchCoat();
  const size_t n = c.feathers.size();
  auto at = [&](double tol) {
    CoatMeshInput in = input(c);
    in.instanceTolerance = tol;
    return in;
  };
  CoatMesher incremental;
  TriMesh mesh;
  incremental.update(at(0.02), mesh);
  c.packed.elevation[3] += 0.1;
  c.feathers.age[7] = 0.6;
  c.feathers.present[12] = 0;
  c.lods.assign(n, 1.0);
  c.lods[25] = 0.5;
  incremental.update(at(0.02), mesh);
  EXPECT_GT(incremental.reused(), n / 2);
  {
    CoatMesher full;
    TriMesh fresh;
    full.update(at(0.02), fresh);
    expectSameResult(incremental, mesh, full, fresh);
    EXPECT_EQ(incremental.instancing().storedVertices, full.instancing().storedVertices);
    EXPECT_EQ(incremental.instancing().meshes, full.instancing().meshes);
  }
  for (double tol : {0.05, 0.0}) {
    incremental.update(at(tol), mesh);
    CoatMesher full;
    TriMesh fresh;
    full.update(at(tol), fresh);
    expectSameResult(incremental, mesh, full, fresh);
  }
}

// A coat meshed from its interpolated parameters (no packed key barbs, as a draped coat is) chooses
// representatives among every feather, present or not: feathers that stay present and mature keep their
// shapes bit for bit while others moult out and grow back, and each frame equals a fresh mesher's.
TEST(CoatMesher, InstancedShapesHoldStillThroughAMoult) {
  Coat c = patchCoat();
  const size_t n = c.feathers.size();
  // The patch's feathers are copies of one: make them differ smoothly, as interpolated feathers do.
  for (size_t i = 0; i < n; ++i) {
    c.feathers.params[i].barbLength *= 1.0 + 0.004 * static_cast<double>(i % 25);
    c.feathers.params[i].rachisVentralDorsalCurvature += 0.005 * static_cast<double>(i % 25);
  }
  coat::PackResult flat;
  flat.order = c.feathers.layerOrder;
  flat.elevation.assign(n, 0.0);
  c.packed = flat;
  auto at = [&] {
    CoatMeshInput in = input(c);
    in.instanceTolerance = 0.02;
    return in;
  };
  // Vertex positions per feather of a mesh.
  auto byFeather = [&](const TriMesh& m) {
    std::vector<std::vector<glm::vec3>> out(n);
    for (size_t v = 0; v < m.positions.size(); ++v) out[m.featherId[v]].push_back(m.positions[v]);
    return out;
  };
  CoatMesher mesher;
  TriMesh mesh;
  mesher.update(at(), mesh);
  const auto before = byFeather(mesh);
  EXPECT_LT(mesher.instancing().representatives, n / 2);
  EXPECT_GT(mesher.instancing().representatives, 4u);
  // Moult out the first feathers in index order (the likeliest representatives) and start some growing.
  std::vector<uint8_t> changed(n, 0);
  for (size_t i = 0; i < n; i += 3) {
    c.feathers.present[i] = 0;
    changed[i] = 1;
  }
  for (size_t i = 1; i < n; i += 7) {
    c.feathers.age[i] = 0.5;
    changed[i] = 1;
  }
  mesher.update(at(), mesh);
  const auto during = byFeather(mesh);
  size_t kept = 0;
  for (size_t i = 0; i < n; ++i)
    if (!changed[i]) {
      EXPECT_EQ(during[i], before[i]) << "feather " << i;
      ++kept;
    }
  EXPECT_GT(kept, n / 2);
  CoatMesher fresh;
  TriMesh freshMesh;
  fresh.update(at(), freshMesh);
  expectSameResult(mesher, mesh, fresh, freshMesh);
}
