// What the CLI asks of the host API beyond evaluating a frame (the CLI is a client of it only): a scene
// file with its seed replaced, progress for every evaluation, images in memory from a kept renderer,
// stage timings, export checks before evaluating, and one feather on its own.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "../install/consumer/icosphere.hpp"
#include "pteryla/pteryla.hpp"

namespace {

namespace fs = std::filesystem;
using pteryla::CoatSetup;
using pteryla::Session;
using pteryla::SkinArrays;

const std::string kData = PTERYLA_DATA_DIR;

Session smallSession() {
  const auto ico = pteryla_test::icosphere(3);
  SkinArrays skin;
  skin.positions = ico.positions;
  skin.triangles = ico.triangles;
  CoatSetup setup;
  pteryla::TractSetup t;
  t.name = "body";
  t.count = 60;
  setup.tracts.push_back(t);
  setup.axis = {{{0, 1.2, 0}}, {{0, -1.2, 0}}};
  Session s(skin, setup);
  s.setLod(0.2);
  return s;
}

std::string tempPath(const std::string& name) { return (fs::path(::testing::TempDir()) / name).string(); }

TEST(HostServices, SceneFileSeedReplacesTheFilesSeed) {
  const std::string scene = kData + "/scenes/sphere.json";
  Session plain = Session::fromSceneFile(scene);
  pteryla::SceneFileOptions other;
  other.seed = 977;
  Session reseeded = Session::fromSceneFile(scene, other);
  ASSERT_TRUE(plain.evaluate());
  ASSERT_TRUE(reseeded.evaluate());
  const pteryla::Frame& a = plain.frame();
  const pteryla::Frame& b = reseeded.frame();
  ASSERT_GT(a.featherCount, 0u);
  // Another seed scatters the follicles elsewhere.
  bool moved = a.featherCount != b.featherCount;
  for (size_t i = 0; !moved && i < a.origins.size; ++i) moved = a.origins[i] != b.origins[i];
  EXPECT_TRUE(moved);
}

TEST(HostServices, SceneFileProgressReportsReadingAndEvaluating) {
  std::vector<std::string> stages;
  pteryla::SceneFileOptions o;
  o.progress = [&](const std::string& stage, double) {
    if (stages.empty() || stages.back() != stage) stages.push_back(stage);
    return true;
  };
  Session s = Session::fromSceneFile(kData + "/scenes/sphere.json", o);
  const size_t whileReading = stages.size();
  EXPECT_GT(whileReading, 0u) << "the constructor reads the skin and the tracts";
  ASSERT_TRUE(s.evaluate());  // no callback of its own: the options' one hears it
  EXPECT_GT(stages.size(), whileReading);
  EXPECT_NE(std::find(stages.begin(), stages.end(), "mesh"), stages.end());
}

TEST(HostServices, ACancelOutsideEvaluateIsAnError) {
  Session s = smallSession();
  s.setProgress([](const std::string&, double) { return false; });
  try {
    s.metrics();
    ADD_FAILURE() << "metrics() ignored the cancel";
  } catch (const pteryla::Error& e) {
    EXPECT_EQ(e.element(), "progress");
    EXPECT_NE(std::string(e.what()).find("cancelled"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(s.evaluate());  // the session's callback answers evaluate() too
  s.setProgress({});
  EXPECT_TRUE(s.evaluate());  // and the stages completed before each cancel were kept
}

TEST(HostServices, TheKeptRendererDrawsWhatAFreshOneDraws) {
  Session s = smallSession();
  pteryla::RenderSettings small;
  small.width = 96;
  small.height = 64;
  const pteryla::render::Image first = s.renderImage(small);
  ASSERT_EQ(first.width, 96);
  ASSERT_EQ(first.height, 64);
  ASSERT_EQ(first.rgba.size(), size_t(96) * 64 * 4);
  // Another size resizes the kept context; coming back draws the same pixels.
  pteryla::RenderSettings other = small;
  other.width = 48;
  other.height = 40;
  EXPECT_EQ(s.renderImage(other).width, 48);
  EXPECT_EQ(s.renderImage(small).rgba, first.rgba);
  // A file written by render() is the same image, and the summary says what was drawn.
  const std::string png = tempPath("services_render.png");
  const pteryla::RenderSummary sum = s.render(png, small);
  EXPECT_EQ(sum.width, 96);
  EXPECT_EQ(sum.height, 64);
  EXPECT_EQ(pteryla::render::loadImage(png).rgba, first.rgba);
  ASSERT_TRUE(s.evaluate());
  EXPECT_EQ(sum.feathers, s.frame().ranges.size);
  EXPECT_EQ(sum.triangles, s.frame().indices.size / 3);
  EXPECT_GT(sum.triangles, 0u);
  // Released, a new context draws it again, identically.
  s.releaseRenderer();
  EXPECT_EQ(s.renderImage(small).rgba, first.rgba);
  EXPECT_EQ(s.sceneImageSize()[0], 960);
  EXPECT_EQ(s.sceneImageSize()[1], 720);
}

// Each session keeps its own context; dropping one must not touch what another uploaded (the renderer
// deletes its GL objects in its own context, whichever was current).
TEST(HostServices, SessionsKeepTheirRenderersApart) {
  pteryla::RenderSettings small;
  small.width = 80;
  small.height = 60;
  Session b = smallSession();
  const pteryla::render::Image before = b.renderImage(small);
  {
    Session a = Session::fromSceneFile(kData + "/scenes/sphere.json");
    a.setLod(0.2);
    EXPECT_NE(a.renderImage(small).rgba, before.rgba);  // another coat: the comparison below means something
  }                                                     // a's renderer goes with a, while a's context is current
  EXPECT_EQ(b.renderImage(small).rgba, before.rgba);
  Session c = smallSession();
  c.renderImage(small);
  c.releaseRenderer();  // c's context was current; b's must survive that too
  EXPECT_EQ(b.renderImage(small).rgba, before.rgba);
}

TEST(HostServices, StageSecondsAndAFullPack) {
  Session s = smallSession();
  const pteryla::StageSeconds before = s.stageSeconds();
  EXPECT_EQ(before.mesh, 0.0);  // nothing meshed yet
  ASSERT_TRUE(s.evaluate());
  const pteryla::StageSeconds st = s.stageSeconds();
  EXPECT_GT(st.distribute, 0.0);
  EXPECT_GT(st.mesh, 0.0);
  EXPECT_GT(s.timeFullPack(1), 0.0);
  EXPECT_THROW(s.timeFullPack(0), pteryla::Error);
  EXPECT_NO_THROW(s.frame());  // timing the pack keeps the frame
}

TEST(HostServices, ExportSettingsAreRefusedBeforeEvaluating) {
  auto elementOf = [](const std::string& path, const pteryla::ExportSettings& e) -> std::string {
    try {
      pteryla::checkExportSettings(path, e);
    } catch (const pteryla::Error& err) {
      return err.element();
    }
    return "(accepted)";
  };
  pteryla::ExportSettings ok;
  EXPECT_EQ(elementOf("coat.usda", ok), "(accepted)");
  EXPECT_EQ(elementOf("coat.abc", ok), "--out");
  pteryla::ExportSettings e = ok;
  e.coatAs = "hair";
  EXPECT_EQ(elementOf("coat.usda", e), "--as");
  e = ok;
  e.times = {0, 1};
  EXPECT_EQ(elementOf("coat.glb", e), "(accepted)");
  EXPECT_EQ(elementOf("coat.obj", e), "times");
  e.times = {1, 0};
  EXPECT_EQ(elementOf("coat.glb", e), "times[1]");
  e = ok;
  e.metersPerUnit = 0;
  EXPECT_EQ(elementOf("coat.usda", e), "metersPerUnit");
  e = ok;
  e.fps = -1;
  EXPECT_EQ(elementOf("coat.usda", e), "fps");
  EXPECT_EQ(pteryla::exportFrameTimes(0, 1, 2), (std::vector<double>{0, 0.5, 1}));
  EXPECT_THROW(pteryla::exportFrameTimes(1, 0, 2), pteryla::Error);
}

TEST(HostServices, ExportSummaryCountsWhatWasWritten) {
  Session s = smallSession();
  const std::string glb = tempPath("services.glb");
  const pteryla::ExportSummary r = s.exportTo(glb);
  EXPECT_EQ(r.bytes, fs::file_size(glb));
  EXPECT_EQ(r.frames, 1u);
  EXPECT_EQ(r.feathers, 60u);
  EXPECT_GT(r.triangles, 0u);
  EXPECT_GT(r.seconds, 0.0);
  EXPECT_LE(r.writeSeconds, r.seconds);
  pteryla::ExportSettings curves;
  curves.coatAs = "curves";
  EXPECT_GT(s.exportTo(tempPath("services.usda"), curves).curves, 60u);  // rachis and barbs per feather
}

TEST(HostServices, OneFeatherAsAMeshOrAnImage) {
  const std::string feather = kData + "/feathers/contour.json";
  const std::string obj = tempPath("services_feather/contour.obj");
  fs::remove_all(fs::path(obj).parent_path());
  const size_t full = pteryla::writeFeather(feather, obj);
  EXPECT_GT(full, 0u);
  EXPECT_GT(fs::file_size(obj), 0u);
  pteryla::FeatherOutput coarse;
  coarse.lod = 0.25;
  EXPECT_LT(pteryla::writeFeather(feather, tempPath("services_coarse.ply"), coarse), full);
  pteryla::FeatherOutput picture;
  picture.width = 80;
  picture.height = 120;
  pteryla::writeFeather(feather, tempPath("services_feather.png"), picture);
  const pteryla::render::Image img = pteryla::render::loadImage(tempPath("services_feather.png"));
  EXPECT_EQ(img.width, 80);
  EXPECT_EQ(img.height, 120);
  // A missing feather file is refused, and leaves no directory behind.
  const std::string lost = tempPath("services_nothing/x.obj");
  fs::remove_all(fs::path(lost).parent_path());
  EXPECT_THROW(pteryla::writeFeather(kData + "/feathers/no_such.json", lost), pteryla::Error);
  EXPECT_FALSE(fs::exists(fs::path(lost).parent_path()));
  EXPECT_THROW(pteryla::writeFeather(feather, tempPath("x.stl")), pteryla::Error);
}

}  // namespace

namespace {

std::string elementOfScanError(const std::string& image, const std::string& out, const pteryla::ScanSettings& s = {}) {
  try {
    pteryla::writeFeatherFromScan(image, out, s);
  } catch (const pteryla::Error& e) {
    return e.element();
  }
  return "(accepted)";
}

}  // namespace

// The scan door refuses what it cannot measure, naming the setting (the CLI maps them to its options),
// before writing anything.
TEST(HostServices, FeatherFromScanNamesWhatItRefuses) {
  const std::string out = tempPath("services_scan/f.json");
  fs::remove_all(fs::path(out).parent_path());
  EXPECT_EQ(elementOfScanError(kData + "/textures/no_such.png", out), "scan");
  EXPECT_EQ(elementOfScanError(kData + "/textures/barb_alpha.png", tempPath("f.obj")), "out");
  pteryla::ScanSettings outside;
  outside.rachis = {{{0, 0}}, {{1e6, 3}}};
  EXPECT_EQ(elementOfScanError(kData + "/textures/barb_alpha.png", out, outside), "rachis");
  pteryla::ScanSettings badResolution;
  badResolution.pixelsPerUnit = -2;
  EXPECT_EQ(elementOfScanError(kData + "/textures/barb_alpha.png", out, badResolution), "pixelsPerUnit");
  pteryla::ScanSettings badTexture;
  badTexture.texture = tempPath("t.jpg");
  EXPECT_EQ(elementOfScanError(kData + "/textures/barb_alpha.png", out, badTexture), "texture");
  EXPECT_FALSE(fs::exists(fs::path(out).parent_path()));
}
