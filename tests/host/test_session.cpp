// The host API (include/pteryla/pteryla.hpp): a Session over a mesh held in memory.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "../install/consumer/icosphere.hpp"
#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pteryla.hpp"

namespace {

using pteryla::CoatSetup;
using pteryla::Frame;
using pteryla::Session;
using pteryla::SkinArrays;

const std::string kData = PTERYLA_DATA_DIR;

SkinArrays sphereSkin() {
  const auto ico = pteryla_test::icosphere(3);  // 642 vertices, 1280 faces
  SkinArrays s;
  s.positions = ico.positions;
  s.triangles = ico.triangles;
  return s;
}

// Small and quick: 120 follicles, a third of the barbs.
CoatSetup smallSetup(uint64_t seed = 5) {
  CoatSetup c;
  pteryla::TractSetup t;
  t.name = "body";
  t.count = 120;
  c.tracts.push_back(t);
  c.axis = {{{0, 1.2, 0}}, {{0, -1.2, 0}}};
  c.seed = seed;
  return c;
}

// Two tracts of 60 follicles: the upper ("top") and lower ("bottom") halves of the skin.
CoatSetup topAndBottom(const SkinArrays& skin) {
  CoatSetup setup;
  setup.axis = {{{0, 1.2, 0}}, {{0, -1.2, 0}}};
  pteryla::TractSetup top, bottom;
  top.name = "top";
  bottom.name = "bottom";
  top.count = bottom.count = 60;
  for (uint32_t f = 0; f < skin.triangles.size() / 3; ++f) {
    double y = 0;
    for (int c = 0; c < 3; ++c) y += skin.positions[3 * skin.triangles[3 * f + c] + 1];
    (y > 0 ? top : bottom).faces.push_back(f);
  }
  setup.tracts = {top, bottom};
  return setup;
}

// `setup` edited by `edit` must be refused by the Session constructor with pteryla::Error at `element`.
void expectSetupErrorAt(const SkinArrays& skin, const CoatSetup& setup, const std::string& element,
                        const std::function<void(CoatSetup&)>& edit) {
  CoatSetup bad = setup;
  edit(bad);
  try {
    Session x(skin, bad);
    ADD_FAILURE() << "no error for " << element;
  } catch (const pteryla::Error& e) {
    EXPECT_EQ(e.element(), element) << e.what();
  }
}

Session evaluated(const SkinArrays& skin, const CoatSetup& setup) {
  Session s(skin, setup);
  s.setLod(0.3);
  EXPECT_TRUE(s.evaluate());
  return s;
}

template <class T>
bool sameBits(pteryla::View<T> a, pteryla::View<T> b) {
  return a.size == b.size && (a.size == 0 || std::memcmp(a.data, b.data, a.size * sizeof(T)) == 0);
}

// Every view of two frames, bit for bit.
void expectIdentical(const Frame& a, const Frame& b) {
  ASSERT_EQ(a.featherCount, b.featherCount);
  EXPECT_TRUE(sameBits(a.follicleKeys, b.follicleKeys));
  EXPECT_TRUE(sameBits(a.tracts, b.tracts));
  EXPECT_TRUE(sameBits(a.present, b.present));
  EXPECT_TRUE(sameBits(a.origins, b.origins));
  EXPECT_TRUE(sameBits(a.normals, b.normals));
  EXPECT_TRUE(sameBits(a.tangents, b.tangents));
  EXPECT_TRUE(sameBits(a.binormals, b.binormals));
  EXPECT_TRUE(sameBits(a.elevations, b.elevations));
  EXPECT_TRUE(sameBits(a.positions, b.positions));
  EXPECT_TRUE(sameBits(a.vertexNormals, b.vertexNormals));
  EXPECT_TRUE(sameBits(a.uvs, b.uvs));
  EXPECT_TRUE(sameBits(a.alphas, b.alphas));
  EXPECT_TRUE(sameBits(a.vertexFeathers, b.vertexFeathers));
  EXPECT_TRUE(sameBits(a.indices, b.indices));
  ASSERT_EQ(a.ranges.size, b.ranges.size);
  for (size_t k = 0; k < a.ranges.size; ++k) {
    EXPECT_EQ(a.ranges[k].feather, b.ranges[k].feather);
    EXPECT_EQ(a.ranges[k].firstIndex, b.ranges[k].firstIndex);
    EXPECT_EQ(a.ranges[k].indexCount, b.ranges[k].indexCount);
    EXPECT_EQ(a.ranges[k].material, b.ranges[k].material);
  }
}

// Runs f and returns the pteryla::Error it throws (fails the test when it throws nothing).
template <class F>
pteryla::Error errorOf(F&& f) {
  try {
    f();
  } catch (const pteryla::Error& e) {
    return e;
  }
  ADD_FAILURE() << "no pteryla::Error thrown";
  return pteryla::Error("none");
}

TEST(HostSession, FrameIsConsistent) {
  Session s = evaluated(sphereSkin(), smallSetup());
  const Frame& f = s.frame();
  ASSERT_EQ(f.featherCount, 120u);
  EXPECT_EQ(f.origins.size, 3 * f.featherCount);
  EXPECT_EQ(f.elevations.size, f.featherCount);
  ASSERT_GT(f.indices.size, 0u);
  EXPECT_EQ(f.indices.size % 3, 0u);
  const size_t nv = f.positions.size / 3;
  EXPECT_EQ(f.vertexNormals.size, 3 * nv);
  EXPECT_EQ(f.vertexFeathers.size, nv);
  EXPECT_EQ(f.uvs.size, 2 * nv);
  for (uint32_t i : f.indices) ASSERT_LT(i, nv);
  for (float x : f.positions) ASSERT_TRUE(std::isfinite(x));
  for (double x : f.origins) ASSERT_TRUE(std::isfinite(x));
  // The host gets float normals decoded from the mesh's 16-bit ones: unit within their rounding.
  for (size_t v = 0; v < nv; ++v) {
    const float* n = &f.vertexNormals[3 * v];
    ASSERT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0f, 5e-5f) << v;
  }
  // Follicles sit on the unit sphere; frames are orthonormal with B = N x T.
  for (size_t i = 0; i < f.featherCount; ++i) {
    const double* o = &f.origins[3 * i];
    EXPECT_NEAR(std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]), 1.0, 0.02);
    const double *n = &f.normals[3 * i], *t = &f.tangents[3 * i], *b = &f.binormals[3 * i];
    EXPECT_NEAR(n[0] * t[0] + n[1] * t[1] + n[2] * t[2], 0.0, 1e-9);
    EXPECT_NEAR(b[0], n[1] * t[2] - n[2] * t[1], 1e-9);
    EXPECT_NEAR(b[1], n[2] * t[0] - n[0] * t[2], 1e-9);
    EXPECT_NEAR(b[2], n[0] * t[1] - n[1] * t[0], 1e-9);
  }
  // One range per present feather; each covers triangles of its own feather only.
  ASSERT_EQ(f.ranges.size, f.featherCount);
  std::vector<int> seen(f.featherCount, 0);
  for (const auto& r : f.ranges) {
    ASSERT_LT(r.feather, f.featherCount);
    ++seen[r.feather];
    ASSERT_LE(size_t(r.firstIndex) + r.indexCount, f.indices.size);
    for (uint32_t k = r.firstIndex; k < r.firstIndex + r.indexCount; ++k)
      ASSERT_EQ(f.vertexFeathers[f.indices[k]], r.feather);
  }
  for (int c : seen) EXPECT_EQ(c, 1);
  // Keys are distinct.
  std::vector<uint64_t> keys(f.follicleKeys.begin(), f.follicleKeys.end());
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(std::unique(keys.begin(), keys.end()), keys.end());
}

