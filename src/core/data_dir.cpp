// Where the bundled data lives at run time (include/pteryla/core/data_dir.hpp).
#include "pteryla/core/data_dir.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>

namespace pteryla {
namespace {

std::mutex gMutex;
std::string gExplicit;

// <directory of the binary holding this code>/<PTERYLA_DATA_RELATIVE>, when it holds the default
// feather; "" otherwise (an executable linked with the static archives finds nothing there).
std::string besideLibrary() {
  Dl_info info{};
  if (dladdr(static_cast<const void*>(&gMutex), &info) == 0 || !info.dli_fname || !*info.dli_fname) return {};
  std::error_code ec;
  const std::filesystem::path lib = std::filesystem::canonical(info.dli_fname, ec);
  if (ec) return {};
  const std::filesystem::path dir = (lib.parent_path() / PTERYLA_DATA_RELATIVE).lexically_normal();
  if (!std::filesystem::is_regular_file(dir / "feathers" / "contour.json", ec)) return {};
  return dir.string();
}

}  // namespace

void setDataDirectory(const std::string& dir) {
  std::lock_guard<std::mutex> lock(gMutex);
  gExplicit = dir;
}

std::string dataDirectory() {
  {
    std::lock_guard<std::mutex> lock(gMutex);
    if (!gExplicit.empty()) return gExplicit;
  }
  for (const char* name : {"PTERYLA_DATA_DIR", "PTERYLA_DATA"})
    if (const char* e = std::getenv(name); e && *e) return e;
  static const std::string installed = besideLibrary();
  if (!installed.empty()) return installed;
  return PTERYLA_DATA_DIR;
}

}  // namespace pteryla
