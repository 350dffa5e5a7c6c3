// The painting tools in the real viewer under xvfb-run, driven like a user: the face brush (select, then
// "New tract from selection" in the Tracts panel; remove from the patch tract) and the density brush,
// each dragged across the 3D view, and mirror from the Tracts panel. What they painted must reach the
// saved scene (and its density side file) and evaluate there. Also the bare skin of colour by coverage.
// Skipped only when xvfb-run is missing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fixtures.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/render/image.hpp"
#include "pteryla/render/image_diff.hpp"
#include "viewer_run.hpp"

using namespace pteryla;
using viewer_test::haveXvfbRun;
using viewer_test::runViewer;
using viewer_test::slurp;
using viewer_test::ViewerRun;

TEST(ViewerPaint, FaceBrushStrokesReachTheSavedTracts) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("paint_faces");
  const std::string saved = dir + "/painted.json", script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "count 0 24\n"
                           "relax 3\n"
                           "show panels off\n"
                           // Select a band across the middle of the patch, make it a tract from the panel.
                           "tool paint-faces select 0.2\n"
                           "drag 42% 52% 56% 52%\n"
                           "ui Tracts \"new from selection\" band\n"
                           "count band 12\n"
                           // Remove a spot from the patch tract (the tract chosen in the panel).
                           "ui Tracts select patch\n"
                           "show panels off\n"
                           "tool paint-faces remove 0.15\n"
                           "drag 55% 44% 57% 44%\n"
                           "undo\n"
                           "redo\n"
                           "wait\n"
                        << "save " << saved << "\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");

  const Json j = readJsonFile(saved);
  ASSERT_EQ(j["tracts"].size(), 2u) << j["tracts"].dump();
  const Json& patch = j["tracts"][0];
  const Json& band = j["tracts"][1];
  EXPECT_EQ(band["name"], "band");
  ASSERT_TRUE(band.contains("faces"));
  const auto bandFaces = band["faces"].get<std::vector<int>>();
  EXPECT_GT(bandFaces.size(), 10u);
  EXPECT_LT(bandFaces.size(), 400u);
  // The removal made the patch an explicit face list without the removed spot.
  EXPECT_FALSE(patch.contains("groups"));
  ASSERT_TRUE(patch.contains("faces"));
  const auto patchFaces = patch["faces"].get<std::vector<int>>();
  EXPECT_LT(patchFaces.size(), 800u);
  EXPECT_GT(patchFaces.size(), 700u);
  EXPECT_EQ(patch["count"], 24);

  // The saved scene evaluates with both tracts as painted.
  const pipeline::Scene back = pipeline::loadScene(saved);
  pipeline::Pipeline p(back);
  ASSERT_EQ(p.tracts().size(), 2u);
  EXPECT_EQ(p.tracts()[1].faces.size(), bandFaces.size());  // the patch's polygons are triangles
  EXPECT_EQ(p.tracts()[0].faces.size(), patchFaces.size());
  size_t inBand = 0;
  for (uint32_t t : p.follicles().tract) inBand += t == 1 ? 1 : 0;
  EXPECT_EQ(inBand, 12u);
}

TEST(ViewerPaint, DensityBrushStrokeReachesTheSavedSideFile) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("paint_density");
  const std::string saved = dir + "/dense.json", script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "density 0 20\n"
                           "relax 3\n"
                           "show panels off\n"
                           "tool paint-density 4 0.4 1\n"
                           "drag 40% 52% 58% 52%\n"
                           "ui Follicles strength 0.5\n"
                           "wait\n"
                        << "save " << saved << "\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");

  const Json j = readJsonFile(saved);
  ASSERT_TRUE(j.contains("density_map")) << j.dump();
  EXPECT_EQ(j["density_map"], "dense.density.json");
  const std::vector<float> f = pipeline::readDensityMap(dir + "/dense.density.json");
  ASSERT_EQ(f.size(), 441u);
  const size_t painted = size_t(std::count_if(f.begin(), f.end(), [](float x) { return x != 1.0f; }));
  EXPECT_GT(painted, 10u);
  EXPECT_LT(painted, 300u);
  EXPECT_NEAR(*std::max_element(f.begin(), f.end()), 4.0f, 0.05f) << "full strength under the stroke";
  EXPECT_EQ(*std::min_element(f.begin(), f.end()), 1.0f);

  // The painted region carries more follicles than the same scene without the map.
  const pipeline::Scene back = pipeline::loadScene(saved);
  pipeline::Scene plain = back;
  plain.densityFactor.reset();
  pipeline::Pipeline a(back), b(plain);
  EXPECT_GT(a.follicles().size(), b.follicles().size() + 10);
}