TEST(HostSession, SameSeedIsBitIdenticalOtherSeedIsNot) {
  const SkinArrays skin = sphereSkin();
  Session a = evaluated(skin, smallSetup(5));
  Session b = evaluated(skin, smallSetup(5));
  expectIdentical(a.frame(), b.frame());
  Session c = evaluated(skin, smallSetup(6));
  EXPECT_FALSE(sameBits(a.frame().origins, c.frame().origins));
}

TEST(HostSession, TranslatedPoseTranslatesTheCoat) {
  const SkinArrays skin = sphereSkin();
  CoatSetup setup = smallSetup();
  setup.packing = CoatSetup::Packing::HeightField;
  Session s = evaluated(skin, setup);
  const Frame& f0 = s.frame();
  const std::vector<uint64_t> keys(f0.follicleKeys.begin(), f0.follicleKeys.end());
  const std::vector<double> origins(f0.origins.begin(), f0.origins.end()),
      normals(f0.normals.begin(), f0.normals.end());
  const std::vector<float> coat(f0.positions.begin(), f0.positions.end());
  const std::vector<uint32_t> indices(f0.indices.begin(), f0.indices.end());

  const double d[3] = {0.75, -0.5, 2.0};
  std::vector<double> moved = skin.positions;
  for (size_t k = 0; k < moved.size(); ++k) moved[k] += d[k % 3];
  s.setPose(moved);
  EXPECT_THROW(s.frame(), pteryla::Error);  // stale until evaluated
  ASSERT_TRUE(s.evaluate());
  const Frame& f1 = s.frame();
  // The same follicles (not re-distributed), carried along by the skin.
  ASSERT_EQ(f1.featherCount, keys.size());
  EXPECT_TRUE(std::equal(keys.begin(), keys.end(), f1.follicleKeys.begin()));
  for (size_t k = 0; k < origins.size(); ++k) {
    EXPECT_NEAR(f1.origins[k], origins[k] + d[k % 3], 1e-12);
    EXPECT_NEAR(f1.normals[k], normals[k], 1e-12);
  }
  // The coat moves with it: the same triangles, every vertex shifted by d.
  ASSERT_EQ(f1.positions.size, coat.size());
  EXPECT_TRUE(std::equal(indices.begin(), indices.end(), f1.indices.begin()));
  double worst = 0;
  for (size_t k = 0; k < coat.size(); ++k) worst = std::max(worst, std::abs(f1.positions[k] - (coat[k] + d[k % 3])));
  EXPECT_LT(worst, 1e-4) << "largest deviation from the translated coat";

  // Back to rest: the first frame again, bit for bit.
  s.clearPose();
  ASSERT_TRUE(s.evaluate());
  EXPECT_TRUE(std::equal(coat.begin(), coat.end(), s.frame().positions.begin()));
}

TEST(HostSession, BendingPoseMovesTheCoatAndKeepsFollicles) {
  const SkinArrays skin = sphereSkin();
  Session s = evaluated(skin, smallSetup());
  const std::vector<uint64_t> keys(s.frame().follicleKeys.begin(), s.frame().follicleKeys.end());
  const std::vector<float> coat(s.frame().positions.begin(), s.frame().positions.end());
  // Squash the sphere along y (float input, as a DCC hands it over).
  std::vector<float> squashed(skin.positions.begin(), skin.positions.end());
  for (size_t v = 0; v < squashed.size() / 3; ++v) squashed[3 * v + 1] *= 0.6f;
  s.setPose(squashed.data(), squashed.size() / 3);
  ASSERT_TRUE(s.evaluate());
  const Frame& f = s.frame();
  EXPECT_TRUE(std::equal(keys.begin(), keys.end(), f.follicleKeys.begin()));
  for (size_t i = 0; i < f.featherCount; ++i) EXPECT_LE(std::abs(f.origins[3 * i + 1]), 0.6 + 1e-6);
  EXPECT_FALSE(std::equal(coat.begin(), coat.end(), f.positions.begin(), f.positions.end()));
  for (float x : f.positions) ASSERT_TRUE(std::isfinite(x));
}

