// coat::Packer (packer.hpp): a packer held across packs reuses its skin samples and its last result, and
// gives the bits of fresh one-shot packs; what it keeps is dropped when the skin or the options change.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "pack_fixtures.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/packer.hpp"
#include "pteryla/coat/primitives.hpp"
#include "pteryla/core/error.hpp"

using namespace pteryla;
using namespace pteryla::coat;
using glm::dvec3;

namespace {

// Every output of a pack bit for bit: elevations, packed key barbs, points and the culling spheres.
void expectSameBits(const PackResult& a, const PackResult& b) {
  auto same = [](const auto& x, const auto& y) {
    return x.size() == y.size() && (x.empty() || std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0);
  };
  EXPECT_TRUE(same(a.elevation, b.elevation));
  EXPECT_TRUE(same(a.packedKeys.keyOffset, b.packedKeys.keyOffset));
  EXPECT_TRUE(same(a.packedKeys.rp, b.packedKeys.rp));
  EXPECT_TRUE(same(a.packedKeys.cvs, b.packedKeys.cvs));
  EXPECT_TRUE(same(a.pointOffset, b.pointOffset));
  EXPECT_TRUE(same(a.points, b.points));
  EXPECT_TRUE(same(a.bounds, b.bounds));
  EXPECT_TRUE(same(a.groupBounds, b.groupBounds));
  EXPECT_TRUE(same(a.barbsChanged, b.barbsChanged));
}

struct Sphere {
  SkinMesh skin = makeIcosphere(3);
  CoatFeathers coat = packtest::sphereCoat(skin, 400, 1.0);
};

// Feathers turned about their normals by `angle`: a styling edit.
std::vector<uint32_t> turn(CoatFeathers& c, const std::vector<uint32_t>& which, double angle) {
  for (uint32_t i : which) {
    FeatherFrame& f = c.frames[i];
    f.tangent = std::cos(angle) * f.tangent + std::sin(angle) * f.binormal;
    f.binormal = glm::normalize(glm::cross(f.normal, f.tangent));
  }
  return which;
}

}  // namespace

TEST(Packer, ReusedAcrossPackAndRepackGivesFreshPacksBits) {
  const Sphere s;
  PackOptions o;
  o.threads = 2;
  Packer packer(s.skin, o);
  const PackResult& first = packer.pack(s.coat);
  expectSameBits(first, pack(s.skin, s.coat, o));
  const auto samples = first.skinSamples;
  ASSERT_NE(samples, nullptr);

  // A few feathers turned: the packer repacks from its last result.
  CoatFeathers edited = s.coat;
  const std::vector<uint32_t> changed = turn(edited, {10, 57, 123, 200, 301}, 0.3);
  const PackResult fresh = pack(s.skin, edited, o);
  const PackResult& inc = packer.repack(edited, changed);
  expectSameBits(fresh, inc);
  EXPECT_GE(inc.stats.recomputed, changed.size());
  EXPECT_LT(inc.stats.recomputed, fresh.stats.recomputed) << "the repack was incremental";
  EXPECT_EQ(inc.skinSamples, samples) << "the skin did not change: its samples were reused";

  // Again with nothing changed, on one thread: nothing recomputed, the same bits.
  o.threads = 1;
  packer.use(s.skin, o);
  expectSameBits(fresh, packer.repack(edited, {}));
  EXPECT_EQ(packer.result().stats.recomputed, 0u);

  // A second packer seeded with the first one's result shares its samples.
  Packer other(s.skin, o);
  CoatFeathers back = edited;
  turn(back, changed, -0.3);
  expectSameBits(other.repackFrom(packer.result(), back, changed), pack(s.skin, back, o));
  EXPECT_EQ(other.result().skinSamples, samples);

  // release() hands the result out and leaves nothing to repack from: the next repack is a full pack.
  const PackResult out = packer.release();
  EXPECT_FALSE(packer.hasResult());
  expectSameBits(out, fresh);
  EXPECT_EQ(packer.repack(edited, {}).stats.recomputed, fresh.stats.packed);
}

