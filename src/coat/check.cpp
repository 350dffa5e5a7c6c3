// Independent interpenetration and coverage check of a feather coat at full geometry (Streit 2003, 6.3.4
// and 9.1.2 state the packing's goal: no feather-skin or feather-feather interpenetration; Figure 9.17
// shows where the height-field method can fail). Uses only the coat's triangles and the skin:
// Moeller's triangle-triangle test between the BVHs of feathers whose bounds meet, pseudo-normal signed distance
// (Baerentzen & Aanaes, "Signed distance computation using the angle weighted pseudonormal", IEEE TVCG 11(3), 2005),
// and ray casting along the skin normal for coverage.
#include "pteryla/coat/check.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/coat/pack.hpp"
#include "spatial.hpp"

namespace pteryla::coat {

using glm::dvec3;

namespace {

uint32_t triFeather(const TriMesh& m, size_t t) { return m.featherId.empty() ? 0u : m.featherId[m.indices[3 * t]]; }

// Reports `fraction` of the check (scaled into [lo, hi]) on the calling thread; false = stop.
struct Progress {
  const ProgressFn* fn = nullptr;
  double lo = 0, hi = 1;
  bool operator()(double fraction) const {
    return !fn || report(*fn, "check", lo + (hi - lo) * std::clamp(fraction, 0.0, 1.0));
  }
  Progress part(double a, double b) const { return {fn, lo + (hi - lo) * a, lo + (hi - lo) * b}; }
};

// Parallel work over [0, n) cut into batches, with a progress report after each: a cancelled check
// stops within one batch. Returns false when cancelled.
template <class F>
bool batched(size_t n, size_t grain, const Progress& progress, F&& f) {
  const size_t batches =
      progress.fn ? std::min<size_t>(32, std::max<size_t>(1, n / std::max<size_t>(1, 4 * grain))) : 1;
  for (size_t b = 0; b < batches; ++b) {
    const size_t begin = n * b / batches, end = n * (b + 1) / batches;
    if (begin < end) tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, grain), f);
    if (!progress(double(b + 1) / double(batches))) return false;
  }
  return true;
}

// A triangle whose three corners are one vertex (how the drape removes a trimmed triangle) meets no other
// triangle and no ray: trianglesIntersect and rayTriangle both answer no for it.
bool collapsed(const TriMesh& m, size_t t) {
  const uint32_t* i = &m.indices[3 * t];
  return i[0] == i[1] && i[0] == i[2];
}

// The coat's triangles grouped by feather, a BVH per feather (small trees, built in parallel) and one
// over the feathers' bounds; shared by the pair search and the coverage rays. Intersecting pairs are
// searched only between feathers whose bounds meet, tree against tree: exactly the triangle pairs of
// different feathers whose boxes overlap, the candidates a single BVH over the coat would give.
// Collapsed triangles are left out (they meet nothing), and what the triangle test needs of each
// triangle alone (TriangleShape) is made once per triangle.
struct CoatBvh {
  const TriMesh& coat;
  std::vector<uint32_t> order;                // triangles by feather (ascending within one); slot -> triangle
  std::vector<uint32_t> begin;                // per group: its first slot in order; groups.size() + 1 entries
  std::vector<uint32_t> featherOf;            // per group
  std::vector<uint32_t> indices;              // order's index triples, each feather's contiguous
  std::vector<detail::TriangleShape> shapes;  // per slot
  std::vector<detail::TriangleBvh> trees;
  std::vector<glm::dvec3> boxCorners;  // the feather trees' bounds as buildBoxTree holds them
  std::vector<uint32_t> boxIndices;
  detail::TriangleBvh top;

  bool complete = true;  // false: the progress callback stopped the build (the trees are unusable)