// PoseMode::Follow carries the laid coat with the skin. A rotation plus translation of the whole skin is
// a rigid motion of every local frame: the carried coat must be exactly the rest coat moved rigidly,
// its normals rotated, its elevations unchanged, and no evaluation of the time stages needed.
TEST(HostSession, FollowPoseCarriesTheRestCoatRigidly) {
  const SkinArrays skin = sphereSkin();
  Session s = evaluated(skin, smallSetup());
  s.setPoseMode(pteryla::PoseMode::Follow);
  ASSERT_TRUE(s.evaluate());
  const Frame& f0 = s.frame();
  const std::vector<float> coat(f0.positions.begin(), f0.positions.end()),
      vn(f0.vertexNormals.begin(), f0.vertexNormals.end());
  const std::vector<double> origins(f0.origins.begin(), f0.origins.end()),
      tangents(f0.tangents.begin(), f0.tangents.end());
  const std::vector<double> elevations(f0.elevations.begin(), f0.elevations.end());
  const std::vector<uint32_t> indices(f0.indices.begin(), f0.indices.end());

  // The rest pose itself: the same coat (up to rounding through the local frames).
  s.setPose(skin.positions);
  ASSERT_TRUE(s.evaluate());
  for (size_t k = 0; k < coat.size(); ++k) ASSERT_NEAR(s.frame().positions[k], coat[k], 1e-5);

  // Rotate 40 degrees about z, then translate.
  const double c = std::cos(0.7), sn = std::sin(0.7), d[3] = {0.3, -1.0, 0.5};
  auto rotate = [&](const double* p, double* out, bool translate) {
    out[0] = c * p[0] - sn * p[1] + (translate ? d[0] : 0);
    out[1] = sn * p[0] + c * p[1] + (translate ? d[1] : 0);
    out[2] = p[2] + (translate ? d[2] : 0);
  };
  std::vector<double> moved(skin.positions.size());
  for (size_t v = 0; v < moved.size() / 3; ++v) rotate(&skin.positions[3 * v], &moved[3 * v], true);
  s.setPose(moved);
  EXPECT_THROW(s.frame(), pteryla::Error);  // stale until evaluated
  ASSERT_TRUE(s.evaluate());
  const Frame& f1 = s.frame();
  ASSERT_EQ(f1.positions.size, coat.size());
  EXPECT_TRUE(std::equal(indices.begin(), indices.end(), f1.indices.begin()));
  double worstP = 0, worstN = 0, worstO = 0, worstT = 0;
  for (size_t v = 0; v < coat.size() / 3; ++v) {
    const double p[3] = {coat[3 * v], coat[3 * v + 1], coat[3 * v + 2]},
                 n[3] = {vn[3 * v], vn[3 * v + 1], vn[3 * v + 2]};
    double q[3], m[3];
    rotate(p, q, true);
    rotate(n, m, false);
    for (int k = 0; k < 3; ++k) {
      worstP = std::max(worstP, std::abs(f1.positions[3 * v + k] - q[k]));
      worstN = std::max(worstN, std::abs(f1.vertexNormals[3 * v + k] - m[k]));
    }
  }
  for (size_t i = 0; i < f1.featherCount; ++i) {
    double q[3], t[3];
    rotate(&origins[3 * i], q, true);
    rotate(&tangents[3 * i], t, false);
    for (int k = 0; k < 3; ++k) {
      worstO = std::max(worstO, std::abs(f1.origins[3 * i + k] - q[k]));
      worstT = std::max(worstT, std::abs(f1.tangents[3 * i + k] - t[k]));
    }
    EXPECT_EQ(f1.elevations[i], elevations[i]);
  }
  EXPECT_LT(worstP, 2e-5);
  EXPECT_LT(worstN, 2e-5);
  EXPECT_LT(worstO, 1e-9);
  EXPECT_LT(worstT, 1e-9);

  // A new level of detail is a new coat: bound again, still carried rigidly.
  s.setLod(0.2);
  ASSERT_TRUE(s.evaluate());
  const std::vector<float> moved02(s.frame().positions.begin(), s.frame().positions.end());
  Session rest = evaluated(skin, smallSetup());
  rest.setLod(0.2);
  ASSERT_TRUE(rest.evaluate());
  ASSERT_EQ(rest.frame().positions.size, moved02.size());
  double worst02 = 0;
  for (size_t v = 0; v < moved02.size() / 3; ++v) {
    const double p[3] = {rest.frame().positions[3 * v], rest.frame().positions[3 * v + 1],
                         rest.frame().positions[3 * v + 2]};
    double q[3];
    rotate(p, q, true);
    for (int k = 0; k < 3; ++k) worst02 = std::max(worst02, std::abs(double(moved02[3 * v + k]) - q[k]));
  }
  EXPECT_LT(worst02, 2e-5);

  // What Follow cannot do yet is refused, naming the setting; exportMesh writes the carried frame.
  EXPECT_THROW(s.metrics(), pteryla::Error);
  const std::string dir = (std::filesystem::temp_directory_path() / "pteryla_follow").string();
  std::filesystem::create_directories(dir);
  EXPECT_THROW(s.exportTo(dir + "/coat.glb"), pteryla::Error);
  s.exportMesh(dir + "/coat.obj");
  std::ifstream obj(dir + "/coat.obj");
  std::string tag;
  double x, y, z;
  while (obj >> tag && tag != "v") obj.ignore(1 << 20, '\n');
  ASSERT_TRUE(obj >> x >> y >> z);
  EXPECT_NEAR(x, moved02[0], 1e-4);
  EXPECT_NEAR(y, moved02[1], 1e-4);
  EXPECT_NEAR(z, moved02[2], 1e-4);
}

