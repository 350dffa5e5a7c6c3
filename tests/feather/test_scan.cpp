// Feather acquisition from a scan (scan.hpp): a scan rendered from a known feather (synthetic_scan.hpp)
// must give back that feather's parameters. The tolerances are the ones docs/feather-format.md states.
#include <gtest/gtest.h>

#include <glm/vec4.hpp>

#include <filesystem>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/feather/scan.hpp"
#include "synthetic_scan.hpp"

using namespace pteryla;
using namespace pteryla::feather;
using namespace pteryla::feather::testing;
namespace fs = std::filesystem;

namespace {

constexpr double kPixelsPerUnit = 170;  // the synthetic scans' resolution (pixels per centimetre)
constexpr double kDeg = kPi / 180;

// Tolerances (docs/feather-format.md, "Feathers from scans"); measured errors on these scans are about
// half of them or less.
constexpr double kLengthTol = 0.02;         // rachis length, relative
constexpr double kCurvatureTol = 0.03;      // lateral curvature, radians
constexpr double kSpacingTol = 0.04;        // spacing at base and tip, relative
constexpr double kAngleTol = 1.5 * kDeg;    // barb angles at base and tip, straight barbs
constexpr double kBentAngleTol = 3 * kDeg;  // ... bent barbs
constexpr double kBendTol = 0.1;            // key barb turning, radians
constexpr double kSilhouetteTol = 0.05;     // barb length, fraction of the longest barb, rp in [0.1, 0.9]
constexpr double kCalamusTol = 0.1;         // calamus length, relative
constexpr double kWidthTol = 0.2;           // rachis width, relative (8 pixels at the base)

void printFit(const ScanResult& r) {
  const FeatherParams& p = r.feather;
  std::printf("rachis %.4f (%.1f px) curvature %.4f calamus %.4f width %.4f spacing %.4f %.4f (%d windows)\n",
              p.rachisLength, r.rachisLengthPixels, p.rachisLateralCurvature, p.calamusLength, p.rachisWidth,
              p.spacingBase, p.spacingTip, r.spacingWindows);
  for (int v = 0; v < 2; ++v)
    std::printf("vane %d: angles %.4f %.4f bend %.4f %.4f (%d windows)\n", v, r.vanes[v].baseAngle, r.vanes[v].tipAngle,
                r.vanes[v].bendBase, r.vanes[v].bendTip, r.vanes[v].windows);
  for (const auto& n : r.notes) std::printf("note: %s\n", n.c_str());
}

// Every recovered parameter against the truth, within the stated tolerances.
void expectRecovered(const FeatherParams& truth, const ScanResult& r, double bendBase, double bendTip,
                     double angleTol = kAngleTol) {
  const FeatherParams& p = r.feather;
  printFit(r);
  EXPECT_NEAR(p.rachisLength, truth.rachisLength, kLengthTol * truth.rachisLength);
  EXPECT_NEAR(p.rachisLateralCurvature, truth.rachisLateralCurvature, kCurvatureTol);
  EXPECT_EQ(p.rachisVentralDorsalCurvature, 0.0);
  EXPECT_NEAR(p.calamusLength, truth.calamusLength, kCalamusTol * truth.calamusLength);
  EXPECT_NEAR(p.rachisWidth, truth.rachisWidth, kWidthTol * truth.rachisWidth);
  EXPECT_NEAR(p.spacingBase, truth.spacingBase, kSpacingTol * truth.spacingBase);
  EXPECT_NEAR(p.spacingTip, truth.spacingTip, kSpacingTol * truth.spacingTip);
  EXPECT_GE(r.spacingWindows, 8);
  for (int v = 0; v < 2; ++v) {
    SCOPED_TRACE(v == 0 ? "left vane" : "right vane");
    const VaneParams& want = truth.vane(v);
    ASSERT_TRUE(r.vanes[v].measured);
    EXPECT_NEAR(p.vane(v).baseAngle, want.baseAngle, angleTol);
    EXPECT_NEAR(p.vane(v).tipAngle, want.tipAngle, angleTol);
    EXPECT_NEAR(r.vanes[v].bendBase, bendBase, kBendTol);
    EXPECT_NEAR(r.vanes[v].bendTip, bendTip, kBendTol);
    // Two key barbs, at rp 0 and 1, in the key-barb form (cv[0] at the origin, chord 1, flat).
    ASSERT_EQ(p.vane(v).keyBarbs.size(), 2u);
    EXPECT_EQ(p.vane(v).keyBarbs[0].rp, 0.0);
    EXPECT_EQ(p.vane(v).keyBarbs[1].rp, 1.0);
    for (const KeyBarb& k : p.vane(v).keyBarbs) {
      EXPECT_NEAR(glm::length(k.cvs.back() - k.cvs.front()), 1.0, 1e-9);
      for (const auto& cv : k.cvs) EXPECT_EQ(cv.z, 0.0);
    }
    double longest = 0;
    for (double rp = 0; rp <= 1; rp += 0.01) longest = std::max(longest, truth.barbLengthAt(v, rp));
    double worst = 0, worstRp = 0;
    for (double rp = 0.1; rp <= 0.9 + 1e-9; rp += 0.05) {
      const double e = std::abs(p.barbLengthAt(v, rp) - truth.barbLengthAt(v, rp));
      if (e > worst) worst = e, worstRp = rp;
    }
    std::printf("vane %d: silhouette error %.4f (%.1f%% of the longest barb) at rp %.2f\n", v, worst,
                100 * worst / longest, worstRp);
    EXPECT_LT(worst, kSilhouetteTol * longest) << "at rp " << worstRp;
  }
}

std::string tempPath(const std::string& name) { return (fs::path(PTERYLA_BUILD_DIR) / name).string(); }

}  // namespace