  explicit CoatBvh(const TriMesh& m, const Progress& progress = {}) : coat(m) {
    const size_t nt = m.triangleCount();
    std::vector<uint32_t> f;  // per slot
    order.reserve(nt);
    f.reserve(nt);
    for (size_t t = 0; t < nt; ++t)
      if (!collapsed(m, t)) {
        order.push_back(static_cast<uint32_t>(t));
        f.push_back(triFeather(m, t));
      }
    const size_t ns = order.size();
    // The coat mesh keeps each feather's triangles together; anything else is sorted by feather.
    bool grouped = true;
    {
      std::vector<uint32_t> runs;  // the feather of each run of equal feathers
      for (size_t k = 0; k < ns; ++k)
        if (k == 0 || f[k] != f[k - 1]) runs.push_back(f[k]);
      std::sort(runs.begin(), runs.end());
      grouped = std::adjacent_find(runs.begin(), runs.end()) == runs.end();
    }
    if (!grouped) {
      std::vector<uint64_t> keyed(ns);  // (feather, triangle): sorted, each feather's ascending
      for (size_t k = 0; k < ns; ++k) keyed[k] = (uint64_t(f[k]) << 32) | order[k];
      std::sort(keyed.begin(), keyed.end());
      for (size_t k = 0; k < ns; ++k) {
        f[k] = static_cast<uint32_t>(keyed[k] >> 32);
        order[k] = static_cast<uint32_t>(keyed[k] & 0xffffffffu);
      }
    }
    for (size_t k = 0; k < ns; ++k)
      if (k == 0 || f[k] != f[k - 1]) {
        begin.push_back(static_cast<uint32_t>(k));
        featherOf.push_back(f[k]);
      }
    begin.push_back(static_cast<uint32_t>(ns));
    indices.resize(3 * ns);
    for (size_t k = 0; k < ns; ++k)
      for (int c = 0; c < 3; ++c) indices[3 * k + c] = m.indices[3 * static_cast<size_t>(order[k]) + c];
    shapes.resize(ns);
    const size_t ng = featherOf.size();
    trees.resize(ng);
    complete = batched(ng, 4, progress, [&](const tbb::blocked_range<size_t>& r) {
      for (size_t g = r.begin(); g < r.end(); ++g) {
        trees[g].build(m.positions.data(), indices.data() + 3 * static_cast<size_t>(begin[g]), begin[g + 1] - begin[g]);
        trees[g].makePrimBoxes();
        for (uint32_t s = begin[g]; s < begin[g + 1]; ++s)
          shapes[s] = detail::triangleShape(vertex(s, 0), vertex(s, 1), vertex(s, 2));
      }
    });
    if (!complete) return;
    std::vector<detail::Box> bounds(ng);
    for (size_t g = 0; g < ng; ++g) {
      glm::vec3 lo(0), hi(0);
      trees[g].bounds(lo, hi);  // a group has a triangle
      bounds[g].add(glm::dvec3(lo));
      bounds[g].add(glm::dvec3(hi));
    }
    detail::buildBoxTree(bounds, boxCorners, boxIndices, top);
  }
  size_t groups() const { return featherOf.size(); }
  // Pairs of groups whose bounds meet (g < h), sorted.
  std::vector<std::pair<uint32_t, uint32_t>> meetingGroups() const {
    std::vector<std::pair<uint32_t, uint32_t>> out;
    top.overlappingPairs(top, [&](uint32_t g, uint32_t h) {
      if (g < h) out.emplace_back(g, h);
    });
    std::sort(out.begin(), out.end());
    return out;
  }
  bool anyHit(const glm::dvec3& origin, const glm::dvec3& dir, double tMin, double tMax) const {
    return top.anyLeafHit(origin, dir, tMin, tMax,
                          [&](uint32_t g) { return trees[g].anyHit(origin, dir, tMin, tMax); });
  }
  // Corner c of the triangle in slot s.
  glm::dvec3 vertex(uint32_t s, int c) const { return dvec3(coat.positions[indices[3 * static_cast<size_t>(s) + c]]); }
  // Does the triangle in slot s cross the one in slot r? Moeller's test on the lower triangle index first.
  bool cross(uint32_t s, uint32_t r) const {
    if (order[r] < order[s]) std::swap(s, r);
    return detail::trianglesIntersect(vertex(s, 0), vertex(s, 1), vertex(s, 2), shapes[s], vertex(r, 0), vertex(r, 1),
                                      vertex(r, 2), shapes[r]);
  }
};