// Switching modes keeps the host's pose: Follow -> Repack gives what a Repack session with that pose gives.
TEST(HostSession, SwitchingPoseModeKeepsThePose) {
  const SkinArrays skin = sphereSkin();
  std::vector<double> squashed = skin.positions;
  for (size_t v = 0; v < squashed.size() / 3; ++v) squashed[3 * v + 1] *= 0.7;
  Session repack = evaluated(skin, smallSetup());
  repack.setPose(squashed);
  ASSERT_TRUE(repack.evaluate());
  Session s = evaluated(skin, smallSetup());
  s.setPoseMode(pteryla::PoseMode::Follow);
  EXPECT_EQ(s.poseMode(), pteryla::PoseMode::Follow);
  s.setPose(squashed);
  ASSERT_TRUE(s.evaluate());
  // Carried, not repacked: follicles sit on the squashed skin, the elevations are the rest coat's.
  for (size_t i = 0; i < s.frame().featherCount; ++i) EXPECT_LE(std::abs(s.frame().origins[3 * i + 1]), 0.7 + 1e-6);
  EXPECT_FALSE(sameBits(s.frame().positions, repack.frame().positions));
  s.setPoseMode(pteryla::PoseMode::Repack);
  ASSERT_TRUE(s.evaluate());
  expectIdentical(s.frame(), repack.frame());
  // And back: Follow with the same pose as before.
  s.setPoseMode(pteryla::PoseMode::Follow);
  ASSERT_TRUE(s.evaluate());
  EXPECT_FALSE(sameBits(s.frame().positions, repack.frame().positions));
  s.clearPose();
  ASSERT_TRUE(s.evaluate());
  Session rest = evaluated(skin, smallSetup());
  expectIdentical(s.frame(), rest.frame());
  // Bad poses are refused in Follow mode too, and the last good pose is kept.
  std::vector<double> bad = squashed;
  bad[7] = std::nan("");
  EXPECT_THROW(s.setPose(bad), pteryla::Error);
  bad[7] = 1e9;
  EXPECT_THROW(s.setPose(bad), pteryla::Error);
  EXPECT_THROW(s.setPose(std::vector<double>(9, 0.0)), pteryla::Error);
}

// A tract's own seed re-scatters that tract and no other.
TEST(HostSession, TractSeedRescattersOnlyItsTract) {
  const SkinArrays skin = sphereSkin();
  CoatSetup setup = topAndBottom(skin);
  auto originsOf = [](const Session& s, uint32_t tract) {
    std::vector<double> o;
    const Frame& f = s.frame();
    for (size_t i = 0; i < f.featherCount; ++i)
      if (f.tracts[i] == tract) o.insert(o.end(), &f.origins[3 * i], &f.origins[3 * i] + 3);
    return o;
  };
  Session a = evaluated(skin, setup);
  setup.tracts[0].seed = 77;
  Session b = evaluated(skin, setup);
  Session b2 = evaluated(skin, setup);
  EXPECT_NE(originsOf(a, 0), originsOf(b, 0));
  EXPECT_EQ(originsOf(a, 1), originsOf(b, 1));
  expectIdentical(b.frame(), b2.frame());
  setup.tracts[0].seed = 78;
  Session c = evaluated(skin, setup);
  EXPECT_NE(originsOf(b, 0), originsOf(c, 0));
}

// The typed moult: off by default; on, the window takes feathers out mid-moult (not before it starts or
// after it ends), a tract with moult false keeps every feather, and bad values fail at construction.
TEST(HostSession, MoultWindowTakesFeathersOutOfMoultingTractsOnly) {
  const SkinArrays skin = sphereSkin();
  CoatSetup setup = topAndBottom(skin);
  setup.tracts[1].moult = false;
  auto missing = [](const Session& s, uint32_t tract) {
    size_t n = 0;
    for (size_t i = 0; i < s.frame().featherCount; ++i) n += s.frame().tracts[i] == tract && !s.frame().present[i];
    return n;
  };
  Session off = evaluated(skin, setup);
  off.setTime(5);
  ASSERT_TRUE(off.evaluate());
  EXPECT_EQ(missing(off, 0) + missing(off, 1), 0u);

  setup.moult.enabled = true;
  setup.moult.start = 2;
  setup.moult.duration = 6;
  setup.moult.window = 0.3;
  setup.moult.gap = 0.5;
  Session s = evaluated(skin, setup);
  for (double t : {0.0, 1.9, 8.5}) {
    s.setTime(t);
    ASSERT_TRUE(s.evaluate());
    EXPECT_EQ(missing(s, 0), 0u) << "t = " << t;
  }
  s.setTime(5);
  ASSERT_TRUE(s.evaluate());
  EXPECT_GT(missing(s, 0), 3u);
  EXPECT_EQ(missing(s, 1), 0u);

  auto failsAt = [&](const std::string& element, const std::function<void(CoatSetup&)>& edit) {
    expectSetupErrorAt(skin, setup, element, edit);
  };
  failsAt("moult.window", [](CoatSetup& c) { c.moult.window = 1.5; });
  failsAt("moult.duration", [](CoatSetup& c) { c.moult.duration = 0; });
  failsAt("moult.sequence", [](CoatSetup& c) { c.moult.sequence = "sideways"; });
  failsAt("moult.gap", [](CoatSetup& c) { c.moult.gap = std::nan(""); });
}

