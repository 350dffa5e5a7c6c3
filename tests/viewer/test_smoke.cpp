// CI smoke test: the real viewer binary under xvfb-run runs a scripted session on the patch scene
// (panel actions, timeline, controls, every panel and window open for a few frames, save, screenshot,
// quit); the saved scene must reload identically
// and the screenshot must show something (not one flat colour). Skipped only when xvfb-run is missing.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

#include "fixtures.hpp"
#include "viewer_run.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/feather/io.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/render/image.hpp"
#include "pteryla/render/image_diff.hpp"

using namespace pteryla;

using viewer_test::haveXvfbRun;
using viewer_test::runViewer;
using viewer_test::slurp;
using viewer_test::ViewerRun;

TEST(ViewerSmoke, ScriptedSessionUnderXvfb) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("smoke");
  const std::string saved = dir + "/groomed.json", shot = dir + "/view.png", window = dir + "/window.png";
  const std::string wire = dir + "/wireframe.png";
  const std::string script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "count 0 30\n"
                           "relax 4\n"
                           "lod 0.3\n"
                           "pack\n"
                           "time 0.5\n"
                           "control 0 0.05 0 0.6\n"
                           "lift 0 0.8\n"
                           "keyframe 0 0.5\n"
                           "vector 0.3 0.05 0 1 0 0.3\n"
                           "brush -0.3 0.05 0 0.25 40\n"
                           "undo\n"
                           "redo\n"
                           "orbit 20 10\n"
                           "frame\n"
                           "check\n"
                           "tool vector\n"
                           "drag 50% 50% 58% 46%\n"
                           "tool brush\n"
                           "click 48% 52%\n"
                           "tool control\n"
                           "click 52% 48%\n"
                           "tool orbit\n"
                           "drag 50% 50% 60% 50%\n"
                           "panel * open\n"
                           "show designer on\n"
                           "show follicles on\n"
                           "show directions on\n"
                           "show tract on\n"
                           "frames 2\n"
                           "show json on\n"
                           "show help on\n"
                           "frames 2\n"
                        << "save " << saved << "\n"
                        << "screenshot " << shot << "\n"
                        << "screenshot-window " << window << "\n"
                        << "show wireframe on\n"
                           "frames 2\n"
                        << "screenshot " << wire << "\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");

  // The saved scene reloads to the same scene (what loadScene reads, sceneToJson writes back).
  const pipeline::Scene back = pipeline::loadScene(saved);
  EXPECT_EQ(pipeline::sceneToJson(back, saved), readJsonFile(saved));
  EXPECT_EQ(back.tracts[0]["count"], 30);
  // Script commands and the viewport tools (scripted mouse): patch.json has one styling vector.
  EXPECT_EQ(back.directions["vectors"].size(), 3u);
  EXPECT_EQ(back.controls.size(), 2u);
  EXPECT_EQ(back.packing["styling"].size(), 2u);
  EXPECT_DOUBLE_EQ(back.time, 0.5);

  // The checker's metrics were printed as one JSON line.
  const Json m = Json::parse(r.out.substr(0, r.out.find('\n')));
  EXPECT_EQ(m["follicles"], 30);

  // Screenshots: the 3D view (right of the panels) and the whole window, both with real content.
  for (const std::string& path : {shot, window}) {
    const render::Image img = render::loadImage(path);
    if (path == window) {
      EXPECT_EQ(img.width, 1000);
      EXPECT_EQ(img.height, 700);
    } else {
      EXPECT_GT(img.width, 400);
      EXPECT_LT(img.width, 1000);
      EXPECT_GT(img.height, 400);
    }
    std::set<uint32_t> colours;
    for (size_t i = 0; i + 3 < img.rgba.size() && colours.size() < 64; i += 4 * 7)
      colours.insert(uint32_t(img.rgba[i]) << 16 | uint32_t(img.rgba[i + 1]) << 8 | img.rgba[i + 2]);
    EXPECT_GE(colours.size(), 16u) << path << " is (nearly) one flat colour";
    const uint8_t bg[3] = {img.rgba[0], img.rgba[1], img.rgba[2]};
    EXPECT_GT(render::coveredFraction(img, bg, 8), 0.02) << path << ": nothing drawn over the background";
  }
  // The window capture is drawn everywhere: menu bar and panels on the left, the 3D view on the
  // right, the status bar at the bottom (a stale or mis-bound framebuffer leaves flat regions).
  const render::Image win = render::loadImage(window);
  auto distinct = [&](int x0, int y0, int x1, int y1) {
    std::set<uint32_t> c;
    for (int y = y0; y < y1; y += 3)
      for (int x = x0; x < x1; x += 3) {
        const uint8_t* p = win.pixel(x, y);
        c.insert(uint32_t(p[0]) << 16 | uint32_t(p[1]) << 8 | p[2]);
      }
    return c.size();
  };
  EXPECT_GE(distinct(0, 0, 500, 20), 3u) << "menu bar";
  EXPECT_GE(distinct(0, 0, 400, 700), 8u) << "panel column";
  EXPECT_GE(distinct(500, 50, 1000, 650), 8u) << "3D view";
  EXPECT_GE(distinct(0, 672, 1000, 700), 3u) << "status bar";
  // The wireframe view (the renderer's polygon mode) shows the same framing in edges: more background.
  const render::Image shotImg = render::loadImage(shot), wireImg = render::loadImage(wire);
  ASSERT_EQ(wireImg.width, shotImg.width);
  const uint8_t bgShot[3] = {shotImg.rgba[0], shotImg.rgba[1], shotImg.rgba[2]};
  EXPECT_GT(render::meanAbsoluteError(shotImg, wireImg), 0.01);
  EXPECT_LT(render::coveredFraction(wireImg, bgShot, 8), render::coveredFraction(shotImg, bgShot, 8));
  EXPECT_GE(distinct(900, 0, 1000, 700), 2u) << "right edge";
}

