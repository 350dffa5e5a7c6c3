// Golden frames for CI users (issue #30 item 7): `pteryla diff`, `frames --golden`, and the bundled
// scenes' own goldens (tests/golden/frames/<scene>/frame_NNNN.png, two times each). The goldens are
// rewritten only with PTERYLA_UPDATE_GOLDEN=1 (then each scene test renders into the golden directory).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unistd.h>

#include "pteryla/render/image.hpp"
#include "run.hpp"

namespace fs = std::filesystem;
using pteryla::render::Image;

namespace {

const std::string kBuild = PTERYLA_BUILD_DIR;
const std::string kData = PTERYLA_DATA_DIR;
const std::string kGoldens = std::string(PTERYLA_TEST_DIR) + "/../golden/frames";

std::string freshDir(const std::string& name) {
  const std::string d = kBuild + "/golden_cli/" + name + "_" + std::to_string(::getpid());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

bool contains(const std::string& s, const std::string& sub) { return s.find(sub) != std::string::npos; }

bool updating() {
  const char* v = std::getenv("PTERYLA_UPDATE_GOLDEN");
  return v && std::string(v) == "1";
}

// Two small images differing in one pixel by `delta` in red.
void writePair(const std::string& dir, int delta) {
  Image a(20, 10, 40, 80, 120, 255), b = a;
  b.pixel(4, 6)[0] = static_cast<uint8_t>(40 + delta);
  pteryla::render::saveImage(dir + "/a.png", a);
  pteryla::render::saveImage(dir + "/b.png", b);
}

}  // namespace

TEST(Diff, EqualImagesExitZeroWithFiguresOnStdout) {
  const std::string d = freshDir("diff_equal");
  writePair(d, 0);
  const RunResult r = runPteryla("diff " + d + "/a.png " + d + "/b.png");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["match"].get<bool>());
  EXPECT_EQ(j["changed_pixels"].get<int>(), 0);
  EXPECT_EQ(j["max_error"].get<double>(), 0.0);
}

TEST(Diff, AChangedPixelOverTheBarExitsOneAndIsPictured) {
  const std::string d = freshDir("diff_changed");
  writePair(d, 100);  // 1 of 200 pixels (0.5%) by 100/255
  const RunResult r = runPteryla("diff " + d + "/b.png " + d + "/a.png --out " + d + "/diff.png");
  ASSERT_EQ(r.code, 1) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_FALSE(j["match"].get<bool>());
  EXPECT_EQ(j["changed_pixels"].get<int>(), 1);
  EXPECT_EQ(j["max_at"], nlohmann::json::array({4, 6}));
  EXPECT_NEAR(j["max_error"].get<double>(), 100.0 / 255.0, 1e-12);
  EXPECT_TRUE(contains(r.err, "differ")) << r.err;
  const Image pic = pteryla::render::loadImage(d + "/diff.png");
  EXPECT_GE(pic.pixel(4, 6)[0], 160);
  EXPECT_EQ(pic.pixel(0, 0)[0], 0);
  // Loosened bars let the same pair pass.
  EXPECT_EQ(runPteryla("diff " + d + "/b.png " + d + "/a.png --fraction 0.01 --max-error 0.5 -q").code, 0);
}

TEST(Diff, SizeMismatchDiffersAndUnreadableInputIsBadInput) {
  const std::string d = freshDir("diff_bad");
  pteryla::render::saveImage(d + "/small.png", Image(8, 8));
  pteryla::render::saveImage(d + "/big.png", Image(9, 8));
  const RunResult size = runPteryla("diff " + d + "/small.png " + d + "/big.png");
  EXPECT_EQ(size.code, 1) << size.err;
  EXPECT_FALSE(nlohmann::json::parse(size.out)["same_size"].get<bool>());
  const RunResult missing = runPteryla("diff " + d + "/small.png " + d + "/nope.png");
  EXPECT_EQ(missing.code, 2);
  EXPECT_TRUE(contains(missing.err, "nope.png")) << missing.err;
  const RunResult tol = runPteryla("diff " + d + "/small.png " + d + "/small.png --tolerance 2");
  EXPECT_EQ(tol.code, 2) << tol.err;
}

