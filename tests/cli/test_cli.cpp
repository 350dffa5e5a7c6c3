#include <gtest/gtest.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "run.hpp"

namespace {
bool contains(const std::string& s, const std::string& sub) { return s.find(sub) != std::string::npos; }
int lineCount(const std::string& s) {
  int n = 0;
  for (char c : s) n += (c == '\n');
  return n;
}
}  // namespace

TEST(Cli, MissingSceneExits2WithOneLine) {
  auto r = runPteryla("render does-not-exist.json --out x.png");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "pteryla: error:")) << r.err;
  EXPECT_TRUE(contains(r.err, "does-not-exist.json")) << r.err;
  EXPECT_EQ(lineCount(r.err), 1) << r.err;
}

TEST(Cli, EverySubcommandHasHelp) {
  for (const char* sub : {"render", "check", "bench", "export", "feather", "frames", "farm slurm", "diff"}) {
    auto r = runPteryla(std::string(sub) + " --help");
    EXPECT_EQ(r.code, 0) << sub;
    EXPECT_TRUE(contains(r.out, "--quiet")) << sub << r.out;
  }
  auto top = runPteryla("--help");
  EXPECT_EQ(top.code, 0);
  for (const char* sub : {"render", "check", "bench", "export", "feather", "frames", "farm", "diff"})
    EXPECT_TRUE(contains(top.out, sub));
}

TEST(Cli, UnknownOptionExits2) {
  auto r = runPteryla("render scene.json --out x.png --bogus");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "pteryla: error:"));
}

TEST(Cli, MalformedJsonNamesFileAndLine) {
  const auto p = writeTemp("bad_syntax.json", "{\n  \"pteryla\": 1,\n  \"mesh\": \"x.obj\",,\n}\n");
  auto r = runPteryla("check " + p);
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "bad_syntax.json")) << r.err;
  EXPECT_TRUE(contains(r.err, "line 3")) << r.err;
  EXPECT_TRUE(r.out.empty());
}

TEST(Cli, UnknownSceneKeyIsRejectedWithItsPath) {
  const auto mesh = writeTemp("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto p = writeTemp("unknown_key.json",
                           "{\"pteryla\": 1, \"mesh\": \"tri.obj\", \"render\": {\"lod\": 0.5, \"colour\": 1}}");
  auto r = runPteryla("check " + p);
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "render.colour")) << r.err;
  (void)mesh;
}

TEST(Cli, MissingVersionAndOutOfRangeValues) {
  writeTemp("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  auto r = runPteryla("check " + writeTemp("noversion.json", "{\"mesh\": \"tri.obj\"}"));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "pteryla")) << r.err;
  r = runPteryla("check " +
                 writeTemp("badlod.json", "{\"pteryla\": 1, \"mesh\": \"tri.obj\", \"render\": {\"lod\": 7}}"));
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "render.lod")) << r.err;
}

TEST(Cli, BadSizeOptionExits2) {
  writeTemp("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  auto r = runPteryla("render " + std::string(PTERYLA_BUILD_DIR) + "/tri.obj --out x.png --size 12by3");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "--size")) << r.err;
}

TEST(Cli, EmptyAndNanMeshesExit2NamingTheProblem) {
  const auto empty = writeTemp("empty_mesh.obj", "# nothing here\n");
  auto r = runPteryla("check " + empty);
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(contains(r.err, "empty_mesh.obj")) << r.err;
  const auto nan = writeTemp("nan_mesh.obj", "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n");
  r = runPteryla("render " + nan + " --out " + std::string(PTERYLA_BUILD_DIR) + "/nan.png -q");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(contains(r.err, "nan_mesh.obj")) << r.err;
  EXPECT_EQ(lineCount(r.err), 1) << r.err;
}

TEST(Cli, MissingFeatherFileInSceneNamesTheKey) {
  writeTemp("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto p = writeTemp("missing_feather.json",
                           "{\"pteryla\": 1, \"mesh\": \"tri.obj\", \"feathers\": {\"c\": \"nope.json\"}}");
  auto r = runPteryla("check " + p);
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "feathers.c")) << r.err;
}

TEST(Cli, FeatherCommandWritesMeshAndRejectsBadFiles) {
  const std::string out = std::string(PTERYLA_BUILD_DIR) + "/cli_contour.obj";
  auto r =
      runPteryla("feather " + std::string(PTERYLA_DATA_DIR) + "/feathers/contour.json --out " + out + " --lod 0.5 -q");
  EXPECT_EQ(r.code, 0) << r.err;
  FILE* f = fopen(out.c_str(), "r");
  ASSERT_NE(f, nullptr);
  fclose(f);
  const auto bad = writeTemp("bad_feather.json", "{\"pteryla_feather\": 1, \"rachis\": {\"length\": -1}}");
  r = runPteryla("feather " + bad + " --out x.obj");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "bad_feather.json")) << r.err;
}

TEST(Cli, BenchPrintsEveryStageWithRealTimings) {
  auto r = runPteryla("bench " + std::string(PTERYLA_DATA_DIR) + "/scenes/patch.json --size 64x64 -q");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* k : {"load", "distribute", "interpolate", "pack", "pack_repeat", "mesh", "render"}) {
    ASSERT_TRUE(j.contains(k)) << k;
    EXPECT_GT(j[k].get<double>(), 0.0) << k << " was not timed";  // every stage ran once
  }
  EXPECT_GT(j["triangles"].get<double>(), 0.0);
  EXPECT_GT(j["peak_rss_mb"].get<double>(), 0.0);
}

// bench reports the mesh stage's unplaced store: one mesh per feather without instancing, far fewer with
// --instance-tolerance; a tolerance out of range is refused, naming the option.
TEST(Cli, BenchReportsWhatInstancingSaves) {
  const std::string scene = std::string(PTERYLA_DATA_DIR) + "/scenes/sphere_250.json";
  auto off = runPteryla("bench " + scene + " --size 64x64 -q");
  ASSERT_EQ(off.code, 0) << off.err;
  auto on = runPteryla("bench " + scene + " --size 64x64 --instance-tolerance 0.02 -q");
  ASSERT_EQ(on.code, 0) << on.err;
  const auto a = nlohmann::json::parse(off.out), b = nlohmann::json::parse(on.out);
  EXPECT_EQ(a["representatives"].get<size_t>(), a["feathers"].get<size_t>());
  EXPECT_LT(b["representatives"].get<size_t>(), b["feathers"].get<size_t>() / 2);
  EXPECT_GE(b["unplaced_meshes"].get<size_t>(), b["representatives"].get<size_t>());
  EXPECT_LT(b["unplaced_mb"].get<double>(), 0.5 * b["unplaced_mb_unshared"].get<double>());
  EXPECT_EQ(a["triangles"], b["triangles"]);
  auto bad = runPteryla("bench " + scene + " --size 64x64 --instance-tolerance 0.5 -q");
  EXPECT_EQ(bad.code, 2);
  EXPECT_TRUE(contains(bad.err, "--instance-tolerance")) << bad.err;
}
