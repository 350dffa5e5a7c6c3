// Issue 21 (part 1): the viewer never crashes and never loses work. The real viewer binary under xvfb-run
// runs scripts that use the panels' own widgets (`ui PANEL WIDGET VALUE`): the two reported repros (a
// control's lift/aim sliders on the crest scene; removing a key feather of the bird's "capital" tract)
// used to abort in ImGui ("Forgot to call Render() or EndFrame()") because the panels kept references
// into the scene across the edit. An exception inside a panel must leave the viewer running, and
// unsaved work autosaved to the recovery file must come back after a crash.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include "fixtures.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "viewer_run.hpp"

using namespace pteryla;
using viewer_test::haveXvfbRun;
using viewer_test::runViewer;
using viewer_test::slurp;
using viewer_test::ViewerRun;

namespace {

#define NEED_XVFB() \
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)"

// Recovery files go to $XDG_STATE_HOME/pteryla/recovery: each test has its own.
std::string stateEnv(const std::string& dir) { return "XDG_STATE_HOME=\"" + dir + "/state\""; }

size_t filesIn(const std::string& dir) {
  std::error_code ec;
  size_t n = 0;
  for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) ++n;
  return n;
}

// What the viewer reported through its error modal (scripted runs print it on stderr too).
bool reportedError(const std::string& err) { return err.find("pteryla-viewer: error:") != std::string::npos; }

}  // namespace

// Repro 1: crest.json, Expressive controls, select "crest", drag lift, click aim.
TEST(ViewerRobust, ControlSlidersOnTheCrestScene) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_crest");
  const std::string saved = dir + "/crest.json", script = dir + "/s.txt";
  std::ofstream(script) << "ui \"Expressive controls\" select crest\n"
                           "ui \"Expressive controls\" lift 0.3\n"
                           "ui \"Expressive controls\" lift 0.8\n"
                           "ui \"Expressive controls\" aim 0.5\n"
                           "frames 3\n"
                        << "save " << saved << "\n"
                        << "quit\n";
  const ViewerRun r =
      runViewer("\"" + viewer_test::dataPath("scenes/crest.json") + "\" --lod 0.2 --script \"" + script + "\"",
                dir + "/stderr.txt", stateEnv(dir));
  const std::string err = slurp(dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << err;
  EXPECT_FALSE(reportedError(err)) << err;
  // The edits went through the panel: aim is a constant, lift is keyed (a key at the scene's time 1.5).
  const pipeline::Scene back = pipeline::loadScene(saved);
  ASSERT_EQ(back.controls.size(), 1u);
  const Json& c = back.controls[0];
  EXPECT_DOUBLE_EQ(c.value("aim", -1.0), 0.5);
  bool keyed = false;
  for (const auto& k : c["keys"])
    if (k.value("t", -1.0) == 1.5) {
      EXPECT_NEAR(k.value("lift", -1.0), 0.8, 1e-6);
      keyed = true;
    }
  EXPECT_TRUE(keyed) << c.dump();
}

// Repro 2: bird.json --lod 0.2, Key feathers, tract "capital", remove.
TEST(ViewerRobust, RemoveKeyFeathersOfTheBird) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_bird");
  const std::string saved = dir + "/bird.json", script = dir + "/s.txt";
  const Json before = pipeline::loadScene(viewer_test::dataPath("scenes/bird.json")).tracts;
  size_t capital = before.size();
  for (size_t i = 0; i < before.size(); ++i)
    if (before[i].value("name", std::string()) == "capital") capital = i;
  ASSERT_LT(capital, before.size());
  const Json keys = before[capital]["key_feathers"];
  ASSERT_GE(keys.size(), 3u);
  std::ofstream(script) << "ui \"Key feathers\" tract capital\n"
                           "ui \"Key feathers\" remove 0\n"
                           "ui \"Key feathers\" remove 1\n"
                           "frames 3\n"
                        << "save " << saved << "\n"
                        << "quit\n";
  const ViewerRun r =
      runViewer("\"" + viewer_test::dataPath("scenes/bird.json") + "\" --lod 0.2 --script \"" + script + "\"",
                dir + "/stderr.txt", stateEnv(dir));
  const std::string err = slurp(dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << err;
  EXPECT_FALSE(reportedError(err)) << err;
  const pipeline::Scene back = pipeline::loadScene(saved);
  const Json& left = back.tracts[capital]["key_feathers"];
  // Removed the first, then the second of the remaining ones (the original third).
  ASSERT_EQ(left.size(), keys.size() - 2);
  EXPECT_EQ(left[0]["at"], keys[1]["at"]);
  for (size_t i = 1; i < left.size(); ++i) EXPECT_EQ(left[i]["at"], keys[i + 2]["at"]);
}