TEST(ViewerSmoke, BadScriptExitsWithTwoAndNamesTheLine) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("smoke_bad");
  const std::string script = dir + "/bad.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\nrelax lots\nquit\n";
  const ViewerRun r = runViewer("--script \"" + script + "\"", dir + "/stderr.txt");
  const std::string err = slurp(dir + "/stderr.txt");
  EXPECT_EQ(r.code, 2) << err;
  EXPECT_NE(err.find("line 2"), std::string::npos) << err;
}

// Issue #30 item 4: the designer edits a helical feather's speed curves (V_e, V_b) as undoable edits and
// saves them to the feather file. The saved file must hold the edits that survived undo/redo, and the
// feather it loads to must be the one grown with them.
TEST(ViewerSmoke, DesignerEditsHelicalSpeedCurvesAndSavesThem) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("designer_helical");
  const std::string featherFile = dir + "/helical.json", sceneFile = dir + "/scene.json";
  const std::string saved = dir + "/edited.json", script = dir + "/session.txt";
  std::remove(saved.c_str());
  const Json original = readJsonFile(viewer_test::dataPath("feathers/helical-contour.json"));
  std::ofstream(featherFile) << original.dump(1);
  std::ofstream(sceneFile) << Json{{"pteryla", 1},
                                   {"mesh", viewer_test::dataPath("meshes/patch.obj")},
                                   {"feathers", {{"h", featherFile}}},
                                   {"tracts", Json::array({{{"name", "all"}, {"count", 12}}})}}
                                  .dump(1);
  std::ofstream(script) << "load " << sceneFile << "\n"
                        << "ui \"Feather designer\" \"emitter speed 1\" 0.02\n"  // kept
                           "ui \"Feather designer\" \"barb speed 0\" 0.09\n"     // undone, redone: kept
                           "ui \"Feather designer\" undo\n"
                           "ui \"Feather designer\" redo\n"
                           "ui \"Feather designer\" \"barb speed 2\" 0.03\n"  // undone: not kept
                           "ui \"Feather designer\" undo\n"
                           "frames 2\n"
                        << "ui \"Feather designer\" save " << saved << "\n"
                        << "frames 2\n"
                           "quit\n";
  const ViewerRun r = runViewer("--size 1100x800 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");

  const Json& before = original["helical"];
  const Json after = readJsonFile(saved).at("helical");
  ASSERT_EQ(after["emitterSpeed"].size(), before["emitterSpeed"].size());
  EXPECT_NEAR(after["emitterSpeed"][1][1].get<double>(), 0.02, 1e-6);
  EXPECT_NEAR(after["barbSpeed"][0][1].get<double>(), 0.09, 1e-6);
  EXPECT_EQ(after["barbSpeed"][2], before["barbSpeed"][2]);
  EXPECT_EQ(after["emitterSpeed"][0], before["emitterSpeed"][0]);
  // The saved derived fields are those of the edited curves (loading regrows them: same feather).
  const feather::FeatherParams edited = feather::loadFeather(saved);
  EXPECT_NE(edited.silhouette.left.points, feather::loadFeather(featherFile).silhouette.left.points);
  const Json savedJson = readJsonFile(saved);
  Json reloaded = feather::featherToJson(edited);
  EXPECT_EQ(reloaded["left_vane"], savedJson["left_vane"]);
}

