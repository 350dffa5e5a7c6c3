#pragma once
// Output guards: no NaN or infinity ever leaves pteryla in a file or an image. Writers call these on the
// data they are about to write, before creating the file.
#include <string>

#include "pteryla/core/trimesh.hpp"

namespace pteryla {

// Throws pteryla::Error naming `file` and the first offending element ("vertex 17 position") when any
// float attribute of `m` is NaN or infinite.
void requireFinite(const TriMesh& m, const std::string& file);

}  // namespace pteryla
