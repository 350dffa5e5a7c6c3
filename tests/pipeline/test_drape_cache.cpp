// coat::DrapeCache (coat/drape.hpp): a drape that reuses the last one gives the same bits as a drape
// without it, whatever changed in between (a feather turned, grown, lost, the layer order, the skin), and
// really lays again only part of the coat when little changed. Also a draped moult scrub through the
// pipeline equals fresh evaluations.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include "coat_mesher.hpp"
#include "frames.hpp"
#include "pteryla/coat/check.hpp"
#include "pteryla/coat/drape.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"

using namespace pteryla;
using pipeline::CoatMesher;
using pipeline::CoatMeshInput;
using pipeline_test::sameBytes;
using pipeline_test::sameMesh;

namespace {

const std::string kSceneFile = std::string(PTERYLA_DATA_DIR) + "/scene_test.json";

// The sphere, draped: feathers over feathers in several layers, a follicle under most feathers' tips.
Json sphereJson(int count) {
  Json j = Json::parse(R"({"pteryla": 1, "seed": 3, "mesh": "meshes/sphere_1600.obj",
    "feathers": {"contour": "feathers/contour.json"},
    "tracts": [{"name": "all", "count": 200, "feather_scale": "auto", "feather_spacings": 3.0,
                "parameterization": {"method": "projection", "view_direction": [0, -1, 0]}}],
    "directions": {"axis": [[0, 1.5, 0], [0, -1.5, 0]]},
    "ordering": {"method": "axis", "axis": [[0, 1.5, 0], [0, -1.5, 0]]},
    "packing": {"method": "drape"}})");
  j["tracts"][0]["count"] = count;
  return j;
}

// The flat coat the mesh stage drapes (every feather at elevation 0, in layer order).
struct FlatCoat {
  coat::CoatFeathers feathers;
  coat::PackResult flat;
  CoatMesher mesher;
  TriMesh mesh;
  void remesh() {
    flat = coat::PackResult{};
    flat.order = feathers.layerOrder;
    flat.elevation.assign(feathers.size(), 0.0);
    CoatMeshInput in;
    in.coat = &feathers;
    in.packedCoat = &feathers;
    in.packed = &flat;
    in.lod = 0.3;
    mesher.update(in, mesh);
  }
};

void expectSameDrape(const TriMesh& a, const coat::DrapeResult& ra, const TriMesh& b, const coat::DrapeResult& rb,
                     const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_TRUE(sameMesh(a, b));
  EXPECT_TRUE(sameBytes(ra.elevation, rb.elevation));
  EXPECT_EQ(ra.trimmed, rb.trimmed);
  EXPECT_EQ(ra.hidden, rb.hidden);
  EXPECT_EQ(ra.stats.draped, rb.stats.draped);
  EXPECT_EQ(ra.stats.trimmedFeathers, rb.stats.trimmedFeathers);
  EXPECT_EQ(ra.stats.hiddenFeathers, rb.stats.hiddenFeathers);
  EXPECT_EQ(ra.stats.trimmedTriangles, rb.stats.trimmedTriangles);
  EXPECT_EQ(ra.stats.overhangingNodes, rb.stats.overhangingNodes);
  EXPECT_EQ(ra.stats.gap, rb.stats.gap);
}

// Drapes the coat with the cache and without; both must agree. Returns the cached drape's result.
coat::DrapeResult drapeBoth(const coat::SkinMesh& skin, const FlatCoat& c, coat::DrapeCache& cache,
                            const std::string& what) {
  TriMesh withCache = c.mesh, without = c.mesh;
  const coat::DrapeResult r = coat::drapeCoatMesh(skin, c.feathers, withCache, {}, cache);
  const coat::DrapeResult fresh = coat::drapeCoatMesh(skin, c.feathers, without, {});
  expectSameDrape(withCache, r, without, fresh, what);
  EXPECT_EQ(r.stats.relaid + r.stats.reused, r.stats.draped) << what;
  return r;
}

// A triangle the drape removed (its corners collapsed onto the first).
bool collapsed(const TriMesh& m, size_t t) {
  const uint32_t* tri = &m.indices[3 * t];
  return tri[1] == tri[0] && tri[2] == tri[0];
}