// #28 "see the problems": each colour mode reaches the 3D view (the coat changes colour), with a
// legend; problems after a check.
TEST(ViewerSmoke, ColourModesRecolourTheCoat) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("smoke_colour");
  const std::string script = dir + "/s.txt";
  std::ofstream s(script);
  s << "count 0 30\nwait\nscreenshot " << dir << "/material.png\n";
  for (const char* m : {"elevation", "layer", "tract", "age"})
    s << "ui View \"colour by\" " << m << "\nframes 3\nscreenshot " << dir << "/" << m << ".png\n";
  s << "check\nui View \"colour by\" problems\nframes 3\nscreenshot-window " << dir << "/problems.png\n"
    << "ui View \"colour by\" material\nframes 3\nscreenshot " << dir << "/material_again.png\nquit\n";
  s.close();
  const ViewerRun r = runViewer(
      "\"" + viewer_test::dataPath("scenes/patch.json") + "\" --lod 0.3 --size 1000x700 --script \"" + script + "\"",
      dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << slurp(dir + "/stderr.txt");
  const render::Image material = render::loadImage(dir + "/material.png");
  for (const char* m : {"elevation", "layer", "tract", "age"}) {
    const render::ImageDiff d = render::diffImages(render::loadImage(dir + "/" + m + ".png"), material);
    ASSERT_TRUE(d.sameSize) << m;
    EXPECT_GT(d.changedFraction, 0.05) << m << ": the coat did not change colour";
  }
  // Back to materials: the first image again.
  EXPECT_TRUE(render::diffImages(render::loadImage(dir + "/material_again.png"), material).matches);
}

