// The coat's draw plan (Streit 2003, 7.1.2 octant order, 7.2 layer order and blending): culling
// against the view and the skin's depth, view-dependent order, material runs. No GL here.
#include "pteryla/render/draw_plan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pteryla/core/error.hpp"

namespace pteryla::render {
namespace {

constexpr int kTile = DepthTiles::kTile;

// False only when the window-space triangle abc (bounds x0..y1) certainly covers no sample point
// (x + s.x, y + s.y) of any pixel (x, y), for each of the rasterizer's sample positions s within a pixel
// (one sample at the centre (0.5, 0.5) without multisampling): no such point in its bounds, or none of
// the few in its bounds inside all three edges. Everything is widened by kSubpixelSlack pixels, far more
// than the rounding between this projection and the rasterizer's (fixed point, 1/256 px), so a dropped
// triangle never had a fragment (nor, with multisampling, a covered sample). Larger triangles (more than
// 16 points of one sample position in their bounds) are kept untested.
constexpr float kSubpixelSlack = 0.05f;
bool mayCoverSample(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, float x0, float y0, float x1, float y1,
                    const glm::vec2& s) {
  const float e = kSubpixelSlack;
  const float cx0 = std::ceil(x0 - s.x - e), cx1 = std::floor(x1 - s.x + e);
  const float cy0 = std::ceil(y0 - s.y - e), cy1 = std::floor(y1 - s.y + e);
  if (cx0 > cx1 || cy0 > cy1) return false;
  if ((cx1 - cx0 + 1.0f) * (cy1 - cy0 + 1.0f) > 16.0f) return true;
  const float area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
  if (!(std::abs(area) > 1e-6f)) return true;  // (nearly) degenerate: leave it to the rasterizer
  const float sign = area > 0.0f ? 1.0f : -1.0f;
  const glm::vec2 v[3] = {{a.x, a.y}, {b.x, b.y}, {c.x, c.y}};
  float len[3];
  for (int k = 0; k < 3; ++k) len[k] = glm::length(v[(k + 1) % 3] - v[k]);
  for (float py = cy0 + s.y; py <= cy1 + s.y; py += 1.0f)
    for (float px = cx0 + s.x; px <= cx1 + s.x; px += 1.0f) {
      bool inside = true;
      for (int k = 0; k < 3 && inside; ++k) {
        const glm::vec2& p0 = v[k];
        const glm::vec2& p1 = v[(k + 1) % 3];
        const float edge = sign * ((p1.x - p0.x) * (py - p0.y) - (p1.y - p0.y) * (px - p0.x));
        inside = edge >= -e * len[k];
      }
      if (inside) return true;
    }
  return false;
}

// The tiles under the pixel rectangle [x0, x1] x [y0, y1], clamped to the grid.
struct TileRect {
  int tx0, tx1, ty0, ty1;
};
TileRect tileRect(const DepthTiles& t, float x0, float y0, float x1, float y1) {
  return {std::clamp(static_cast<int>(std::floor(x0)) / kTile, 0, t.tilesX - 1),
          std::clamp(static_cast<int>(std::ceil(x1)) / kTile, 0, t.tilesX - 1),
          std::clamp(static_cast<int>(std::floor(y0)) / kTile, 0, t.tilesY - 1),
          std::clamp(static_cast<int>(std::ceil(y1)) / kTile, 0, t.tilesY - 1)};
}

// True when every depth tile over the pixel rectangle is nearer than windowDepth.
bool hiddenRect(const DepthTiles& t, float x0, float y0, float x1, float y1, float windowDepth) {
  const TileRect r = tileRect(t, x0, y0, x1, y1);
  for (int ty = r.ty0; ty <= r.ty1; ++ty)
    for (int tx = r.tx0; tx <= r.tx1; ++tx)
      if (t.farthest[static_cast<size_t>(ty) * t.tilesX + tx] >= windowDepth - 1e-6f) return false;
  return true;
}

}  // namespace

void DepthTiles::build(const float* depth, int w, int h) {
  tilesX = (w + kTile - 1) / kTile;
  tilesY = (h + kTile - 1) / kTile;
  farthest.assign(static_cast<size_t>(tilesX) * tilesY, 0.0f);
  nearest.assign(static_cast<size_t>(tilesX) * tilesY, 1.0f);
  for (int y = 0; y < h; ++y) {
    const float* row = depth + static_cast<size_t>(y) * w;
    float* hi = farthest.data() + static_cast<size_t>(y / kTile) * tilesX;
    float* lo = nearest.data() + static_cast<size_t>(y / kTile) * tilesX;
    for (int x = 0; x < w; ++x) {
      hi[x / kTile] = std::max(hi[x / kTile], row[x]);
      lo[x / kTile] = std::min(lo[x / kTile], row[x]);
    }
  }
}

void DrawPlan::validateRanges(const std::vector<FeatherDrawRange>& ranges, size_t n) {
  for (size_t i = 0; i < ranges.size(); ++i) {
    const FeatherDrawRange& f = ranges[i];
    const std::string el = "ranges[" + std::to_string(i) + "]";
    if (f.firstIndex % 3 != 0 || f.indexCount % 3 != 0)
      throw Error("feather draw range must start and span whole triangles (multiples of 3)", {}, el);
    if (static_cast<size_t>(f.firstIndex) + f.indexCount > n)
      throw Error("feather draw range [" + std::to_string(f.firstIndex) + ", +" + std::to_string(f.indexCount) +
                      ") exceeds the " + std::to_string(n) + " coat indices",
                  {}, el);
    uint64_t sum = 0;
    for (uint32_t c : f.partCount) {
      if (c % 3 != 0) throw Error("feather part index counts must be multiples of 3", {}, el + ".partCount");
      sum += c;
    }
    if (sum != 0 && sum != f.indexCount)
      throw Error(
          "feather part counts sum to " + std::to_string(sum) + ", expected indexCount " + std::to_string(f.indexCount),
          {}, el + ".partCount");
  }
  // Ranges may come in any order but must not share indices: each frame's surviving triangles are
  // written into a buffer the size of the coat's index list.
  std::vector<std::pair<uint32_t, size_t>> byFirst;
  for (size_t i = 0; i < ranges.size(); ++i)
    if (ranges[i].indexCount > 0) byFirst.push_back({ranges[i].firstIndex, i});
  std::sort(byFirst.begin(), byFirst.end());
  for (size_t k = 1; k < byFirst.size(); ++k) {
    const FeatherDrawRange& prev = ranges[byFirst[k - 1].second];
    if (size_t(prev.firstIndex) + prev.indexCount > byFirst[k].first) {
      const size_t a = std::min(byFirst[k - 1].second, byFirst[k].second),
                   b = std::max(byFirst[k - 1].second, byFirst[k].second);
      throw Error(
          "feather draw range overlaps ranges[" + std::to_string(a) + "] (each triangle belongs to one feather)", {},
          "ranges[" + std::to_string(b) + "]");
    }
  }
}

void DrawPlan::setCoat(const std::vector<glm::vec3>& positions, const std::vector<uint32_t>& indices,
                       const std::vector<FeatherDrawRange>& ranges) {
  ownPositions_ = positions;
  ownIndices_ = indices;
  positions_ = ownPositions_.data();
  coatIndices_ = ownIndices_.data();
  indexCount_ = ownIndices_.size();
  prepare(ranges);
}

void DrawPlan::setCoatReference(const std::vector<glm::vec3>& positions, const std::vector<uint32_t>& indices,
                                const std::vector<FeatherDrawRange>& ranges) {
  ownPositions_ = {};
  ownIndices_ = {};
  positions_ = positions.data();
  coatIndices_ = indices.data();
  indexCount_ = indices.size();
  prepare(ranges);
}

void DrawPlan::prepare(const std::vector<FeatherDrawRange>& ranges) {
  const size_t n = indexCount_;
  const glm::vec3* positions = positions_;
  const uint32_t* indices = coatIndices_;
  ranges_ = ranges;
  if (ranges_.empty() && n > 0) {
    FeatherDrawRange all;
    all.indexCount = static_cast<uint32_t>(n);
    all.origin = glm::vec3(0.0f);
    ranges_.push_back(all);
  }
  // Per feather: chunk boxes, and the feather's box and bounding sphere (box centre, farthest
  // vertex) for frustum and occlusion culling.
  spheres_.resize(ranges_.size());
  boxes_.resize(2 * ranges_.size());
  chunks_.clear();
  partChunks_.assign(5 * ranges_.size() + 1, 0);
  for (size_t i = 0; i < ranges_.size(); ++i) {
    const FeatherDrawRange& f = ranges_[i];
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    const bool hasParts = f.partCount[0] + f.partCount[1] + f.partCount[2] + f.partCount[3] > 0;
    uint32_t partFirst = f.firstIndex;
    for (int k = 0; k < 4; ++k) {
      partChunks_[5 * i + k] = static_cast<uint32_t>(chunks_.size());
      const uint32_t count = hasParts ? f.partCount[k] : (k == 0 ? f.indexCount : 0);
      for (uint32_t c = 0; c < count; c += 3 * kChunkTriangles) {
        Chunk ch{glm::vec3(std::numeric_limits<float>::max()),
                 glm::vec3(-std::numeric_limits<float>::max()),
                 partFirst + c,
                 std::min(3 * kChunkTriangles, count - c),
                 UINT32_MAX,
                 0};
        for (uint32_t j = ch.first; j < ch.first + ch.count; ++j) {
          const glm::vec3& q = positions[indices[j]];
          ch.lo = glm::min(ch.lo, q);
          ch.hi = glm::max(ch.hi, q);
          ch.vertexLo = std::min(ch.vertexLo, indices[j]);
          ch.vertexHi = std::max(ch.vertexHi, indices[j]);
        }
        lo = glm::min(lo, ch.lo);
        hi = glm::max(hi, ch.hi);
        chunks_.push_back(ch);
      }
      partFirst += count;
    }
    partChunks_[5 * i + 4] = static_cast<uint32_t>(chunks_.size());
    if (f.indexCount == 0) lo = hi = glm::vec3(0.0f);
    const glm::vec3 c = 0.5f * (lo + hi);
    spheres_[i] = glm::vec4(c, glm::length(hi - c) * 1.001f + 1e-6f);
    boxes_[2 * i] = lo;
    boxes_[2 * i + 1] = hi;
  }
  // The shadow pass: runs of consecutive feathers of one material, each drawn from the full index list.
  shadowRuns_.clear();
  shadowRunRanges_.clear();
  size_t i = 0;
  while (i < ranges_.size()) {
    const uint32_t material = ranges_[i].material;
    const size_t first = ranges_[i].firstIndex;
    size_t last = first + ranges_[i].indexCount, j = i + 1;
    while (j < ranges_.size() && ranges_[j].material == material && ranges_[j].firstIndex == last)
      last += ranges_[j].indexCount, ++j;
    if (last > first) {
      shadowRuns_.push_back({material, first, last - first});
      shadowRunRanges_.emplace_back(static_cast<uint32_t>(i), static_cast<uint32_t>(j));
    }
    i = j;
  }
}

// Where the box [lo, hi] lies against the occluders' depth: Hidden when its nearest point is behind the
// farthest depth over every tile its projection touches; InFront when its farthest point is nearer than
// the nearest depth over all those tiles (nothing of it can be hidden); else Mixed.
DrawPlan::Depth DrawPlan::classify(const glm::vec3& lo, const glm::vec3& hi, const glm::mat4& viewProj,
                                   const glm::mat4& view, const glm::mat4& proj, int w, int h,
                                   const DepthTiles& tiles) const {
  const float zNear = proj[3][2] / (proj[2][2] - 1.0f);
  float nearest = std::numeric_limits<float>::max(), farthest = 0.0f;
  float x0 = 1e30f, y0 = 1e30f, x1 = -1e30f, y1 = -1e30f;
  for (int k = 0; k < 8; ++k) {
    const glm::vec4 corner(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z, 1.0f);
    const float d = -(view * corner).z;
    nearest = std::min(nearest, d);
    farthest = std::max(farthest, d);
    const glm::vec4 q = viewProj * corner;
    if (q.w <= 0.0f) return Depth::Mixed;
    const float sx = (q.x / q.w * 0.5f + 0.5f) * w, sy = (q.y / q.w * 0.5f + 0.5f) * h;
    x0 = std::min(x0, sx), x1 = std::max(x1, sx), y0 = std::min(y0, sy), y1 = std::max(y1, sy);
  }
  if (nearest <= zNear * 1.01f) return Depth::Mixed;
  // Window depth at view distance d (glm perspective: z_clip = P22 z + P32, w = -z).
  auto windowDepth = [&](float d) { return ((proj[2][2] * -d + proj[3][2]) / d) * 0.5f + 0.5f; };
  if (hiddenRect(tiles, x0, y0, x1, y1, windowDepth(nearest))) return Depth::Hidden;
  const float far = windowDepth(farthest);
  const TileRect r = tileRect(tiles, x0, y0, x1, y1);
  for (int ty = r.ty0; ty <= r.ty1; ++ty)
    for (int tx = r.tx0; tx <= r.tx1; ++tx)
      if (tiles.nearest[static_cast<size_t>(ty) * tiles.tilesX + tx] <= far + 1e-6f) return Depth::Mixed;
  return Depth::InFront;
}

// Writes a chunk's triangles to `out`, forward or in reverse triangle order; with `test`, only the
// triangles that may be visible: a triangle is dropped when it lies outside the viewport or its
// nearest vertex is behind the farthest depth of `test` over every tile its bounds touch (window depth
// is affine over a triangle, so its nearest point is a vertex). Returns the indices written.
// `projected` is scratch space. Thread-safe (reads shared state only).
// With `subpixel`, triangles that cover no pixel centre are dropped as well (they produce no fragment
// without multisampling, but llvmpipe still shades their vertices and sets them up).
// `tiny` counts the triangles dropped only for covering no pixel centre.
uint32_t DrawPlan::emitChunk(const Chunk& ch, bool backward, const DepthTiles* test, bool subpixel,
                             const glm::mat4& viewProj, int w, int h, uint32_t* out, std::vector<glm::vec3>& projected,
                             uint32_t& tiny) const {
  const uint32_t* idx = coatIndices_ + ch.first;
  const uint32_t tris = ch.count / 3;
  if (!test && !subpixel) {
    if (!backward) {
      std::copy(idx, idx + ch.count, out);
    } else {
      for (uint32_t t = 0; t < tris; ++t) std::copy(idx + 3 * (tris - 1 - t), idx + 3 * (tris - t), out + 3 * t);
    }
    return ch.count;
  }
  const uint32_t nv = ch.vertexHi - ch.vertexLo + 1;
  projected.resize(nv);
  for (uint32_t v = 0; v < nv; ++v) {
    const glm::vec4 q = viewProj * glm::vec4(positions_[ch.vertexLo + v], 1.0f);
    if (q.w <= 1e-6f) {
      projected[v] = glm::vec3(std::numeric_limits<float>::quiet_NaN());
      continue;
    }
    const float inv = 1.0f / q.w;
    projected[v] =
        glm::vec3((q.x * inv * 0.5f + 0.5f) * float(w), (q.y * inv * 0.5f + 0.5f) * float(h), q.z * inv * 0.5f + 0.5f);
  }
  uint32_t written = 0;
  for (uint32_t n = 0; n < tris; ++n) {
    const uint32_t* t = idx + 3 * (backward ? tris - 1 - n : n);
    const glm::vec3& a = projected[t[0] - ch.vertexLo];
    const glm::vec3& b = projected[t[1] - ch.vertexLo];
    const glm::vec3& c = projected[t[2] - ch.vertexLo];
    bool keep = true;
    if (!(std::isnan(a.x) || std::isnan(b.x) || std::isnan(c.x))) {
      const float x0 = std::min({a.x, b.x, c.x}), x1 = std::max({a.x, b.x, c.x});
      const float y0 = std::min({a.y, b.y, c.y}), y1 = std::max({a.y, b.y, c.y});
      if (x1 < -1.0f || y1 < -1.0f || x0 > float(w) + 1.0f || y0 > float(h) + 1.0f) {
        keep = false;
      } else {
        if (test) {
          const float nearest = std::min({a.z, b.z, c.z});
          keep = !(nearest > 0.0f) || !hiddenRect(*test, x0, y0, x1, y1, nearest);
        }
        if (keep && subpixel) {
          bool covers = false;
          for (const glm::vec2& sp : samples_)
            if (mayCoverSample(a, b, c, x0, y0, x1, y1, sp)) {
              covers = true;
              break;
            }
          if (!covers) {
            keep = false;
            ++tiny;
          }
        }
      }
    }
    if (keep) {
      std::copy(t, t + 3, out + written);
      written += 3;
    }
  }
  return written;
}

void DrawPlan::build(const Camera& camera, int width, int height, const DrawOptions& options,
                     const DepthTiles* occluders) {
  counts_ = DrawCounts();
  runs_.clear();
  const glm::mat4 view = camera.view(), proj = camera.projection(float(width) / float(height));
  const glm::mat4 viewProj = proj * view;
  // Frustum planes (Gribb-Hartmann) for per-feather culling with the bounding spheres.
  glm::vec4 planes[6];
  const glm::mat4 m = glm::transpose(viewProj);
  for (int k = 0; k < 3; ++k) {
    planes[2 * k] = m[3] + m[k];
    planes[2 * k + 1] = m[3] - m[k];
  }
  for (auto& pl : planes) pl /= glm::length(glm::vec3(pl));
  auto visible = [&](const glm::vec4& sphere) {
    for (const auto& pl : planes)
      if (glm::dot(glm::vec3(pl), glm::vec3(sphere)) + pl.w < -sphere.w) return false;
    return true;
  };

  // Pass 1, in parallel over feathers: visibility and octant order of each feather, and the
  // surviving triangles of each chunk in its draw direction, written to the chunk's own slot of
  // `scratch_` (same offsets as the coat's indices).
  const bool ordered = options.viewDependentOrder;
  const bool subpixel = options.subpixelCulling;
  samples_ = options.samplePositions;
  if (samples_.empty()) samples_.push_back(glm::vec2(0.5f));
  feathers_.resize(ranges_.size());
  scratch_.resize(indexCount_);
  kept_.resize(chunks_.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, ranges_.size(), 16), [&](const tbb::blocked_range<size_t>& br) {
    std::vector<glm::vec3> projected;
    for (size_t i = br.begin(); i != br.end(); ++i) {
      Feather& pl = feathers_[i];
      pl = Feather();
      const FeatherDrawRange& f = ranges_[i];
      if (f.indexCount == 0) continue;
      if (!visible(spheres_[i])) {
        pl.state = Feather::kCulled;
        continue;
      }
      const Depth depth =
          occluders ? classify(boxes_[2 * i], boxes_[2 * i + 1], viewProj, view, proj, width, height, *occluders)
                    : Depth::InFront;
      if (depth == Depth::Hidden) {
        pl.state = Feather::kOccluded;
        continue;
      }
      pl.state = Feather::kDrawn;
      // Octant rule (7.1.2): farther substructures first, from this feather's own view direction.
      const glm::vec3 toEye = camera.eye - f.origin;
      pl.backward = ordered && glm::dot(toEye, f.axisX) <= 0.0f;
      if (ordered) {
        const bool leftNear = glm::dot(toEye, f.axisY) > 0.0f;
        const int8_t farVane = leftNear ? 2 : 1, nearVane = leftNear ? 1 : 2;
        const bool dorsal = glm::dot(toEye, glm::cross(f.axisX, f.axisY)) > 0.0f;
        const int8_t o[4] = {int8_t(dorsal ? 3 : 0), farVane, nearVane, int8_t(dorsal ? 0 : 3)};
        std::copy(o, o + 4, pl.order);
      }
      // Chunks hidden behind the skin are left out, the ones that may be partly hidden are tested
      // per triangle.
      const uint32_t c0 = partChunks_[5 * i], c1 = partChunks_[5 * i + 4];
      for (uint32_t c = c0; c < c1; ++c) {
        const Chunk& ch = chunks_[c];
        uint32_t tiny = 0;
        Depth d = depth;
        if (d == Depth::Mixed && c1 - c0 > 1)
          d = classify(ch.lo, ch.hi, viewProj, view, proj, width, height, *occluders);
        const uint32_t n = d == Depth::Hidden
                               ? 0
                               : emitChunk(ch, pl.backward, d == Depth::Mixed ? occluders : nullptr, subpixel, viewProj,
                                           width, height, scratch_.data() + ch.first, projected, tiny);
        kept_[c] = n;
        pl.triangles += n / 3;
        pl.occludedTriangles += (ch.count - n) / 3 - tiny;
        pl.subpixelTriangles += tiny;
      }
    }
  });