// Vertices of live (not collapsed) triangles under the skin, as the checker counts them.
size_t liveVerticesUnderSkin(const coat::SkinMesh& skin, const TriMesh& m, const coat::CoatFeathers& feathers) {
  coat::CheckOptions co;
  coat::setFeatherBases(co, feathers, coat::DrapeOptions{}.baseAllowance);
  const std::vector<uint8_t> inside = coat::verticesInsideSkin(skin, m, co);
  size_t under = 0;
  for (size_t t = 0; t < m.triangleCount(); ++t)
    if (!collapsed(m, t))
      for (int c = 0; c < 3; ++c) under += inside[m.indices[3 * t + c]];
  return under;
}

// How far the coat stands off the skin: the 90th percentile of the distances from its live vertices (every
// 7th) to the skin.
double standOff(const coat::SkinMesh& skin, const TriMesh& m) {
  std::vector<uint8_t> live(m.positions.size(), 0);
  for (size_t t = 0; t < m.triangleCount(); ++t)
    if (!collapsed(m, t))
      for (int c = 0; c < 3; ++c) live[m.indices[3 * t + c]] = 1;
  std::vector<double> d;
  for (size_t v = 0; v < m.positions.size(); v += 7) {
    if (!live[v]) continue;
    const glm::dvec3 p(m.positions[v]);
    double best = 1e300;
    for (const auto& f : skin.faces) {
      const glm::dvec3 q =
          coat::closestPointOnTriangle(p, skin.positions[f[0]], skin.positions[f[1]], skin.positions[f[2]]);
      best = std::min(best, glm::length(q - p));
    }
    d.push_back(best);
  }
  if (d.empty()) return 0;
  std::nth_element(d.begin(), d.begin() + d.size() * 9 / 10, d.end());
  return d[d.size() * 9 / 10];
}

// Turns feather i's frame about its normal by `radians`.
void turn(coat::FeatherFrame& F, double radians) {
  const glm::dvec3 t = std::cos(radians) * F.tangent + std::sin(radians) * F.binormal;
  F.tangent = t;
  F.binormal = glm::cross(F.normal, t);
}

}  // namespace

