#pragma once
// The coat's draw plan (Streit 2003, 7.1.2 and 7.2): which feathers and which of their triangles a
// frame draws, in which order, and in how many submissions. Pure CPU, no GL: the Renderer uploads
// indices() once per frame and issues one draw per run; tests check the plan without a context.
//
// Colour pass, per frame (build):
//  - culling: a feather whose bounding sphere lies outside the view frustum is skipped. With the
//    occluders' depth tiles (the skin's depth, read back), so is a feather whose box lies behind
//    them everywhere; within the other feathers, each part is cut into chunks of kChunkTriangles
//    consecutive triangles (a few barbs) with their own boxes: a chunk behind the occluders is
//    skipped, one wholly in front of them kept whole, the others tested per triangle (its nearest
//    vertex against the farthest depth over the tiles it touches; triangles outside the viewport go
//    too). DrawOptions::subpixelCulling also drops triangles that cover no pixel centre. Every test
//    is conservative: what is dropped would have produced no fragment.
//  - order: layer order (the order of the ranges), each feather's parts in octant order and each
//    part forward or backward (FeatherDrawRange).
//  - runs: the surviving indices in that order, split into maximal runs of one material.
// Shadow pass (shadowRuns, view-independent): every triangle, in layer order, from the coat's own
// index list, one run per stretch of consecutive feathers of one material that are contiguous in it.
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "pteryla/render/camera.hpp"

namespace pteryla::render {

// Where one feather's triangles sit in the coat index buffer, and how to order them.
// Indices [firstIndex, firstIndex + indexCount) of coat.indices belong to the feather (a multiple of
// 3). When partCount is all zero the range is drawn as one block, front-to-back or back-to-front
// along the shaft by the view direction (fallback). Otherwise the range is split into consecutive
// parts in the order shaft, left vane, right vane, afterfeather, with partCount[k] indices each
// (summing to indexCount; any may be 0). The mesher emits each vane's barbs in barb order from the
// feather base to the tip, each barb's triangles from the rachis toward the barb tip.
//
// Octant rule (7.1.2), with v the direction from `origin` to the eye and Z = axisX x axisY (dorsal):
//  - parts far from the viewer first: if v.Z > 0 (dorsal view) afterfeather, right/left vanes by
//    v.axisY (v.axisY > 0: the left vane is nearer, so right vane first), shaft last; if v.Z <= 0
//    the shaft first, then the vanes, the afterfeather last;
//  - inside a vane (and for the fallback block): when the tip is nearer (v.axisX > 0) barbs are drawn
//    base-to-tip (forward), else tip-to-base (backward). Backward order reverses whole triangles, so
//    each barb is then also drawn tip-to-rachis (a documented simplification of the thesis' separate
//    per-barb direction choice).
// v is taken per feather (from its own origin), so near views stay locally correct (7.1.2).
struct FeatherDrawRange {
  uint32_t firstIndex = 0;
  uint32_t indexCount = 0;
  uint32_t material = 0;                 // index into setMaterials(); out of range -> Error
  glm::vec3 origin{0.0f};                // follicle position, world
  glm::vec3 axisX{1.0f, 0.0f, 0.0f};     // feather-local +x (shaft, base to tip) in world, unit
  glm::vec3 axisY{0.0f, 1.0f, 0.0f};     // feather-local +y (toward the left vane) in world, unit
  uint32_t partCount[4] = {0, 0, 0, 0};  // shaft, left vane, right vane, afterfeather
};

// One draw submission: indices [first, first + count) of its pass's index list, one material.
struct DrawRun {
  uint32_t material = 0;
  size_t first = 0;
  size_t count = 0;
};

// Window depth of what hides the coat (the skin), reduced to kTile x kTile pixel tiles.
struct DepthTiles {
  static constexpr int kTile = 8;  // pixels
  int tilesX = 0, tilesY = 0;
  std::vector<float> nearest;  // per tile, row-major, bottom row first (GL window order)
  std::vector<float> farthest;
  // From a width x height window depth buffer in [0, 1], bottom row first (glReadPixels order).
  void build(const float* depth, int width, int height);
};

struct DrawOptions {
  bool viewDependentOrder = true;  // false: every part forward, in stored order
  // Drop triangles that cover no sample point (within 0.05 px): no pixel centre, or with multisampling
  // none of the pixels' sample positions (samplePositions). Exact when samplePositions are the
  // rasterizer's; the renderer queries them (GL_SAMPLE_POSITION) for a multisampled target.
  bool subpixelCulling = false;
  // Where the rasterizer samples coverage within a pixel, each in [0,1)^2 from the pixel's lower-left
  // corner; empty: the pixel centre (0.5, 0.5), single-sample rasterization.
  std::vector<glm::vec2> samplePositions;
};

// Triangles and feathers of one colour-pass plan (RenderStats takes them over).
struct DrawCounts {
  size_t triangles = 0;          // drawn
  size_t backwardParts = 0;      // non-empty parts of drawn feathers ordered backward
  size_t culledFeathers = 0;     // outside the view frustum
  size_t occludedFeathers = 0;   // wholly behind the occluders
  size_t occludedTriangles = 0;  // of drawn feathers: behind the occluders or outside the viewport
  size_t subpixelTriangles = 0;  // of drawn feathers: covering no pixel centre
};

class DrawPlan {
 public:
  static constexpr uint32_t kChunkTriangles = 32;  // two barbs at full detail

