// Scratchboard rendering of feather structure (Streit 2003, 7.3): scratches placed along the barbs on a
// black canvas, their density and thickness chosen to preserve the relative tone of the shaded coat.
// The thesis omits its details; this is our design: a CPU z-buffer gives tone and barb direction per
// pixel, strokes are streamlines of the barb direction field seeded on a jittered grid.
#include "pteryla/render/scratchboard.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"

namespace pteryla::render {
namespace {

struct GBuffer {
  int w = 0, h = 0;
  std::vector<float> depth, tone;
  std::vector<glm::vec2> dir;
  std::vector<int32_t> id;  // -1 background, 0 skin, featherId + 1 for the coat
  size_t at(int x, int y) const { return static_cast<size_t>(y) * w + x; }
};

struct ScreenVertex {
  glm::vec3 p;  // pixel x, pixel y (down), ndc depth
  float tone;
  glm::vec2 dir;
  bool valid;
};

void rasterize(GBuffer& g, const TriMesh& mesh, const glm::mat4& viewProj, const glm::vec3& eye,
               const std::vector<Light>& lights, float albedo, float ambient, bool isCoat, const glm::vec2& fixedDir) {
  const size_t nv = mesh.vertexCount();
  if (mesh.indices.empty() || nv == 0) return;
  for (uint32_t i : mesh.indices)
    if (i >= nv) throw Error("mesh index out of range in scratchboard input", {}, "indices");
  const bool hasN = mesh.normals.size() == nv, hasT = mesh.tangents.size() == nv;
  const bool hasA = mesh.alpha.size() == nv, hasId = mesh.featherId.size() == nv;
  std::vector<ScreenVertex> sv(nv);
  auto project = [&](const glm::vec3& p, bool& ok) {
    const glm::vec4 c = viewProj * glm::vec4(p, 1.0f);
    ok = c.w > 1e-6f;
    const glm::vec3 ndc = ok ? glm::vec3(c) / c.w : glm::vec3(0.0f);
    return glm::vec3((ndc.x * 0.5f + 0.5f) * g.w, (0.5f - ndc.y * 0.5f) * g.h, ndc.z);
  };
  for (size_t v = 0; v < nv; ++v) {
    const glm::vec3& p = mesh.positions[v];
    bool ok = false;
    sv[v].p = project(p, ok);
    sv[v].valid = ok;
    glm::vec3 n = hasN ? mesh.normals[v].get() : glm::vec3(0, 0, 1);
    const float nl = glm::length(n);
    n = nl > 0.0f ? n / nl : glm::vec3(0, 0, 1);
    if (glm::dot(n, eye - p) < 0.0f) n = -n;
    float light = ambient;
    for (const Light& l : lights) {
      const float ll = glm::length(l.direction);
      if (ll <= 0.0f) continue;
      const float lum = 0.2126f * l.color.r + 0.7152f * l.color.g + 0.0722f * l.color.b;
      light += lum * std::max(0.0f, glm::dot(n, l.direction / ll));
    }
    float tone = albedo * light * (isCoat && hasA ? std::clamp(static_cast<float>(mesh.alpha[v]), 0.0f, 1.0f) : 1.0f);
    sv[v].tone = std::clamp(tone, 0.0f, 1.0f);
    sv[v].dir = fixedDir;
    if (isCoat && hasT) {
      bool ok2 = false;
      const float scale = 1e-3f * std::max(1.0f, glm::length(p - eye));
      const glm::vec3 q = project(p + mesh.tangents[v].get() * scale, ok2);
      glm::vec2 d(q.x - sv[v].p.x, q.y - sv[v].p.y);
      const float len = glm::length(d);
      sv[v].dir = (ok2 && len > 1e-9f) ? d / len : fixedDir;
    }
  }
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const uint32_t ia = mesh.indices[t], ib = mesh.indices[t + 1], ic = mesh.indices[t + 2];
    const ScreenVertex &A = sv[ia], &B = sv[ib], &C = sv[ic];
    if (!A.valid || !B.valid || !C.valid) continue;
    const int32_t id = isCoat ? static_cast<int32_t>(hasId ? mesh.featherId[ia] + 1 : 1) : 0;
    const float area = (B.p.x - A.p.x) * (C.p.y - A.p.y) - (B.p.y - A.p.y) * (C.p.x - A.p.x);
    if (std::abs(area) < 1e-12f) continue;
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({A.p.x, B.p.x, C.p.x}))));
    const int x1 = std::min(g.w - 1, static_cast<int>(std::ceil(std::max({A.p.x, B.p.x, C.p.x}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({A.p.y, B.p.y, C.p.y}))));
    const int y1 = std::min(g.h - 1, static_cast<int>(std::ceil(std::max({A.p.y, B.p.y, C.p.y}))));
    // Triangle direction: barbs are straight within a triangle, so one direction is enough.
    glm::vec2 dir = A.dir + B.dir * (glm::dot(A.dir, B.dir) < 0 ? -1.0f : 1.0f) +
                    C.dir * (glm::dot(A.dir, C.dir) < 0 ? -1.0f : 1.0f);
    const float dl = glm::length(dir);
    dir = dl > 1e-6f ? dir / dl : A.dir;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const float px = x + 0.5f, py = y + 0.5f;
        const float w0 = ((B.p.x - px) * (C.p.y - py) - (B.p.y - py) * (C.p.x - px)) / area;
        const float w1 = ((C.p.x - px) * (A.p.y - py) - (C.p.y - py) * (A.p.x - px)) / area;
        const float w2 = 1.0f - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const float z = w0 * A.p.z + w1 * B.p.z + w2 * C.p.z;
        if (z < -1.0f || z > 1.0f) continue;
        const size_t k = g.at(x, y);
        if (z >= g.depth[k]) continue;
        g.depth[k] = z;
        g.tone[k] = w0 * A.tone + w1 * B.tone + w2 * C.tone;
        g.dir[k] = dir;
        g.id[k] = id;
      }
    }
  }
}

