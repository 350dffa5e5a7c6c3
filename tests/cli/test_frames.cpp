// Issue #31: frame ranges split into chunks (`frames --chunk K --task I`), sidecar checksums that let a
// requeued task redo only missing or corrupt frames, `--assemble`, and `farm slurm` scripts. Every test
// runs the real binary over moult.json at a low LOD and a small size (a frame takes ~0.1 s).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <unistd.h>

#include "run.hpp"

namespace fs = std::filesystem;

namespace {

const std::string kBuild = PTERYLA_BUILD_DIR;
const std::string kData = PTERYLA_DATA_DIR;
const std::string kScene = kData + "/scenes/moult.json";
// 7 frames over the moult (t = 0..6): feathers drop and regrow, so frames differ.
const std::string kRange = " --from 0 --to 6 --fps 1 --lod 0.1 --size 48x48";
constexpr int kFrames = 7;

bool contains(const std::string& s, const std::string& sub) { return s.find(sub) != std::string::npos; }

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string freshDir(const std::string& name) {
  const std::string d = kBuild + "/frames_farm/" + name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

std::string frame(int k) {
  char b[32];
  std::snprintf(b, sizeof b, "frame_%04d.png", k);
  return b;
}

// The whole range rendered by one process, once per test process (ctest runs each test in its own process,
// in parallel: each has its own reference directory, removed at exit).
std::string g_referenceDir;
const std::string& reference() {
  static const std::string dir = [] {
    g_referenceDir = freshDir("reference_" + std::to_string(::getpid()));
    const std::string d = g_referenceDir + "/seq";
    const RunResult r = runPteryla("frames " + kScene + kRange + " -q -o " + d);
    EXPECT_EQ(r.code, 0) << r.err;
    return d;
  }();
  return dir;
}

struct RemoveReference : ::testing::Environment {
  void TearDown() override {
    if (!g_referenceDir.empty()) fs::remove_all(g_referenceDir);
  }
};
const auto* const kRemoveReference = ::testing::AddGlobalTestEnvironment(new RemoveReference);

void expectSameFrames(const std::string& dir) {
  for (int k = 0; k < kFrames; ++k) {
    ASSERT_TRUE(fs::exists(dir + "/" + frame(k))) << frame(k);
    EXPECT_EQ(readAll(dir + "/" + frame(k)), readAll(reference() + "/" + frame(k))) << frame(k) << " differs";
  }
}

int temporaries(const std::string& d) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(d)) n += contains(e.path().filename().string(), ".tmp-");
  return n;
}

}  // namespace

TEST(Frames, ChunkedOutputIsByteIdenticalToOneProcess) {
  const std::string out = freshDir("chunked") + "/seq";
  for (const int task : {2, 0, 1}) {  // any order: each chunk is a pure function of its frame indices
    const RunResult r =
        runPteryla("frames " + kScene + kRange + " --chunk 3 --task " + std::to_string(task) + " -o " + out);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(contains(r.err, "chunk " + std::to_string(task) + " of 3")) << r.err;
  }
  EXPECT_FALSE(fs::exists(out + "/frames.json"));  // chunks write no manifest; --assemble does
  expectSameFrames(out);
  const RunResult a = runPteryla("frames " + kScene + kRange + " --assemble -o " + out);
  ASSERT_EQ(a.code, 0) << a.err;
  const auto m = nlohmann::json::parse(readAll(out + "/frames.json"));
  const auto ref = nlohmann::json::parse(readAll(reference() + "/frames.json"));
  ASSERT_EQ(m["count"].get<int>(), kFrames);
  ASSERT_EQ(m["frames"].size(), size_t(kFrames));
  for (int k = 0; k < kFrames; ++k) {
    EXPECT_EQ(m["frames"][k]["file"], frame(k));
    EXPECT_EQ(m["frames"][k]["sha256"].get<std::string>().size(), 64u);
    EXPECT_EQ(m["frames"][k]["sha256"], ref["frames"][k]["sha256"]) << k;
    EXPECT_GT(m["frames"][k]["seconds"].get<double>(), 0.0);
    EXPECT_FALSE(m["frames"][k]["host"].get<std::string>().empty());
  }
  EXPECT_EQ(m["contact_sheet"], "contact_sheet.png");
  const std::string sheet = readAll(out + "/contact_sheet.png");
  ASSERT_GT(sheet.size(), 8u);
  EXPECT_EQ(sheet.substr(1, 3), "PNG");
  EXPECT_EQ(temporaries(out), 0);
}