  // Throws pteryla::Error (element "ranges[i]") for ranges that do not fit `indexCount` indices,
  // do not span whole triangles, whose parts do not sum to the range, or that share indices.
  static void validateRanges(const std::vector<FeatherDrawRange>& ranges, size_t indexCount);

  // Keeps a copy of the coat's positions and indices and prepares each feather's chunks and bounds.
  // `ranges` must pass validateRanges and `indices` address `positions`. Empty `ranges` with a
  // non-empty mesh: the whole mesh is one feather of material 0.
  void setCoat(const std::vector<glm::vec3>& positions, const std::vector<uint32_t>& indices,
               const std::vector<FeatherDrawRange>& ranges);
  // The same without the copy: the plan reads `positions` and `indices` where they are whenever it
  // builds, so both must stay alive and unchanged until the next setCoat or setCoatReference.
  void setCoatReference(const std::vector<glm::vec3>& positions, const std::vector<uint32_t>& indices,
                        const std::vector<FeatherDrawRange>& ranges);

  // Plans the colour pass of a width x height frame. `occluders` (nullptr: no occlusion culling) must
  // be built for the same size, from the depth of the same camera.
  void build(const Camera& camera, int width, int height, const DrawOptions& options,
             const DepthTiles* occluders = nullptr);

  const std::vector<FeatherDrawRange>& ranges() const { return ranges_; }
  // Feather i's bounding box; a point at the origin for an empty range.
  glm::vec3 featherLo(size_t i) const { return boxes_[2 * i]; }
  glm::vec3 featherHi(size_t i) const { return boxes_[2 * i + 1]; }

  // Plans the shadow pass of a size x size single-sample depth map seen through `viewProj`: every
  // triangle in the coat's index-list order, less those that cover no texel centre (within 0.05 texel)
  // or lie outside the map, which draw no depth; the runs are shadowRuns() with their survivors. Sets
  // indices() and runs() (the next build() replaces them); counts() are left as they were.
  void buildShadow(const glm::mat4& viewProj, int size);

  // The last build or buildShadow: surviving coat indices in draw order, and the runs over them.
  const std::vector<uint32_t>& indices() const { return frameIndices_; }
  const std::vector<DrawRun>& runs() const { return runs_; }
  const DrawCounts& counts() const { return counts_; }
  // The shadow pass over the coat's own index list (set by setCoat).
  const std::vector<DrawRun>& shadowRuns() const { return shadowRuns_; }
  const uint32_t* coatIndices() const { return coatIndices_; }
  size_t coatIndexCount() const { return indexCount_; }

 private:
  // A run of at most kChunkTriangles consecutive triangles of one part, with its box.
  struct Chunk {
    glm::vec3 lo, hi;
    uint32_t first, count;        // indices
    uint32_t vertexLo, vertexHi;  // the vertices its triangles use lie in [vertexLo, vertexHi]
  };
  struct Feather {  // per frame
    enum State : uint8_t { kEmpty, kCulled, kOccluded, kDrawn };
    State state = kEmpty;
    bool backward = false;
    int8_t order[4] = {0, 1, 2, 3};  // parts: shaft, left, right, afterfeather
    uint32_t triangles = 0, occludedTriangles = 0, subpixelTriangles = 0;
  };
  enum class Depth { Hidden, InFront, Mixed };

  Depth classify(const glm::vec3& lo, const glm::vec3& hi, const glm::mat4& viewProj, const glm::mat4& view,
                 const glm::mat4& proj, int w, int h, const DepthTiles& tiles) const;
  uint32_t emitChunk(const Chunk& ch, bool backward, const DepthTiles* test, bool subpixel, const glm::mat4& viewProj,
                     int w, int h, uint32_t* out, std::vector<glm::vec3>& projected, uint32_t& tiny) const;

  std::vector<FeatherDrawRange> ranges_;
  std::vector<glm::vec2> samples_;  // of the last build: where coverage is sampled within a pixel
  std::vector<glm::vec4> spheres_;  // per range: bounding sphere (centre, radius), frustum culling
  std::vector<glm::vec3> boxes_;    // per range: lo, hi (2 entries), occlusion culling
  // The chunks of part k of range i are chunks_[partChunks_[5 i + k], partChunks_[5 i + k + 1]).
  std::vector<Chunk> chunks_;
  std::vector<uint32_t> partChunks_;
  std::vector<std::pair<uint32_t, uint32_t>> shadowRunRanges_;  // per shadow run: its ranges [first, last)
  void prepare(const std::vector<FeatherDrawRange>& ranges);
  // The coat's positions and indices: setCoat's copies, or the caller's arrays (setCoatReference).
  std::vector<glm::vec3> ownPositions_;
  std::vector<uint32_t> ownIndices_;
  const glm::vec3* positions_ = nullptr;
  const uint32_t* coatIndices_ = nullptr;
  size_t indexCount_ = 0;
  std::vector<DrawRun> shadowRuns_;
  // Per frame.
  std::vector<Feather> feathers_;
  std::vector<uint32_t> scratch_;  // each chunk's surviving indices at the chunk's own offset
  std::vector<uint32_t> kept_;     // per chunk: indices surviving
  std::vector<uint32_t> frameIndices_;
  std::vector<DrawRun> runs_;
  DrawCounts counts_;
};

}  // namespace pteryla::render