TEST(DrapeCache, EveryEditDrapesAsWithoutTheCache) {
  pipeline::Pipeline p(pipeline::sceneFromJson(sphereJson(260), kSceneFile));
  const coat::SkinMesh skin = p.posedSkin();
  FlatCoat c;
  c.feathers = p.feathers();
  const size_t n = c.feathers.size();
  ASSERT_GT(n, 200u);
  c.remesh();
  coat::DrapeCache cache;

  coat::DrapeResult r = drapeBoth(skin, c, cache, "first drape");
  EXPECT_EQ(r.stats.relaid, r.stats.draped);
  EXPECT_GT(r.stats.trimmedFeathers, 0u);  // the trims are exercised, not only the laying

  r = drapeBoth(skin, c, cache, "nothing changed");
  EXPECT_EQ(r.stats.relaid, 0u);
  EXPECT_GT(cache.bytes(), 0u);

  // One feather in the middle of the layers turned: it, what lies over it and the feathers whose
  // trims its follicle's root zone touches are laid again, not the coat.
  const uint32_t mid = c.feathers.layerOrder[c.feathers.layerOrder.size() / 2];
  turn(c.feathers.frames[mid], 0.3);
  c.remesh();
  r = drapeBoth(skin, c, cache, "one feather turned");
  EXPECT_GT(r.stats.relaid, 0u);
  EXPECT_LT(r.stats.relaid, r.stats.draped / 2);

  // Shorter feathers (as when growing), a few of them.
  for (uint32_t k = 0; k < n; k += 37) c.feathers.params[k].rachisLength *= 0.6;
  c.remesh();
  drapeBoth(skin, c, cache, "feathers shortened");
  // With the gap and spacing fixed (as a timeline fixes them from its rest coat), shortening feathers
  // lays again only part of the coat.
  {
    coat::DrapeOptions fixed;
    const coat::DrapeSpacing ds = coat::drapeSpacing(skin, c.feathers, c.mesh, fixed);
    EXPECT_GT(ds.gap, 0);
    EXPECT_GT(ds.spacing, 0);
    fixed.gap = ds.gap;
    fixed.spacing = ds.spacing;
    coat::DrapeCache fixedCache;
    TriMesh m = c.mesh;
    coat::drapeCoatMesh(skin, c.feathers, m, fixed, fixedCache);
    for (uint32_t k = 5; k < n; k += 41) c.feathers.params[k].rachisLength *= 0.8;
    c.remesh();
    TriMesh a = c.mesh, b = c.mesh;
    const coat::DrapeResult ra = coat::drapeCoatMesh(skin, c.feathers, a, fixed, fixedCache);
    const coat::DrapeResult rb = coat::drapeCoatMesh(skin, c.feathers, b, fixed);
    expectSameDrape(a, ra, b, rb, "shortened with a fixed spacing");
    EXPECT_GT(ra.stats.relaid, 0u);
    EXPECT_LT(ra.stats.relaid, ra.stats.draped);
    // The auto spacing of a drape is what drapeSpacing says.
    TriMesh d = c.mesh;
    const coat::DrapeSpacing auto2 = coat::drapeSpacing(skin, c.feathers, c.mesh, {});
    EXPECT_EQ(coat::drapeCoatMesh(skin, c.feathers, d, {}).stats.gap, auto2.gap);
  }

  // A lost feather (absent: no vertices), and one back.
  c.feathers.present[mid] = 0;
  c.remesh();
  r = drapeBoth(skin, c, cache, "a feather lost");
  EXPECT_EQ(r.stats.draped, n - 1);
  c.feathers.present[mid] = 1;
  c.remesh();
  drapeBoth(skin, c, cache, "the feather back");

  // A follicle moved along the skin (the later-follicle tests of the feathers under it change).
  const uint32_t low = c.feathers.layerOrder[c.feathers.layerOrder.size() / 4];
  c.feathers.frames[low].origin += 0.01 * c.feathers.frames[low].tangent;
  c.remesh();
  drapeBoth(skin, c, cache, "a follicle moved");

  // Two feathers swap layers: everything is laid again.
  std::swap(c.feathers.layerOrder[10], c.feathers.layerOrder[11]);
  c.remesh();
  r = drapeBoth(skin, c, cache, "layer order changed");
  EXPECT_EQ(r.stats.relaid, r.stats.draped);

  // Another skin (inflated): everything again.
  coat::SkinMesh bigger = skin;
  for (auto& v : bigger.positions) v *= 1.01;
  r = drapeBoth(bigger, c, cache, "skin changed");
  EXPECT_EQ(r.stats.relaid, r.stats.draped);
  drapeBoth(skin, c, cache, "skin back");

  // Other options: everything again.
  TriMesh a = c.mesh, b = c.mesh;
  coat::DrapeOptions o;
  o.maxSlope = 0.5;
  const coat::DrapeResult ra = coat::drapeCoatMesh(skin, c.feathers, a, o, cache);
  const coat::DrapeResult rb = coat::drapeCoatMesh(skin, c.feathers, b, o);
  expectSameDrape(a, ra, b, rb, "options changed");
  EXPECT_EQ(ra.stats.relaid, ra.stats.draped);
}

TEST(DrapeCache, ACancelledDrapeClearsTheCache) {
  pipeline::Pipeline p(pipeline::sceneFromJson(sphereJson(120), kSceneFile));
  FlatCoat c;
  c.feathers = p.feathers();
  c.remesh();
  coat::DrapeCache cache;
  TriMesh m = c.mesh;
  coat::drapeCoatMesh(p.posedSkin(), c.feathers, m, {}, cache);
  coat::DrapeOptions o;
  o.progress = [](const std::string&, double f) -> bool {
    if (f > 0.2) throw Error("cancelled");
    return true;
  };
  m = c.mesh;
  EXPECT_THROW(coat::drapeCoatMesh(p.posedSkin(), c.feathers, m, o, cache), Error);
  m = c.mesh;
  const coat::DrapeResult r = coat::drapeCoatMesh(p.posedSkin(), c.feathers, m, {}, cache);
  EXPECT_EQ(r.stats.relaid, r.stats.draped);  // nothing half-written was reused
  TriMesh fresh = c.mesh;
  const coat::DrapeResult rf = coat::drapeCoatMesh(p.posedSkin(), c.feathers, fresh, {});
  expectSameDrape(m, r, fresh, rf, "after the cancel");
}