TEST(ViewerPaint, MirrorFromTheTractsPanelIsOneUndoStepThatSaveWrites) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("paint_mirror");
  const std::string redo = dir + "/mirrored.json", undo = dir + "/undone.json", script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "count 0 24\n"
                           "relax 3\n"
                           "select-faces 0.6 0.05 0.3 0.3\n"
                           "tract-from-selection band_left\n"
                           "count band_left 8\n"
                           "brush 0.5 0.05 -0.4 0.2 40\n"
                           "control 0.7 0.05 0.5 0.3\n"
                           "ui Tracts select band_left\n"
                           "ui Tracts \"mirror plane\" x\n"
                           "ui Tracts mirror\n"
                           "wait\n"
                        << "save " << redo << "\n"
                        << "undo\n"
                        << "save " << undo << "\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");

  const Json m = readJsonFile(redo);
  ASSERT_EQ(m["tracts"].size(), 3u) << m["tracts"].dump();
  EXPECT_EQ(m["tracts"][2]["name"], "band_right");
  EXPECT_EQ(m["tracts"][2]["count"], 8);
  ASSERT_EQ(m["packing"]["styling"].size(), 2u);
  EXPECT_EQ(m["packing"]["styling"][1]["center"], Json::parse("[-0.5, 0.05, -0.4]"));
  ASSERT_EQ(m["controls"].size(), 2u);
  EXPECT_EQ(m["controls"][1]["at"], Json::parse("[-0.7, 0.05, 0.5]"));
  // The mirrored tract's follicles lie on the other side.
  const pipeline::Scene back = pipeline::loadScene(redo);
  pipeline::Pipeline p(back);
  const coat::Follicles& f = p.follicles();
  size_t right = 0;
  for (size_t i = 0; i < f.size(); ++i)
    if (f.tract[i] == 2) {
      EXPECT_LT(f.position[i].x, 0.0);
      ++right;
    }
  EXPECT_EQ(right, 8u);

  // One undo removed all of it.
  const Json u = readJsonFile(undo);
  EXPECT_EQ(u["tracts"].size(), 2u);
  EXPECT_EQ(u["packing"]["styling"].size(), 1u);
  EXPECT_EQ(u["controls"].size(), 1u);
}

// Colour by coverage: after a check of a sparse coat, the bare skin faces show in the bare colour on the
// skin (and the legend names them); in the material view that colour is absent.
TEST(ViewerPaint, ColourByCoverageShowsBareSkinAfterACheck) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("paint_coverage");
  const std::string script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "count 0 6\n"
                           "relax 3\n"
                           "show panels off\n"
                           "check\n"
                           "frames 3\n"
                        << "screenshot-window " << dir << "/material.png\n"
                        << "ui View \"colour by\" coverage\n"
                           "show panels off\n"
                           "frames 3\n"
                        << "screenshot-window " << dir << "/coverage.png\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");
  // The checker's coverage of six feathers on the patch is far from whole.
  ASSERT_NE(r.out.find("\"coverage\": 0."), std::string::npos) << r.out;
  auto bareShare = [](const render::Image& im) {
    size_t n = 0;
    for (int y = 0; y < im.height; ++y)
      for (int x = 0; x < im.width; ++x) {
        const uint8_t* p = im.pixel(x, y);
        // The bare colour (0.95, 0.12, 0.35) at 2/3 over skin, feathers or background.
        n += p[0] > 170 && p[1] < 110 && p[2] > 70 && p[2] < 170 && p[0] > p[2] + 60 ? 1 : 0;
      }
    return double(n) / double(im.width * im.height);
  };
  const double coverage = bareShare(render::loadImage(dir + "/coverage.png"));
  const double material = bareShare(render::loadImage(dir + "/material.png"));
  EXPECT_GT(coverage, 0.02);
  EXPECT_LT(material, 0.002);
}

