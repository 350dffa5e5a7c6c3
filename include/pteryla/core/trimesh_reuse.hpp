#pragma once
// Reusing a TriMesh's buffers across frames (the coat mesher, the mesh benchmark): every array emptied,
// its capacity kept, so the next fill allocates nothing. Kept out of trimesh.hpp, which nearly every file
// includes; a field added to TriMesh must be added to clearKeepingCapacity (trimesh.cpp) too.
#include "pteryla/core/trimesh.hpp"

namespace pteryla {

void clearKeepingCapacity(TriMesh& m);

}  // namespace pteryla