TEST(Scan, RecoversAKnownFeatherFromAMarkedRachis) {
  const FeatherParams truth = scanTruth();
  const SyntheticScan scan = renderScan(truth, kPixelsPerUnit, 0.3, 7);
  ScanOptions opt;
  opt.rachis = {scan.base, scan.tip};
  opt.pixelsPerUnit = kPixelsPerUnit;
  const ScanResult r = acquireScan(scan.gray(), opt);
  EXPECT_FALSE(r.rachisDetected);
  expectRecovered(truth, r, 0, 0);
}

TEST(Scan, DetectsTheRachisWithoutAMark) {
  const FeatherParams truth = scanTruth();
  const FeatherParams bent = scanTruth(0.4, 0.15);
  struct Case {
    const FeatherParams* feather;
    double rotation;
    uint64_t seed;
  };
  for (const Case& c : {Case{&truth, -0.5, 8}, Case{&truth, 1.5, 9}, Case{&bent, 0.3, 7}, Case{&bent, 3.0, 10}}) {
    SCOPED_TRACE("rotation " + std::to_string(c.rotation));
    const SyntheticScan scan = renderScan(*c.feather, kPixelsPerUnit, c.rotation, c.seed);
    const std::vector<glm::dvec2> found = detectRachis(scan.gray());
    ASSERT_GE(found.size(), 2u);
    // The base is where the vanes begin; the tip, where the shaft's arc leaves the feather, is looser
    // (the shaft tapers to nothing and the tip barbs reach past it).
    EXPECT_LT(glm::length(found.front() - scan.base), 4.0) << found.front().x << "," << found.front().y;
    EXPECT_LT(glm::length(found.back() - scan.tip), 8.0) << found.back().x << "," << found.back().y;
  }
  const SyntheticScan scan = renderScan(truth, kPixelsPerUnit, -0.5, 8);
  ScanOptions opt;
  opt.pixelsPerUnit = kPixelsPerUnit;
  const ScanResult r = acquireScan(scan.gray(), opt);
  EXPECT_TRUE(r.rachisDetected);
  expectRecovered(truth, r, 0, 0);
}

TEST(Scan, RecoversBentKeyBarbs) {
  const double bendBase = 0.4, bendTip = 0.15;
  const FeatherParams truth = scanTruth(bendBase, bendTip);
  const SyntheticScan scan = renderScan(truth, kPixelsPerUnit, 0.1, 9);
  ScanOptions opt;
  opt.rachis = {scan.base, scan.tip};
  opt.pixelsPerUnit = kPixelsPerUnit;
  const ScanResult r = acquireScan(scan.gray(), opt);
  expectRecovered(truth, r, bendBase, bendTip, kBentAngleTol);
}

