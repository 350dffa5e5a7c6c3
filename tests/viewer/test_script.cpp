// Scripted sessions: parsing, argument checking with line numbers, and a session of panel actions whose
// saved scene reloads identically.
#include <gtest/gtest.h>

#include <sstream>

#include "document.hpp"
#include "fixtures.hpp"
#include "pteryla/core/error.hpp"
#include "script.hpp"

using namespace pteryla;
using namespace pteryla::viewer;

TEST(Script, ParsesCommentsQuotesAndLines) {
  const auto cmds = parseScript("# header\n\nload \"my dir/x.json\"  # trailing\n  relax 20 spinal\r\nquit\n", "s.txt");
  ASSERT_EQ(cmds.size(), 3u);
  EXPECT_EQ(cmds[0].line, 3);
  EXPECT_EQ(cmds[0].verb, "load");
  EXPECT_EQ(cmds[0].args, std::vector<std::string>{"my dir/x.json"});
  EXPECT_EQ(cmds[1].line, 4);
  EXPECT_EQ(cmds[1].args, (std::vector<std::string>{"20", "spinal"}));
  EXPECT_EQ(cmds[2].verb, "quit");
  try {
    parseScript("ok\nload \"unterminated\n", "s.txt");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "line 2");
    EXPECT_EQ(e.file(), "s.txt");
  }
}

TEST(Script, BadCommandsNameTheLine) {
  Document d;
  std::ostringstream out;
  auto run = [&](const std::string& text) {
    for (const auto& c : parseScript(text, "t.txt")) runDocumentCommand(d, c, "t.txt", out);
  };
  auto expectLine = [&](const std::string& text, const std::string& line, const std::string& what) {
    try {
      run(text);
      FAIL() << "no error for: " << text;
    } catch (const Error& e) {
      EXPECT_EQ(e.element(), line) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expectLine("relax 3\n", "line 1", "no scene is open");
  run("load " + viewer_test::dataPath("scenes/patch.json") + "\n");
  expectLine("\nfrobnicate 1\n", "line 2", "unknown command");
  expectLine("relax many\n", "line 1", "expected a number");
  expectLine("relax -3\n", "line 1", "non-negative integer");
  expectLine("count 5 10\n", "line 1", "out of range");
  expectLine("lod 0\n", "line 1", "(0, 1]");
  expectLine("lift 0 0.5\n", "line 1", "control index 0 out of range");
  expectLine("save\n", "line 1", "usage");
  expectLine("set /render/brdf/h 9\n", "line 1", "brdf.h");
  EXPECT_FALSE(runDocumentCommand(d, parseScript("screenshot x.png", "t")[0], "t", out));  // the app's
}

TEST(Script, SessionSavesASceneThatReloadsIdentically) {
  const std::string dir = viewer_test::scratchDir("script_session");
  const std::string saved = dir + "/session.json";
  const std::string text = "load " + viewer_test::dataPath("scenes/patch.json") + "\n" +
                           "count 0 20\n"
                           "relax 2\n"
                           "lod 0.2\n"
                           "render-lod 0.6\n"
                           "pack\n"
                           "time 0.5\n"
                           "control 0 0.05 0 0.6\n"
                           "lift 0 0.8\n"
                           "keyframe 0 0\n"
                           "random 0 0.3\n"
                           "vector 0.2 0.05 0 1 0 0.2\n"
                           "brush -0.3 0.05 0 0.25 35\n"
                           "set /moult/duration 4\n"
                           "brdf 1.5 0.1\n"
                           "echo done\n"
                           "save " +
                           saved + "\n";
  Document d;
  std::ostringstream out;
  for (const auto& c : parseScript(text, "session.txt")) {
    ASSERT_TRUE(runDocumentCommand(d, c, "session.txt", out)) << c.verb;
    ASSERT_TRUE(d.waitIdle()) << "line " << c.line << ": " << d.takeError().value_or("");
  }
  EXPECT_EQ(out.str(), "done\n");
  const pipeline::Scene back = pipeline::loadScene(saved);
  EXPECT_EQ(pipeline::sceneToJson(back, saved), readJsonFile(saved));
  EXPECT_EQ(back.tracts[0]["count"], 20);
  EXPECT_DOUBLE_EQ(back.time, 0.5);
  // The preview level of detail stays the viewer's; the scene keeps its own render.lod (#28).
  EXPECT_DOUBLE_EQ(d.lod(), 0.2);
  EXPECT_DOUBLE_EQ(back.render.lod, 0.6);
  EXPECT_DOUBLE_EQ(back.render.brdfH, 0.1);
  EXPECT_EQ(back.controls[0]["keys"][0]["lift"], 0.8);
  EXPECT_EQ(back.moult["duration"], 4);
  // Saving to the document's own file is fine; once it lives elsewhere, replacing `saved` needs
  // "overwrite".
  const auto saves = parseScript(
      "save " + saved + "\nsave " + dir + "/other.json\nsave " + saved + "\nsave " + saved + " overwrite", "s");
  runDocumentCommand(d, saves[0], "s", out);
  runDocumentCommand(d, saves[1], "s", out);
  EXPECT_THROW(runDocumentCommand(d, saves[2], "s", out), Error);
  EXPECT_NO_THROW(runDocumentCommand(d, saves[3], "s", out));
  // The check command prints the checker's metrics.
  std::ostringstream metrics;
  runDocumentCommand(d, parseScript("check", "s")[0], "s", metrics);
  const Json m = Json::parse(metrics.str());
  EXPECT_EQ(m["follicles"], 20);
  EXPECT_TRUE(m["coverage"].is_number());
}