// #28 "viewport selection": a click on a feather selects it (the readout names it), F frames it, a
// click on empty background clears the selection.
TEST(ViewerSmoke, AClickSelectsTheFeatherUnderTheMouse) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("smoke_select");
  const std::string script = dir + "/s.txt";
  std::ofstream(script) << "count 0 30\nwait\nselection\nclick 50% 50%\nframes 2\nselection\n"
                        << "screenshot-window " << dir << "/selected.png\n"
                        << "click 2% 2%\nframes 2\nselection\nquit\n";
  const ViewerRun r = runViewer(
      "\"" + viewer_test::dataPath("scenes/patch.json") + "\" --lod 0.3 --size 1000x700 --script \"" + script + "\"",
      dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << slurp(dir + "/stderr.txt");
  const std::vector<Json> lines = viewer_test::jsonLines(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  EXPECT_TRUE(lines[0]["feather"].is_null());
  ASSERT_TRUE(lines[1]["feather"].is_number()) << "the click at the centre of the patch selected nothing";
  EXPECT_EQ(lines[1]["tract"], "patch");
  EXPECT_FALSE(lines[1]["type"].get<std::string>().empty());
  EXPECT_GE(lines[1]["elevation_deg"].get<double>(), 0.0);
  EXPECT_TRUE(lines[2]["feather"].is_null()) << "a click on the background keeps a selection";
}

// #28 "the missing stages": the Scene panel's master seed and layer order reach the saved scene, and
// its Export writes the coat.
TEST(ViewerSmoke, ScenePanelSeedOrderingAndExport) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("smoke_scene_panel");
  const std::string script = dir + "/s.txt", saved = dir + "/saved.json", glb = dir + "/coat.glb";
  std::ofstream(script) << "count 0 20\nwait\n"
                        << "ui Scene seed 4242\nwait\n"
                        << "ui Scene ordering flow\nwait\n"
                        << "ui Scene export " << glb << "\nwait\nframes 3\n"
                        << "screenshot-window " << dir << "/scene_panel.png\n"
                        << "save " << saved << "\nquit\n";
  const ViewerRun r = runViewer(
      "\"" + viewer_test::dataPath("scenes/patch.json") + "\" --lod 0.3 --size 1000x700 --script \"" + script + "\"",
      dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << slurp(dir + "/stderr.txt");
  const pipeline::Scene s = pipeline::loadScene(saved);
  EXPECT_EQ(s.seed, 4242u);
  EXPECT_EQ(s.ordering.value("method", std::string()), "flow");
  const std::string bytes = slurp(glb);
  ASSERT_GT(bytes.size(), 1000u) << "the export wrote nothing";
  EXPECT_EQ(bytes.substr(0, 4), "glTF");
}

// #28 "readable": the panel column is resizable from its right edge (the 3D view gives way).
TEST(ViewerSmoke, ThePanelColumnResizesFromItsEdge) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("smoke_panel_width");
  const std::string script = dir + "/s.txt";
  std::ofstream(script) << "frames 3\nscreenshot-window " << dir << "/before.png\n"
                        << "drag -2 300 200 300 left 12\nframes 3\nscreenshot-window " << dir << "/after.png\nquit\n";
  const ViewerRun r = runViewer(
      "\"" + viewer_test::dataPath("scenes/patch.json") + "\" --lod 0.2 --size 1000x700 --script \"" + script + "\"",
      dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << slurp(dir + "/stderr.txt");
  // A point just right of the old edge, low in the window: the light view background before, the dark
  // panel after.
  auto luminance = [](const render::Image& im, int x, int y) {
    const uint8_t* p = im.pixel(x, y);
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
  };
  const render::Image before = render::loadImage(dir + "/before.png"), after = render::loadImage(dir + "/after.png");
  ASSERT_EQ(before.width, 1000);
  EXPECT_GT(luminance(before, 480, 640), 150.0);
  EXPECT_LT(luminance(after, 480, 640), 80.0) << "the panel column did not widen";
}

// A 3D-view screenshot with the navigation view forced on used to wait forever for a full-resolution
// frame that forced navigation never draws; it now captures what the navigation view shows.
TEST(ViewerSmoke, AScreenshotOfTheForcedNavigationViewFinishes) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("smoke_nav_shot");
  const std::string script = dir + "/s.txt";
  std::ofstream(script) << "wait\nshow navigation on\nframes 2\nscreenshot " << dir << "/nav.png\nquit\n";
  const ViewerRun r = runViewer("\"" + viewer_test::dataPath("scenes/patch.json") + "\" --lod 0.2 --script \"" +
                                    script + "\" --autosave-seconds 0",
                                dir + "/stderr.txt", "");
  ASSERT_EQ(r.code, 0) << slurp(dir + "/stderr.txt");
  EXPECT_FALSE(render::loadImage(dir + "/nav.png").empty());
}

// The moult scene thinned (25 feathers a tract: every frame of a range is another coat, quickly), then
// `commands`: the JSON lines the run printed (empty, with a failure, when it did not exit 0).
static std::vector<Json> runThinnedMoult(const std::string& dir, const std::string& commands,
                                         const std::string& size = "800x600") {
  const std::string script = dir + "/s.txt";
  std::ofstream(script) << "count 0 25\ncount 1 25\ncount 2 25\n" << commands;
  const ViewerRun r = runViewer("\"" + viewer_test::dataPath("scenes/moult.json") + "\" --lod 0.2 --size " + size +
                                    " --script \"" + script + "\"",
                                dir + "/stderr.txt");
  if (r.code != 0) {
    ADD_FAILURE() << "the viewer exited " << r.code << ": " << slurp(dir + "/stderr.txt");
    return {};
  }
  std::vector<Json> lines = viewer_test::jsonLines(r.out);
  if (lines.empty()) ADD_FAILURE() << "no JSON printed: " << r.out;
  return lines;
}