// Fixed elevations from the host replace what packing gives those feathers, exactly; the others are
// packed against them; clearing gives the packed coat back bit for bit.
TEST(HostSession, FixedElevationsReplaceThePackedOnes) {
  const SkinArrays skin = sphereSkin();
  CoatSetup setup = smallSetup();
  setup.packing = CoatSetup::Packing::HeightField;
  Session s = evaluated(skin, setup);
  const Frame& f0 = s.frame();
  const std::vector<uint64_t> keys(f0.follicleKeys.begin(), f0.follicleKeys.end());
  const std::vector<double> packed(f0.elevations.begin(), f0.elevations.end());
  const std::vector<float> coat(f0.positions.begin(), f0.positions.end());
  s.setFixedElevations({keys[3], keys[40], keys[77]}, {0.6, 1.2, 0.0});
  EXPECT_THROW(s.frame(), pteryla::Error);
  ASSERT_TRUE(s.evaluate());
  const Frame& f1 = s.frame();
  EXPECT_EQ(f1.elevations[3], 0.6);
  EXPECT_EQ(f1.elevations[40], 1.2);
  EXPECT_EQ(f1.elevations[77], 0.0);
  EXPECT_FALSE(std::equal(coat.begin(), coat.end(), f1.positions.begin(), f1.positions.end()));
  auto elementOf = [&](const std::function<void()>& f) {
    try {
      f();
    } catch (const pteryla::Error& e) {
      return e.element();
    }
    return std::string("no error");
  };
  EXPECT_EQ(elementOf([&] { s.setFixedElevations({keys[0], 987654321}, {0.1, 0.1}); }), "follicleKeys[1]");
  EXPECT_EQ(elementOf([&] { s.setFixedElevations({keys[0]}, {2.0}); }), "elevations[0]");
  EXPECT_EQ(elementOf([&] { s.setFixedElevations({keys[0]}, {std::nan("")}); }), "elevations[0]");
  EXPECT_EQ(elementOf([&] { s.setFixedElevations({keys[0]}, {}); }), "elevations");
  EXPECT_NO_THROW(s.frame());  // the refused calls kept the set and the frame
  s.setFixedElevations({}, {});
  ASSERT_TRUE(s.evaluate());
  EXPECT_TRUE(std::equal(packed.begin(), packed.end(), s.frame().elevations.begin()));
  EXPECT_TRUE(std::equal(coat.begin(), coat.end(), s.frame().positions.begin()));
  // A draped coat (the default) is laid along the skin: refused, naming the packing.
  Session draped = evaluated(skin, smallSetup());
  EXPECT_EQ(elementOf([&] { draped.setFixedElevations({keys[0]}, {0.3}); }), "packing");
}

// A typed control raises the feathers it binds to its max_lift at lift 1 (packed coat), is animated by
// its keys, and bad values fail at construction naming the element.
TEST(HostSession, TypedControlRaisesTheFeathersItBinds) {
  const SkinArrays skin = sphereSkin();
  CoatSetup setup = smallSetup();
  setup.packing = CoatSetup::Packing::HeightField;
  pteryla::ControlSetup c;
  c.name = "crest";
  c.at = {{0, 0.8, 0.6}};
  c.radius = 0.45;
  c.maxLiftDeg = 60;
  pteryla::ControlKey k0, k1;
  k0.t = 0;
  k0.lift = 0.0;
  k1.t = 1;
  k1.lift = 1.0;
  c.keys = {k0, k1};
  setup.controls = {c};
  Session s = evaluated(skin, setup);
  Session still = evaluated(skin, smallSetup());
  const double target = 60 * 3.14159265358979323846 / 180;
  auto near = [&](const Frame& f, size_t i) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += (f.origins[3 * i + k] - c.at[k]) * (f.origins[3 * i + k] - c.at[k]);
    return std::sqrt(d2) < 0.5 * c.radius;
  };
  size_t raised = 0, nearCount = 0;
  s.setTime(1.0);
  ASSERT_TRUE(s.evaluate());
  for (size_t i = 0; i < s.frame().featherCount; ++i)
    if (near(s.frame(), i)) {
      ++nearCount;
      raised += s.frame().elevations[i] >= target - 1e-9;
    }
  EXPECT_GE(nearCount, 2u);
  EXPECT_EQ(raised, nearCount);
  // At t = 0 the lift is 0: nothing is raised to the target.
  s.setTime(0.0);
  ASSERT_TRUE(s.evaluate());
  for (size_t i = 0; i < s.frame().featherCount; ++i) {
    if (near(s.frame(), i)) {
      EXPECT_LT(s.frame().elevations[i], target - 1e-3);
    }
  }

  auto failsAt = [&](const std::string& element, const std::function<void(CoatSetup&)>& edit) {
    expectSetupErrorAt(skin, setup, element, edit);
  };
  failsAt("controls[0].radius", [](CoatSetup& x) { x.controls[0].radius = 0; });
  failsAt("controls[0].keys[1].lift", [](CoatSetup& x) { x.controls[0].keys[1].lift = 2.0; });
  failsAt("controls[0].tracts[0]", [](CoatSetup& x) { x.controls[0].tracts = {"tail"}; });
  failsAt("controls[0].keys", [](CoatSetup& x) { x.controls[0].keys.clear(); });
  failsAt("controls[0].interpolation", [](CoatSetup& x) { x.controls[0].interpolation = "bouncy"; });
  failsAt("controls[0].at", [](CoatSetup& x) { x.controls[0].at[1] = std::nan(""); });
}