TEST(Scan, TextureIsTheScanInTheFeathersTextureSpace) {
  const FeatherParams truth = scanTruth();
  const SyntheticScan scan = renderScan(truth, kPixelsPerUnit, 0.3, 10);
  const std::string path = tempPath("test_scan_texture_source.png");
  ASSERT_TRUE(scan.save(path));
  ScanOptions opt;
  opt.rachis = {scan.base, scan.tip};
  opt.pixelsPerUnit = kPixelsPerUnit;
  const ScanResult r = acquireScan(loadGrayImage(path), opt);
  const ScanTexture tex = scanTexture(path, r);
  ASSERT_GT(tex.width, 50);
  ASSERT_GT(tex.height, 50);
  // Feather-global space (mesh.hpp): u across (0 left-vane edge, 0.5 rachis), v base (0) to tip (1),
  // texture row 0 = v 1. The extent along is the shaft plus what barbs reach beyond it.
  auto texel = [&](double u, double v) {
    const int i = std::clamp(static_cast<int>(u * tex.width), 0, tex.width - 1);
    const int j = std::clamp(static_cast<int>((1 - v) * tex.height), 0, tex.height - 1);
    const uint8_t* t = &tex.rgba[(static_cast<size_t>(j) * tex.width + i) * 4];
    return glm::dvec4(t[0], t[1], t[2], t[3]) / 255.0;
  };
  auto patch = [&](double u, double v) {  // mean colour of a small neighbourhood
    glm::dvec4 acc(0.0);
    for (int a = -3; a <= 3; ++a)
      for (int b = -3; b <= 3; ++b) acc += texel(u + a / double(tex.width), v + b / double(tex.height));
    return acc / 49.0;
  };
  // The rachis runs up the centre column: dark (the shaft ink) wherever it is wider than 3 pixels.
  const double vBase = truth.calamusLength / (truth.totalLength() * 1.02), vTop = 0.55;
  int dark = 0, rows = 0;
  for (double v = vBase + 0.01; v < vTop; v += 0.005, ++rows) {
    const glm::dvec4 t = texel(0.5, v);
    if (0.2126 * t.r + 0.7152 * t.g + 0.0722 * t.b < 0.3) ++dark;
  }
  EXPECT_GE(dark, 0.9 * rows) << dark << " of " << rows;
  // Left vane red, right vane blue (the scan's vane colours), each on its side of the rachis.
  for (double v : {0.3, 0.5, 0.7}) {
    const glm::dvec4 left = patch(0.3, v), right = patch(0.62, v);
    EXPECT_GT(left.r, left.b + 0.15) << "v " << v;
    EXPECT_GT(right.b, right.r + 0.15) << "v " << v;
    EXPECT_EQ(left.a, 1.0);
  }
  // Beyond the left vane: the paper.
  const glm::dvec4 paper = patch(0.02, 0.1);
  EXPECT_GT(paper.r, 0.85);
  EXPECT_GT(paper.b, 0.85);
  // Written through AtomicFile as a PNG that reads back at the same size.
  const std::string out = tempPath("test_scan_texture.png");
  saveScanTexture(out, tex);
  const GrayImage back = loadGrayImage(out);
  EXPECT_EQ(back.width, tex.width);
  EXPECT_EQ(back.height, tex.height);
}

TEST(Scan, BadInputNamesTheProblem) {
  GrayImage blank;
  blank.width = 64, blank.height = 64;
  blank.pixels.assign(64 * 64, 0.9f);
  ScanOptions opt;
  try {
    acquireScan(blank, opt);
    FAIL() << "a blank image was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "image") << e.what();
  }
  // A few specks of dust are no feather either.
  blank.pixels[100] = blank.pixels[2000] = 0.1f;
  EXPECT_THROW(detectRachis(blank), Error);

  const FeatherParams truth = scanTruth();
  const SyntheticScan scan = renderScan(truth, kPixelsPerUnit, 0.0, 11);
  opt.rachis = {scan.base, {scan.tip.x, -5.0}};
  try {
    acquireScan(scan.gray(), opt);
    FAIL() << "a rachis outside the image was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "rachis") << e.what();
  }
  opt.rachis.clear();
  opt.pixelsPerUnit = 0;
  EXPECT_THROW(acquireScan(scan.gray(), opt), Error);

  // Without a calamus nothing tells the base from the tip: the rachis must be marked.
  FeatherParams bare = truth;
  bare.calamusLength = 0;
  const SyntheticScan noCalamus = renderScan(bare, kPixelsPerUnit, 0.0, 12);
  try {
    detectRachis(noCalamus.gray());
    FAIL() << "a feather without a calamus got a base";
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "rachis") << e.what();
    EXPECT_NE(std::string(e.what()).find("base from the tip"), std::string::npos) << e.what();
  }
}

TEST(Scan, BarbsTooFineForTheScanKeepTheDefaultsAndSaySo) {
  // At 85 pixels per cm neighbouring barbs are under 3.5 pixels apart across their direction over most
  // of the vanes: their orientation aliases with the pixel grid, so no angle is trusted.
  const FeatherParams truth = scanTruth();
  const SyntheticScan scan = renderScan(truth, 85, 0.3, 13);
  ScanOptions opt;
  opt.rachis = {scan.base, scan.tip};
  opt.pixelsPerUnit = 85;
  const ScanResult r = acquireScan(scan.gray(), opt);
  printFit(r);
  const FeatherParams defaults;
  for (int v = 0; v < 2; ++v) {
    EXPECT_FALSE(r.vanes[v].measured);
    EXPECT_EQ(r.feather.vane(v).baseAngle, defaults.vane(v).baseAngle);
    EXPECT_EQ(r.feather.vane(v).tipAngle, defaults.vane(v).tipAngle);
  }
  int angleNotes = 0, spacingNotes = 0;
  for (const auto& n : r.notes) {
    angleNotes += n.find("barb orientation") != std::string::npos;
    spacingNotes += n.find("spacing") != std::string::npos;
  }
  EXPECT_EQ(angleNotes, 2);
  EXPECT_EQ(spacingNotes, 1);
  // The silhouette and the rachis do not depend on resolving barbs.
  EXPECT_NEAR(r.feather.rachisLength, truth.rachisLength, kLengthTol * truth.rachisLength);
  EXPECT_NEAR(r.feather.rachisLateralCurvature, truth.rachisLateralCurvature, kCurvatureTol);
}
