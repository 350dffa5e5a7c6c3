// Autosave and recovery (recovery.hpp): file names, the write-then-rename format, the autosave timer,
// restoring into a document (one undo step back to the file) and removal once the work is saved.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "document.hpp"
#include "fixtures.hpp"
#include "pteryla/core/error.hpp"
#include "recovery.hpp"

using namespace pteryla;
using namespace pteryla::viewer;
using viewer_test::smallPatch;

namespace {

// A scene file in a fresh directory, recovery files in <dir>/state (XDG_STATE_HOME).
struct Fixture {
  std::string dir, scene;
  explicit Fixture(const std::string& name) {
    dir = viewer_test::scratchDir(name);
    setenv("XDG_STATE_HOME", (dir + "/state").c_str(), 1);
    scene = dir + "/groom.json";
    pipeline::saveScene(scene, smallPatch());
  }
  std::string fileText(const std::string& p) const {
    std::ifstream f(p);
    return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  }
};

bool exists(const std::string& p) { return std::filesystem::exists(p); }

}  // namespace

TEST(Recovery, FilesLiveInTheStateDirectoryOnePerScene) {
  Fixture f("recovery_names");
  EXPECT_EQ(recoveryDir(), f.dir + "/state/pteryla/recovery");
  const std::string a = recoveryPath(f.scene), b = recoveryPath(f.dir + "/other/groom.json");
  EXPECT_NE(a, b) << "same file name in two directories";
  EXPECT_EQ(a, recoveryPath(f.dir + "/./groom.json"));
  EXPECT_EQ(std::filesystem::path(a).parent_path().string(), recoveryDir());
  EXPECT_EQ(std::filesystem::path(a).filename().string().rfind("groom-", 0), 0u);
  EXPECT_EQ(recoveryPath(""), recoveryDir() + "/untitled.json");
}

TEST(Recovery, WriteReadRestoreKeepsTheSceneFileAndOneUndoStep) {
  Fixture f("recovery_roundtrip");
  const std::string original = f.fileText(f.scene);
  Document d;
  d.open(f.scene);
  d.edit("count", [](pipeline::Scene& s) { s.tracts[0]["count"] = 41; });
  d.setTime(0.75);
  const double renderLod = d.scene().render.lod;
  d.setLod(0.3);  // the viewer's preview level of detail: restored, but not as the scene's render.lod
  const std::string file = writeRecovery(d);
  EXPECT_EQ(file, recoveryPath(f.scene));
  EXPECT_EQ(std::filesystem::directory_iterator(recoveryDir())->path().string(), file) << "no temporary left";
  EXPECT_EQ(f.fileText(f.scene), original);

  const Recovery r = readRecovery(file);
  EXPECT_EQ(r.scenePath, d.path());
  EXPECT_FALSE(r.savedAt.empty());
  EXPECT_EQ(r.scene.tracts[0]["count"], 41);
  EXPECT_DOUBLE_EQ(r.scene.time, 0.75);
  EXPECT_DOUBLE_EQ(r.scene.render.lod, renderLod);
  EXPECT_EQ(r.viewLod, 0.3);
  ASSERT_EQ(findRecovery(f.scene), file);
  ASSERT_EQ(findRecovery(""), file);

  Document fresh;  // the next start
  fresh.open(f.scene);
  restoreRecovery(fresh, r);
  EXPECT_TRUE(fresh.modified());
  EXPECT_EQ(fresh.scene().tracts[0]["count"], 41);
  EXPECT_DOUBLE_EQ(fresh.time(), 0.75);
  EXPECT_DOUBLE_EQ(fresh.lod(), 0.3);
  EXPECT_DOUBLE_EQ(fresh.scene().render.lod, renderLod);
  EXPECT_EQ(fresh.path(), d.path());
  EXPECT_EQ(f.fileText(f.scene), original) << "a restore does not write the scene file";
  ASSERT_TRUE(fresh.undo());
  EXPECT_EQ(fresh.scene().tracts[0]["count"], smallPatch().tracts[0]["count"]) << "undo returns to the file";

  // A start with no scene opens the scene file the work belongs to.
  Document none;
  restoreRecovery(none, r);
  EXPECT_EQ(none.path(), d.path());
  EXPECT_EQ(none.scene().tracts[0]["count"], 41);
}