TEST(Frames, RerunSkipsCompleteFramesAndRedoesCorruptOnes) {
  const std::string out = freshDir("rerun") + "/seq";
  const std::string task1 = "frames " + kScene + kRange + " --chunk 3 --task 1 -o " + out;
  ASSERT_EQ(runPteryla(task1).code, 0);
  const auto before = fs::last_write_time(out + "/" + frame(4));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  RunResult r = runPteryla(task1);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "rendered 0, skipped 3 complete")) << r.err;
  EXPECT_EQ(fs::last_write_time(out + "/" + frame(4)), before);

  // A truncated PNG (checksum mismatch) and a PNG without its sidecar (crash between the two) are redone.
  const std::string bytes = readAll(out + "/" + frame(3));
  std::ofstream(out + "/" + frame(3), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  fs::remove(out + "/" + frame(5) + ".json");
  r = runPteryla("frames " + kScene + kRange + " --assemble -o " + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, "--assemble")) << r.err;
  EXPECT_TRUE(contains(r.err, frame(3) + " (checksum mismatch)")) << r.err;
  EXPECT_TRUE(contains(r.err, frame(5) + " (no sidecar)")) << r.err;
  EXPECT_TRUE(contains(r.err, frame(0) + " (missing)")) << r.err;
  EXPECT_FALSE(fs::exists(out + "/frames.json"));
  r = runPteryla(task1);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "rendered 2, skipped 1 complete")) << r.err;
  EXPECT_EQ(fs::last_write_time(out + "/" + frame(4)), before);
  EXPECT_EQ(readAll(out + "/" + frame(3)), readAll(reference() + "/" + frame(3)));

  // Other parameters (here the LOD) make a frame incomplete: the sidecar records what made it.
  r = runPteryla("frames " + kScene + " --from 0 --to 6 --fps 1 --lod 0.11 --size 48x48 --chunk 3 --task 1 -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "rendered 3")) << r.err;
}

TEST(Frames, AChunkKeepsOtherFramesAndAssembleRemovesStaleOnes) {
  const std::string out = freshDir("keep") + "/seq";
  fs::create_directories(out);
  for (const int k : {0, 1, 100}) std::ofstream(out + "/" + frame(k)) << "another task's or an older run's";
  ASSERT_EQ(runPteryla("frames " + kScene + kRange + " -q --chunk 3 --task 2 -o " + out).code, 0);
  for (const int k : {0, 1, 100}) EXPECT_TRUE(fs::exists(out + "/" + frame(k))) << frame(k);
  for (const int task : {0, 1}) {
    ASSERT_EQ(
        runPteryla("frames " + kScene + kRange + " -q --chunk 3 --task " + std::to_string(task) + " -o " + out).code,
        0);
  }
  const RunResult a = runPteryla("frames " + kScene + kRange + " --assemble -o " + out);
  ASSERT_EQ(a.code, 0) << a.err;
  EXPECT_FALSE(fs::exists(out + "/" + frame(100)));  // beyond the range: would look like part of it
  expectSameFrames(out);
}

TEST(Frames, BadChunkOrTaskExits2NamingTheOption) {
  const std::string out = freshDir("bad") + "/seq";
  const struct {
    std::string args, name;
  } cases[] = {
      {"--chunk 0 --task 0", "--chunk"},
      {"--chunk -3 --task 0", "--chunk"},
      {"--chunk 3 --task 3", "--task"},
      {"--chunk 3 --task -1", "--task"},
      {"--chunk 3", "--task"},
      {"--task 0", "--chunk"},
      {"--chunk x --task 0", "--chunk"},
      {"--chunk 3 --task 1.5", "--task"},
      {"--chunk 3 --task 0 --assemble", "--assemble"},
  };
  for (const auto& c : cases) {
    const RunResult r = runPteryla("frames " + kScene + kRange + " -o " + out + " " + c.args);
    EXPECT_EQ(r.code, 2) << c.args << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "pteryla: error:")) << r.err;
    EXPECT_TRUE(contains(r.err, c.name)) << c.args << ": " << r.err;
  }
  EXPECT_TRUE(contains(runPteryla("frames " + kScene + kRange + " -o " + out + " --chunk 3 --task 3").err, "[0, 2]"));
  EXPECT_FALSE(fs::exists(out));
  const RunResult help = runPteryla("frames --help");
  EXPECT_TRUE(contains(help.out, "0-based")) << help.out;
}