TEST(HostSession, BadPosesAreErrorsNamingTheElement) {
  const SkinArrays skin = sphereSkin();
  Session s = evaluated(skin, smallSetup());
  const size_t nv = skin.positions.size() / 3;
  EXPECT_EQ(s.vertexCount(), nv);

  std::vector<double> shortPose(skin.positions.begin(), skin.positions.end() - 3);
  pteryla::Error e = errorOf([&] { s.setPose(shortPose); });
  EXPECT_EQ(e.element(), "positions");
  EXPECT_NE(e.detail().find(std::to_string(3 * nv)), std::string::npos) << e.what();

  std::vector<double> nanPose = skin.positions;
  nanPose[3 * 17 + 1] = std::nan("");
  e = errorOf([&] { s.setPose(nanPose); });
  EXPECT_EQ(e.element(), "vertex 17");

  std::vector<double> farPose = skin.positions;
  farPose[3 * 4] = 1e300;
  e = errorOf([&] { s.setPose(farPose); });
  EXPECT_EQ(e.element(), "vertex 4");

  std::vector<float> floats(skin.positions.begin(), skin.positions.end());
  e = errorOf([&] { s.setPose(floats.data(), nv + 1); });
  EXPECT_EQ(e.element(), "positions");
  floats[3 * 9] = INFINITY;
  e = errorOf([&] { s.setPose(floats.data(), nv); });
  EXPECT_EQ(e.element(), "vertex 9");

  e = errorOf([&] { s.setTime(std::nan("")); });
  EXPECT_EQ(e.element(), "time");
  e = errorOf([&] { s.setLod(0); });
  EXPECT_EQ(e.element(), "lod");

  // A refused pose leaves the session as it was: the frame is still the rest frame.
  EXPECT_NO_THROW(s.frame());
  EXPECT_EQ(s.frame().featherCount, 120u);
}

TEST(HostSession, BadSkinAndSetupAreErrorsNamingTheElement) {
  const SkinArrays good = sphereSkin();
  const CoatSetup setup = smallSetup();

  SkinArrays skin = good;
  skin.positions.pop_back();
  EXPECT_EQ(errorOf([&] { Session(skin, setup); }).element(), "positions");
  skin = good;
  skin.triangles.pop_back();
  EXPECT_EQ(errorOf([&] { Session(skin, setup); }).element(), "triangles");
  skin = good;
  skin.positions[3 * 7 + 2] = std::nan("");
  EXPECT_EQ(errorOf([&] { Session(skin, setup); }).element(), "vertex 7");
  skin = good;
  skin.triangles[3 * 11 + 1] = 100000;
  EXPECT_EQ(errorOf([&] { Session(skin, setup); }).element(), "face 11");
  skin = good;
  skin.faceGroups.assign(3, 0);
  skin.groupNames = {"back"};
  EXPECT_EQ(errorOf([&] { Session(skin, setup); }).element(), "faceGroups");
  skin = good;
  skin.groupNames = {"back"};
  skin.faceGroups.assign(good.triangles.size() / 3, 0);
  skin.faceGroups[5] = 1;
  EXPECT_EQ(errorOf([&] { Session(skin, setup); }).element(), "faceGroups[5]");

  CoatSetup c = setup;
  c.tracts[0].groups = {"wing"};  // the skin has no groups
  EXPECT_EQ(errorOf([&] { Session(good, c); }).element(), "tracts[0].groups[0]");
  c = setup;
  c.tracts[0].faces = {3, 999999};
  EXPECT_EQ(errorOf([&] { Session(good, c); }).element(), "tracts[0].faces[1]");
  c = setup;
  c.tracts[0].count = 0;
  c.tracts[0].density = -2;
  EXPECT_EQ(errorOf([&] { Session(good, c); }).element(), "tracts[0].density");
  c = setup;
  c.tracts[0].featherScale = std::nan("");
  EXPECT_EQ(errorOf([&] { Session(good, c); }).element(), "tracts[0].feather_scale");
  c = setup;
  c.tracts[0].featherFile = "/no/such/feather.json";
  EXPECT_EQ(errorOf([&] { Session(good, c); }).element(), "tracts[0].featherFile");
  c = setup;
  c.tracts.push_back(c.tracts[0]);  // same name twice
  EXPECT_EQ(errorOf([&] { Session(good, c); }).element(), "tracts[1].name");
  c = setup;
  c.axis[1] = {0, 1.2, 0};  // coincides with the first point
  EXPECT_EQ(errorOf([&] { Session(good, c); }).element(), "axis[1]");
  c = setup;
  c.axis.resize(1);
  EXPECT_EQ(errorOf([&] { Session(good, c); }).element(), "axis");
  c = setup;
  c.axis[1][2] = INFINITY;
  EXPECT_EQ(errorOf([&] { Session(good, c); }).element(), "axis[1]");
  c = setup;
  c.ordering = CoatSetup::Ordering::Tracts;
  c.tractOrder = {"body", "nope"};
  EXPECT_EQ(errorOf([&] { Session(good, c); }).element(), "tractOrder[1]");
}

TEST(HostSession, CancelStopsAndTheNextEvaluationCompletesIdentically) {
  const SkinArrays skin = sphereSkin();
  Session s(skin, smallSetup());
  s.setLod(0.3);
  std::vector<std::string> stages;
  const bool done = s.evaluate([&](const std::string& stage, double) {
    stages.push_back(stage);
    return stage != "distribute";  // cancel inside the follicle relaxation
  });
  EXPECT_FALSE(done);
  ASSERT_FALSE(stages.empty());
  EXPECT_EQ(stages.back(), "distribute");
  EXPECT_THROW(s.frame(), pteryla::Error);
  // A cancel in the mesh stage, after distribution completed.
  EXPECT_FALSE(s.evaluate([](const std::string& stage, double) { return stage != "mesh"; }));
  ASSERT_TRUE(s.evaluate());
  Session fresh = evaluated(skin, smallSetup());
  expectIdentical(s.frame(), fresh.frame());
}