// Handles with the orbit tool: a control dragged over the skin moves (and stays on it), a brush clicked
// and deleted with the Delete key is gone from the saved scene; a drag where nothing is orbits.
TEST(ViewerPaint, HandlesDragToMoveAndDeleteToRemove) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("paint_handles");
  const std::string before = dir + "/before.json", after = dir + "/after.json", script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "count 0 24\n"
                           "relax 3\n"
                           "show panels off\n"
                           "tool control\n"
                           "click 50% 50%\n"
                           "tool brush\n"
                           "click 40% 62%\n"
                           "tool orbit\n"
                           "wait\n"
                        << "save " << before << "\n"
                        << "drag 50% 50% 62% 58%\n"
                           "wait\n"
                           "click 40% 62%\n"
                           "key delete\n"
                           "wait\n"
                        << "save " << after << "\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");
  const Json b = readJsonFile(before), a = readJsonFile(after);
  ASSERT_EQ(b["controls"].size(), 1u);
  ASSERT_EQ(b["packing"]["styling"].size(), 1u);
  ASSERT_EQ(a["controls"].size(), 1u);
  const auto p0 = b["controls"][0]["at"].get<std::vector<double>>(),
             p1 = a["controls"][0]["at"].get<std::vector<double>>();
  EXPECT_GT(std::hypot(p1[0] - p0[0], p1[2] - p0[2]), 0.2) << "the control moved";
  EXPECT_LT(std::abs(p1[1]), 0.15) << "onto the patch's skin";
  EXPECT_EQ(a["controls"][0]["radius"], b["controls"][0]["radius"]);
  EXPECT_FALSE(a.contains("packing") && a["packing"].contains("styling")) << a["packing"].dump();
}

// Box selection: the whole view boxes every feather (and, shown, every follicle); the left half a part;
// follicles only while they are shown.
TEST(ViewerPaint, BoxSelectionTakesWhatProjectsInsideTheBox) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("paint_box");
  const std::string script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "count 0 30\n"
                           "relax 3\n"
                           "show panels off\n"
                           "box-select 0% 0% 100% 100%\n"
                           "box-selection\n"
                           "show follicles on\n"
                           "box-select 0% 0% 100% 100%\n"
                           "box-selection\n"
                           "box-select 0% 0% 50% 100%\n"
                           "box-selection\n"
                           "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");
  std::vector<Json> lines;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);)
    if (line.rfind("{\"feathers\"", 0) == 0) lines.push_back(Json::parse(line));
  ASSERT_EQ(lines.size(), 3u) << r.out;
  EXPECT_EQ(lines[0]["feathers"].size(), 30u);
  EXPECT_TRUE(lines[0]["follicles"].empty()) << "follicles are boxed only while shown";
  EXPECT_EQ(lines[1]["follicles"].size(), 30u);
  const size_t half = lines[2]["feathers"].size();
  EXPECT_GT(half, 0u);
  EXPECT_LT(half, 30u);
}

// Render frames: the range at the rate, one PNG per frame at the scene's render size, each at its own time
// (a keyed lift makes the last frame differ from the first).
TEST(ViewerPaint, RenderFramesWritesTheRangeAtItsTimes) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("paint_frames");
  const std::string frames = dir + "/frames", script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "count 0 12\n"
                           "relax 3\n"
                           "render-lod 0.2\n"
                           "control 0 0.05 0 0.8\n"
                           "time 0\n"
                           "lift 0 0\n"
                           "keyframe 0 0\n"
                           "time 1\n"
                           "lift 0 1\n"
                           "keyframe 0 1\n"
                           "time 0\n"
                        << "render-frames " << frames << " 0 1 2\n"
                        << "echo frames done\n"
                           "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");
  ASSERT_NE(r.out.find("frames done"), std::string::npos);
  std::vector<render::Image> im;
  for (const char* f : {"frame_0000.png", "frame_0001.png", "frame_0002.png"}) {
    ASSERT_TRUE(std::filesystem::is_regular_file(frames + "/" + f)) << f;
    im.push_back(render::loadImage(frames + "/" + f));
    EXPECT_EQ(im.back().width, 640);
    EXPECT_EQ(im.back().height, 360);
  }
  EXPECT_FALSE(std::filesystem::exists(frames + "/frame_0003.png"));
  EXPECT_GT(render::diffImages(im[0], im[2]).changedFraction, 0.01) << "the lift at t = 1 shows";
}