TEST(Frames, FarmSlurmDryRunWritesScriptsThatReproduceTheSequence) {
  const std::string out = freshDir("slurm_dry") + "/seq";
  const RunResult r =
      runPteryla("farm slurm " + kScene + kRange + " --chunk 3 --partition render --mem 2G --dry-run -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* s : {"#SBATCH --array=0-2", "#SBATCH --partition=render", "#SBATCH --mem=2G",
                        "--chunk 3 --task \"$SLURM_ARRAY_TASK_ID\"", "--assemble",
                        "--dependency=afterok:", "JOB=$(sbatch --parsable", "nothing was submitted"})
    EXPECT_TRUE(contains(r.out, s)) << "missing '" << s << "' in:\n" << r.out;
  EXPECT_TRUE(contains(r.out, "'" + fs::absolute(kScene).lexically_normal().string() + "'")) << r.out;
  EXPECT_TRUE(contains(r.out, "'" + fs::absolute(out).lexically_normal().string() + "'")) << r.out;
  const std::string frames = out + "/slurm/frames.sbatch", assemble = out + "/slurm/assemble.sbatch";
  ASSERT_TRUE(fs::exists(frames));
  ASSERT_TRUE(fs::exists(assemble));
  // What Slurm would do: run the array script once per task (in any order), then the assembly script.
  for (const int task : {1, 2, 0})
    ASSERT_EQ(std::system(("SLURM_ARRAY_TASK_ID=" + std::to_string(task) + " bash '" + frames + "'").c_str()), 0);
  ASSERT_EQ(std::system(("bash '" + assemble + "'").c_str()), 0);
  expectSameFrames(out);
  EXPECT_TRUE(fs::exists(out + "/frames.json"));
  EXPECT_TRUE(fs::exists(out + "/contact_sheet.png"));
}

TEST(Frames, FarmSlurmSubmitsTheArrayThenTheDependentAssembly) {
  const std::string d = freshDir("slurm_submit");
  // A stand-in sbatch: logs its arguments, prints a job id as `sbatch --parsable` does.
  fs::create_directories(d + "/bin");
  std::ofstream(d + "/bin/sbatch") << "#!/bin/sh\necho \"$@\" >> '" << d << "/sbatch.log'\nn=$(wc -l < '" << d
                                   << "/sbatch.log')\necho \"$((41 + n));cluster\"\n";
  fs::permissions(d + "/bin/sbatch", fs::perms::owner_all);
  const std::string cmd = "farm slurm " + kScene + kRange + " --chunk 2 -o " + d + "/seq";
  const RunResult s = [&] {
    const std::string saved = std::getenv("PATH") ? std::getenv("PATH") : "";
    setenv("PATH", (d + "/bin:" + saved).c_str(), 1);
    const RunResult res = runPteryla(cmd);
    setenv("PATH", saved.c_str(), 1);
    return res;
  }();
  ASSERT_EQ(s.code, 0) << s.err;
  const auto j = nlohmann::json::parse(s.out);
  EXPECT_EQ(j["array_job"].get<int>(), 42);
  EXPECT_EQ(j["tasks"].get<int>(), 4);
  EXPECT_EQ(j["assemble_job"].get<int>(), 43);
  const std::string log = readAll(d + "/sbatch.log");
  EXPECT_TRUE(
      contains(log, "--parsable " + fs::absolute(d + "/seq").lexically_normal().string() + "/slurm/frames.sbatch"))
      << log;
  EXPECT_TRUE(contains(log, "--dependency=afterok:42 ")) << log;

  // Without sbatch on PATH: exit 2 saying so, and nothing written.
  const std::string saved = std::getenv("PATH") ? std::getenv("PATH") : "";
  setenv("PATH", "/nonexistent", 1);
  const RunResult m = runPteryla(cmd.substr(0, cmd.size() - 3) + "nosub");
  setenv("PATH", saved.c_str(), 1);
  EXPECT_EQ(m.code, 2) << m.err;
  EXPECT_TRUE(contains(m.err, "sbatch not found")) << m.err;
  EXPECT_FALSE(fs::exists(d + "/nosub"));
}

