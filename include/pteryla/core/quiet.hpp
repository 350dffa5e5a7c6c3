#pragma once
// Third-party libraries (OpenMesh's omerr/omlog, libpng's warnings through OpenImageIO) print to stderr
// on their own. pteryla reports every problem itself, so under `--quiet` those lines are dropped:
// setQuiet(true) once, then wrap library calls in a QuietThirdParty scope.
#include "pteryla/export.hpp"

namespace pteryla {

PTERYLA_API void setQuiet(bool quiet);
PTERYLA_API bool quiet();

// While alive and quiet() holds, file descriptor 2 points at /dev/null (restored on destruction).
class QuietThirdParty {
 public:
  QuietThirdParty();
  ~QuietThirdParty();
  QuietThirdParty(const QuietThirdParty&) = delete;
  QuietThirdParty& operator=(const QuietThirdParty&) = delete;

 private:
  int saved_ = -1;
};

}  // namespace pteryla