GBuffer buildGBuffer(const TriMesh& coat, const TriMesh& skin, const Camera& camera, const std::vector<Light>& lights,
                     const ScratchboardSettings& s) {
  if (s.width <= 0 || s.height <= 0 || s.width > 16384 || s.height > 16384)
    throw Error("scratchboard size must be in [1, 16384]", {}, "width/height");
  if (!(s.strokeSpacing >= 1.0f) || !(s.strokeLength >= 1.0f) || !(s.minWidth > 0.0f) || !(s.maxWidth >= s.minWidth))
    throw Error("scratchboard stroke spacing/length must be >= 1 px and 0 < minWidth <= maxWidth", {}, "stroke");
  GBuffer g;
  g.w = s.width;
  g.h = s.height;
  const size_t n = static_cast<size_t>(g.w) * g.h;
  g.depth.assign(n, 2.0f);
  g.tone.assign(n, 0.0f);
  g.dir.assign(n, glm::vec2(1, 0));
  g.id.assign(n, -1);
  const glm::mat4 vp = camera.projection(float(s.width) / float(s.height)) * camera.view();
  const glm::vec2 skinDir(std::cos(s.skinStrokeAngle), std::sin(s.skinStrokeAngle));
  if (s.drawSkin) rasterize(g, skin, vp, camera.eye, lights, s.skinAlbedo, s.ambient, false, skinDir);
  rasterize(g, coat, vp, camera.eye, lights, s.coatAlbedo, s.ambient, true, skinDir);
  return g;
}

// Draws an anti-aliased capsule from a to b of width w, keeping the brighter value per pixel.
void drawSegment(std::vector<float>& canvas, int W, int H, glm::vec2 a, glm::vec2 b, float w) {
  const float r = 0.5f * w;
  const int x0 = std::max(0, static_cast<int>(std::floor(std::min(a.x, b.x) - r - 1)));
  const int x1 = std::min(W - 1, static_cast<int>(std::ceil(std::max(a.x, b.x) + r + 1)));
  const int y0 = std::max(0, static_cast<int>(std::floor(std::min(a.y, b.y) - r - 1)));
  const int y1 = std::min(H - 1, static_cast<int>(std::ceil(std::max(a.y, b.y) + r + 1)));
  const glm::vec2 ab = b - a;
  const float len2 = glm::dot(ab, ab);
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const glm::vec2 p(x + 0.5f, y + 0.5f);
      const float t = len2 > 0.0f ? std::clamp(glm::dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
      const float d = glm::length(p - (a + ab * t));
      const float c = std::clamp(r + 0.5f - d, 0.0f, 1.0f) * std::min(1.0f, w);
      float& dst = canvas[static_cast<size_t>(y) * W + x];
      dst = std::max(dst, c);
    }
  }
}

}  // namespace

Image scratchboardTone(const TriMesh& coat, const TriMesh& skin, const Camera& camera, const std::vector<Light>& lights,
                       const ScratchboardSettings& s) {
  const GBuffer g = buildGBuffer(coat, skin, camera, lights, s);
  Image img(g.w, g.h, 0, 0, 0, 255);
  for (int y = 0; y < g.h; ++y)
    for (int x = 0; x < g.w; ++x) {
      const size_t k = g.at(x, y);
      const uint8_t v = g.id[k] < 0 ? 0 : static_cast<uint8_t>(std::lround(std::clamp(g.tone[k], 0.0f, 1.0f) * 255.0f));
      uint8_t* px = img.pixel(x, y);
      px[0] = px[1] = px[2] = v;
    }
  return img;
}