// Box selection does more than frame: the handles inside the box (here pinned follicles, a key feather and
// the styling vector) are removed by Delete as one edit, the others stay, and undo brings them all back.
TEST(ViewerPaint, BoxSelectionDeleteRemovesTheBoxedHandles) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("paint_box_delete");
  const std::string script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "count 0 24\n"
                           "relax 2\n"
                           "pin 0 -0.6 0.05 0.3\n"
                           "pin 0 -0.5 0.05 -0.3\n"
                           "pin 0 0.9 0.05 -0.2\n"
                           "wait\n"
                           "show panels off\n"
                           "box-select 0% 0% 45% 100%\n"
                           "box-selection\n"
                           "key delete\n"
                           "wait\n"
                        << "save " << dir << "/deleted.json\n"
                        << "undo\n"
                        << "save " << dir << "/undone.json\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");
  const std::vector<Json> lines = viewer_test::jsonLines(r.out);
  ASSERT_EQ(lines.size(), 1u) << r.out;
  size_t pinnedBoxed = 0, keysBoxed = 0;
  for (const Json& h : lines[0]["handles"]) {
    pinnedBoxed += h["kind"] == "pinned follicle" ? 1 : 0;
    keysBoxed += h["kind"] == "key feather" ? 1 : 0;
  }
  // The two pinned follicles on the left (-x) side and the contour key feather at x = -0.8 are boxed; the
  // pinned follicle at x = 0.9 and the covert key feather at x = 0.8 are not.
  ASSERT_EQ(pinnedBoxed, 2u) << lines[0].dump();
  ASSERT_EQ(keysBoxed, 1u) << lines[0].dump();

  const Json deleted = readJsonFile(dir + "/deleted.json")["tracts"][0];
  ASSERT_TRUE(deleted.contains("pinned")) << deleted.dump();
  ASSERT_EQ(deleted["pinned"].size(), 1u);
  EXPECT_EQ(deleted["pinned"][0]["at"][0], 0.9);
  ASSERT_EQ(deleted["key_feathers"].size(), 1u);
  EXPECT_EQ(deleted["key_feathers"][0]["feather"], "covert");
  // One undo step brings every boxed handle back.
  const Json undone = readJsonFile(dir + "/undone.json")["tracts"][0];
  EXPECT_EQ(undone["pinned"].size(), 3u);
  EXPECT_EQ(undone["key_feathers"].size(), 2u);
}

// Render frames can be cancelled part way: fewer frames than asked, each of them whole (no partial or
// temporary file left), and the viewer keeps running the script afterwards.
TEST(ViewerPaint, RenderFramesCancelStopsPartWay) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("paint_frames_cancel");
  const std::string frames = dir + "/frames", script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "count 0 12\n"
                           "relax 2\n"
                           "render-lod 0.2\n"
                           "show panels off\n"
                        << "render-frames " << frames << " 0 4 12 cancel-after 2\n"
                        << "echo still running\n"
                           "count 0 10\n"
                           "wait\n"
                        << "save " << dir << "/after.json\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");
  const std::vector<Json> lines = viewer_test::jsonLines(r.out);
  ASSERT_EQ(lines.size(), 1u) << r.out;
  const size_t written = lines[0]["frames_written"].get<size_t>();
  EXPECT_EQ(lines[0]["frames_total"], 49);
  EXPECT_GE(written, 2u);
  EXPECT_LT(written, 49u);
  EXPECT_NE(lines[0]["frames_status"].get<std::string>().find("cancelled"), std::string::npos);
  // Exactly frames 0 .. written-1, each a whole PNG of the render size; nothing else in the directory.
  size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(frames)) {
    ++files;
    const std::string name = e.path().filename().string();
    ASSERT_EQ(name.rfind("frame_", 0), 0u) << name;
    ASSERT_EQ(e.path().extension(), ".png") << name;
    const render::Image im = render::loadImage(e.path().string());
    EXPECT_EQ(im.width, 640) << name;
    EXPECT_EQ(im.height, 360) << name;
  }
  EXPECT_EQ(files, written);
  char last[32];
  std::snprintf(last, sizeof last, "/frame_%04zu.png", written - 1);
  EXPECT_TRUE(std::filesystem::exists(frames + last));
  // The viewer went on: the script's later lines ran and their edit reached the saved scene.
  EXPECT_NE(r.out.find("still running"), std::string::npos);
  EXPECT_EQ(readJsonFile(dir + "/after.json")["tracts"][0]["count"], 10);
}
