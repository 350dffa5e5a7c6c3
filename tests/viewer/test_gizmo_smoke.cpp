// The gizmos in the real viewer under xvfb-run, driven with the mouse as a user would (`gizmo-drag`
// presses on the handle or ring and drags; K keys): a control's offset dragged along x, then keyed at
// another time after a drag along y; a skeleton joint's ring turned and keyed. What they did must be in
// the saved scene, and the saved scene must evaluate. Skipped only when xvfb-run is missing.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "fixtures.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/moult/controls.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "viewer_run.hpp"

using namespace pteryla;
using viewer_test::haveXvfbRun;
using viewer_test::runViewer;
using viewer_test::slurp;
using viewer_test::ViewerRun;

TEST(ViewerGizmo, ControlOffsetDraggedAndKeyedReachesTheSavedScene) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("gizmo_offset");
  const std::string saved = dir + "/offset.json", script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "count 0 24\n"
                           "relax 2\n"
                           "control 0 0.05 0 0.6\n"
                           "direction 0 1\n"
                           "wait\n"
                           "ui \"Expressive controls\" select control0\n"
                           "show panels off\n"
                           "frames 2\n"
                           // An unkeyed offset: the drag sets the constant.
                           "gizmo-drag offset x 0.3\n"
                           "wait\n"
                           "save "
                        << dir << "/constant.json\n"
                        << "time 1\n"
                           "gizmo-drag offset y 0.2\n"
                           "key k\n"  // K: key every behaviour and the offset at t = 1
                           "time 2\n"
                           "gizmo-drag offset z -0.25\n"  // keyed now: a second key at t = 2
                           "wait\n"
                        << "save " << saved << "\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");

  // The first drag: a constant offset along x (the mouse lands on whole pixels: a few percent).
  const Json first = readJsonFile(dir + "/constant.json")["controls"][0];
  ASSERT_TRUE(first.contains("offset")) << first.dump();
  EXPECT_NEAR(first["offset"][0].get<double>(), 0.3, 0.02);
  EXPECT_NEAR(first["offset"][1].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(first["offset"][2].get<double>(), 0.0, 1e-9);
  EXPECT_FALSE(first.contains("keys"));

  const Json c = readJsonFile(saved)["controls"][0];
  EXPECT_FALSE(c.contains("offset")) << c.dump();  // keyed: no constant
  ASSERT_TRUE(c.contains("keys")) << c.dump();
  ASSERT_EQ(c["keys"].size(), 2u) << c.dump();
  const Json& k1 = c["keys"][0];
  const Json& k2 = c["keys"][1];
  EXPECT_EQ(k1["t"], 1.0);
  EXPECT_EQ(k2["t"], 2.0);
  EXPECT_NEAR(k1["offset"][0].get<double>(), 0.3, 0.02);
  EXPECT_NEAR(k1["offset"][1].get<double>(), 0.2, 0.02);
  EXPECT_DOUBLE_EQ(k1["direction"].get<double>(), 1.0);  // K keyed the behaviours too
  EXPECT_NEAR(k2["offset"][1].get<double>(), k1["offset"][1].get<double>(), 1e-9);
  EXPECT_NEAR(k2["offset"][2].get<double>(), -0.25, 0.02);
  EXPECT_FALSE(k2.contains("lift"));  // only the offset was keyed at t = 2

  // The saved scene reads, and its control's offset at t = 1.5 is between the keys.
  const pipeline::Scene back = pipeline::loadScene(saved);
  JsonReader reader(back.controls[0], back.file, "controls[0]");
  const moult::ControlValues v = moult::controlValuesAt(moult::readControl(reader), 1.5);
  EXPECT_NEAR(v.offset.z, 0.5 * k2["offset"][2].get<double>(), 1e-9);
  EXPECT_DOUBLE_EQ(v.direction, 1.0);
}