Image renderScratchboard(const TriMesh& coat, const TriMesh& skin, const Camera& camera,
                         const std::vector<Light>& lights, const ScratchboardSettings& s) {
  const GBuffer g = buildGBuffer(coat, skin, camera, lights, s);
  std::vector<float> canvas(static_cast<size_t>(g.w) * g.h, 0.0f);
  const float sp = s.strokeSpacing, len = s.strokeLength;
  // One seed per cell of area spacing x length: a stroke of width w covers w / spacing of its cell.
  const float cell = std::sqrt(sp * len);
  const int cols = static_cast<int>(std::ceil(g.w / cell)), rows = static_cast<int>(std::ceil(g.h / cell));
  std::vector<glm::vec2> pts, half;
  for (int cy = 0; cy < rows; ++cy) {
    for (int cx = 0; cx < cols; ++cx) {
      const uint64_t key = static_cast<uint64_t>(cy) * 1000003ull + static_cast<uint64_t>(cx);
      const glm::vec2 seedPt((cx + static_cast<float>(hashUniform(s.seed, key, 1))) * cell,
                             (cy + static_cast<float>(hashUniform(s.seed, key, 2))) * cell);
      const int sx = static_cast<int>(seedPt.x), sy = static_cast<int>(seedPt.y);
      if (sx < 0 || sy < 0 || sx >= g.w || sy >= g.h) continue;
      const size_t k0 = g.at(sx, sy);
      const int32_t id = g.id[k0];
      if (id < 0) continue;
      const float tone = std::clamp(g.tone[k0], 0.0f, 1.0f);
      // Random overlap of strokes makes covered fraction 1 - exp(-density): invert it so the white
      // fraction follows the tone.
      const float want = std::min(-std::log(std::max(1e-4f, 1.0f - 0.98f * tone)), 4.0f) * sp;
      float width = want;
      int count = 1;
      if (width < s.minWidth) {
        if (hashUniform(s.seed, key, 3) >= width / s.minWidth) continue;  // thinner: fewer strokes
        width = s.minWidth;
      } else if (width > s.maxWidth) {
        count = static_cast<int>(std::ceil(width / s.maxWidth));  // wider: more strokes
        width /= static_cast<float>(count);
      }
      const glm::vec2 d0 = g.dir[k0];
      const glm::vec2 perp(-d0.y, d0.x);
      for (int j = 0; j < count; ++j) {
        const glm::vec2 start = seedPt + perp * ((static_cast<float>(j) - 0.5f * (count - 1)) * sp / count);
        // Streamline of the barb direction both ways from the seed, half the length each.
        pts.clear();
        for (int dirSign = -1; dirSign <= 1; dirSign += 2) {
          glm::vec2 p = start, prev = d0 * static_cast<float>(dirSign);
          half.clear();
          const float zRef = g.depth[k0];
          for (float walked = 0.0f; walked < 0.5f * len; walked += 1.0f) {
            const int px = static_cast<int>(p.x), py = static_cast<int>(p.y);
            if (px < 0 || py < 0 || px >= g.w || py >= g.h) break;
            const size_t k = g.at(px, py);
            if (g.id[k] != id || std::abs(g.depth[k] - zRef) > 0.02f) break;
            glm::vec2 d = g.dir[k];
            if (glm::dot(d, prev) < 0.0f) d = -d;
            half.push_back(p);
            p += d;
            prev = d;
          }
          if (dirSign < 0)
            pts.assign(half.rbegin(), half.rend());
          else if (!half.empty())
            pts.insert(pts.end(), half.begin() + (pts.empty() ? 0 : 1), half.end());
        }
        if (pts.size() < 2) {
          drawSegment(canvas, g.w, g.h, start, start, width);
          continue;
        }
        for (size_t i = 0; i + 1 < pts.size(); ++i) drawSegment(canvas, g.w, g.h, pts[i], pts[i + 1], width);
      }
    }
  }
  Image img(g.w, g.h, 0, 0, 0, 255);
  for (size_t k = 0; k < canvas.size(); ++k) {
    const uint8_t v = static_cast<uint8_t>(std::lround(std::clamp(canvas[k], 0.0f, 1.0f) * 255.0f));
    img.rgba[4 * k] = img.rgba[4 * k + 1] = img.rgba[4 * k + 2] = v;
  }
  return img;
}

}  // namespace pteryla::render
