// Synthetic feathers and coats for the renderer's tests and benchmarks: barbs as two triangle strips
// with the per-vertex alpha of Streit 2003, 7.1.2 (quadratic decrease near the barb tip, starting one
// segment earlier at the fringe edges), fewer and wider barbs standing for several (barbCount) at a
// lower level of detail (7.1.3), feathers placed with the follicle frame and elevation of
// docs/architecture.md and drawn tail-first (layer order, 7.2).
#include "pteryla/render/synthetic.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/core/frame.hpp"
#include "pteryla/core/rng.hpp"

namespace pteryla::render {
namespace {
constexpr float kPi = 3.14159265358979f;
}

TriMesh makeEllipsoid(const glm::vec3& radii, int rings, int segments) {
  if (rings < 2 || segments < 3) throw Error("sphere needs rings >= 2 and segments >= 3");
  TriMesh m;
  for (int i = 0; i <= rings; ++i) {
    const float th = kPi * float(i) / float(rings);
    for (int j = 0; j <= segments; ++j) {
      const float ph = 2.0f * kPi * float(j) / float(segments);
      const glm::vec3 n(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
      m.positions.push_back(n * radii);
      m.normals.push_back(glm::normalize(n / radii));
      m.uvGlobal.emplace_back(float(j) / float(segments), 1.0f - float(i) / float(rings));
    }
  }
  const uint32_t row = static_cast<uint32_t>(segments + 1);
  for (int i = 0; i < rings; ++i) {
    for (int j = 0; j < segments; ++j) {
      const uint32_t a = i * row + j, b = a + 1, c = a + row, d = c + 1;
      if (i != 0) m.indices.insert(m.indices.end(), {a, c, b});
      if (i != rings - 1) m.indices.insert(m.indices.end(), {b, c, d});
    }
  }
  return m;
}

TriMesh makeUvSphere(float radius, int rings, int segments) {
  return makeEllipsoid(glm::vec3(radius), rings, segments);
}

SyntheticFeather makeSyntheticFeather(const SyntheticFeatherParams& p) {
  if (!(p.length > 0.0f) || !(p.width > 0.0f) || p.barbsPerVane < 1 || p.segmentsPerBarb < 1)
    throw Error("synthetic feather needs positive length, width, barbs and segments");
  const float f = std::clamp(p.lodFraction, 0.01f, 1.0f);
  const int nb = std::max(1, static_cast<int>(std::lround(f * p.barbsPerVane)));
  const float represented = float(p.barbsPerVane) / float(nb);
  const int S = p.segmentsPerBarb;
  const float L = p.length, W = p.width;
  SyntheticFeather out;
  TriMesh& m = out.mesh;

  auto vertex = [&](const glm::vec3& pos, const glm::vec3& n, const glm::vec3& t, glm::vec2 uvB, float a, float bc) {
    m.positions.push_back(pos);
    m.normals.push_back(glm::normalize(n));
    m.tangents.push_back(glm::normalize(t));
    m.uvBarb.push_back(uvB);
    m.alpha.push_back(a);
    m.barbCount.push_back(bc);
    m.featherId.push_back(p.featherId);
    return static_cast<uint32_t>(m.positions.size() - 1);
  };
  auto cup = [&](float y) { return -p.cupping * W * (y / W) * (y / W); };
  auto cupNormal = [&](float y) { return glm::vec3(0.0f, 2.0f * p.cupping * y / W, 1.0f); };

  // Rachis: a thin strip along +x.
  const int shaftSegs = 8;
  const float rw = 0.012f * L + 0.05f * W;
  for (int k = 0; k <= shaftSegs; ++k) {
    const float x = L * float(k) / float(shaftSegs);
    const float w = rw * (1.0f - 0.7f * float(k) / float(shaftSegs));
    vertex({x, -w, 0.0f}, {0, 0, 1}, {1, 0, 0}, {0.42f, 0.0f}, 1.0f, 1.0f);
    vertex({x, w, 0.0f}, {0, 0, 1}, {1, 0, 0}, {0.58f, 0.0f}, 1.0f, 1.0f);
  }
  for (int k = 0; k < shaftSegs; ++k) {
    const uint32_t a = 2 * k, b = a + 1, c = a + 2, d = a + 3;
    m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
  }
  out.partCount[0] = static_cast<uint32_t>(m.indices.size());

  // Vanes: left (+y) then right (-y); barbs base to tip, each barb rachis to tip.
  for (int vane = 0; vane < 2; ++vane) {
    const float side = vane == 0 ? 1.0f : -1.0f;
    const size_t before = m.indices.size();
    const float dx = 0.9f * L / float(nb);
    for (int b = 0; b < nb; ++b) {
      const float t = (float(b) + 0.5f) / float(nb);
      const float x0 = L * 0.08f + 0.9f * L * t;
      const float theta = p.barbAngle * (1.0f - 0.3f * t);
      const float len = W * std::pow(std::sin(kPi * (0.12f + 0.88f * t)), 0.6f) + 0.05f * W;
      const glm::vec3 dir(std::cos(theta), side * std::sin(theta), 0.0f);
      const glm::vec3 across(-dir.y, dir.x, 0.0f);
      const float half = 0.65f * dx * std::sin(theta);
      const uint32_t first = static_cast<uint32_t>(m.positions.size());
      for (int k = 0; k <= S; ++k) {
        const float s = float(k) / float(S);
        glm::vec3 c = glm::vec3(x0, 0.0f, 0.0f) + dir * (len * s);
        for (int col = 0; col < 3; ++col) {
          // Quadratic alpha falloff near the tip, one segment earlier on the fringe edges (7.1.2).
          const float start = col == 1 ? 0.65f : 0.65f - 1.0f / float(S);
          const float u = std::max(0.0f, (s - start) / (1.0f - start));
          const float a = std::max(0.0f, 1.0f - u * u);
          glm::vec3 pos = c + across * (half * float(col - 1));
          pos.z = cup(pos.y);
          vertex(pos, cupNormal(pos.y), dir, {0.5f * float(col), s}, a, represented);
        }
      }
      for (int k = 0; k < S; ++k) {
        for (int col = 0; col < 2; ++col) {
          const uint32_t a = first + 3 * k + col, bb = a + 1, c = a + 3, d = a + 4;
          m.indices.insert(m.indices.end(), {a, bb, c, bb, d, c});
        }
      }
    }
    out.partCount[1 + vane] = static_cast<uint32_t>(m.indices.size() - before);
  }

  // Feather-global and growth texture coordinates (7.1.1).
  float maxX = 0.0f;
  for (const auto& q : m.positions) maxX = std::max(maxX, q.x);
  for (const auto& q : m.positions) {
    const float u = std::clamp(0.5f + q.y / (2.0f * W), 0.0f, 1.0f);
    m.uvGlobal.emplace_back(u, std::clamp(q.x / maxX, 0.0f, 1.0f));
    m.uvGrowth.emplace_back(u, std::clamp(q.x / L, 0.0f, 1.0f));
  }
  return out;
}

void placeFeather(TriMesh& mesh, const glm::vec3& origin, const glm::vec3& X, const glm::vec3& Y) {
  const glm::vec3 Z = glm::cross(X, Y);
  auto rot = [&](const glm::vec3& v) { return v.x * X + v.y * Y + v.z * Z; };
  for (auto& q : mesh.positions) q = origin + rot(q);
  for (auto& n : mesh.normals) n = rot(n);
  for (auto& t : mesh.tangents) t = rot(t);
}

SyntheticCoat makeSyntheticCoat(const SyntheticCoatParams& p) {
  if (p.featherCount < 1 || p.materialCount < 1) throw Error("synthetic coat needs feathers and materials");
  SyntheticCoat out;
  out.skin = makeEllipsoid(p.bodyRadii, 48, 96);
  const int n = p.featherCount;
  struct Follicle {
    glm::vec3 pos, X, Y;
    float scale;
    uint32_t material;
  };
  std::vector<Follicle> fol(n);
  const float golden = kPi * (3.0f - std::sqrt(5.0f));
  for (int i = 0; i < n; ++i) {
    // Fibonacci points, denser toward the head end is not needed for a fixture.
    const float y = 1.0f - 2.0f * (float(i) + 0.5f) / float(n);
    const float r = std::sqrt(std::max(0.0f, 1.0f - y * y));
    const float ph = golden * float(i);
    const glm::vec3 s(y, r * std::cos(ph), r * std::sin(ph));  // x along the body axis
    const glm::vec3 pos = s * p.bodyRadii;
    const glm::vec3 N = glm::normalize(s / p.bodyRadii);
    glm::vec3 T = glm::vec3(-1, 0, 0) - N * glm::dot(glm::vec3(-1, 0, 0), N);
    if (glm::length(T) < 1e-3f) T = glm::vec3(0, 0, -1) - N * glm::dot(glm::vec3(0, 0, -1), N);
    T = glm::normalize(T);
    const float e = p.elevation;
    const glm::vec3 B = glm::cross(N, T);
    const glm::vec3 Tp = elevatedAxes(T, B, N, e).x;
    const float scale = 0.85f + 0.3f * static_cast<float>(hashUniform(p.seed, static_cast<uint64_t>(i), 1));
    const auto mat = static_cast<uint32_t>(hashUniform(p.seed, static_cast<uint64_t>(i), 2) * p.materialCount);
    fol[i] = {pos, Tp, B, scale, std::min<uint32_t>(mat, p.materialCount - 1)};
  }
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return fol[a].pos.x < fol[b].pos.x; });
  // TriMesh::append reserves exactly, which is quadratic over thousands of appends: reserve up front.
  {
    SyntheticFeatherParams fp = p.feather;
    fp.length = p.featherLength;
    fp.width = p.featherWidth;
    const TriMesh probe = makeSyntheticFeather(fp).mesh;
    const size_t nv = probe.vertexCount() * n, ni = probe.indices.size() * n;
    TriMesh& c = out.coat;
    c.positions.reserve(nv), c.normals.reserve(nv), c.tangents.reserve(nv), c.uvGlobal.reserve(nv);
    c.uvBarb.reserve(nv), c.uvGrowth.reserve(nv), c.alpha.reserve(nv), c.barbCount.reserve(nv);
    c.featherId.reserve(nv), c.indices.reserve(ni);
  }
  for (int id : order) {
    const Follicle& fo = fol[id];
    SyntheticFeatherParams fp = p.feather;
    fp.length = p.featherLength * fo.scale;
    fp.width = p.featherWidth * fo.scale;
    fp.featherId = static_cast<uint32_t>(id);
    SyntheticFeather f = makeSyntheticFeather(fp);
    placeFeather(f.mesh, fo.pos, fo.X, fo.Y);
    FeatherDrawRange r;
    r.firstIndex = static_cast<uint32_t>(out.coat.indices.size());
    r.indexCount = static_cast<uint32_t>(f.mesh.indices.size());
    r.material = fo.material;
    r.origin = fo.pos;
    r.axisX = fo.X;
    r.axisY = fo.Y;
    std::copy(f.partCount, f.partCount + 4, r.partCount);
    out.coat.append(f.mesh);
    out.ranges.push_back(r);
  }
  return out;
}

}  // namespace pteryla::render