// `frames --export`: each frame is exported instead of rendered, under the same contract (stable names,
// sidecars, chunks, --assemble, goldens).
namespace {

std::string exported(int k, const std::string& ext) {
  char b[32];
  std::snprintf(b, sizeof b, "frame_%04d", k);
  return b + ext;
}

}  // namespace

TEST(FramesExport, EachFrameIsTheFileExportWritesAtItsTime) {
  const std::string d = freshDir("export_usda");
  const RunResult r =
      runPteryla("frames " + kScene + " --from 0 --to 4 --fps 1 --lod 0.1 --export usda --as cards -o " + d + "/seq");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "exported 5 frames")) << r.err;
  EXPECT_FALSE(fs::exists(d + "/seq/" + frame(0)));  // no PNG
  for (const int k : {0, 4}) {                       // before and during the moult: the coat differs
    const std::string one = d + "/one_" + std::to_string(k) + ".usda";
    const RunResult e =
        runPteryla("export " + kScene + " --time " + std::to_string(k) + " --fps 1 --lod 0.1 --as cards -q -o " + one);
    ASSERT_EQ(e.code, 0) << e.err;
    EXPECT_EQ(readAll(d + "/seq/" + exported(k, ".usda")), readAll(one)) << k;
  }
  EXPECT_NE(readAll(d + "/seq/" + exported(0, ".usda")), readAll(d + "/seq/" + exported(4, ".usda")));
  const auto m = nlohmann::json::parse(readAll(d + "/seq/frames.json"));
  EXPECT_EQ(m["export"], ".usda");
  EXPECT_EQ(m["as"], "cards");
  EXPECT_FALSE(m.contains("contact_sheet"));
  ASSERT_EQ(m["frames"].size(), size_t(5));
  EXPECT_EQ(m["frames"][4]["file"], exported(4, ".usda"));
  const auto side = nlohmann::json::parse(readAll(d + "/seq/" + exported(4, ".usda") + ".json"));
  EXPECT_EQ(side["params"]["export"], ".usda");
  EXPECT_FALSE(side["params"].contains("width"));  // an export has no image size

  // Another --as is another file: nothing is skipped.
  const RunResult again =
      runPteryla("frames " + kScene + " --from 0 --to 4 --fps 1 --lod 0.1 --export .usda -o " + d + "/seq");
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_TRUE(contains(again.err, "exported 5 frames")) << again.err;
  EXPECT_TRUE(contains(readAll(d + "/seq/" + exported(2, ".usda")), "BasisCurves"));
}

