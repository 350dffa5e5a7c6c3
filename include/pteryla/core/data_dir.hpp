#pragma once
// The bundled data directory (feathers, textures, meshes, scenes: data/ in the source tree,
// <prefix>/share/pteryla once installed). Part of the installed host API: standard headers only.
//
// dataDirectory() answers, first match wins:
//   1. the directory given to setDataDirectory();
//   2. the environment variable PTERYLA_DATA_DIR (PTERYLA_DATA, its older name, is still read);
//   3. the directory installed next to the library that holds this code: <libdir>/../share/pteryla
//      (found through dladdr; used only when it holds feathers/contour.json);
//   4. the source tree's data/ directory, compiled in (in-tree builds, tests).
#include <string>

#include "pteryla/export.hpp"

namespace pteryla {

// Overrides the lookup for this process ("" = back to the lookup above). Thread-safe.
PTERYLA_API void setDataDirectory(const std::string& dir);
PTERYLA_API std::string dataDirectory();

}  // namespace pteryla