// Counts intersecting triangle pairs of different feathers; with `attribution`, also lists the feather
// pair of every intersecting triangle pair (as (a << 32 | b), a < b, unsorted). nullopt = cancelled.
std::optional<size_t> intersectingPairs(const CoatBvh& cb, std::vector<uint64_t>* attribution = nullptr,
                                        std::vector<uint64_t>* triangles = nullptr, const Progress& progress = {},
                                        const std::vector<uint8_t>* only = nullptr) {
  // Feathers whose bounds meet, then each such pair's trees against each other: every pair of triangles
  // of different feathers with overlapping boxes is visited once, and Moeller's test (always on the
  // lower triangle index first) decides. With `only`, just the feather pairs with a feather it marks.
  std::vector<std::pair<uint32_t, uint32_t>> tasks = cb.meetingGroups();
  if (only)
    tasks.erase(std::remove_if(tasks.begin(), tasks.end(),
                               [&](const std::pair<uint32_t, uint32_t>& gh) {
                                 const uint32_t fg = cb.featherOf[gh.first], fh = cb.featherOf[gh.second];
                                 return !(fg < only->size() && (*only)[fg]) && !(fh < only->size() && (*only)[fh]);
                               }),
                tasks.end());
  tbb::combinable<std::vector<uint64_t>> found;
  tbb::combinable<size_t> count([] { return size_t(0); });
  const bool done = batched(tasks.size(), 16, progress, [&](const tbb::blocked_range<size_t>& r) {
    std::vector<uint64_t>* mine = attribution || triangles ? &found.local() : nullptr;
    size_t acc = 0;
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const uint32_t g = tasks[k].first, h = tasks[k].second;
      const uint32_t fg = cb.featherOf[g], fh = cb.featherOf[h];
      const uint64_t featherKey = (uint64_t(std::min(fg, fh)) << 32) | std::max(fg, fh);
      const uint32_t bg = cb.begin[g], bh = cb.begin[h];
      cb.trees[g].overlappingPairs(cb.trees[h], [&](uint32_t a, uint32_t b) {
        if (cb.cross(bg + a, bh + b)) {
          ++acc;
          if (mine) {
            const uint32_t t = cb.order[bg + a], u = cb.order[bh + b];
            mine->push_back(triangles ? (uint64_t(std::min(t, u)) << 32) | std::max(t, u) : featherKey);
          }
        }
      });
    }
    count.local() += acc;
  });
  if (!done) return std::nullopt;
  if (std::vector<uint64_t>* out = triangles ? triangles : attribution) {
    out->clear();
    found.combine_each([&](const std::vector<uint64_t>& v) { out->insert(out->end(), v.begin(), v.end()); });
    if (triangles) std::sort(out->begin(), out->end());
  }
  return count.combine([](size_t a, size_t b) { return a + b; });
}

size_t intersectingPairs(const TriMesh& coat, std::vector<uint64_t>* attribution = nullptr,
                         std::vector<uint64_t>* triangles = nullptr) {
  if (coat.triangleCount() < 2) return 0;
  const CoatBvh cb(coat);
  return *intersectingPairs(cb, attribution, triangles);
}

// The reference pair search (CheckOptions::reference): one BVH over the coat, its self-traversal
// between triangles of different feathers, Moeller's test from scratch on the lower index first.
size_t referencePairs(const TriMesh& coat, std::vector<uint64_t>* attribution) {
  const size_t nt = coat.triangleCount();
  if (nt < 2) return 0;
  detail::TriangleBvh bvh;
  bvh.build(coat.positions.data(), coat.indices.data(), nt);
  std::vector<uint32_t> group(nt);
  for (size_t t = 0; t < nt; ++t) group[t] = triFeather(coat, t);
  bvh.setGroups(group.data());
  const std::vector<std::pair<uint32_t, uint32_t>> tasks = bvh.pairTasks(64);
  tbb::combinable<std::vector<uint64_t>> found;
  tbb::combinable<size_t> count([] { return size_t(0); });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, tasks.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k)
      bvh.overlappingPairs(tasks[k], [&](uint32_t t, uint32_t u) {
        if (!detail::trianglesIntersect(bvh.vertex(t, 0), bvh.vertex(t, 1), bvh.vertex(t, 2), bvh.vertex(u, 0),
                                        bvh.vertex(u, 1), bvh.vertex(u, 2)))
          return;
        ++count.local();
        if (attribution) {
          const uint32_t a = group[t], b = group[u];
          found.local().push_back((uint64_t(std::min(a, b)) << 32) | std::max(a, b));
        }
      });
  });
  if (attribution) {
    attribution->clear();
    found.combine_each(
        [&](const std::vector<uint64_t>& v) { attribution->insert(attribution->end(), v.begin(), v.end()); });
  }
  return count.combine([](size_t a, size_t b) { return a + b; });
}