// A draped moult scrubbed back and forth: every frame equals a fresh evaluation, and frames next to
// each other lay only part of the coat again.
TEST(DrapeCache, DrapedMoultScrubEqualsFreshEvaluation) {
  Json j = sphereJson(200);
  j["moult"] = Json::parse(R"({"start": 0, "duration": 10, "window": 0.3, "sequence": "centre_out", "gap": 0,
                               "seed": 3})");
  const pipeline::Scene scene = pipeline::sceneFromJson(j, kSceneFile);
  pipeline::Pipeline scrub(scene);
  scrub.setLod(0.2);
  const double times[] = {4.0, 4.05, 4.1, 4.1, 2.0, 4.05};
  size_t partial = 0;
  for (double t : times) {
    scrub.setTime(t);
    const pipeline_test::Frame f = pipeline_test::grab(scrub);
    const pipeline::FrameReuse r = scrub.frameReuse();
    partial += r.drapeReused > 0 ? 1 : 0;
    pipeline::Pipeline fresh(scene);
    fresh.setLod(0.2);
    fresh.setTime(t);
    pipeline_test::expectIdentical(f, pipeline_test::grab(fresh), t);
  }
  EXPECT_GE(partial, 2u);
}

// A moult frame laid over the mature coat's drape: unchanged feathers are the mature drape's bits, lost
// ones are gone, growing ones lie on their mature charts, and the guarantees hold (no vertex of a live
// triangle under the skin, no crossing triangles).
TEST(DrapeCache, MoultFramesLieOverTheMatureCoat) {
  pipeline::Pipeline p(pipeline::sceneFromJson(sphereJson(260), kSceneFile));
  const coat::SkinMesh skin = p.posedSkin();
  FlatCoat mature;
  mature.feathers = p.feathers();
  const size_t n = mature.feathers.size();
  mature.remesh();
  coat::DrapeCache cache;
  TriMesh matureMesh = mature.mesh;
  coat::drapeCoatMesh(skin, mature.feathers, matureMesh, {}, cache);

  // The same coat over itself is the mature drape.
  {
    TriMesh m = mature.mesh;
    const coat::DrapeResult r = coat::drapeOverMature(skin, mature.feathers, m, cache);
    EXPECT_TRUE(sameMesh(m, matureMesh));
    EXPECT_EQ(r.stats.relaid, 0u);
  }

  // Lose every 7th feather, grow every 5th.
  FlatCoat frame;
  frame.feathers = mature.feathers;
  size_t lost = 0, growing = 0;
  for (uint32_t i = 0; i < n; ++i) {
    if (i % 7 == 3) {
      frame.feathers.present[i] = 0;
      ++lost;
    } else if (i % 5 == 1) {
      frame.feathers.age[i] = 0.6;
      ++growing;
    }
  }
  frame.remesh();
  TriMesh m = frame.mesh;
  const coat::DrapeResult r = coat::drapeOverMature(skin, frame.feathers, m, cache);
  EXPECT_EQ(r.stats.draped, n - lost);
  EXPECT_GE(r.stats.relaid, growing / 2);  // growing feathers placed on their charts (some may be the mature mesh)
  EXPECT_LT(r.stats.relaid, r.stats.draped / 2);

  // Copied feathers keep the mature drape's positions.
  std::vector<uint32_t> firstOf(n, UINT32_MAX), firstMature(n, UINT32_MAX);
  for (uint32_t v = static_cast<uint32_t>(m.positions.size()); v-- > 0;) firstOf[m.featherId[v]] = v;
  for (uint32_t v = static_cast<uint32_t>(matureMesh.positions.size()); v-- > 0;)
    firstMature[matureMesh.featherId[v]] = v;
  size_t same = 0;
  for (uint32_t i = 0; i < n; ++i)
    if (frame.feathers.present[i] && frame.feathers.age[i] == 1 && firstOf[i] != UINT32_MAX)
      same += m.positions[firstOf[i] + 2] == matureMesh.positions[firstMature[i] + 2] ? 1 : 0;
  EXPECT_GT(same, (n - lost - growing) * 9 / 10);

  // The guarantees: nothing crosses, no live vertex under the skin.
  EXPECT_TRUE(coat::intersectingTrianglePairs(m).empty());
  EXPECT_EQ(liveVerticesUnderSkin(skin, m, frame.feathers), 0u);

  // Another skin than the mature drape's is an error, not a wrong coat.
  coat::SkinMesh other = skin;
  other.positions[0] *= 1.01;
  TriMesh m2 = frame.mesh;
  EXPECT_THROW(coat::drapeOverMature(other, frame.feathers, m2, cache), Error);
  coat::DrapeCache empty;
  EXPECT_THROW(coat::drapeOverMature(skin, frame.feathers, m2, empty), Error);
}