  // Pass 2: the surviving triangles in draw order (layer order, then each feather's parts in
  // octant order), split into maximal runs of one material: a feather none of whose triangles
  // survived neither starts a run nor splits one.
  // Sized to what survives (not the whole coat): the list is kept between frames.
  size_t total = 0;
  for (const Feather& pl : feathers_)
    if (pl.state == Feather::kDrawn) total += 3 * size_t(pl.triangles);
  frameIndices_.resize(total);
  size_t used = 0;
  for (size_t i = 0; i < ranges_.size(); ++i) {
    const Feather& pl = feathers_[i];
    if (pl.state == Feather::kCulled) ++counts_.culledFeathers;
    if (pl.state == Feather::kOccluded) ++counts_.occludedFeathers;
    if (pl.state != Feather::kDrawn) continue;
    counts_.triangles += pl.triangles;
    counts_.occludedTriangles += pl.occludedTriangles;
    counts_.subpixelTriangles += pl.subpixelTriangles;
    const uint32_t material = ranges_[i].material;
    if (pl.triangles > 0 && (runs_.empty() || runs_.back().material != material)) runs_.push_back({material, used, 0});
    for (int8_t k : pl.order) {
      const uint32_t c0 = partChunks_[5 * i + k], c1 = partChunks_[5 * i + k + 1];
      if (c0 == c1) continue;
      counts_.backwardParts += pl.backward ? 1 : 0;
      for (uint32_t n = 0; n < c1 - c0; ++n) {
        const uint32_t c = pl.backward ? c1 - 1 - n : c0 + n;
        const uint32_t* from = scratch_.data() + chunks_[c].first;
        std::copy(from, from + kept_[c], frameIndices_.data() + used);
        used += kept_[c];
      }
    }
    if (!runs_.empty()) runs_.back().count = used - runs_.back().first;
  }
  PTERYLA_CHECK_EQ(used, total, "draw plan index count");
}