std::vector<FeatherPairCount> groupPairs(std::vector<uint64_t>& keys) {
  std::sort(keys.begin(), keys.end());
  std::vector<FeatherPairCount> out;
  for (size_t k = 0; k < keys.size();) {
    size_t e = k;
    while (e < keys.size() && keys[e] == keys[k]) ++e;
    out.push_back({static_cast<uint32_t>(keys[k] >> 32), static_cast<uint32_t>(keys[k] & 0xffffffffu),
                   static_cast<uint32_t>(e - k)});
    k = e;
  }
  return out;
}

double diagonal(const SkinMesh& s) {
  detail::Box b;
  for (const auto& p : s.positions) b.add(p);
  return b.empty() ? 1.0 : glm::length(b.hi - b.lo);
}

// Pseudo-normals of the skin for the inside/below test.
struct SkinSign {
  std::vector<dvec3> vertexN;               // angle-weighted
  std::vector<std::array<dvec3, 3>> edgeN;  // per face edge c (corners c, c+1)
  std::vector<std::array<uint8_t, 3>> edgeBoundary;
  std::vector<uint8_t> vertexBoundary;
  std::vector<uint32_t> flat;  // faces as a flat index array for the BVH
};

SkinSign buildSign(const SkinMesh& s) {
  SkinSign g;
  const size_t nf = s.faces.size();
  g.vertexN.assign(s.positions.size(), dvec3(0));
  g.vertexBoundary.assign(s.positions.size(), 0);
  g.edgeN.resize(nf);
  g.edgeBoundary.resize(nf);
  g.flat.resize(3 * nf);
  for (size_t f = 0; f < nf; ++f) {
    const auto& t = s.faces[f];
    const dvec3 n = s.faceNormals[f];
    for (int c = 0; c < 3; ++c) {
      g.flat[3 * f + c] = t[c];
      const dvec3 p = s.positions[t[c]];
      const dvec3 e1 = s.positions[t[(c + 1) % 3]] - p, e2 = s.positions[t[(c + 2) % 3]] - p;
      const double l1 = glm::length(e1), l2 = glm::length(e2);
      const double ang = (l1 > 0 && l2 > 0) ? std::acos(std::clamp(glm::dot(e1, e2) / (l1 * l2), -1.0, 1.0)) : 0.0;
      g.vertexN[t[c]] += ang * n;
      const int32_t nb = s.faceNeighbors.empty() ? -1 : s.faceNeighbors[f][c];
      if (nb < 0) {
        g.edgeN[f][c] = n;
        g.edgeBoundary[f][c] = 1;
        g.vertexBoundary[t[c]] = 1;
        g.vertexBoundary[t[(c + 1) % 3]] = 1;
      } else {
        g.edgeN[f][c] = n + s.faceNormals[nb];
        g.edgeBoundary[f][c] = 0;
      }
    }
  }
  return g;
}

