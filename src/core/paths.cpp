#include "pteryla/core/paths.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace pteryla {

std::string resolveRelative(const std::string& baseFile, const std::string& path) {
  namespace fs = std::filesystem;
  fs::path p(path);
  if (p.is_absolute() || baseFile.empty()) return p.lexically_normal().string();
  return (fs::path(baseFile).parent_path() / p).lexically_normal().string();
}

std::string extensionOf(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

bool fileExists(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

}  // namespace pteryla
