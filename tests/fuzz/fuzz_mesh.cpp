// Fuzz target: the mesh readers (coat::loadSkinMesh: own OBJ reader; PLY, OFF, STL through OpenMesh's
// readers) followed by validation and triangulation. The readers choose the format by extension, so the
// extension is taken from the content: "ply" -> .ply, "OFF" in the first line's magic -> .off, "solid" or a
// NUL byte in the first 84 bytes (binary STL header/count) -> .stl, anything else -> .obj. The last byte's
// low bit turns on repair, so both the strict and the repairing paths are covered.
//
// No input is skipped: the mesh header checks (src/coat/mesh_header.cpp) refuse every PLY/OFF/STL layout
// that OpenMesh would loop on, crash on or read differently from the file, before OpenMesh sees it. Two
// such layouts this target found are in tests/fuzz/corpus/mesh/ as regression inputs.
#include <OpenMesh/Core/System/omstream.hh>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "fuzz_common.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/error.hpp"

namespace {

const char* extensionFor(const uint8_t* data, size_t size) {
  auto startsWith = [&](const char* s) { return size >= std::strlen(s) && std::memcmp(data, s, std::strlen(s)) == 0; };
  if (startsWith("ply")) return ".ply";
  // OFF magic: [ST][C][N][4][n]OFF
  for (size_t i = 0; i + 3 <= size && i < 6; ++i)
    if (std::memcmp(data + i, "OFF", 3) == 0) return ".off";
  if (startsWith("solid")) return ".stl";
  if (size >= 84 && std::memchr(data, 0, 84) != nullptr) return ".stl";
  return ".obj";
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // OpenMesh logs every rejected file to std::cerr: keep the fuzzer's output readable.
  omerr().disable();
  omout().disable();
  omlog().disable();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string ext = extensionFor(data, size);
  const std::string path = pteryla::fuzz::writeInput(data, size, "mesh" + ext);
  pteryla::coat::MeshLoadOptions options;
  options.repair = size > 0 && (data[size - 1] & 1) != 0;
  try {
    (void)pteryla::coat::loadSkinMesh(path, options);
  } catch (const pteryla::Error&) {
    // bad input: expected
  }
  return 0;
}