// Coat vertices inside (below) the skin: the nearest skin point's angle-weighted pseudo-normal points
// away from the vertex; vertices within their feather's base radius and within tol of the skin are not.
// Empty when cancelled.
std::vector<uint8_t> insideSkin(const SkinMesh& skin, const SkinSign& sign, const TriMesh& coat, const CheckOptions& o,
                                double tol, const Progress& progress = {}) {
  detail::TriangleBvh sb;
  sb.build(skin.positions.data(), sign.flat.data(), skin.faces.size());
  const size_t nv = coat.positions.size();
  std::vector<uint8_t> bad(nv, 0);
  const bool done = batched(nv, 512, progress, [&](const tbb::blocked_range<size_t>& r) {
    int64_t last = -1;  // the previous vertex's nearest face: a neighbour's, usually near this one's
    for (size_t v = r.begin(); v < r.end(); ++v) {
      const dvec3 p(coat.positions[v]);
      if (!o.featherOrigins.empty() && !coat.featherId.empty()) {
        const uint32_t f = coat.featherId[v];
        if (f < o.featherOrigins.size() && glm::length(p - o.featherOrigins[f]) <= o.featherBaseRadius[f]) continue;
      }
      glm::dvec3 bary;
      double d2 = 0;
      // The distance to the last vertex's face bounds the search (nearest() computes it the same way,
      // keeps faces at exactly that distance and breaks ties by index), so the answer is the one of
      // an unbounded search, found sooner.
      double bound = std::numeric_limits<double>::infinity();
      if (last >= 0 && !o.reference) {
        const auto& t = skin.faces[static_cast<size_t>(last)];
        const dvec3 d = closestPointOnTriangle(p, skin.positions[t[0]], skin.positions[t[1]], skin.positions[t[2]]) - p;
        bound = glm::dot(d, d);
      }
      int64_t f = sb.nearest(p, bound, bary, d2);
      if (f < 0 && last >= 0) f = sb.nearest(p, std::numeric_limits<double>::infinity(), bary, d2);
      last = f;
      if (f < 0 || d2 <= tol * tol) continue;
      const auto& t = skin.faces[static_cast<size_t>(f)];
      const dvec3 q = bary.x * skin.positions[t[0]] + bary.y * skin.positions[t[1]] + bary.z * skin.positions[t[2]];
      dvec3 n;
      const int zeros = (bary.x == 0) + (bary.y == 0) + (bary.z == 0);
      if (zeros >= 2) {
        const int c = bary.x != 0 ? 0 : (bary.y != 0 ? 1 : 2);
        if (sign.vertexBoundary[t[c]]) continue;
        n = sign.vertexN[t[c]];
      } else if (zeros == 1) {
        const int c = bary.z == 0 ? 0 : (bary.x == 0 ? 1 : 2);
        if (sign.edgeBoundary[static_cast<size_t>(f)][c]) continue;
        n = sign.edgeN[static_cast<size_t>(f)][c];
      } else {
        n = skin.faceNormals[static_cast<size_t>(f)];
      }
      if (glm::dot(p - q, n) < 0) bad[v] = 1;
    }
  });
  if (!done) bad.clear();
  return bad;
}

}  // namespace

size_t countIntersectingPairs(const TriMesh& coat, int threads) {
  if (threads >= 1) {
    tbb::task_arena arena(threads);
    return arena.execute([&] { return intersectingPairs(coat); });
  }
  return intersectingPairs(coat);
}

std::optional<size_t> countIntersectingPairs(const TriMesh& coat, const ProgressFn& progress, int threads) {
  std::optional<size_t> n;
  detail::inArena(threads, [&] {
    const Progress whole{progress ? &progress : nullptr, 0, 1};
    if (!whole(0)) return;
    if (coat.triangleCount() < 2) {
      n = whole(1) ? std::optional<size_t>(0) : std::nullopt;
      return;
    }
    const CoatBvh cb(coat, whole.part(0, 0.4));
    if (!cb.complete) return;
    n = intersectingPairs(cb, nullptr, nullptr, whole.part(0.4, 1));
  });
  return n;
}

std::vector<uint64_t> intersectingTrianglePairs(const TriMesh& coat) {
  std::vector<uint64_t> tris;
  intersectingPairs(coat, nullptr, &tris);
  return tris;
}

std::vector<uint64_t> intersectingTrianglePairs(const TriMesh& coat, const ProgressFn& progress) {
  const Progress whole{progress ? &progress : nullptr, 0, 1};
  std::vector<uint64_t> tris;
  if (!whole(0)) return tris;
  if (coat.triangleCount() >= 2) {
    const CoatBvh cb(coat, whole.part(0, 0.3));
    if (!cb.complete || !intersectingPairs(cb, nullptr, &tris, whole.part(0.3, 1))) return {};
  }
  whole(1);
  return tris;
}

std::vector<uint64_t> intersectingTrianglePairsWith(const TriMesh& coat, const std::vector<uint8_t>& feathers,
                                                    const ProgressFn& progress) {
  const Progress whole{progress ? &progress : nullptr, 0, 1};
  std::vector<uint64_t> tris;
  if (!whole(0)) return tris;
  if (coat.triangleCount() >= 2) {
    const CoatBvh cb(coat, whole.part(0, 0.3));
    if (!cb.complete || !intersectingPairs(cb, nullptr, &tris, whole.part(0.3, 1), &feathers)) return {};
  }
  whole(1);
  return tris;
}