TEST(ViewerGizmo, JointRingTurnedAndKeyedReachesTheSavedSkeleton) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("gizmo_joint");
  const std::string saved = dir + "/joint.json", script = dir + "/session.txt";
  // wing.json: the elbow is keyed 0 at t = 0 and -20 degrees about z at t = 1 (smooth), so at t = 0.5 it
  // is -10 degrees. A 25 degree turn of its z ring makes it +15 there.
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/wing.json") << "\n"
                        << "lod 0.2\n"
                           "count coverts 30\n"
                           "time 0.5\n"
                           "wait\n"
                           "ui Skeleton select elbow\n"
                           "show panels off\n"
                           "frames 2\n"
                           "screenshot "
                        << dir << "/before.png\n"
                        << "gizmo-drag joint z 25\n"
                           "wait\n"
                           "frames 2\n"
                           "screenshot "
                        << dir << "/after.png\n"
                        << "time 2.5\n"
                           "ui Skeleton select wrist\n"
                           "show panels off\n"
                           "key k\n"  // K: the wrist's pose at t = 2.5 as a key
                           "wait\n"
                        << "save " << saved << "\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");

  const Json keys = readJsonFile(saved)["skeleton"]["keys"];
  const Json original = readJsonFile(viewer_test::dataPath("scenes/wing.json"))["skeleton"]["keys"];
  ASSERT_EQ(keys.size(), original.size() + 2) << keys.dump();
  const Json* elbow = nullptr;
  const Json* wrist = nullptr;
  for (const Json& k : keys) {
    if (k["joint"] == "elbow" && k["t"] == 0.5) elbow = &k;
    if (k["joint"] == "wrist" && k["t"] == 2.5) wrist = &k;
  }
  ASSERT_TRUE(elbow) << keys.dump();
  ASSERT_TRUE(wrist) << keys.dump();
  const Json& rot = (*elbow)["rotation"];
  EXPECT_NEAR(rot[0].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(rot[1].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(rot[2].get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(rot[3].get<double>(), 15.0, 1.0);
  // The wrist is keyed 20 degrees at t = 2 and 35 at t = 3 (smooth): 27.5 between them.
  const Json& w = (*wrist)["rotation"];
  EXPECT_NEAR(w[2].get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(w[3].get<double>(), 27.5, 1e-6);

  // The posed coat followed the turn: the 3D view changed.
  EXPECT_NE(slurp(dir + "/before.png"), slurp(dir + "/after.png"));
  // The saved scene evaluates with the new keys.
  const pipeline::Scene back = pipeline::loadScene(saved);
  EXPECT_EQ(back.skeleton["keys"].size(), keys.size());
}

// Scripted gizmo use without a gizmo is a script error (exit 2, the line named), not a crash or a silent
// no-op: no control selected, a scene without a skeleton, an unknown joint.
TEST(ViewerGizmo, GizmoCommandsWithoutTheirTargetFailTheScript) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("gizmo_errors");
  const struct {
    const char* line;
    const char* message;
  } cases[] = {{"gizmo-drag offset x 0.1", "no control is selected"},
               {"gizmo-drag joint z 10", "no joint is selected"},
               {"joint-key elbow 0 0 1 10", "no skeleton"},
               {"offset 3 0 0 0.1", "control index 3 out of range"}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.line);
    const std::string script = dir + "/session.txt";
    std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                          << "lod 0.2\n"
                             "count 0 12\n"
                             "relax 0\n"
                             "wait\n"
                          << c.line << "\n"
                          << "quit\n";
    const ViewerRun r = runViewer("--size 800x600 --script \"" + script + "\"", dir + "/stderr.txt");
    EXPECT_EQ(r.code, 2) << "stdout: " << r.out;
    const std::string err = slurp(dir + "/stderr.txt");
    EXPECT_NE(err.find("line 6"), std::string::npos) << err;
    EXPECT_NE(err.find(c.message), std::string::npos) << err;
  }
}
