// AtomicFile, the memory ceiling and the finite-output guard (issue #21).
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <csignal>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/finite.hpp"
#include "pteryla/core/limits.hpp"

namespace fs = std::filesystem;
using namespace pteryla;

namespace {
std::string readAll(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
std::string freshDir(const std::string& name) {
  const std::string d = std::string(PTERYLA_BUILD_DIR) + "/core_" + name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}
size_t entries(const std::string& d) {
  size_t n = 0;
  for (auto it = fs::directory_iterator(d); it != fs::directory_iterator(); ++it) ++n;
  return n;
}
}  // namespace

TEST(AtomicFile, ReplacesTheFileOnlyOnCommit) {
  const std::string d = freshDir("atomic_commit");
  const std::string p = d + "/out.txt";
  writeFileAtomic(p, "old");
  {
    AtomicFile f(p);
    f.write("new contents");
    EXPECT_EQ(readAll(p), "old");  // not visible before commit
    EXPECT_TRUE(fs::exists(f.tempPath()));
    f.commit();
  }
  EXPECT_EQ(readAll(p), "new contents");
  {
    AtomicFile f(p);
    f.write("abandoned");
  }  // no commit: an exception on the way out, say
  EXPECT_EQ(readAll(p), "new contents");
  EXPECT_EQ(entries(d), 1u) << "temporary file left behind";
}

TEST(AtomicFile, AWriteErrorKeepsTheOldFileAndNamesIt) {
  const std::string d = freshDir("atomic_error");
  const std::string p = d + "/out.bin";
  writeFileAtomic(p, "previous");
  // Files may not grow past 4 KB: writes beyond fail with EFBIG, as on a full disk.
  struct sigaction ignore {
  }, before{};
  ignore.sa_handler = SIG_IGN;
  sigaction(SIGXFSZ, &ignore, &before);
  rlimit old{};
  getrlimit(RLIMIT_FSIZE, &old);
  rlimit lim = old;
  lim.rlim_cur = 4096;
  setrlimit(RLIMIT_FSIZE, &lim);
  std::string message;
  try {
    writeFileAtomic(p, std::string(3 << 20, 'x'));
  } catch (const Error& e) {
    message = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &old);
  sigaction(SIGXFSZ, &before, nullptr);
  EXPECT_NE(message.find(p), std::string::npos) << message;
  EXPECT_NE(message.find("unchanged"), std::string::npos) << message;
  EXPECT_EQ(readAll(p), "previous");
  EXPECT_EQ(entries(d), 1u);
}

TEST(AtomicFile, AnUnwritableDirectoryIsAnError) {
  EXPECT_THROW(writeFileAtomic("/proc/definitely/not/here.txt", "x"), Error);
}

TEST(MemoryCeiling, RefusesAboveItNamingFileElementAndFlag) {
  const double saved = memoryLimitBytes();
  setMemoryLimitBytes(1e9);
  EXPECT_NO_THROW(requireMemory(0.9e9, "a thing", "f.json", "key"));
  try {
    requireMemory(2e9, "a coat", "f.json", "tracts[0].count");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_EQ(e.file(), "f.json");
    EXPECT_EQ(e.element(), "tracts[0].count");
    EXPECT_NE(m.find("--max-memory"), std::string::npos) << m;
    EXPECT_NE(m.find("2 GB"), std::string::npos) << m;
  }
  EXPECT_THROW(requireMemory(std::numeric_limits<double>::infinity(), "x", "", ""), Error);
  EXPECT_THROW(requireMemory(std::nan(""), "x", "", ""), Error);
  setMemoryLimitBytes(saved);
}

TEST(FiniteGuard, NamesTheFirstNonFiniteVertex) {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.indices = {0, 1, 2};
  EXPECT_NO_THROW(requireFinite(m, "out.obj"));
  m.uvGlobal = {{0, 0}, {0, 0}, {std::nanf(""), 0}};
  try {
    requireFinite(m, "out.obj");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "out.obj");
    EXPECT_EQ(e.element(), "vertex 2");
  }
  m.uvGlobal.clear();
  m.positions[1].y = std::numeric_limits<float>::infinity();
  EXPECT_THROW(requireFinite(m, "out.obj"), Error);
}