std::vector<uint8_t> verticesInsideSkin(const SkinMesh& skin, const TriMesh& coat, const CheckOptions& o) {
  if (skin.faces.empty()) return std::vector<uint8_t>(coat.positions.size(), 0);
  const double tol = o.skinTolerance > 0 ? o.skinTolerance : 1e-6 * diagonal(skin);
  return insideSkin(skin, buildSign(skin), coat, o, tol, Progress{o.progress ? &o.progress : nullptr, 0, 1});
}

std::vector<FeatherPairCount> intersectingFeatherPairs(const TriMesh& coat, int threads) {
  std::vector<uint64_t> keys;
  if (threads >= 1) {
    tbb::task_arena arena(threads);
    arena.execute([&] { intersectingPairs(coat, &keys); });
  } else {
    intersectingPairs(coat, &keys);
  }
  return groupPairs(keys);
}

CheckResult check(const SkinMesh& skin, const std::vector<uint32_t>& tractFaces, const TriMesh& coat,
                  const CheckOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!coat.featherId.empty() && coat.featherId.size() != coat.positions.size())
    throw Error("coat mesh featherId must have one entry per vertex", {}, "featherId");
  for (size_t k = 0; k < tractFaces.size(); ++k)
    if (tractFaces[k] >= skin.faces.size())
      throw Error("tract face " + std::to_string(tractFaces[k]) + " out of range", {},
                  "tractFaces[" + std::to_string(k) + "]");
  if (!o.featherOrigins.empty() && o.featherOrigins.size() != o.featherBaseRadius.size())
    throw Error("featherOrigins and featherBaseRadius differ in size", {}, "featherBaseRadius");
  CheckResult res;
  res.coatTriangles = coat.triangleCount();
  const bool skinParts = (o.penetrations || o.coverage) && !skin.faces.empty();
  const bool coverage = skinParts && o.coverage && o.coverageSamples > 0;
  // Progress over the parts by their rough cost (one BVH over the coat for the pairs and the coverage
  // rays, the pair search, one nearest-skin query per coat vertex, the rays).
  const double wBuild = o.intersections || coverage ? 3 : 0, wPairs = o.intersections ? 4 : 0;
  const double wPen = skinParts && o.penetrations ? 3 : 0, wCov = coverage ? 1 : 0;
  const double wAll = std::max(1.0, wBuild + wPairs + wPen + wCov);
  const Progress whole{o.progress ? &o.progress : nullptr, 0, 1};
  double at = 0;
  auto next = [&](double w) {
    const Progress p = whole.part(at / wAll, (at + w) / wAll);
    at += w;
    return p;
  };
  auto body = [&] {
    if (!whole(0)) return;
    std::optional<CoatBvh> cb;
    detail::TriangleBvh wholeTree;  // CheckOptions::reference: the coverage rays' tree
    if (o.reference) {
      if (coverage) wholeTree.build(coat.positions.data(), coat.indices.data(), coat.triangleCount());
    } else if (o.intersections || coverage) {
      cb.emplace(coat, next(wBuild));
      if (!cb->complete) return;
    }
    if (o.intersections) {
      std::vector<uint64_t> keys;
      const std::optional<size_t> pairs =
          o.reference ? std::optional<size_t>(referencePairs(coat, o.attribute ? &keys : nullptr))
                      : intersectingPairs(*cb, o.attribute ? &keys : nullptr, nullptr, next(wPairs));
      if (!pairs) return;
      res.intersectingPairs = *pairs;
      if (o.attribute) res.featherPairs = groupPairs(keys);
    }
    const double diag = diagonal(skin);
    const double tol = o.skinTolerance > 0 ? o.skinTolerance : 1e-6 * diag;
    if (skinParts) {
      const SkinSign sign = buildSign(skin);
      if (o.penetrations) {
        const size_t nv = coat.positions.size();
        const std::vector<uint8_t> bad = insideSkin(skin, sign, coat, o, tol, next(wPen));
        if (bad.size() != nv) return;
        res.samplePoints = nv;
        std::vector<uint8_t> featherBad;
        for (size_t v = 0; v < nv; ++v) {
          if (!bad[v]) continue;
          ++res.skinPenetrations;
          const uint32_t f = coat.featherId.empty() ? 0 : coat.featherId[v];
          if (featherBad.size() <= f) featherBad.resize(f + 1, 0);
          featherBad[f] = 1;
          if (o.attribute) {
            if (res.featherPenetrations.size() <= f) res.featherPenetrations.resize(f + 1, 0);
            ++res.featherPenetrations[f];
          }
        }
        for (uint32_t f = 0; f < featherBad.size(); ++f)
          if (featherBad[f]) res.penetratingFeathers.push_back(f);
      }
      if (coverage) {
        std::vector<uint32_t> faces = tractFaces;
        if (faces.empty())
          for (uint32_t f = 0; f < skin.faces.size(); ++f) faces.push_back(f);
        std::vector<double> cdf(faces.size());
        double acc = 0;
        for (size_t k = 0; k < faces.size(); ++k) {
          acc += skin.faceAreas[faces[k]];
          cdf[k] = acc;
        }
        const double off = o.rayOffset > 0 ? o.rayOffset : 1e-6 * diag;
        const double tMax = o.maxRayDistance > 0 ? o.maxRayDistance : std::numeric_limits<double>::infinity();
        const size_t ns = acc > 0 ? o.coverageSamples : 0;
        std::atomic<size_t> covered{0};
        std::vector<std::atomic<uint32_t>> faceSamples(o.attribute ? skin.faces.size() : 0),
            faceUncovered(o.attribute ? skin.faces.size() : 0);
        const bool done = batched(ns, 256, next(wCov), [&](const tbb::blocked_range<size_t>& r) {
          size_t hits = 0;
          for (size_t s = r.begin(); s < r.end(); ++s) {
            const double x = hashUniform(o.seed, s, 0) * acc;
            size_t k = static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin());
            k = std::min(k, faces.size() - 1);
            const uint32_t f = faces[k];
            double a = hashUniform(o.seed, s, 1), b = hashUniform(o.seed, s, 2);
            if (a + b > 1) {
              a = 1 - a;
              b = 1 - b;
            }
            const dvec3 bary(1 - a - b, a, b);
            const dvec3 p = pointAt(skin, f, bary);
            const dvec3 n = normalAt(skin, f, bary);
            const dvec3 origin = p + off * skin.faceNormals[f];
            const bool hit = o.reference ? wholeTree.anyHit(origin, n, 0.0, tMax) : cb->anyHit(origin, n, 0.0, tMax);
            if (hit) ++hits;
            if (o.attribute) {
              faceSamples[f].fetch_add(1, std::memory_order_relaxed);
              if (!hit) faceUncovered[f].fetch_add(1, std::memory_order_relaxed);
            }
          }
          covered += hits;
        });
        if (!done) return;
        if (o.attribute) {
          res.faceSamples.resize(skin.faces.size());
          res.faceUncovered.resize(skin.faces.size());
          for (size_t f = 0; f < skin.faces.size(); ++f) {
            res.faceSamples[f] = faceSamples[f].load();
            res.faceUncovered[f] = faceUncovered[f].load();
          }
        }
        res.coverageSamples = ns;
        res.coveredSamples = covered.load();
        res.coverage = ns > 0 ? static_cast<double>(res.coveredSamples) / ns : 0.0;
      }
    }
    res.complete = true;
  };
  detail::inArena(o.threads, body);
  if (res.complete) whole(1);
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