// A skin that moves at every drape (an animated pose) makes the cache keep nothing, with the same
// results; once the skin holds still, drapes are kept and reused again.
TEST(DrapeCache, AMovingSkinIsNotKeptUntilItHoldsStill) {
  pipeline::Pipeline p(pipeline::sceneFromJson(sphereJson(120), kSceneFile));
  const coat::SkinMesh skin = p.posedSkin();
  FlatCoat c;
  c.feathers = p.feathers();
  c.remesh();
  coat::DrapeCache cache;
  auto scaled = [&](double s) {
    coat::SkinMesh m = skin;
    for (auto& v : m.positions) v *= s;
    return m;
  };
  drapeBoth(scaled(1.0), c, cache, "rest");
  const size_t kept = cache.bytes();
  drapeBoth(scaled(1.01), c, cache, "moved once");
  EXPECT_GT(cache.bytes(), kept / 2);  // a single move still keeps the drape
  drapeBoth(scaled(1.02), c, cache, "moved twice");
  EXPECT_LT(cache.bytes(), kept / 4);  // moving every frame: nothing kept
  drapeBoth(scaled(1.02), c, cache, "held still");
  const coat::DrapeResult r = drapeBoth(scaled(1.02), c, cache, "still again");
  EXPECT_EQ(r.stats.relaid, 0u);
  // A cache told to keep every drape keeps through the moves.
  coat::DrapeCache always;
  always.keepEveryDrape();
  for (double s : {1.0, 1.01, 1.02}) drapeBoth(scaled(s), c, always, "kept");
  EXPECT_GT(always.bytes(), kept / 2);
}

// Posed frames carried from the rest pose's drape (coat::drapeCarried, packing.posed_drape "carry").

// Per vertex: 1 when a live (not collapsed) triangle uses it.
std::vector<uint8_t> liveVertices(const TriMesh& m) {
  std::vector<uint8_t> live(m.positions.size(), 0);
  for (size_t t = 0; t < m.triangleCount(); ++t)
    if (!collapsed(m, t))
      for (int k = 0; k < 3; ++k) live[m.indices[3 * t + k]] = 1;
  return live;
}

// The draped sphere (120 feathers) with its drape kept in a cache, the reference a carry starts from.
struct DrapedSphere {
  coat::SkinMesh skin;
  FlatCoat c;
  coat::DrapeCache cache;
  TriMesh draped;
  coat::DrapeResult result;
  DrapedSphere() {
    pipeline::Pipeline p(pipeline::sceneFromJson(sphereJson(120), kSceneFile));
    skin = p.posedSkin();
    c.feathers = p.feathers();
    c.remesh();
    draped = c.mesh;
    result = coat::drapeCoatMesh(skin, c.feathers, draped, {}, cache);
  }
};

// The rest skin carries to itself: every feather copied, the reference drape's bits.
TEST(DrapeCarry, TheRestPoseCarriesToItself) {
  DrapedSphere d;
  const coat::SkinMesh& skin = d.skin;
  const FlatCoat& c = d.c;
  coat::DrapeCache& cache = d.cache;
  const TriMesh& draped = d.draped;
  const coat::DrapeResult& ref = d.result;
  TriMesh m = c.mesh;
  coat::DrapeCache kept;
  const coat::DrapeResult r = coat::drapeCarried(skin, skin, c.feathers, m, cache, {}, &kept);
  EXPECT_TRUE(sameMesh(m, draped));
  EXPECT_EQ(r.stats.relaid, 0u);
  EXPECT_EQ(r.stats.reused, ref.stats.draped);
  EXPECT_EQ(r.trimmed, ref.trimmed);
  // What it kept is a drape a moult can be laid over: the same coat over it is the same mesh.
  TriMesh over = c.mesh;
  coat::drapeOverMature(skin, c.feathers, over, kept);
  EXPECT_TRUE(sameMesh(over, draped));
  // A reference of another skin or coat is an error, not a wrong coat.
  coat::SkinMesh other = skin;
  other.positions[0] *= 1.01;
  TriMesh m2 = c.mesh;
  EXPECT_THROW(coat::drapeCarried(other, other, c.feathers, m2, cache), Error);
  coat::DrapeCache empty;
  EXPECT_THROW(coat::drapeCarried(skin, skin, c.feathers, m2, empty), Error);
  EXPECT_THROW(coat::drapeCarried(skin, skin, c.feathers, m2, cache, {}, &cache), Error);
}