// #26: playback follows the wall clock (frames not ready in time are dropped, never waited for), and
// after `cache-range` every frame of the range plays from the flipbook without evaluating anything.
TEST(ViewerSmoke, PlaybackDropsFramesAndPlaysTheFlipbook) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::vector<Json> lines = runThinnedMoult(
      viewer_test::scratchDir("smoke_play"),
      "time 3\nwait\nrange 3 4 0.01 once\nplay 5 240\nrange 3 4 0.25 loop\ncache-range\nplay 2 10\nquit\n");
  ASSERT_EQ(lines.size(), 2u);
  const Json& live = lines[0];
  const Json& cached = lines[1];
  // 101 frames at 240 a second, once: the clock passes the last frame after 0.42 s and playback ends
  // there, having shown only the frames that were ready (a playback that waited for each frame would
  // evaluate all 101 and take many seconds).
  EXPECT_LT(live["play_seconds"].get<double>(), 2.0) << "playback waited for frames: " << live.dump();
  EXPECT_GE(live["frames_shown"].get<int>(), 1);
  EXPECT_LT(live["frames_shown"].get<int>(), 50) << live.dump() << cached.dump();
  // Played once to the end: the playhead stops on the range's last frame.
  EXPECT_NEAR(live["time_shown"].get<double>(), 4.0, 1e-6) << live.dump();
  // Every frame it evaluated was drawn before the next was asked for: each is in the flipbook (with
  // the frame playback started on).
  EXPECT_GE(live["frames_evaluated"].get<int>(), 1) << live.dump() << cached.dump();
  EXPECT_GE(live["flipbook_frames"].get<int>(), live["frames_evaluated"].get<int>() + 1)
      << live.dump() << cached.dump();
  // Cached: the range's 5 frames, looped at 10 fps, all from the flipbook.
  EXPECT_GE(cached["flipbook_frames"].get<int>(), 5);
  EXPECT_EQ(cached["frames_evaluated"].get<int>(), 0) << live.dump() << cached.dump();
  EXPECT_GE(cached["frames_from_flipbook"].get<int>(), 10) << live.dump() << cached.dump();
  EXPECT_GE(cached["fps_shown"].get<double>(), 5.0) << live.dump() << cached.dump();
}

// #26: with a flipbook, playback evaluates ahead of the clock and draws every evaluated frame into the
// flipbook, even one the clock passed before it was ready: a looped range is evaluated once, frame by
// frame, and its later passes play from the flipbook.
TEST(ViewerSmoke, PlaybackEvaluatesEachFrameOnceAndPlaysLaterPassesFromTheFlipbook) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::vector<Json> lines = runThinnedMoult(viewer_test::scratchDir("smoke_play_ahead"),
                                                  "time 3\nwait\nrange 3 4 0.1 loop\nplay 6 10\nquit\n", "640x480");
  ASSERT_EQ(lines.size(), 1u);
  const Json& play = lines[0];
  // 11 frames, the first drawn before playing: each other one evaluated exactly once and kept.
  EXPECT_EQ(play["frames_evaluated"].get<int>(), 10) << play.dump();
  EXPECT_GE(play["flipbook_frames"].get<int>(), 11) << play.dump();
  // 60 frames due; once the range is in the flipbook (a few seconds at most) every one due is shown.
  EXPECT_GE(play["frames_shown"].get<int>(), 25) << play.dump();
  EXPECT_GT(play["evaluation_seconds"].get<double>(), 0.0) << play.dump();
}

// #26: fast playback draws each played frame like a moving view (fewer pixels, no multisampling), and
// the paused frame at full quality again; off, every played frame is drawn at full quality.
TEST(ViewerSmoke, FastPlaybackDrawsPlayedFramesCheaplyAndThePausedFrameInFull) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("smoke_fast_play");
  for (const bool fast : {true, false}) {
    SCOPED_TRACE(fast);
    const std::string shot = dir + (fast ? "/fast.png" : "/full.png");
    const std::vector<Json> lines = runThinnedMoult(
        dir, std::string("show fast-playback ") + (fast ? "on" : "off") +
                 "\ntime 3\nwait\nrange 3 4 0.05 loop\nplay 2 24\ntime 3.5\nwait\nscreenshot " + shot + "\nquit\n");
    ASSERT_EQ(lines.size(), 1u);
    const Json& play = lines[0];
    ASSERT_GE(play["frames_evaluated"].get<int>(), 1) << play.dump();
    if (fast)
      EXPECT_GE(play["frames_drawn_fast"].get<int>(), play["frames_evaluated"].get<int>()) << play.dump();
    else
      EXPECT_EQ(play["frames_drawn_fast"].get<int>(), 0) << play.dump();
  }
  // The paused view is drawn at full resolution and quality either way: the same image.
  const render::Image a = render::loadImage(dir + "/fast.png"), b = render::loadImage(dir + "/full.png");
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.rgba, b.rgba);
}

