// Independent interpenetration and coverage check of a feather coat at full geometry (Streit 2003, 6.3.4
// and 9.1.2 state the packing's goal: no feather-skin or feather-feather interpenetration; Figure 9.17
// shows where the height-field method can fail). Uses only the coat's triangles and the skin:
// Moeller's triangle-triangle test over a BVH, pseudo-normal signed distance (Baerentzen & Aanaes, "Signed
// distance computation using the angle weighted pseudonormal", IEEE TVCG 11(3), 2005), and ray casting
// along the skin normal for coverage.
#include "pteryla/coat/check.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/coat/pack.hpp"
#include "spatial.hpp"

namespace pteryla::coat {

using glm::dvec3;

namespace {

uint32_t triFeather(const TriMesh& m, size_t t) {
  return m.featherId.empty() ? 0u : m.featherId[m.indices[3 * t]];
}

// Counts intersecting triangle pairs of different feathers; with `attribution`, also lists the feather
// pair of every intersecting triangle pair (as (a << 32 | b), a < b, unsorted).
size_t intersectingPairs(const TriMesh& coat, std::vector<uint64_t>* attribution = nullptr,
                         std::vector<uint64_t>* triangles = nullptr) {
  const size_t nt = coat.triangleCount();
  if (nt < 2) return 0;
  detail::TriangleBvh bvh;
  bvh.build(coat.positions.data(), coat.indices.data(), nt);
  std::vector<uint32_t> featherOf(nt);
  for (size_t t = 0; t < nt; ++t) featherOf[t] = triFeather(coat, t);
  bvh.setGroups(featherOf.data());  // no pair inside one feather is ever visited
  // A dual traversal of the BVH against itself, cut into independent node pairs for the threads: each
  // pair of triangles with overlapping boxes is visited once (t < u), then Moeller's test decides.
  const std::vector<std::pair<uint32_t, uint32_t>> tasks = bvh.pairTasks(1024);
  tbb::combinable<std::vector<uint64_t>> found;
  const size_t total = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, tasks.size(), 1), size_t(0),
      [&](const tbb::blocked_range<size_t>& r, size_t acc) {
        std::vector<uint64_t>* mine = attribution || triangles ? &found.local() : nullptr;
        for (size_t k = r.begin(); k < r.end(); ++k) {
          bvh.overlappingPairs(tasks[k], [&](uint32_t t, uint32_t u) {
            const uint32_t ft = featherOf[t], fu = featherOf[u];
            if (detail::trianglesIntersect(bvh.vertex(t, 0), bvh.vertex(t, 1), bvh.vertex(t, 2), bvh.vertex(u, 0),
                                           bvh.vertex(u, 1), bvh.vertex(u, 2))) {
              ++acc;
              if (mine)
                mine->push_back(triangles ? (uint64_t(t) << 32) | u : (uint64_t(std::min(ft, fu)) << 32) | std::max(ft, fu));
            }
          });
        }
        return acc;
      },
      [](size_t a, size_t b) { return a + b; });
  if (std::vector<uint64_t>* out = triangles ? triangles : attribution) {
    out->clear();
    found.combine_each([&](const std::vector<uint64_t>& v) { out->insert(out->end(), v.begin(), v.end()); });
    if (triangles) std::sort(out->begin(), out->end());
  }
  return total;
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
  std::vector<uint32_t> flat;               // faces as a flat index array for the BVH
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
std::vector<uint8_t> insideSkin(const SkinMesh& skin, const SkinSign& sign, const TriMesh& coat, const CheckOptions& o,
                          double tol) {
  detail::TriangleBvh sb;
  sb.build(skin.positions.data(), sign.flat.data(), skin.faces.size());
  const size_t nv = coat.positions.size();
  std::vector<uint8_t> bad(nv, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, nv, 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v < r.end(); ++v) {
      const dvec3 p(coat.positions[v]);
      if (!o.featherOrigins.empty() && !coat.featherId.empty()) {
        const uint32_t f = coat.featherId[v];
        if (f < o.featherOrigins.size() && glm::length(p - o.featherOrigins[f]) <= o.featherBaseRadius[f]) continue;
      }
      glm::dvec3 bary;
      double d2 = 0;
      const int64_t f = sb.nearest(p, std::numeric_limits<double>::infinity(), bary, d2);
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

std::vector<uint64_t> intersectingTrianglePairs(const TriMesh& coat) {
  std::vector<uint64_t> tris;
  intersectingPairs(coat, nullptr, &tris);
  return tris;
}

std::vector<uint8_t> verticesInsideSkin(const SkinMesh& skin, const TriMesh& coat, const CheckOptions& o) {
  if (skin.faces.empty()) return std::vector<uint8_t>(coat.positions.size(), 0);
  const double tol = o.skinTolerance > 0 ? o.skinTolerance : 1e-6 * diagonal(skin);
  return insideSkin(skin, buildSign(skin), coat, o, tol);
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
      throw Error("tract face " + std::to_string(tractFaces[k]) + " out of range", {}, "tractFaces[" + std::to_string(k) + "]");
  if (!o.featherOrigins.empty() && o.featherOrigins.size() != o.featherBaseRadius.size())
    throw Error("featherOrigins and featherBaseRadius differ in size", {}, "featherBaseRadius");
  CheckResult res;
  res.coatTriangles = coat.triangleCount();
  auto body = [&] {
    if (o.intersections) {
      if (o.attribute) {
        std::vector<uint64_t> keys;
        res.intersectingPairs = intersectingPairs(coat, &keys);
        res.featherPairs = groupPairs(keys);
      } else {
        res.intersectingPairs = intersectingPairs(coat);
      }
    }
    const double diag = diagonal(skin);
    const double tol = o.skinTolerance > 0 ? o.skinTolerance : 1e-6 * diag;
    if ((o.penetrations || o.coverage) && !skin.faces.empty()) {
      const SkinSign sign = buildSign(skin);
      if (o.penetrations) {
        const size_t nv = coat.positions.size();
        const std::vector<uint8_t> bad = insideSkin(skin, sign, coat, o, tol);
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
      if (o.coverage && o.coverageSamples > 0) {
        std::vector<uint32_t> faces = tractFaces;
        if (faces.empty())
          for (uint32_t f = 0; f < skin.faces.size(); ++f) faces.push_back(f);
        std::vector<double> cdf(faces.size());
        double acc = 0;
        for (size_t k = 0; k < faces.size(); ++k) {
          acc += skin.faceAreas[faces[k]];
          cdf[k] = acc;
        }
        detail::TriangleBvh cb;
        cb.build(coat.positions.data(), coat.indices.data(), coat.triangleCount());
        const double off = o.rayOffset > 0 ? o.rayOffset : 1e-6 * diag;
        const double tMax = o.maxRayDistance > 0 ? o.maxRayDistance : std::numeric_limits<double>::infinity();
        const size_t ns = acc > 0 ? o.coverageSamples : 0;
        std::atomic<size_t> covered{0};
        std::vector<std::atomic<uint32_t>> faceSamples(o.attribute ? skin.faces.size() : 0),
            faceUncovered(o.attribute ? skin.faces.size() : 0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, ns, 256), [&](const tbb::blocked_range<size_t>& r) {
          size_t hits = 0;
          for (size_t s = r.begin(); s < r.end(); ++s) {
            const double x = hashUniform(o.seed, s, 0) * acc;
            size_t k = static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin());
            k = std::min(k, faces.size() - 1);
            const uint32_t f = faces[k];
            double a = hashUniform(o.seed, s, 1), b = hashUniform(o.seed, s, 2);
            if (a + b > 1) { a = 1 - a; b = 1 - b; }
            const dvec3 bary(1 - a - b, a, b);
            const dvec3 p = pointAt(skin, f, bary);
            const dvec3 n = normalAt(skin, f, bary);
            const bool hit = cb.anyHit(p + off * skin.faceNormals[f], n, 0.0, tMax);
            if (hit) ++hits;
            if (o.attribute) {
              faceSamples[f].fetch_add(1, std::memory_order_relaxed);
              if (!hit) faceUncovered[f].fetch_add(1, std::memory_order_relaxed);
            }
          }
          covered += hits;
        });
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
  };
  if (o.threads >= 1) {
    tbb::task_arena arena(o.threads);
    arena.execute(body);
  } else {
    body();
  }
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
  PTERYLA_CHECK(elevation.size() == n && params.size() == n, "proxyCoatMesh needs one elevation and params per feather");
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
