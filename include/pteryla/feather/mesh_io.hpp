#pragma once
// Export of render meshes (one feather or a whole coat) as Wavefront OBJ or PLY, with texture
// coordinates. OBJ carries one set of texture coordinates (vt) and normals (vn); PLY carries every
// TriMesh attribute that is present as vertex properties: x y z, nx ny nz, u v (the chosen set),
// u_barb v_barb u_growth v_growth, alpha, sheath, barb_count, feather_id. Unwritable paths throw
// pteryla::Error naming the file.
#include <string>

#include "pteryla/core/trimesh.hpp"

namespace pteryla::feather {

enum class UvSet { Global, Barb, Growth };

void writeObj(const std::string& path, const TriMesh& mesh, UvSet uv = UvSet::Global);

struct PlyOptions {
  bool binary = true;        // binary_little_endian (compact for coats); false = ascii
  UvSet uv = UvSet::Global;  // which set becomes the standard u, v properties
};
void writePly(const std::string& path, const TriMesh& mesh, const PlyOptions& opt = {});

// Writes OBJ or PLY by the extension of `path` (".obj" / ".ply", case-insensitive); Error otherwise.
void writeMesh(const std::string& path, const TriMesh& mesh);

}  // namespace pteryla::feather