// An exception inside a panel's body (here inside the Tracts table) goes to the error modal; the frame
// ends cleanly and the session carries on (without the guard the scripted run ends with code 2, an
// interactive one aborts in ImGui at the next frame).
TEST(ViewerRobust, ExceptionInsideAPanelKeepsTheViewerRunning) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_throw");
  const std::string saved = dir + "/patch.json", script = dir + "/s.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "count 0 24\n"
                           "relax 2\n"
                           "lod 0.2\n"
                           "ui Tracts throw\n"
                           "frames 3\n"
                           "ui \"Key feathers\" throw\n"
                           "frames 3\n"
                           "ui Tracts select patch\n"
                           "count 0 30\n"
                           "frames 3\n"
                        << "save " << saved << "\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--script \"" + script + "\"", dir + "/stderr.txt", stateEnv(dir));
  const std::string err = slurp(dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << err;
  EXPECT_NE(err.find("pteryla-viewer: error: Tracts: scripted fault inside the panel"), std::string::npos) << err;
  EXPECT_NE(err.find("pteryla-viewer: error: Key feathers: scripted fault inside the panel"), std::string::npos) << err;
  EXPECT_EQ(pipeline::loadScene(saved).tracts[0]["count"], 30);
}

// Autosave by the timer, a crash, and the next start restores the groom (--recover); the scene file is
// never written, and the recovery file goes away once the work is saved.
TEST(ViewerRobust, AutosaveRecoversTheGroomAfterACrash) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_autosave");
  const std::string scene = dir + "/groom.json", recovered = dir + "/recovered.json";
  pipeline::Scene start = viewer_test::smallPatch();
  pipeline::saveScene(scene, start);
  const std::string original = slurp(scene);

  // Session 1: edits, waits past the autosave interval (the timer writes the file), then crashes.
  const std::string s1 = dir + "/s1.txt";
  std::ofstream(s1) << "count 0 31\n"
                       "relax 2\n"
                       "control 0 0.05 0 0.5\n"
                       "lift 0 0.7\n"
                       "sleep 2.5\n"
                       "crash\n";
  const ViewerRun r1 =
      runViewer("\"" + scene + "\" --autosave-seconds 1 --script \"" + s1 + "\"", dir + "/stderr1.txt", stateEnv(dir));
  const std::string err1 = slurp(dir + "/stderr1.txt");
  ASSERT_EQ(r1.code, 70) << "the crash command ends the process with 70\n" << err1;
  EXPECT_NE(err1.find("pteryla-viewer: autosaved "), std::string::npos) << err1;
  const std::string recoveryDir = dir + "/state/pteryla/recovery";
  ASSERT_EQ(filesIn(recoveryDir), 1u) << "one recovery file, no temporary left";
  EXPECT_EQ(slurp(scene), original) << "autosave never writes the scene file";

  // Session 2: the same scene with --recover: the groom is back, unsaved; Save As writes it.
  const std::string s2 = dir + "/s2.txt";
  std::ofstream(s2) << "save " << recovered << "\n"
                    << "quit\n";
  const ViewerRun r2 =
      runViewer("\"" + scene + "\" --recover --script \"" + s2 + "\"", dir + "/stderr2.txt", stateEnv(dir));
  const std::string err2 = slurp(dir + "/stderr2.txt");
  ASSERT_EQ(r2.code, 0) << err2;
  EXPECT_NE(err2.find("pteryla-viewer: restored unsaved work from "), std::string::npos) << err2;
  const pipeline::Scene back = pipeline::loadScene(recovered);
  EXPECT_EQ(back.tracts[0]["count"], 31);
  EXPECT_EQ(back.tracts[0]["relax"]["iterations"], 2);
  ASSERT_EQ(back.controls.size(), 1u);
  EXPECT_DOUBLE_EQ(back.controls[0].value("lift", -1.0), 0.7);
  EXPECT_EQ(slurp(scene), original) << "restoring never writes the scene file";
  EXPECT_EQ(filesIn(recoveryDir), 0u) << "saving removes the recovery file";

  // Nothing left to recover: --recover says so (exit 2).
  const ViewerRun r3 =
      runViewer("\"" + scene + "\" --recover --script \"" + s2 + "\"", dir + "/stderr3.txt", stateEnv(dir));
  EXPECT_EQ(r3.code, 2) << slurp(dir + "/stderr3.txt");
}