// A rigid motion of the skin and the follicles carries every feather rigidly: each live vertex is the
// rest drape's moved, to rounding, and the guarantees hold on the moved skin. The whole skin is one rigid
// piece, so every feather moves with it as it lay (rigidPieces); placed on its carried chart instead, each
// lies where the piece would have put it.
TEST(DrapeCarry, ARigidMotionCarriesEveryFeatherRigidly) {
  const DrapedSphere d;
  const coat::SkinMesh& skin = d.skin;
  const FlatCoat& c = d.c;
  const TriMesh& draped = d.draped;
  const double a = 0.7;
  const glm::dmat3 R(std::cos(a), std::sin(a), 0, -std::sin(a), std::cos(a), 0, 0, 0, 1);
  const glm::dvec3 shift(0.3, -0.2, 0.5);
  coat::SkinMesh moved = skin;
  for (auto& v : moved.positions) v = R * v + shift;
  coat::recomputeGeometry(moved);
  FlatCoat mc;
  mc.feathers = c.feathers;
  for (coat::FeatherFrame& F : mc.feathers.frames) {
    F.origin = R * F.origin + shift;
    F.normal = R * F.normal;
    F.tangent = R * F.tangent;
    F.binormal = R * F.binormal;
  }
  mc.remesh();
  for (const bool pieces : {true, false}) {
    SCOPED_TRACE(pieces ? "moved with the piece" : "placed on carried charts");
    coat::DrapeOptions o;
    o.rigidPieces = pieces;
    TriMesh m = mc.mesh;
    const coat::DrapeResult r = coat::drapeCarried(skin, moved, mc.feathers, m, d.cache, o);
    if (pieces) {
      EXPECT_EQ(r.stats.relaid, 0u);  // nothing placed
      EXPECT_EQ(r.stats.rigid, d.result.stats.draped);
      EXPECT_EQ(r.stats.reused, d.result.stats.draped);
      EXPECT_EQ(r.trimmed, d.result.trimmed);  // as it lay at rest
    } else {
      EXPECT_EQ(r.stats.reused, 0u);  // every feather moved
      EXPECT_EQ(r.stats.rigid, 0u);
    }
    ASSERT_EQ(m.positions.size(), draped.positions.size());
    size_t live = 0, off = 0, liveBoth = 0;
    const std::vector<uint8_t> liveDraped = liveVertices(draped), liveNow = liveVertices(m);
    for (size_t v = 0; v < m.positions.size(); ++v) {
      live += liveNow[v];
      if (!liveNow[v] || !liveDraped[v]) continue;
      ++liveBoth;
      const glm::dvec3 want = R * glm::dvec3(draped.positions[v]) + shift;
      off += glm::length(glm::dvec3(m.positions[v]) - want) > 1e-5 ? 1 : 0;
    }
    if (pieces)
      EXPECT_EQ(liveBoth, live);  // the rest drape's live triangles, no others
    else
      EXPECT_GT(liveBoth, live * 99 / 100);  // rounding may flip a test at a touching pair, no more
    EXPECT_EQ(off, 0u);
    EXPECT_TRUE(coat::intersectingTrianglePairs(m).empty());
    EXPECT_EQ(liveVerticesUnderSkin(moved, m, mc.feathers), 0u);
  }
}