TEST(FramesExport, ChunksAreByteIdenticalToOneProcessAndRerunsSkipThem) {
  const std::string d = freshDir("export_glb");
  const std::string range = " --from 0 --to 3 --fps 1 --lod 0.1 --export .glb";  // 4 frames, 2 chunks
  ASSERT_EQ(runPteryla("frames " + kScene + range + " -q -o " + d + "/one").code, 0);
  for (const int task : {1, 0}) {
    const RunResult r =
        runPteryla("frames " + kScene + range + " --chunk 2 --task " + std::to_string(task) + " -o " + d + "/chunked");
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(contains(r.err, "exported")) << r.err;
  }
  for (int k = 0; k < 4; ++k) {
    const std::string name = exported(k, ".glb");
    ASSERT_TRUE(fs::exists(d + "/chunked/" + name)) << name;
    EXPECT_EQ(readAll(d + "/chunked/" + name), readAll(d + "/one/" + name)) << name;
    EXPECT_EQ(readAll(d + "/chunked/" + name).substr(0, 4), "glTF") << name;
  }
  RunResult r = runPteryla("frames " + kScene + range + " --chunk 2 --task 1 -o " + d + "/chunked");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "exported 0, skipped 2 complete")) << r.err;
  // A truncated file is exported again; --assemble names it until then.
  const std::string f3 = d + "/chunked/" + exported(3, ".glb");
  const std::string bytes = readAll(f3);
  std::ofstream(f3, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  r = runPteryla("frames " + kScene + range + " --assemble -o " + d + "/chunked");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(contains(r.err, exported(3, ".glb") + " (checksum mismatch)")) << r.err;
  r = runPteryla("frames " + kScene + range + " --chunk 2 --task 1 -o " + d + "/chunked");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "exported 1, skipped 1 complete")) << r.err;
  EXPECT_EQ(readAll(f3), bytes);
  r = runPteryla("frames " + kScene + range + " --assemble -o " + d + "/chunked");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(d + "/chunked/contact_sheet.png"));
  const auto m = nlohmann::json::parse(readAll(d + "/chunked/frames.json"));
  const auto ref = nlohmann::json::parse(readAll(d + "/one/frames.json"));
  for (int k = 0; k < 4; ++k) EXPECT_EQ(m["frames"][k]["sha256"], ref["frames"][k]["sha256"]) << k;

  // Goldens of exported frames compare bytes: one changed byte is a failure.
  const std::string golden = d + "/golden";
  fs::copy(d + "/one", golden);
  ASSERT_EQ(runPteryla("frames " + kScene + range + " -q --assemble --golden " + golden + " -o " + d + "/chunked").code,
            0);
  std::string g = readAll(golden + "/" + exported(2, ".glb"));
  g[g.size() - 1] ^= 1;
  std::ofstream(golden + "/" + exported(2, ".glb"), std::ios::binary) << g;
  r = runPteryla("frames " + kScene + range + " --assemble --golden " + golden + " -o " + d + "/chunked");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_TRUE(contains(r.err, exported(2, ".glb") + " (the file differs from the golden)")) << r.err;
}

TEST(FramesExport, BadExportOptionsExit2NamingTheOption) {
  const std::string out = freshDir("export_bad") + "/seq";
  const struct {
    std::string args, name;
  } cases[] = {
      {"--export .obj", "--export"},
      {"--export png", "--export"},
      {"--export .glb --as curves", "--as"},
      {"--as cards", "--as"},
      {"--export .usda --as hair", "--as"},
      {"--export .usda --size 64x64", "--size"},
      {"--export .usda --style shaded", "--style"},
      {"--meters-per-unit 0.01", "--meters-per-unit"},
      {"--export .usda --meters-per-unit -1", "--meters-per-unit"},
  };
  for (const auto& c : cases) {
    const RunResult r = runPteryla("frames " + kScene + " --from 0 --to 2 --fps 1 --lod 0.1 -o " + out + " " + c.args);
    EXPECT_EQ(r.code, 2) << c.args << ": " << r.err;
    EXPECT_TRUE(contains(r.err, c.name)) << c.args << ": " << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
}

TEST(FramesExport, FarmSlurmScriptsCarryTheExport) {
  const std::string out = freshDir("export_slurm") + "/seq";
  const RunResult r = runPteryla("farm slurm " + kScene +
                                 " --from 0 --to 3 --fps 1 --lod 0.1 --chunk 2 --export USDA --as instances "
                                 "--meters-per-unit 0.01 --dry-run -o " +
                                 out);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "--export .usda --as 'instances' --meters-per-unit 0.01")) << r.out;
  for (const int task : {0, 1})
    ASSERT_EQ(std::system(
                  ("SLURM_ARRAY_TASK_ID=" + std::to_string(task) + " bash '" + out + "/slurm/frames.sbatch'").c_str()),
              0);
  ASSERT_EQ(std::system(("bash '" + out + "/slurm/assemble.sbatch'").c_str()), 0);
  for (int k = 0; k < 4; ++k) EXPECT_TRUE(contains(readAll(out + "/" + exported(k, ".usda")), "PointInstancer")) << k;
  EXPECT_TRUE(fs::exists(out + "/frames.json"));
}