// The explicit `autosave` command, quitting without saving (a scripted quit does not ask), and a start
// with no scene restores the newest recovery file.
TEST(ViewerRobust, ForcedAutosaveIsRestoredOnAStartWithoutAScene) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_autosave_forced");
  const std::string scene = dir + "/groom.json", recovered = dir + "/recovered.json";
  pipeline::saveScene(scene, viewer_test::smallPatch());
  const std::string s1 = dir + "/s1.txt", s2 = dir + "/s2.txt";
  std::ofstream(s1) << "load " << scene << "\n"
                    << "count 0 27\n"
                       "autosave\n"
                       "quit\n";
  const ViewerRun r1 = runViewer("--autosave-seconds 0 --script \"" + s1 + "\"", dir + "/stderr1.txt", stateEnv(dir));
  ASSERT_EQ(r1.code, 0) << slurp(dir + "/stderr1.txt");
  std::ofstream(s2) << "save " << recovered << "\n"
                    << "quit\n";
  const ViewerRun r2 = runViewer("--recover --script \"" + s2 + "\"", dir + "/stderr2.txt", stateEnv(dir));
  ASSERT_EQ(r2.code, 0) << slurp(dir + "/stderr2.txt");
  EXPECT_EQ(pipeline::loadScene(recovered).tracts[0]["count"], 27);
}

// #28: a broken scene named on the command line of an interactive run opens the window with the error
// (and File > Open at that file) instead of exiting before any window shows. A scripted run still exits 2.
TEST(ViewerRobust, ABrokenSceneOnTheCommandLineOpensTheWindow) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_broken_arg");
  const std::string broken = dir + "/broken.json";
  std::ofstream(broken) << "{\"pteryla\": 1, \"mesh\": ";
  // Interactive: still running (with its error dialog) when `timeout` ends it after 8 s.
  const std::string status = dir + "/status";
  const std::string cmd = "xvfb-run -a -s \"-screen 0 1024x768x24\" sh -c 'env " + stateEnv(dir) + " timeout 8 \"" +
                          std::string(PTERYLA_VIEWER_EXE) + "\" \"" + broken + "\" 2>\"" + dir +
                          "/stderr.txt\"; echo $? >\"" + status + "\"' >/dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(std::atoi(slurp(status).c_str()), 124) << "the viewer did not stay open: " << slurp(dir + "/stderr.txt");
  // Scripted: nobody reads the dialog, so the run ends with exit 2 naming the file.
  const std::string script = dir + "/s.txt";
  std::ofstream(script) << "quit\n";
  const ViewerRun r = runViewer("\"" + broken + "\" --script \"" + script + "\"", dir + "/stderr2.txt", stateEnv(dir));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(slurp(dir + "/stderr2.txt").find("broken.json"), std::string::npos);
}

// #28 "Files": the Save As and Open dialogs confirm with Enter; the path a dialog is given replaces the
// old one (never appended to it); each reaches the disk or the document.
TEST(ViewerRobust, FileDialogsConfirmWithEnter) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_dialogs");
  const std::string first = dir + "/first.json", second = dir + "/second.json", script = dir + "/s.txt";
  std::ofstream(script) << "dialog save-as " << first << "\n"
                        << "key enter\n"
                           "frames 3\n"
                        << "screenshot-window " << dir << "/open_dialog.png\n"
                        << "dialog open " << viewer_test::dataPath("scenes/sphere_small.json") << "\n"
                        << "frames 2\n"
                        << "screenshot-window " << dir << "/open_dialog.png\n"
                        << "key enter\n"
                           "wait\n"
                           "frames 3\n"
                        << "save " << second << "\n"
                        << "quit\n";
  const ViewerRun r =
      runViewer("\"" + viewer_test::dataPath("scenes/patch.json") + "\" --lod 0.2 --script \"" + script + "\"",
                dir + "/stderr.txt", stateEnv(dir));
  const std::string err = slurp(dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << err;
  EXPECT_FALSE(reportedError(err)) << err;
  // Save As + Enter wrote the patch scene; Open + Enter opened the sphere, which `save` then wrote.
  ASSERT_TRUE(std::filesystem::exists(first)) << err;
  EXPECT_EQ(pipeline::loadScene(first).name, pipeline::loadScene(viewer_test::dataPath("scenes/patch.json")).name);
  ASSERT_TRUE(std::filesystem::exists(second)) << err;
  EXPECT_EQ(pipeline::loadScene(second).name,
            pipeline::loadScene(viewer_test::dataPath("scenes/sphere_small.json")).name);
  // Scripts leave the user's recent files alone.
  EXPECT_FALSE(std::filesystem::exists(dir + "/state/pteryla/recent.json"));
}