// --screenshot (no script): the panels are hidden so the capture is the whole width of the window, the
// run ends by itself once the evaluated view is drawn, and the same scene gives the same bits again
// (App::captureScreenshot and Viewport::capture).
TEST(ViewerSmoke, TheScreenshotOptionCapturesTheWholeWidthAndQuits) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found";
  const std::string dir = viewer_test::scratchDir("screenshot_option");
  const std::string scene = "\"" + viewer_test::dataPath("scenes/patch.json") + "\"";
  std::vector<render::Image> shots;
  for (int run = 0; run < 2; ++run) {
    const std::string shot = dir + "/shot" + std::to_string(run) + ".png";
    const ViewerRun r =
        runViewer(scene + " --lod 0.2 --size 800x600 --frames 4 --screenshot \"" + shot + "\"", dir + "/err.txt");
    ASSERT_EQ(r.code, 0) << slurp(dir + "/err.txt");
    EXPECT_NE(slurp(dir + "/err.txt").find("wrote " + shot), std::string::npos);
    shots.push_back(render::loadImage(shot));
  }
  const render::Image& img = shots[0];
  EXPECT_EQ(img.width, 800) << "the panels were not hidden";
  EXPECT_GT(img.height, 500);  // the window less the menu and status bars
  EXPECT_LT(img.height, 600);
  const uint8_t bg[3] = {img.rgba[0], img.rgba[1], img.rgba[2]};
  EXPECT_GT(render::coveredFraction(img, bg, 8), 0.02) << "nothing drawn over the background";
  EXPECT_EQ(shots[0].rgba, shots[1].rgba) << "the same scene captured twice differs";
}

// --benchmark-orbit N: waits for the evaluation, turns the camera in its passes and prints one JSON
// object whose numbers fit together, then quits with 0 (OrbitBenchmark).
TEST(ViewerSmoke, TheOrbitBenchmarkPrintsItsPassesAndQuits) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found";
  const std::string dir = viewer_test::scratchDir("orbit_benchmark");
  const ViewerRun r =
      runViewer("\"" + viewer_test::dataPath("scenes/patch.json") + "\" --lod 0.2 --size 800x600 --benchmark-orbit 6",
                dir + "/err.txt");
  ASSERT_EQ(r.code, 0) << slurp(dir + "/err.txt");
  const std::vector<Json> lines = viewer_test::jsonLines(r.out);
  ASSERT_EQ(lines.size(), 1u) << r.out;
  const Json& b = lines[0];
  EXPECT_EQ(b["orbit_frames"], 6);
  for (const char* k : {"fps", "fps_navigation", "fps_moving_full_coat", "fps_moving", "seconds"})
    EXPECT_GT(b[k].get<double>(), 0.0) << k;
  EXPECT_GT(b["feathers"].get<int>(), 0);
  const size_t coat = b["coat_triangles"].get<size_t>();
  EXPECT_GT(coat, 0u);
  EXPECT_GT(b["drawn_triangles"].get<size_t>(), 0u);
  EXPECT_LE(b["drawn_triangles"].get<size_t>(), coat);
  EXPECT_LE(b["navigation_triangles"].get<size_t>(), coat);
  // The view right of the panel column, between the menu and status bars.
  EXPECT_GT(b["width"].get<int>(), 0);
  EXPECT_LT(b["width"].get<int>(), 800);
  EXPECT_GT(b["height"].get<int>(), 500);
  EXPECT_NEAR(b["lod"].get<double>(), 0.2, 1e-9);
  // What an interactive orbit draws is one of the two measured passes.
  const std::string moving = b["moving_coat"];
  ASSERT_TRUE(moving == "full" || moving == "navigation") << moving;
  EXPECT_EQ(b["fps_moving"].get<double>(),
            b[moving == "full" ? "fps_moving_full_coat" : "fps_navigation"].get<double>());
}