// A cap of the sphere turns rigidly over a bending band: the feathers whose charts lie on the cap move
// with it as they lay at rest (rigidPieces), where placing them on their carried charts puts them to
// rounding; the band's feathers are placed either way, and the guarantees hold both ways.
TEST(DrapeCarry, FeathersOnARigidPieceMoveWhereTheirCarriedChartsPlaceThem) {
  const DrapedSphere d;
  pipeline::Pipeline p(pipeline::sceneFromJson(sphereJson(120), kSceneFile));
  std::vector<glm::dvec3> bent = d.skin.positions;
  const double y0 = -0.8, band = 0.25, angle = 0.6;
  for (auto& q : bent) {
    if (q.y <= y0) continue;
    const double u = std::min(1.0, (q.y - y0) / band), w = angle * u * u * (3 - 2 * u);
    const double y = q.y - y0, z = q.z;
    q.y = y0 + std::cos(w) * y - std::sin(w) * z + 0.2 * u;
    q.z = std::sin(w) * y + std::cos(w) * z;
  }
  p.setSkinPose(bent);
  const coat::SkinMesh posed = p.posedSkin();
  FlatCoat mc;
  mc.feathers = p.feathers();
  mc.remesh();
  TriMesh with = mc.mesh, without = mc.mesh;
  coat::DrapeOptions o;
  const coat::DrapeResult a = coat::drapeCarried(d.skin, posed, mc.feathers, with, d.cache, o);
  o.rigidPieces = false;
  const coat::DrapeResult b = coat::drapeCarried(d.skin, posed, mc.feathers, without, d.cache, o);
  EXPECT_GT(a.stats.rigid, 5u);
  EXPECT_GT(a.stats.relaid, 5u);  // the band's
  EXPECT_EQ(b.stats.rigid, 0u);
  EXPECT_EQ(a.stats.relaid + a.stats.rigid, b.stats.relaid);
  ASSERT_EQ(with.positions.size(), without.positions.size());
  size_t liveA = 0, liveBoth = 0, off = 0;
  const std::vector<uint8_t> la = liveVertices(with), lb = liveVertices(without);
  for (size_t v = 0; v < la.size(); ++v) {
    liveA += la[v];
    if (!la[v] || !lb[v]) continue;
    ++liveBoth;
    off += glm::length(glm::dvec3(with.positions[v]) - glm::dvec3(without.positions[v])) > 1e-5 ? 1 : 0;
  }
  EXPECT_GT(liveBoth, liveA * 99 / 100);
  EXPECT_EQ(off, 0u);
  for (const TriMesh* m : {&with, &without}) {
    EXPECT_TRUE(coat::intersectingTrianglePairs(*m).empty());
    EXPECT_EQ(liveVerticesUnderSkin(posed, *m, mc.feathers), 0u);
  }
  // Kept (`out`), the frame is a drape a moult can be laid over: the same coat over it is the same mesh.
  TriMesh keptMesh = mc.mesh;
  coat::DrapeCache kept;
  coat::drapeCarried(d.skin, posed, mc.feathers, keptMesh, d.cache, {}, &kept);
  EXPECT_TRUE(sameMesh(keptMesh, with));
  TriMesh over = mc.mesh;
  coat::drapeOverMature(posed, mc.feathers, over, kept);
  EXPECT_TRUE(sameMesh(over, with));
  // After a frame of another pose (the reference's pair trees refitted to it), the same bits again.
  pipeline::Pipeline q(pipeline::sceneFromJson(sphereJson(120), kSceneFile));
  std::vector<glm::dvec3> other = d.skin.positions;
  for (auto& v : other) v.y += v.y > 0 ? 0.05 * v.y * v.y : 0.0;
  q.setSkinPose(other);
  FlatCoat oc;
  oc.feathers = q.feathers();
  oc.remesh();
  TriMesh between = oc.mesh, again = mc.mesh;
  coat::drapeCarried(d.skin, q.posedSkin(), oc.feathers, between, d.cache);
  coat::drapeCarried(d.skin, posed, mc.feathers, again, d.cache);
  EXPECT_TRUE(sameMesh(again, with));
}