// #28: an idle viewer draws nothing (it used to redraw ten times a second, 16-20% of a core). An
// interactive run with --quit-after prints how many frames it drew and skipped.
TEST(ViewerRobust, AnIdleViewerDrawsNothing) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_idle");
  const ViewerRun r = runViewer("\"" + viewer_test::dataPath("scenes/patch.json") + "\" --lod 0.2 --quit-after 8",
                                dir + "/stderr.txt", stateEnv(dir));
  ASSERT_EQ(r.code, 0) << slurp(dir + "/stderr.txt");
  const size_t at = r.out.find('{');
  ASSERT_NE(at, std::string::npos) << r.out;
  const Json j = Json::parse(r.out.substr(at, r.out.find('}', at) - at + 1));
  // Evaluation and start-up take the first second or two; after that the loop waits for input (0.5 s
  // per wait) and draws nothing.
  EXPECT_GE(j.at("frames_skipped").get<int>(), 6) << r.out;
  EXPECT_LT(j.at("frames_drawn").get<int>(), 200) << r.out;
}

// A found crash (session 18): edits queued without waiting (a render LOD, a new follicle count, a
// relaxation) left the renderer with a coat whose draw ranges named more materials than it had been
// given (the snapshot's list, from another evaluation), and the view threw "feather draw range uses
// material 8 but 7 materials are set". The renderer now takes the materials of the coat it is given.
TEST(ViewerRobust, QueuedRestEditsKeepTheCoatAndItsMaterialsTogether) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_materials");
  const std::string script = dir + "/s.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\nrender-lod 0.2\ncount 0 12\nrelax 3\nwait\n"
                        << "screenshot " << dir << "/after.png\nquit\n";
  const ViewerRun r = runViewer("--script \"" + script + "\"", dir + "/stderr.txt", stateEnv(dir));
  const std::string err = slurp(dir + "/stderr.txt");
  EXPECT_EQ(r.code, 0) << err;
  EXPECT_EQ(err.find("materials are set"), std::string::npos) << err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/after.png")) << err;
}