TEST(Recovery, WorkOfADeletedSceneFileComesBackUntitled) {
  Fixture f("recovery_untitled");
  Document d;
  d.open(f.scene);
  d.edit("count", [](pipeline::Scene& s) { s.tracts[0]["count"] = 17; });
  Autosaver a(10);
  const std::string file = a.saveNow(d);
  std::filesystem::remove(f.scene);
  Document next;
  restoreRecovery(next, readRecovery(file));
  EXPECT_EQ(next.path(), "");
  EXPECT_TRUE(next.modified());
  EXPECT_EQ(next.scene().tracts[0]["count"], 17);
  Autosaver b(10);
  b.adopt(file, next);  // now the untitled scene's: written under that name before the old one goes
  EXPECT_FALSE(exists(file));
  EXPECT_EQ(readRecovery(recoveryPath("")).scene.tracts[0]["count"], 17);
}

TEST(Recovery, AutosaverWritesAfterTheIntervalAndRemovesOnceSaved) {
  Fixture f("recovery_timer");
  Document d;
  d.open(f.scene);
  Autosaver a(10);
  const std::string file = recoveryPath(f.scene);
  EXPECT_FALSE(a.tick(d, 0.0)) << "nothing unsaved";
  EXPECT_THROW(a.saveNow(d), Error);
  d.edit("count", [](pipeline::Scene& s) { s.tracts[0]["count"] = 50; });
  EXPECT_FALSE(a.tick(d, 100.0));
  EXPECT_FALSE(a.tick(d, 109.0));
  EXPECT_FALSE(exists(file));
  EXPECT_TRUE(a.tick(d, 110.0));
  EXPECT_EQ(readRecovery(file).scene.tracts[0]["count"], 50);
  EXPECT_FALSE(a.tick(d, 500.0)) << "no change since the last write";
  d.endGesture();
  d.edit("count", [](pipeline::Scene& s) { s.tracts[0]["count"] = 51; });
  EXPECT_FALSE(a.tick(d, 501.0));
  EXPECT_TRUE(a.tick(d, 511.0));
  EXPECT_EQ(readRecovery(file).scene.tracts[0]["count"], 51);
  a.finish(d);
  EXPECT_TRUE(exists(file)) << "unsaved work keeps its recovery file at exit";
  d.save();
  a.tick(d, 512.0);
  EXPECT_FALSE(exists(file)) << "saved: the recovery file goes";

  Autosaver off(0);
  d.edit("count", [](pipeline::Scene& s) { s.tracts[0]["count"] = 52; });
  EXPECT_FALSE(off.tick(d, 0.0));
  EXPECT_FALSE(off.tick(d, 1e6));
  EXPECT_FALSE(exists(file)) << "interval 0: off";
  off.saveNow(d);
  EXPECT_TRUE(exists(file));
  off.discard();
  EXPECT_FALSE(exists(file)) << "discarded changes leave no recovery file";
}

TEST(Recovery, NotARecoveryFileIsAnError) {
  Fixture f("recovery_bad");
  EXPECT_THROW(readRecovery(f.scene), Error);
  EXPECT_FALSE(findRecovery(f.scene));
}

// A painted density map (unsaved) is in the recovery: written next to the recovery file, read back with
// it, and removed with it.
TEST(Recovery, PaintedDensityComesBackAndGoesWithTheRecoveryFile) {
  Fixture f("recovery_density");
  Document d;
  d.open(f.scene);
  ASSERT_TRUE(d.waitIdle());
  const size_t n = d.snapshot().restSkin->positions.size();
  std::vector<float> factor(n, 1.0f);
  factor[7] = 2.5f;
  d.edit("paint density",
         [&](pipeline::Scene& s) { s.densityFactor = std::make_shared<const std::vector<float>>(factor); });
  const std::string file = writeRecovery(d);
  const std::string side = pipeline::densityMapPathFor(file);
  EXPECT_TRUE(exists(side));
  const Recovery r = readRecovery(file);
  ASSERT_TRUE(r.scene.densityFactor);
  EXPECT_EQ(*r.scene.densityFactor, factor);
  EXPECT_EQ(findRecovery("").value_or(""), file) << "the side file is not a recovery file";
  removeRecovery(file);
  EXPECT_FALSE(exists(file));
  EXPECT_FALSE(exists(side));
}
