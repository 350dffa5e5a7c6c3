#pragma once
#include <string>

#include "pteryla/export.hpp"

namespace pteryla {

// Resolves `path` relative to the directory containing `baseFile` (absolute paths are kept).
PTERYLA_API std::string resolveRelative(const std::string& baseFile, const std::string& path);
// Lower-case extension with the dot (".obj"), empty when none.
PTERYLA_API std::string extensionOf(const std::string& path);
PTERYLA_API bool fileExists(const std::string& path);

}  // namespace pteryla
