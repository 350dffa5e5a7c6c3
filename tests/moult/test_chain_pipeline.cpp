// The dynamic chain through the Pipeline: a wing whose elbow snaps (step keys) bends the feathers under a
// dynamic control and only those, they settle back to the rigid coat, dynamic 0 is the coat without the
// behaviour bit for bit, and scrubbing gives a fresh evaluation's mesh.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include <cmath>
#include <cstring>
#include <memory>
#include <set>
#include <string>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "wing_scene.hpp"

using namespace pteryla;
using pipeline::Pipeline;

namespace {

const std::string kSceneFile = std::string(PTERYLA_DATA_DIR) + "/scenes/chain_test_in_memory.json";

// The moult tests' wing with an elbow that snaps from 0 to 25 degrees at t = 1.
Json wing() {
  Json j = moult_test::wingScene();
  j["skeleton"] = Json::parse(R"({"file": "../meshes/wing.skeleton.json", "interpolation": "step", "keys": [
      {"joint": "elbow", "t": 0, "rotation": [0, 0, 1, 0]},
      {"joint": "elbow", "t": 1, "rotation": [0, 0, 1, 25]}]})");
  return j;
}

// A control over the outer wing, its offset moving from t = 1.5 to 2; `dynamic` as a constant, or null
// for none.
Json control(const Json& dynamic) {
  Json c = Json::parse(R"({"name": "tip", "at": [1.5, 0.0, 0.1], "radius": 0.45, "falloff": 0.3,
                          "spring": {"frequency": 1.5, "damping": 0.4, "segments": 6},
                          "keys": [{"t": 0, "aim": 0}, {"t": 1.5, "offset": [0, 0, 0]},
                                   {"t": 2, "aim": 0.3, "offset": [0, 0.1, 0]}]})");
  if (!dynamic.is_null()) c["dynamic"] = dynamic;
  return c;
}

std::unique_ptr<Pipeline> make(const Json& dynamic) {
  Json j = wing();
  j["controls"] = Json::array({control(dynamic)});
  auto p = std::make_unique<Pipeline>(pipeline::sceneFromJson(j, kSceneFile));
  p->setLod(0.2);
  return p;
}

template <class T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

// Feathers whose vertices differ between two meshes of the same coat, and the largest move.
std::set<uint32_t> moved(const TriMesh& a, const TriMesh& b, double& largest) {
  std::set<uint32_t> out;
  largest = 0;
  EXPECT_EQ(a.positions.size(), b.positions.size());
  for (size_t v = 0; v < std::min(a.positions.size(), b.positions.size()); ++v)
    if (a.positions[v] != b.positions[v]) {
      out.insert(a.featherId[v]);
      largest = std::max(largest, double(glm::length(a.positions[v] - b.positions[v])));
    }
  return out;
}

}  // namespace

TEST(ChainPipeline, ElbowSnapBendsTheDynamicFeathersAndTheySettle) {
  auto dynP = make(1.0), rigidP = make(Json());
  Pipeline &dyn = *dynP, &rigid = *rigidP;
  double largest = 0;
  // At rest before the snap: the rigid coat.
  dyn.setTime(0.9);
  rigid.setTime(0.9);
  EXPECT_TRUE(sameBits(dyn.coatMesh().mesh.positions, rigid.coatMesh().mesh.positions));
  // Just after it: same pack (the chain bends the mesh only), bent feathers near the control, the others
  // untouched.
  dyn.setTime(1.1);
  rigid.setTime(1.1);
  EXPECT_EQ(dyn.elevations(), rigid.elevations());
  const std::set<uint32_t> bent = moved(dyn.coatMesh().mesh, rigid.coatMesh().mesh, largest);
  EXPECT_GT(bent.size(), 5u);
  EXPECT_GT(largest, 0.01);
  const coat::CoatFeathers& c = dyn.feathers();
  for (uint32_t i : bent) EXPECT_LT(glm::length(c.frames[i].origin - glm::dvec3(1.5, 0, 0.1)), 0.8) << i;
  // Settled long after the last key (the offset's at t = 2): back on the rigid coat to within rounding of
  // the decayed lag.
  dyn.setTime(12);
  rigid.setTime(12);
  moved(dyn.coatMesh().mesh, rigid.coatMesh().mesh, largest);
  EXPECT_LT(largest, 1e-5);
}

TEST(ChainPipeline, DynamicZeroIsTheCoatWithoutIt) {
  auto zeroP = make(0.0), noneP = make(Json());
  Pipeline &zero = *zeroP, &none = *noneP;
  for (double t : {0.5, 1.1, 2.5}) {
    zero.setTime(t);
    none.setTime(t);
    EXPECT_EQ(zero.elevations(), none.elevations()) << t;
    EXPECT_TRUE(sameBits(zero.coatMesh().mesh.positions, none.coatMesh().mesh.positions)) << t;
    EXPECT_TRUE(sameBits(zero.coatMesh().mesh.normals, none.coatMesh().mesh.normals)) << t;
  }
}

TEST(ChainPipeline, ScrubbedMeshIsTheFreshOne) {
  auto scrubP = make(1.0), freshP = make(1.0);
  Pipeline &scrub = *scrubP, &fresh = *freshP;
  for (double t : {3.0, 1.2, 0.4, 1.05, 2.2}) {
    scrub.setTime(t);
    scrub.coatMesh();
  }
  scrub.setTime(1.3);
  fresh.setTime(1.3);
  EXPECT_TRUE(sameBits(scrub.coatMesh().mesh.positions, fresh.coatMesh().mesh.positions));
  EXPECT_TRUE(sameBits(scrub.coatMesh().mesh.normals, fresh.coatMesh().mesh.normals));
}