void setFeatherBases(CheckOptions& o, const CoatFeathers& coat, double baseAllowance) {
  o.featherOrigins.resize(coat.size());
  o.featherBaseRadius.resize(coat.size());
  for (size_t i = 0; i < coat.size(); ++i) {
    const feather::FeatherParams& p = coat.params[i];
    o.featherOrigins[i] = coat.frames[i].origin;
    o.featherBaseRadius[i] = std::max(baseAllowance * p.totalLength(), 0.5 * p.calamusWidthRatio * p.rachisWidth);
  }
}

TriMesh proxyCoatMesh(const CoatFeathers& coat, const std::vector<double>& elevation,
                      const std::vector<feather::FeatherParams>& params, const ProxyMeshOptions& o) {
  const size_t n = coat.size();
  PTERYLA_CHECK(elevation.size() == n && params.size() == n,
                "proxyCoatMesh needs one elevation and params per feather");
  std::vector<TriMesh> parts(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 8), [&](const tbb::blocked_range<size_t>& r) {
    feather::FeatherCurves curves;
    std::vector<glm::vec3> a, b;
    for (size_t i = r.begin(); i < r.end(); ++i) {
      if (!coat.present.empty() && !coat.present[i]) continue;
      TriMesh& m = parts[i];
      const FeatherFrame& F = coat.frames[i];
      const double e = elevation[i];
      const feather::FeatherParams& p = params[i];
      auto vert = [&](const dvec3& local) {
        m.positions.emplace_back(placePoint(F, e, local));
        m.featherId.push_back(static_cast<uint32_t>(i));
        return static_cast<uint32_t>(m.positions.size() - 1);
      };
      auto quad = [&](uint32_t p0, uint32_t p1, uint32_t p2, uint32_t p3) {
        m.indices.insert(m.indices.end(), {p0, p1, p2, p0, p2, p3});
      };
      const bool unopened = !coat.age.empty() && coat.age[i] < o.openingAge;
      const int ss = std::max(1, o.shaftSegments);
      if (unopened) {
        const double w = 0.5 * p.rachisWidth;
        uint32_t prevL = 0, prevR = 0;
        for (int k = 0; k <= ss; ++k) {
          const double x = p.totalLength() * k / ss;
          const uint32_t l = vert({x, w, 0}), rr = vert({x, -w, 0});
          if (k > 0) quad(prevL, prevR, rr, l);
          prevL = l;
          prevR = rr;
        }
        continue;
      }
      // Shaft ribbon.
      {
        uint32_t prevL = 0, prevR = 0;
        for (int k = -2; k <= ss; ++k) {
          dvec3 c, left;
          double w;
          if (k < 0) {
            const double u = (k + 2) / 2.0;
            c = {p.calamusLength * u, 0, 0};
            left = {0, 1, 0};
            w = p.rachisWidth * (p.calamusWidthRatio * (1 - u) + u);
          } else {
            const feather::RachisFrame f = feather::rachisFrame(p, static_cast<double>(k) / ss);
            c = f.point;
            left = f.left;
            w = f.width;
          }
          const uint32_t l = vert(c + 0.5 * w * left), rr = vert(c - 0.5 * w * left);
          if (k > -2) quad(prevL, prevR, rr, l);
          prevL = l;
          prevR = rr;
        }
      }
      // Vanes: strips between consecutive barbs of the main part.
      feather::GenerateOptions go;
      go.afterfeather = false;
      feather::generateBarbs(p, curves, go);
      if (curves.partCount() == 0) continue;
      const int segs = std::max(1, o.barbSegments);
      const uint32_t b0 = curves.barbBegin[0], b1 = curves.barbEnd[0];
      const int stride = std::max(1, o.barbStride);
      for (int v = 0; v < 2; ++v) {
        std::vector<uint32_t> idx;
        for (uint32_t k = b0; k < b1; ++k)
          if (curves.barbs[k].vane == v) idx.push_back(k);
        std::vector<uint32_t> sel;
        for (size_t k = 0; k < idx.size(); k += stride) sel.push_back(idx[k]);
        if (!idx.empty() && sel.back() != idx.back()) sel.push_back(idx.back());
        std::vector<uint32_t> prevRow;
        bool prevSplit = false;
        for (uint32_t k : sel) {
          feather::barbPolyline(curves, curves.barbs[k], segs, a);
          std::vector<uint32_t> row;
          for (const auto& q : a) row.push_back(vert(dvec3(q)));
          if (!prevRow.empty() && !prevSplit)
            for (int s = 0; s < segs; ++s) quad(prevRow[s], prevRow[s + 1], row[s + 1], row[s]);
          prevRow = row;
          prevSplit = curves.barbs[k].splitAfter;
        }
      }
    }
  });
  TriMesh out;
  for (auto& p : parts) {
    const uint32_t base = static_cast<uint32_t>(out.positions.size());
    out.positions.insert(out.positions.end(), p.positions.begin(), p.positions.end());
    out.featherId.insert(out.featherId.end(), p.featherId.begin(), p.featherId.end());
    for (uint32_t k : p.indices) out.indices.push_back(base + k);
  }
  return out;
}

}  // namespace pteryla::coat
