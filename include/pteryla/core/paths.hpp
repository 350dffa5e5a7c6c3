#pragma once
#include <string>

namespace pteryla {

// Resolves `path` relative to the directory containing `baseFile` (absolute paths are kept).
std::string resolveRelative(const std::string& baseFile, const std::string& path);
// Lower-case extension with the dot (".obj"), empty when none.
std::string extensionOf(const std::string& path);
bool fileExists(const std::string& path);

}  // namespace pteryla