// frames --golden over moult.json at a tiny size: goldens made by one run, then a second run matches them;
// a tampered golden makes the exit code 1, is named in the manifest and pictured; a missing golden
// directory is refused before anything renders.
TEST(FramesGolden, ComparesEveryFrameAndReportsTheOnesThatDiffer) {
  const std::string d = freshDir("frames_golden");
  const std::string scene = kData + "/scenes/moult.json";
  const std::string range = " --from 0 --to 4 --fps 0.5 --lod 0.1 --size 48x48 -q";
  ASSERT_EQ(runPteryla("frames " + scene + range + " -o " + d + "/golden").code, 0);
  const RunResult same = runPteryla("frames " + scene + range + " -o " + d + "/run1 --golden " + d + "/golden");
  ASSERT_EQ(same.code, 0) << same.err;
  const auto m = readJson(d + "/run1/frames.json");
  EXPECT_EQ(m["golden"]["compared"].get<int>(), 3);
  EXPECT_TRUE(m["golden"]["failed"].empty());

  // Tamper with frame 1's golden: invert a block of it.
  Image g = pteryla::render::loadImage(d + "/golden/frame_0001.png");
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 20; ++x)
      for (int ch = 0; ch < 3; ++ch) g.pixel(x, y)[ch] = static_cast<uint8_t>(255 - g.pixel(x, y)[ch]);
  pteryla::render::saveImage(d + "/golden/frame_0001.png", g);
  fs::remove(d + "/golden/frame_0002.png");
  const RunResult diff = runPteryla("frames " + scene + range + " -o " + d + "/run2 --golden " + d + "/golden");
  EXPECT_EQ(diff.code, 1) << diff.err;
  EXPECT_TRUE(contains(diff.err, "2 of 3 frames differ")) << diff.err;
  EXPECT_TRUE(contains(diff.err, "frame_0002.png (no golden)")) << diff.err;
  const auto m2 = readJson(d + "/run2/frames.json");
  ASSERT_EQ(m2["golden"]["failed"].size(), 2u);
  EXPECT_EQ(m2["golden"]["failed"][0]["file"], "frame_0001.png");
  EXPECT_TRUE(fs::exists(d + "/run2/golden_diff/frame_0001.png"));
  EXPECT_FALSE(fs::exists(d + "/run2/golden_diff/frame_0000.png"));

  // The assembly step of a farm run compares too.
  const RunResult assembled =
      runPteryla("frames " + scene + range + " -o " + d + "/run2 --assemble --golden " + d + "/golden");
  EXPECT_EQ(assembled.code, 1) << assembled.err;

  const RunResult noDir = runPteryla("frames " + scene + range + " -o " + d + "/run3 --golden " + d + "/absent");
  EXPECT_EQ(noDir.code, 2);
  EXPECT_TRUE(contains(noDir.err, "absent")) << noDir.err;
  EXPECT_FALSE(fs::exists(d + "/run3"));
}

// The bundled scenes' goldens: two times each, at a small size and low detail so CI (under the
// sanitizers) renders them in seconds. At a fixed level (--fixed-lod): the goldens are of the coat meshed
// at --lod, the behaviour before levels by screen size became the default.
struct SceneGolden {
  const char* scene;
  const char* range;
};

class BundledSceneGolden : public ::testing::TestWithParam<SceneGolden> {};

TEST_P(BundledSceneGolden, MatchesItsGoldenFrames) {
  const SceneGolden& s = GetParam();
  const std::string golden = kGoldens + "/" + s.scene;
  const std::string args =
      "frames " + kData + "/scenes/" + s.scene + ".json " + s.range + " --size 192x108 --fixed-lod -q";
  if (updating()) {
    const std::string tmp = freshDir(std::string("update_") + s.scene);
    ASSERT_EQ(runPteryla(args + " -o " + tmp).code, 0);
    fs::create_directories(golden);
    for (const char* f : {"frame_0000.png", "frame_0001.png"})
      fs::copy_file(tmp + "/" + f, golden + "/" + f, fs::copy_options::overwrite_existing);
    GTEST_SKIP() << "updated " << golden;
  }
  const std::string out = freshDir(std::string("scene_") + s.scene);
  const RunResult r = runPteryla(args + " -o " + out + " --golden " + golden);
  EXPECT_EQ(r.code, 0) << r.err << "\n(differences pictured in " << out << "/golden_diff/)";
  EXPECT_EQ(readJson(out + "/frames.json")["golden"]["compared"].get<int>(), 2);
}

INSTANTIATE_TEST_SUITE_P(Scenes, BundledSceneGolden,
                         ::testing::Values(SceneGolden{"moult", "--from 1 --to 3 --fps 0.5 --lod 0.3"},
                                           SceneGolden{"wing", "--from 0 --to 1 --fps 1 --lod 0.3"},
                                           SceneGolden{"crest", "--from 0.5 --to 1.5 --fps 1 --lod 0.3"},
                                           SceneGolden{"bird", "--from 0 --to 1 --fps 1 --lod 0.2"}),
                         [](const ::testing::TestParamInfo<SceneGolden>& i) { return std::string(i.param.scene); });
