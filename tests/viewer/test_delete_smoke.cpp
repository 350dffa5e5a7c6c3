// Deleting feathers in the real viewer under xvfb-run (issue #28, "Delete to remove"): a click selects a
// feather and Delete removes its follicle, or Ctrl + drag boxes feathers and Delete removes all of theirs,
// each one undo step. The deleted follicles' ids must reach the saved scene (the tract's
// "removed_follicles"), the saved scene must evaluate without them and with every other follicle where
// it was, and undo must bring them back. Skipped only when xvfb-run is missing.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "fixtures.hpp"
#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "viewer_run.hpp"

using namespace pteryla;
using viewer_test::haveXvfbRun;
using viewer_test::runViewer;
using viewer_test::slurp;
using viewer_test::ViewerRun;

namespace {

std::vector<uint64_t> removedIds(const Json& scene) {
  const Json& t = scene.at("tracts").at(0);
  return t.contains("removed_follicles") ? t["removed_follicles"].get<std::vector<uint64_t>>()
                                         : std::vector<uint64_t>{};
}

}  // namespace

TEST(ViewerDelete, DeletedFeathersReachTheSavedSceneAndUndoRestoresThem) {
  if (!haveXvfbRun()) GTEST_SKIP() << "xvfb-run not found (install the xvfb and xauth packages: tools/bootstrap.sh)";
  const std::string dir = viewer_test::scratchDir("delete_feathers");
  const std::string before = dir + "/before.json", one = dir + "/one.json", undone = dir + "/undone.json",
                    boxed = dir + "/boxed.json", script = dir + "/session.txt";
  std::ofstream(script) << "load " << viewer_test::dataPath("scenes/patch.json") << "\n"
                        << "lod 0.2\n"
                           "count 0 30\n"
                           "relax 5\n"
                           "show panels off\n"
                           "wait\n"
                        << "save " << before << "\n"
                        << "click 50% 50%\n"
                           "frames 2\n"
                           "selection\n"
                           "key delete\n"
                           "wait\n"
                           "selection\n"
                        << "save " << one << "\n"
                        << "undo\n"
                           "wait\n"
                        << "save " << undone << "\n"
                        << "redo\n"
                           "wait\n"
                           // Only feathers in the box: the handles there (the styling vector, key feathers)
                           // are boxed only while shown.
                           "show keys off\n"
                           "show vectors off\n"
                           "box-select 35% 35% 65% 65%\n"
                           "box-selection\n"
                           "key delete\n"
                           "wait\n"
                        << "save " << boxed << "\n"
                        << "quit\n";
  const ViewerRun r = runViewer("--size 1000x700 --script \"" + script + "\"", dir + "/stderr.txt");
  ASSERT_EQ(r.code, 0) << "stdout: " << r.out << "\nstderr: " << slurp(dir + "/stderr.txt");
  const std::vector<Json> lines = viewer_test::jsonLines(r.out);
  ASSERT_EQ(lines.size(), 3u) << r.out;
  ASSERT_TRUE(lines[0]["feather"].is_number()) << "the click at the centre of the patch selected nothing";
  const uint64_t id = lines[0]["follicle_id"].get<uint64_t>();
  EXPECT_TRUE(lines[1]["feather"].is_null()) << "the deleted feather stayed selected";
  const std::vector<int> boxFeathers = lines[2]["feathers"].get<std::vector<int>>();
  ASSERT_GE(boxFeathers.size(), 3u) << "the box caught too few feathers: " << lines[2].dump();
  EXPECT_TRUE(lines[2]["handles"].empty()) << lines[2].dump();

  // The click + Delete: exactly the selected feather's follicle id reached the saved scene.
  EXPECT_TRUE(removedIds(readJsonFile(before)).empty());
  EXPECT_EQ(removedIds(readJsonFile(one)), std::vector<uint64_t>{id});
  // Undo restored it.
  EXPECT_TRUE(removedIds(readJsonFile(undone)).empty());
  // The box + Delete (after redo): the clicked one and the boxed feathers' follicles, one per feather.
  const std::vector<uint64_t> gone = removedIds(readJsonFile(boxed));
  EXPECT_EQ(gone.front(), id);
  EXPECT_EQ(gone.size(), 1 + boxFeathers.size()) << lines[2].dump();

  // The saved scenes evaluate: the deleted follicles are gone, the others did not move.
  pipeline::Pipeline full(pipeline::loadScene(before)), cut(pipeline::loadScene(one)),
      back(pipeline::loadScene(undone)), box(pipeline::loadScene(boxed));
  const coat::Follicles& f0 = full.follicles();
  ASSERT_EQ(f0.size(), 30u);
  ASSERT_NE(std::find(f0.id.begin(), f0.id.end(), id), f0.id.end());
  std::map<uint64_t, glm::dvec3> at;
  for (size_t k = 0; k < f0.size(); ++k) at[f0.id[k]] = f0.position[k];
  const coat::Follicles& f1 = cut.follicles();
  ASSERT_EQ(f1.size(), 29u);
  EXPECT_EQ(std::find(f1.id.begin(), f1.id.end(), id), f1.id.end());
  for (size_t k = 0; k < f1.size(); ++k) EXPECT_EQ(f1.position[k], at.at(f1.id[k]));
  EXPECT_EQ(cut.feathers().size(), 29u);
  EXPECT_EQ(back.follicles().id, f0.id);
  EXPECT_EQ(box.follicles().size(), 30u - gone.size());
}
