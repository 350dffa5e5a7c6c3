#pragma once
// Resource ceilings checked before allocating (docs/limits.md). pteryla estimates the memory a request
// needs (follicles, barbs, triangles, pixels, textures, declared mesh counts) and refuses it with a
// pteryla::Error naming the file and key when the estimate exceeds the ceiling, instead of running the
// machine out of memory. The ceiling defaults to kDefaultMemoryLimitGb; `pteryla --max-memory GB` raises it.
#include <string>

#include "pteryla/export.hpp"

namespace pteryla {

constexpr double kDefaultMemoryLimitGb = 4.0;

// Process-wide ceiling in bytes.
PTERYLA_API double memoryLimitBytes();
PTERYLA_API void setMemoryLimitBytes(double bytes);

// Throws Error(file, element) when `bytes` exceeds the ceiling:
// "<what> needs about 6.3 GB, above the memory ceiling of 4 GB (raise it with --max-memory GB)".
PTERYLA_API void requireMemory(double bytes, const std::string& what, const std::string& file,
                               const std::string& element);

}  // namespace pteryla