// File > Quit with unsaved changes asks (Dialogs::confirmQuit): Save writes the scene and quits, Discard
// quits leaving the file and removing the recovery file, Cancel keeps the viewer running with the work
// (and its recovery file). The script clicks the menu and the dialog's buttons where they are drawn in
// a 1000x700 window (menu bar over a 420-pixel panel column: clicks are relative to the 3D view); a
// command after the dialog tells whether the viewer was still running.
TEST(ViewerRobust, QuitWithUnsavedChangesAsksThenSavesDiscardsOrCancels) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_quit_asks");
  const std::string recoveryDir = dir + "/state/pteryla/recovery";
  const pipeline::Scene start = viewer_test::smallPatch();
  ASSERT_NE(start.tracts[0]["count"], 31);
  struct Answer {
    const char* button;
    int x;  // view pixels (the dialog is centred in the window)
  };
  for (const Answer a : {Answer{"save", -8}, Answer{"discard", 47}, Answer{"cancel", 107}}) {
    SCOPED_TRACE(a.button);
    const std::string scene = dir + "/" + a.button + ".json", script = dir + "/" + a.button + ".txt";
    std::filesystem::remove_all(dir + "/state");
    pipeline::saveScene(scene, start);
    const std::string original = slurp(scene);
    std::ofstream(script) << "count 0 31\n"
                             "wait\n"
                             "autosave\n"
                             "click -395 -10\n"  // File
                             "frames 2\n"
                             "click -395 86\n"  // Quit
                             "frames 3\n"
                          << "screenshot-window " << dir << "/" << a.button << "_asks.png\n"
                          << "click " << a.x << " 349\n"
                          << "frames 3\n"
                             "selection\n"  // printed only when the viewer is still running
                             "quit\n";
    const ViewerRun r = runViewer("\"" + scene + "\" --lod 0.2 --size 1000x700 --script \"" + script + "\"",
                                  dir + "/" + a.button + "_stderr.txt", stateEnv(dir));
    const std::string err = slurp(dir + "/" + a.button + "_stderr.txt");
    ASSERT_EQ(r.code, 0) << err;
    const bool running = viewer_test::jsonLines(r.out).size() == 1;
    if (std::string(a.button) == "save") {
      EXPECT_FALSE(running) << "Save quits (did the menu or the dialog move? see save_asks.png)";
      EXPECT_EQ(pipeline::loadScene(scene).tracts[0]["count"], 31) << "Save writes the scene";
      EXPECT_EQ(filesIn(recoveryDir), 0u) << "a saved scene leaves no recovery file";
    } else if (std::string(a.button) == "discard") {
      EXPECT_FALSE(running) << "Discard quits";
      EXPECT_EQ(slurp(scene), original) << "Discard never writes the scene";
      EXPECT_EQ(filesIn(recoveryDir), 0u) << "discarded work is not offered for recovery";
    } else {
      EXPECT_TRUE(running) << "Cancel keeps the viewer running";
      EXPECT_EQ(slurp(scene), original);
      EXPECT_EQ(filesIn(recoveryDir), 1u) << "the unsaved work keeps its recovery file";
    }
  }
}

// Save As onto an existing file asks "Replace file?" (Dialogs::saveAsNow): nothing is written until
// Replace; Cancel leaves the file as it was. The dialog is centred in the 1000x700 window and as wide
// as its longest line (the default font is 7 pixels a character, 8 pixels of padding each side); its
// buttons are clicked there (view pixels: the 3D view starts 420 pixels right, 19 down).
TEST(ViewerRobust, SaveAsOntoAnExistingFileAsksBeforeReplacingIt) {
  NEED_XVFB();
  const std::string dir = viewer_test::scratchDir("robust_replace");
  const std::string scene = dir + "/groom.json";
  pipeline::saveScene(scene, viewer_test::smallPatch());
  for (const bool replace : {true, false}) {
    SCOPED_TRACE(replace ? "replace" : "cancel");
    const std::string name = replace ? "replace" : "cancel_";  // the same length: the same dialog
    const std::string target = dir + "/" + name + ".json", script = dir + "/" + name + ".txt";
    std::ofstream(target) << "{}\n";
    const int width = 16 + 7 * int(std::max(target.size() + 8, size_t(27)));
    if (width > 900) GTEST_SKIP() << "the build directory's path is too long for the dialog to fit the window";
    const int left = 500 - width / 2 - 420;
    std::ofstream(script) << "count 0 31\n"
                             "wait\n"
                          << "dialog save-as " << target << "\n"
                          << "key enter\n"
                             "frames 3\n"
                          << "screenshot-window " << dir << "/" << name << "_asks.png\n"
                          << "click " << left + (replace ? 36 : 98) << " 358\n"
                          << "frames 3\n"
                             "selection\n"
                             "quit\n";
    const ViewerRun r = runViewer("\"" + scene + "\" --lod 0.2 --size 1000x700 --script \"" + script + "\"",
                                  dir + "/" + name + "_stderr.txt", stateEnv(dir));
    const std::string err = slurp(dir + "/" + name + "_stderr.txt");
    ASSERT_EQ(r.code, 0) << err;
    EXPECT_EQ(viewer_test::jsonLines(r.out).size(), 1u) << "the viewer keeps running after either answer";
    if (replace) {
      ASSERT_NE(slurp(target), "{}\n") << "Replace writes the file (did the dialog move? see replace_asks.png)";
      EXPECT_EQ(pipeline::loadScene(target).tracts[0]["count"], 31);
    } else {
      EXPECT_EQ(slurp(target), "{}\n") << "Cancel leaves the existing file alone";
    }
    EXPECT_NE(pipeline::loadScene(scene).tracts[0]["count"], 31) << "Save As never writes the old file";
  }
}
