// The Open / Save As file browser and the recent-files list (#28 "Files"): listing order and filters,
// navigation, typed names that replace (never append to) the old one, and a recent list that survives a
// restart and a broken state file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "file_browser.hpp"
#include "fixtures.hpp"

using namespace pteryla::viewer;
namespace fs = std::filesystem;

namespace {

void touch(const fs::path& p, const std::string& text = "{}") {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

std::vector<std::string> names(const FileBrowser& b) {
  std::vector<std::string> out;
  for (const auto& e : b.entries()) out.push_back(e.name + (e.directory ? "/" : ""));
  return out;
}

}  // namespace

TEST(FileBrowser, ListsParentThenDirectoriesThenMatchingFilesByName) {
  const fs::path dir = viewer_test::scratchDir("browser_list");
  touch(dir / "b.json");
  touch(dir / "A.JSON");
  touch(dir / "bird.obj");
  touch(dir / "notes.txt");
  touch(dir / ".hidden.json");
  fs::create_directories(dir / "scenes");
  fs::create_directories(dir / "Meshes");
  FileBrowser b({".json", ".obj"});
  ASSERT_TRUE(b.setDirectory(dir.string())) << b.error();
  EXPECT_EQ(names(b), (std::vector<std::string>{"../", "Meshes/", "scenes/", "A.JSON", "b.json", "bird.obj"}));
  b.setShowHidden(true);
  EXPECT_EQ(names(b)[3], ".hidden.json");
  b.setShowHidden(false);
  // A file's entry gives its absolute path; a directory's enters it; ".." goes back up.
  const auto file = b.choose(3);
  ASSERT_TRUE(file);
  EXPECT_EQ(fs::path(*file), fs::absolute(dir / "A.JSON").lexically_normal());
  EXPECT_FALSE(b.choose(2));  // scenes/
  EXPECT_EQ(fs::path(b.directory()), fs::absolute(dir / "scenes").lexically_normal());
  EXPECT_EQ(names(b), (std::vector<std::string>{"../"}));
  EXPECT_FALSE(b.choose(0));
  EXPECT_EQ(fs::path(b.directory()), fs::absolute(dir).lexically_normal());
  // The root has no "..".
  ASSERT_TRUE(b.setDirectory("/"));
  ASSERT_FALSE(b.entries().empty());
  EXPECT_NE(b.entries()[0].name, "..");
  // A directory that is not there keeps the listing and says why.
  EXPECT_FALSE(b.setDirectory((dir / "missing").string()));
  EXPECT_EQ(b.directory(), "/");
  EXPECT_NE(b.error().find("missing"), std::string::npos);
}

TEST(FileBrowser, ATypedNameReplacesTheOldOneAndResolvesLikeAShell) {
  const fs::path dir = viewer_test::scratchDir("browser_typed");
  touch(dir / "sub" / "x.json");
  FileBrowser b({".json"});
  ASSERT_TRUE(b.setDirectory(dir.string()));
  // Relative names join the current directory; each typed text stands on its own.
  EXPECT_EQ(b.resolveTyped("one.json"), fs::absolute(dir / "one.json").lexically_normal().string());
  EXPECT_EQ(b.resolveTyped("  two.json "), fs::absolute(dir / "two.json").lexically_normal().string());
  EXPECT_EQ(b.resolveTyped("sub/../three.json"), fs::absolute(dir / "three.json").lexically_normal().string());
  // An absolute path stays as it is.
  EXPECT_EQ(b.resolveTyped("/tmp/abs.json"), "/tmp/abs.json");
  // A directory is entered, not returned.
  EXPECT_FALSE(b.resolveTyped("sub"));
  EXPECT_EQ(fs::path(b.directory()), fs::absolute(dir / "sub").lexically_normal());
  // Home.
  const char* home = std::getenv("HOME");
  if (home && home[0] == '/') {
    EXPECT_EQ(b.resolveTyped("~/a.json"), (fs::path(home) / "a.json").lexically_normal().string());
  }
  EXPECT_FALSE(b.resolveTyped("   "));
  EXPECT_FALSE(b.error().empty());
}

TEST(RecentFiles, MostRecentFirstUniqueBoundedAndKeptAcrossRestarts) {
  const fs::path dir = viewer_test::scratchDir("recent_files");
  const std::string file = (dir / "state" / "recent.json").string();
  {
    RecentFiles r(file, 3);
    r.load();
    EXPECT_TRUE(r.list().empty());
    EXPECT_TRUE(r.add((dir / "a.json").string()));
    EXPECT_TRUE(r.add((dir / "b.json").string()));
    EXPECT_TRUE(r.add((dir / "sub/../a.json").string()));  // the same file: moved to the front
    EXPECT_TRUE(r.add((dir / "c.json").string()));
    EXPECT_TRUE(r.add((dir / "d.json").string()));  // the oldest (b) drops out
  }
  RecentFiles again(file, 3);
  again.load();
  const std::vector<std::string> want{(dir / "d.json").lexically_normal().string(),
                                      (dir / "c.json").lexically_normal().string(),
                                      (dir / "a.json").lexically_normal().string()};
  EXPECT_EQ(again.list(), want);
  // A broken state file is an empty list, and the next add repairs it.
  std::ofstream(file) << "{not json";
  RecentFiles broken(file, 3);
  broken.load();
  EXPECT_TRUE(broken.list().empty());
  EXPECT_TRUE(broken.add((dir / "e.json").string()));
  RecentFiles repaired(file, 3);
  repaired.load();
  EXPECT_EQ(repaired.list().size(), 1u);
  // A state file that cannot be written keeps the list in memory.
  RecentFiles nowhere("/proc/pteryla-no-such/recent.json", 3);
  EXPECT_FALSE(nowhere.add((dir / "f.json").string()));
  EXPECT_EQ(nowhere.list().size(), 1u);
}
