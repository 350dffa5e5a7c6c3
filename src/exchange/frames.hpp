#pragma once
// What the writers share: the coat sampled at each export time, in plain arrays.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "pteryla/core/trimesh.hpp"
#include "pteryla/exchange/coat_export.hpp"
#include "pteryla/pipeline/pipeline.hpp"

namespace pteryla::exchange::detail {

struct FeatherRecord {
  uint32_t id = 0;  // index into Pipeline::feathers()
  uint32_t tract = 0;
  uint32_t layer = 0;  // position in the packing order, 0 = bottom
  float age = 1;
  bool present = true;
  uint32_t material = 0;  // index into ExportFrame::materials (by feather definition name)
  // Placement of the feather-local frame: x along the shaft, y to the left vane, z dorsal (unit).
  glm::dvec3 origin{0}, x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
};

struct ExportFrame {
  double time = 0;
  TriMesh skin;
  TriMesh coat;  // as the pipeline meshed it: drape-trimmed triangles are collapsed (a, a, a), not removed
  std::vector<pipeline::CoatDrawRange> ranges;  // per present feather, bottom layer first
  std::vector<FeatherRecord> feathers;          // every feather, present or not, by id
};

struct ExportScene {
  std::vector<pipeline::CoatMaterial> materials;
  std::vector<std::string> tractNames;
  glm::vec3 skinColor{0.78f, 0.62f, 0.52f};
  std::vector<ExportFrame> frames;
  double fps = 24;
  double metersPerUnit = 1;
};

// Writers, through AtomicFile; they return the bytes written. glTF builds the whole file in memory; USD
// streams it (formatted attribute by attribute, large arrays chunk by chunk).
size_t writeGltf(const ExportScene& s, const std::string& path, bool binary);
struct UsdCounts {
  size_t curves = 0, instances = 0, prototypes = 0;
};
size_t writeUsda(const ExportScene& s, const std::string& path, CoatAs as, int prototypesPerMaterial,
                 UsdCounts& counts);

// Shortest decimal text that reads back as exactly `v` ("0", "1.5", "-2.25e-08").
std::string shortest(float v);
std::string shortest(double v);

// PNG bytes of an RGBA8 image (top row first), uncompressed deflate blocks: deterministic and small code.
std::vector<unsigned char> encodePng(int width, int height, const std::vector<uint8_t>& rgba);

// Colour texture of a material as image bytes and MIME type: its texture file, else the bundled
// pattern file data/textures/<pattern>.png, else the pattern synthesised. False when it has none.
bool materialImage(const pipeline::CoatMaterial& m, std::vector<unsigned char>& bytes, std::string& mime);

// Barb polylines recovered from a vane range of the coat mesh (feather/mesh.hpp layout: per kept barb two
// triangle strips around its centre row, rows of `rowLength` vertices). A barb is the centre-row vertices
// centre .. centre + count - 1, rachis to tip; the side rows are centre -/+ rowLength. A barb the drape
// trimmed is cut where its first fully collapsed segment starts (and left out below two points).
struct BarbRow {
  uint32_t centre = 0, rowLength = 0, count = 0;
};
void vaneBarbs(const TriMesh& coat, uint32_t firstIndex, uint32_t indexCount, std::vector<BarbRow>& barbs);
// The rachis of a shaft range (rings of shaftSides + 1 vertices closing at an apex; feather/mesh.hpp):
// per ring its centre and diameter, then the apex (diameter 0). Empty when the range does not have
// that layout or its first ring was trimmed.
void rachisCurve(const TriMesh& coat, uint32_t firstIndex, uint32_t indexCount, std::vector<glm::vec3>& points,
                 std::vector<float>& widths, std::vector<uint32_t>& vertexOfPoint);

inline bool collapsed(const uint32_t* tri) { return tri[1] == tri[0] && tri[2] == tri[0]; }

}  // namespace pteryla::exchange::detail