TEST(Packer, CachedSamplesAndResultAreDroppedWhenTheSkinOrOptionsChange) {
  Sphere s;
  PackOptions o;
  o.threads = 2;
  Packer packer(s.skin, o);
  const auto before = packer.pack(s.coat).skinSamples;
  EXPECT_EQ(packer.pack(s.coat).skinSamples, before) << "same skin, same samples";

  // The skin moved in place (as the pipeline's posed skin does between frames): the samples are built
  // again and the last result is stale, so a repack with nothing changed is a full pack on the new skin.
  for (dvec3& p : s.skin.positions) p *= 1.01;
  recomputeGeometry(s.skin);
  const PackResult& moved = packer.repack(s.coat, {});
  EXPECT_NE(moved.skinSamples, before);
  EXPECT_EQ(moved.stats.recomputed, moved.stats.packed);
  expectSameBits(moved, pack(s.skin, s.coat, o));
  const auto movedSamples = moved.skinSamples;
  const size_t movedCount = moved.stats.skinSamples;

  // Faces turned inside out with the positions kept: new samples too.
  SkinMesh flipped = s.skin;
  for (auto& f : flipped.faces) std::swap(f[1], f[2]);
  recomputeGeometry(flipped);
  packer.use(flipped, o);
  const PackResult& inverted = packer.repack(s.coat, {});
  EXPECT_NE(inverted.skinSamples, movedSamples);
  EXPECT_EQ(inverted.stats.recomputed, inverted.stats.packed);
  expectSameBits(inverted, pack(flipped, s.coat, o));

  // Other options (a denser skin sampling): new samples, a full pack.
  o.skinSampleSpacing = 0.02;
  packer.use(s.skin, o);
  const PackResult& dense = packer.repack(s.coat, {});
  EXPECT_NE(dense.skinSamples, movedSamples);
  EXPECT_GT(dense.stats.skinSamples, movedCount);
  EXPECT_EQ(dense.stats.recomputed, dense.stats.packed);
  expectSameBits(dense, pack(s.skin, s.coat, o));
  // Only the thread count changed: the result still seeds a repack.
  o.threads = 1;
  packer.use(s.skin, o);
  EXPECT_EQ(packer.repack(s.coat, {}).stats.recomputed, 0u);

  // Without the skin there are no samples, and a result packed against the skin seeds nothing.
  o.skin = false;
  packer.use(s.skin, o);
  const PackResult& bare = packer.repack(s.coat, {});
  EXPECT_EQ(bare.skinSamples, nullptr);
  EXPECT_EQ(bare.stats.recomputed, bare.stats.packed);
  expectSameBits(bare, pack(s.skin, s.coat, o));
}

TEST(Packer, RepackIsAFullPackWhenTheChangesMoveTheResolvedClearance) {
  // The first half of the feathers (rounded down) have a narrower rachis: the median width, and with it
  // the automatic clearance, is the wider one. Narrowing a few more moves it, and every feather packs
  // against the new clearance.
  Sphere s;
  const size_t n = s.coat.size();
  for (size_t i = n / 2; i < n; ++i) s.coat.params[i].rachisWidth *= 1.5;
  PackOptions o;
  o.threads = 2;
  const PackResult before = pack(s.skin, s.coat, o);
  CoatFeathers edited = s.coat;
  std::vector<uint32_t> changed;
  for (uint32_t i = static_cast<uint32_t>(n / 2); changed.size() < 12; ++i) {
    edited.params[i].rachisWidth = s.coat.params[0].rachisWidth;
    changed.push_back(i);
  }
  const PackResult fresh = pack(s.skin, edited, o);
  ASSERT_NE(fresh.clearance, before.clearance);
  const PackResult inc = repack(s.skin, edited, before, changed, o);
  EXPECT_EQ(inc.clearance, fresh.clearance);
  expectSameBits(inc, fresh);
}

TEST(Packer, PackOverTakesTheBasesSamplesAndChecksItsSkin) {
  const Sphere s;
  PackOptions o;
  o.threads = 2;
  Packer base(s.skin, o);
  base.pack(s.coat);
  CoatFeathers moulted = s.coat;
  std::vector<uint32_t> changed;
  for (uint32_t i = 3; i < moulted.size(); i += 9) {
    moulted.present[i] = 0;
    changed.push_back(i);
  }
  Packer over(s.skin, o);
  const PackResult& r = over.packOver(base.result(), moulted, changed);
  EXPECT_EQ(r.skinSamples, base.result().skinSamples);
  expectSameBits(r, packOver(s.skin, moulted, base.result(), changed, o));
  // A base packed on another skin is refused, with the element named.
  SkinMesh moved = s.skin;
  moved.positions[0].x += 1e-3;
  recomputeGeometry(moved);
  over.use(moved, o);
  try {
    over.packOver(base.result(), moulted, changed);
    ADD_FAILURE() << "packOver on another skin";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "base");
  }
}