void DrawPlan::buildShadow(const glm::mat4& viewProj, int size) {
  runs_.clear();
  samples_.assign(1, glm::vec2(0.5f));
  scratch_.resize(indexCount_);
  kept_.resize(chunks_.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks_.size(), 64), [&](const tbb::blocked_range<size_t>& br) {
    std::vector<glm::vec3> projected;
    uint32_t tiny = 0;
    for (size_t c = br.begin(); c != br.end(); ++c)
      kept_[c] = emitChunk(chunks_[c], false, nullptr, true, viewProj, size, size, scratch_.data() + chunks_[c].first,
                           projected, tiny);
  });
  size_t total = 0;
  for (const auto& [i0, i1] : shadowRunRanges_)
    for (uint32_t c = partChunks_[5 * size_t(i0)]; c < partChunks_[5 * size_t(i1 - 1) + 4]; ++c) total += kept_[c];
  frameIndices_.resize(total);
  size_t used = 0;
  for (const auto& [i0, i1] : shadowRunRanges_) {
    const size_t first = used;
    // A run's ranges are consecutive in the index list, and so are their chunks.
    for (uint32_t c = partChunks_[5 * size_t(i0)]; c < partChunks_[5 * size_t(i1 - 1) + 4]; ++c) {
      const uint32_t* from = scratch_.data() + chunks_[c].first;
      std::copy(from, from + kept_[c], frameIndices_.data() + used);
      used += kept_[c];
    }
    if (used > first) runs_.push_back({ranges_[i0].material, first, used - first});
  }
}

}  // namespace pteryla::render