// A typed set-up is the scene it stands for: the same coat as the equivalent scene file over the
// same mesh read from disk.
TEST(HostSession, TypedSetupEqualsTheEquivalentSceneFile) {
  const pteryla::coat::SkinMesh mesh = pteryla::coat::loadSkinMesh(kData + "/meshes/sphere_250.obj");
  SkinArrays skin;
  for (const auto& p : mesh.positions) skin.positions.insert(skin.positions.end(), {p.x, p.y, p.z});
  for (const auto& f : mesh.faces) skin.triangles.insert(skin.triangles.end(), f.begin(), f.end());
  CoatSetup c;
  pteryla::TractSetup t;
  t.name = "all";
  t.count = 150;
  t.featherSpacings = 3.0;
  c.tracts.push_back(t);
  c.axis = {{{0, 1.5, 0}}, {{0, -1.5, 0}}};
  c.packing = CoatSetup::Packing::HeightField;
  c.seed = 12;

  const std::filesystem::path dir = std::filesystem::path(PTERYLA_BUILD_DIR) / "test_host";
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "typed_equivalent.json").string();
  const pteryla::Json axis = {{0, 1.5, 0}, {0, -1.5, 0}};
  const pteryla::Json scene = {{"pteryla", 1},
                               {"seed", 12},
                               {"mesh", kData + "/meshes/sphere_250.obj"},
                               {"feathers", {{"contour", kData + "/feathers/contour.json"}}},
                               {"tracts",
                                {{{"name", "all"},
                                  {"count", 150},
                                  {"feather_spacings", 3.0},
                                  {"parameterization", {{"method", "projection"}}}}}},
                               {"directions", {{"axis", axis}}},
                               {"ordering", {{"method", "axis"}, {"axis", axis}}},
                               {"packing", {{"method", "height_field"}}}};
  pteryla::writeJsonFile(file, scene);

  Session typed = evaluated(skin, c);
  Session fromFile = Session::fromSceneFile(file);
  fromFile.setLod(0.3);
  ASSERT_TRUE(fromFile.evaluate());
  expectIdentical(typed.frame(), fromFile.frame());
}

// fromSceneFile is the pipeline the CLI runs, results unchanged.
TEST(HostSession, FromSceneFileEqualsThePipeline) {
  const std::string file = kData + "/scenes/sphere_250.json";
  Session s = Session::fromSceneFile(file);
  ASSERT_TRUE(s.evaluate());
  pteryla::pipeline::Pipeline p(pteryla::pipeline::loadScene(file));
  const auto& mesh = p.coatMesh();
  const Frame& f = s.frame();
  EXPECT_DOUBLE_EQ(s.lod(), p.lod());
  ASSERT_EQ(f.positions.size, 3 * mesh.mesh.positions.size());
  EXPECT_EQ(std::memcmp(f.positions.data, mesh.mesh.positions.data(), f.positions.size * sizeof(float)), 0);
  ASSERT_EQ(f.indices.size, mesh.mesh.indices.size());
  EXPECT_TRUE(std::equal(f.indices.begin(), f.indices.end(), mesh.mesh.indices.begin()));
  const std::vector<double>& el = p.elevations();
  ASSERT_EQ(f.elevations.size, el.size());
  EXPECT_EQ(std::memcmp(f.elevations.data, el.data(), el.size() * sizeof(double)), 0);
  const auto& follicles = p.follicles();
  const auto& coat = p.feathers();
  for (size_t i = 0; i < f.featherCount; ++i) ASSERT_EQ(f.follicleKeys[i], follicles.id[coat.follicle[i]]);
}

// Instancing through the host API: a scene file's option and the setter both reach the mesh stage (its
// store shrinks, its triangles stay), out-of-range values are refused naming the setting and change
// nothing, and 0 gives back the unshared coat bit for bit.
TEST(HostSession, InstanceToleranceSharesTheStoreAndIsRangeChecked) {
  const std::string file = kData + "/scenes/sphere_250.json";
  Session s = Session::fromSceneFile(file);
  ASSERT_TRUE(s.evaluate());
  const std::vector<float> exact(s.frame().positions.begin(), s.frame().positions.end());
  const size_t indices = s.frame().indices.size;
  const Session::MeshStore before = s.meshStore();
  EXPECT_EQ(before.representatives, before.feathers);
  EXPECT_EQ(before.vertices, exact.size() / 3);

  s.setInstanceTolerance(0.02);
  EXPECT_EQ(s.instanceTolerance(), 0.02);
  ASSERT_TRUE(s.evaluate());
  const Session::MeshStore shared = s.meshStore();
  EXPECT_EQ(shared.feathers, before.feathers);
  EXPECT_LT(shared.representatives, shared.feathers / 2);
  EXPECT_LT(shared.storedVertices, before.storedVertices / 2);
  EXPECT_GE(shared.distinctMeshes, shared.representatives);
  EXPECT_EQ(s.frame().indices.size, indices);
  EXPECT_NE(std::memcmp(s.frame().positions.data, exact.data(), exact.size() * sizeof(float)), 0);

  for (double bad : {-0.001, 0.11, std::nan("")})
    EXPECT_EQ(errorOf([&] { s.setInstanceTolerance(bad); }).element(), "instanceTolerance") << bad;
  EXPECT_EQ(s.instanceTolerance(), 0.02);
  pteryla::SceneFileOptions o;
  o.instanceTolerance = 0.5;
  EXPECT_EQ(errorOf([&] { Session::fromSceneFile(file, o); }).element(), "instanceTolerance");

  o.instanceTolerance = 0.02;
  Session fromFile = Session::fromSceneFile(file, o);
  ASSERT_TRUE(fromFile.evaluate());
  expectIdentical(fromFile.frame(), s.frame());

  s.setInstanceTolerance(0);
  ASSERT_TRUE(s.evaluate());
  ASSERT_EQ(s.frame().positions.size, exact.size());
  EXPECT_EQ(std::memcmp(s.frame().positions.data, exact.data(), exact.size() * sizeof(float)), 0);
}

