// `pteryla feather --from-scan`: a synthetic scan of a known feather (tests/feather/synthetic_scan.hpp)
// through the real binary, and its bad input (exit 2, the message names the file or option).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "../feather/synthetic_scan.hpp"
#include "pteryla/feather/io.hpp"
#include "run.hpp"

using namespace pteryla::feather;
namespace synth = pteryla::feather::testing;
namespace fs = std::filesystem;

namespace {

bool contains(const std::string& s, const std::string& sub) { return s.find(sub) != std::string::npos; }

std::string readAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

// A fresh directory in the build tree.
fs::path freshDir(const std::string& name) {
  const fs::path d = fs::path(PTERYLA_BUILD_DIR) / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string q(const fs::path& p) { return "\"" + p.string() + "\""; }

}  // namespace

TEST(CliScan, WritesAFeatherFileThatRendersAndMovesWithItsTexture) {
  const fs::path dir = freshDir("cli_scan");
  const FeatherParams truth = synth::scanTruth();
  const synth::SyntheticScan scan = synth::renderScan(truth, 170, 0.2, 21);
  const fs::path image = dir / "scan.png";
  ASSERT_TRUE(scan.save(image.string()));
  char rachis[128];
  std::snprintf(rachis, sizeof rachis, "%.2f,%.2f,%.2f,%.2f", scan.base.x, scan.base.y, scan.tip.x, scan.tip.y);
  const fs::path out = dir / "made" / "feather.json";
  const std::string cmd =
      "feather --from-scan " + q(image) + " --rachis " + rachis + " --pixels-per-unit 170 --out " + q(out);
  RunResult r = runPteryla(cmd);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "rachis marked")) << r.err;
  // The feather file: the scan's measurements (tolerances of docs/feather-format.md), and the texture
  // beside it, referred to relative to the feather file.
  const FeatherParams p = loadFeather(out.string());
  EXPECT_NEAR(p.rachisLength, truth.rachisLength, 0.02 * truth.rachisLength);
  EXPECT_NEAR(p.spacingBase, truth.spacingBase, 0.04 * truth.spacingBase);
  EXPECT_NEAR(p.spacingTip, truth.spacingTip, 0.04 * truth.spacingTip);
  EXPECT_NEAR(p.left.baseAngle, truth.left.baseAngle, 1.5 * kPi / 180);
  EXPECT_NEAR(p.right.tipAngle, truth.right.tipAngle, 1.5 * kPi / 180);
  EXPECT_EQ(p.material.texture, "feather_texture.png");
  EXPECT_TRUE(fs::exists(dir / "made" / "feather_texture.png"));

  // It renders (the texture loads), here and after moving the two files elsewhere together.
  r = runPteryla("feather " + q(out) + " --out " + q(dir / "rebuilt.png") + " --size 96x128 -q");
  EXPECT_EQ(r.code, 0) << r.err;
  fs::create_directories(dir / "moved");
  fs::rename(dir / "made" / "feather.json", dir / "moved" / "feather.json");
  fs::rename(dir / "made" / "feather_texture.png", dir / "moved" / "feather_texture.png");
  r = runPteryla("feather " + q(dir / "moved" / "feather.json") + " --out " + q(dir / "moved.png") +
                 " --size 96x128 -q");
  EXPECT_EQ(r.code, 0) << r.err;
  // Without the texture beside it, rendering fails naming the texture.
  fs::remove(dir / "moved" / "feather_texture.png");
  r = runPteryla("feather " + q(dir / "moved" / "feather.json") + " --out " + q(dir / "broken.png") +
                 " --size 96x128 -q");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "feather_texture.png")) << r.err;

  // Without --rachis the rachis is found; an existing output is replaced (written to a temporary file
  // and renamed, as every output), --no-texture writes no texture and refers to none.
  const fs::path second = dir / "second.json";
  { std::ofstream(second) << "old"; }
  r = runPteryla("feather --from-scan " + q(image) + " --pixels-per-unit 170 --no-texture -q --out " + q(second));
  ASSERT_EQ(r.code, 0) << r.err;
  const FeatherParams found = loadFeather(second.string());
  EXPECT_NEAR(found.rachisLength, truth.rachisLength, 0.02 * truth.rachisLength);
  EXPECT_TRUE(found.material.texture.empty());
  EXPECT_FALSE(fs::exists(dir / "second_texture.png"));
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_FALSE(contains(e.path().filename().string(), ".tmp-")) << e.path();
}

TEST(CliScan, BadInputExitsTwoNamingTheFileOrOption) {
  const fs::path dir = freshDir("cli_scan_bad");
  const synth::SyntheticScan scan = synth::renderScan(synth::scanTruth(), 170, 0.0, 22);
  const fs::path image = dir / "scan.png";
  ASSERT_TRUE(scan.save(image.string()));
  const fs::path out = dir / "f.json";
  { std::ofstream(out) << "previous"; }

  // A missing image.
  RunResult r = runPteryla("feather --from-scan " + q(dir / "nope.png") + " --out " + q(out));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "nope.png") && contains(r.err, "--from-scan")) << r.err;
  // A file that is no image.
  const fs::path text = dir / "notes.png";
  { std::ofstream(text) << "not an image"; }
  r = runPteryla("feather --from-scan " + q(text) + " --out " + q(out));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "notes.png") && contains(r.err, "--from-scan")) << r.err;
  // Malformed --rachis.
  for (const char* bad : {"1,2,3", "1,2,x,4", "10,20,30,40,50", "1;2;3;4", ""}) {
    r = runPteryla("feather --from-scan " + q(image) + " --rachis '" + bad + "' --out " + q(out));
    EXPECT_EQ(r.code, 2) << bad;
    EXPECT_TRUE(contains(r.err, "--rachis")) << bad << ": " << r.err;
  }
  // A rachis outside the image.
  r = runPteryla("feather --from-scan " + q(image) + " --rachis 10,10,5000,20 --out " + q(out));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "--rachis") && contains(r.err, "outside") && contains(r.err, "scan.png")) << r.err;
  // An image without a feather.
  synth::SyntheticScan blank = scan;
  std::fill(blank.rgb.begin(), blank.rgb.end(), 0.9f);
  const fs::path empty = dir / "empty.png";
  ASSERT_TRUE(blank.save(empty.string()));
  r = runPteryla("feather --from-scan " + q(empty) + " --out " + q(out));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "empty.png") && contains(r.err, "no feather")) << r.err;
  // The output must be a feather file; a feather file and a scan exclude each other; one is needed.
  r = runPteryla("feather --from-scan " + q(image) + " --out " + q(dir / "f.obj"));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "--out") && contains(r.err, ".json")) << r.err;
  r = runPteryla("feather " + q(out) + " --from-scan " + q(image) + " --out " + q(dir / "g.json"));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "--from-scan")) << r.err;
  r = runPteryla("feather --out " + q(dir / "g.obj"));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "--from-scan")) << r.err;
  r = runPteryla("feather --from-scan " + q(image) + " --pixels-per-unit 0 --out " + q(out));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "--pixels-per-unit")) << r.err;
  r = runPteryla("feather --from-scan " + q(image) + " --texture " + q(dir / "t.jpg") + " --out " + q(out));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "--texture")) << r.err;
  // None of the failures touched the existing output.
  EXPECT_EQ(readAll(out.string()), "previous");

  // --help tells the truth about --from-scan and --rachis.
  r = runPteryla("feather --help");
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(contains(r.out, "--from-scan") && contains(r.out, "--rachis") && contains(r.out, "calamus")) << r.out;
}