// Through the pipeline: a host bends a cap of the draped sphere up (rigid cap, bending band). Whatever was
// evaluated before, a posed frame (pose, time) is the same bits as a fresh evaluation of it, with a
// moult too; only feathers the pose moved are placed again; the guarantees hold at every pose.
TEST(DrapeCarry, PosedFramesEqualFreshEvaluationAndKeepTheGuarantees) {
  for (const int variant : {0, 1, 2}) {
    const bool moult = variant >= 1, controls = variant == 2;
    SCOPED_TRACE(std::string(moult ? "moult" : "no moult") + (controls ? ", controls" : ""));
    Json j = sphereJson(150);
    if (moult)
      j["moult"] = Json::parse(R"({"start": 0, "duration": 10, "window": 0.3, "sequence": "centre_out", "gap": 0,
                                   "seed": 3})");
    // A control turning feathers on the cap at random and toward a point beside it (the reference turns
    // them at rest).
    if (controls)
      j["controls"] = Json::parse(R"([{"name": "tuft", "at": [0.0, 0.9, 0.3], "radius": 0.6, "falloff": 0.4,
        "seed": 5, "keys": [{"t": 0, "random": 0.2, "aim": 0.1, "lift": 0.3}, {"t": 4, "random": 0.8, "aim": 0.5}]}])");
    const pipeline::Scene scene = pipeline::sceneFromJson(j, kSceneFile);
    pipeline::Pipeline scrub(scene);
    scrub.setLod(0.2);
    const coat::SkinMesh rest = scrub.restSkin();
    // The cap above y0 turns about the x axis through (0, y0, 0) by `angle` and rises by as much, blended
    // in over a band (a stretching neck under a rigidly moving head).
    auto pose = [&](double angle) {
      std::vector<glm::dvec3> out = rest.positions;
      const double y0 = 0.2, band = 0.5;
      for (auto& q : out) {
        if (q.y <= y0) continue;
        const double u = std::min(1.0, (q.y - y0) / band), w = angle * u * u * (3 - 2 * u);
        const double y = q.y - y0, z = q.z;
        q.y = y0 + std::cos(w) * y - std::sin(w) * z + w;  // and lifted by the angle's measure
        q.z = std::sin(w) * y + std::cos(w) * z;
      }
      return out;
    };
    const std::pair<double, double> frames[] = {{0.3, 4.0}, {0.5, 4.0}, {0.5, 4.1}, {0.0, 4.0}, {0.3, 4.0}, {0.5, 2.0}};
    size_t carried = 0;
    for (const auto& [angle, t] : frames) {
      SCOPED_TRACE("angle " + std::to_string(angle) + " t " + std::to_string(t));
      scrub.setSkinPose(pose(angle));
      scrub.setTime(t);
      const pipeline_test::Frame f = pipeline_test::grab(scrub);
      const pipeline::FrameReuse r = scrub.frameReuse();
      // (A moult frame whose pose and mature coat were draped before reuses that drape.)
      carried += r.drapeCarried ? 1 : 0;
      if (r.drapeCarried && angle > 0) {
        EXPECT_GT(r.drapeCarriedMoved, 0u);
        EXPECT_LT(r.drapeCarriedMoved, scrub.feathers().size() * 3 / 4);  // the lower part did not move
      }
      EXPECT_TRUE(coat::intersectingTrianglePairs(f.mesh).empty());
      EXPECT_EQ(liveVerticesUnderSkin(scrub.posedSkin(), f.mesh, scrub.feathers()), 0u);
      pipeline::Pipeline fresh(scene);
      fresh.setLod(0.2);
      fresh.setSkinPose(pose(angle));
      fresh.setTime(t);
      pipeline_test::expectIdentical(f, pipeline_test::grab(fresh), t);
    }
    EXPECT_GE(carried, 4u);
    // "posed_drape": "full" drapes the posed coat whole, another coat with the same guarantees.
    Json full = j;
    full["packing"]["posed_drape"] = "full";
    pipeline::Pipeline whole(pipeline::sceneFromJson(full, kSceneFile));
    whole.setLod(0.2);
    whole.setSkinPose(pose(0.5));
    whole.setTime(4.0);
    const pipeline_test::Frame g = pipeline_test::grab(whole);
    EXPECT_FALSE(whole.frameReuse().drapeCarried);
    EXPECT_TRUE(coat::intersectingTrianglePairs(g.mesh).empty());
    // The carried coat lies on the bent skin as closely as the full drape's (its feathers went with the
    // skin), and keeps about as many triangles.
    scrub.setSkinPose(pose(0.5));
    scrub.setTime(4.0);
    const pipeline_test::Frame c = pipeline_test::grab(scrub);
    const coat::SkinMesh bent = scrub.posedSkin();
    EXPECT_LT(standOff(bent, c.mesh), 1.1 * standOff(bent, g.mesh));
    size_t liveCarried = 0, liveFull = 0;
    for (size_t t = 0; t < c.mesh.triangleCount(); ++t) liveCarried += collapsed(c.mesh, t) ? 0 : 1;
    for (size_t t = 0; t < g.mesh.triangleCount(); ++t) liveFull += collapsed(g.mesh, t) ? 0 : 1;
    EXPECT_GT(liveCarried, liveFull * 9 / 10);
  }
}