TEST(HostSession, MetricsMatchTheFrame) {
  {
    // A session that only checks gets the metrics without a frame: the checker meshes at full detail,
    // and meshing again at the session's own level would be wasted.
    Session fresh(sphereSkin(), smallSetup());
    fresh.setLod(0.3);
    const pteryla::Metrics m = fresh.metrics();  // evaluates first
    EXPECT_EQ(m.feathers.value_or(0), 120u);
    EXPECT_THROW(fresh.frame(), pteryla::Error);
  }
  Session s(sphereSkin(), smallSetup());
  s.setLod(0.3);
  ASSERT_TRUE(s.evaluate());
  const pteryla::Metrics m = s.metrics();
  ASSERT_TRUE(m.follicles && m.feathers && m.coverage && m.intersectingPairs);
  EXPECT_EQ(*m.follicles, 120u);
  EXPECT_EQ(*m.feathers, 120u);
  EXPECT_GT(*m.coverage, 0.5);
  ASSERT_TRUE(m.fixedFeathers.has_value());  // a draped coat
  // The offending feathers are present frame feathers, ascending, one list per nonzero count.
  EXPECT_EQ(m.intersectingFeathers.empty(), *m.intersectingPairs == 0);
  EXPECT_EQ(m.penetratingFeathers.empty(), m.skinPenetrations.value_or(0) == 0);
  for (const auto* ids : {&m.intersectingFeathers, &m.penetratingFeathers}) {
    EXPECT_TRUE(std::is_sorted(ids->begin(), ids->end()));
    for (uint32_t i : *ids) {
      ASSERT_LT(i, s.frame().featherCount);
      EXPECT_TRUE(s.frame().present[i]);
    }
  }
  // A frame the host had is valid afterwards and at the session's level of detail, not the checker's.
  Session same = evaluated(sphereSkin(), smallSetup());
  expectIdentical(s.frame(), same.frame());
}

// What a DCC shades the coat with and hands on: per-vertex alpha, a material per range, the mesh file.
TEST(HostSession, AlphaMaterialsAndExport) {
  CoatSetup setup = smallSetup();
  pteryla::TractSetup covert;
  covert.name = "covert";
  covert.count = 40;
  covert.featherFile = kData + "/feathers/covert.json";
  const SkinArrays skin = sphereSkin();
  for (uint32_t f = 0; f < skin.triangles.size() / 3; ++f) {  // upper half: contour, lower: covert
    double y = 0;
    for (int k = 0; k < 3; ++k) y += skin.positions[3 * skin.triangles[3 * f + k] + 1];
    (y > 0 ? setup.tracts[0].faces : covert.faces).push_back(f);
  }
  setup.tracts.push_back(covert);
  Session s(skin, setup);
  EXPECT_THROW(s.exportMesh(::testing::TempDir() + "/none.obj"), pteryla::Error);  // nothing evaluated
  s.setLod(0.3);
  ASSERT_TRUE(s.evaluate());
  const Frame& f = s.frame();
  const size_t nv = f.positions.size / 3;
  ASSERT_EQ(f.alphas.size, nv);
  for (float a : f.alphas) ASSERT_TRUE(a >= 0 && a <= 1);
  ASSERT_EQ(f.materials.size, 2u);
  std::vector<std::string> names = {f.materials[0].name, f.materials[1].name};
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"contour", "covert"}));
  for (const auto& r : f.ranges) {
    ASSERT_LT(r.material, f.materials.size);
    EXPECT_EQ(f.materials[r.material].name, f.tracts[r.feather] == 0 ? "contour" : "covert");
  }
  const std::string obj = ::testing::TempDir() + "/pteryla_host_export.obj";
  s.exportMesh(obj);
  std::ifstream in(obj);
  size_t v = 0, t = 0;
  for (std::string line; std::getline(in, line);) {
    v += line.rfind("v ", 0) == 0;
    t += line.rfind("f ", 0) == 0;
  }
  EXPECT_EQ(v, nv);
  EXPECT_EQ(t, f.indices.size / 3);
  const pteryla::Error e = errorOf([&] { s.exportMesh(::testing::TempDir() + "/coat.xyz"); });
  EXPECT_NE(std::string(e.what()).find("coat.xyz"), std::string::npos);
}

TEST(HostSession, MissingSceneFileIsAnError) {
  const pteryla::Error e = errorOf([] { Session::fromSceneFile("/no/such/scene.json"); });
  EXPECT_EQ(e.file(), "/no/such/scene.json");
}

TEST(HostDataDirectory, ExplicitSetterWinsAndResets) {
  const std::string before = pteryla::dataDirectory();
  EXPECT_TRUE(std::filesystem::is_regular_file(std::filesystem::path(before) / "feathers" / "contour.json")) << before;
  pteryla::setDataDirectory("/no/such/data");
  EXPECT_EQ(pteryla::dataDirectory(), "/no/such/data");
  // The default feather is looked up there.
  const pteryla::Error e = errorOf([] { Session(sphereSkin(), smallSetup()); });
  EXPECT_EQ(e.element(), "tracts[0].featherFile");
  EXPECT_NE(e.detail().find("/no/such/data/feathers/contour.json"), std::string::npos) << e.what();
  pteryla::setDataDirectory("");
  EXPECT_EQ(pteryla::dataDirectory(), before);
}

TEST(HostApi, VersionIsTheProjectVersion) { EXPECT_STREQ(pteryla::version(), PTERYLA_PROJECT_VERSION); }

}  // namespace
