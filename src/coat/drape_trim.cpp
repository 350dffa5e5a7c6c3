// The draped packer's trims over later follicles, the crossing pairs near changed triangles, and the
// boxes a chart reads and writes (drape_internal.hpp).
#include "drape_internal.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace pteryla::coat::draping {

using glm::dvec3;

detail::Box trimOverFollicles(const RootZones& Z, size_t k, const TriMesh& mesh, const uint32_t* tris, size_t count,
                              const std::vector<glm::vec3>& surfacePoint, const std::vector<uint8_t>& bad,
                              std::vector<uint8_t>& overFollicle, std::vector<LaterZone>& later) {
  // The later follicles within reach of its surface points (from the grid, once), then per triangle those
  // whose root zone its box comes near: the follicles the test below can find.
  detail::Box fb;
  for (size_t q = 0; q < count; ++q)
    for (int c = 0; c < 3; ++c) fb.add(dvec3(surfacePoint[mesh.indices[3 * static_cast<size_t>(tris[q]) + c]]));
  if (fb.empty()) return fb;
  later.clear();
  Z.grid.query(fb.lo - dvec3(Z.reachMax), fb.hi + dvec3(Z.reachMax), [&](uint32_t j) {
    if (j <= k) return;
    const uint32_t f = Z.order[j];
    const dvec3& g = Z.coat.frames[f].origin;
    const double rj = Z.rootZone[f];
    // A little past rj: the closest point's rounding never matters.
    const double reach = rj + 1e-6 * (rj + std::max({std::abs(g.x), std::abs(g.y), std::abs(g.z)}));
    // Beyond its own reach of the feather's box, no triangle's box comes near it (the test below).
    if (g.x < fb.lo.x - reach || g.y < fb.lo.y - reach || g.z < fb.lo.z - reach || g.x > fb.hi.x + reach ||
        g.y > fb.hi.y + reach || g.z > fb.hi.z + reach)
      return;
    later.push_back({g, rj, reach});
  });
  if (later.empty()) return fb;
  for (size_t q = 0; q < count; ++q) {
    const uint32_t t = tris[q];
    const uint32_t* tri = &mesh.indices[3 * static_cast<size_t>(t)];
    if (bad[tri[0]] || bad[tri[1]] || bad[tri[2]]) continue;
    const dvec3 a(surfacePoint[tri[0]]), b(surfacePoint[tri[1]]), c(surfacePoint[tri[2]]);
    const dvec3 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
    for (const LaterZone& L : later) {
      const dvec3& g = L.g;
      if (g.x < lo.x - L.reach || g.y < lo.y - L.reach || g.z < lo.z - L.reach || g.x > hi.x + L.reach ||
          g.y > hi.y + L.reach || g.z > hi.z + L.reach)
        continue;
      const dvec3 cq = closestPointOnTriangle(g, a, b, c);
      if (glm::dot(cq - g, cq - g) < L.rj * L.rj) {
        overFollicle[t] = 1;
        break;
      }
    }
  }
  return fb;
}

std::vector<uint64_t> pairsWithChanged(const TriMesh& mesh, const std::vector<uint32_t>& order,
                                       const std::vector<uint32_t>& trisOf, const std::vector<uint32_t>& tris,
                                       const std::vector<uint8_t>& changedTri, const ProgressFn& progress) {
  const size_t n = trisOf.size() - 1, nt = mesh.triangleCount(), nv = mesh.positions.size();
  std::vector<uint8_t> touched(n, 0);   // feathers with a changed live triangle
  std::vector<detail::Box> liveBox(n);  // per feather, its live triangles' bounds
  for (uint32_t i : order)
    for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) {
      const size_t t = tris[q];
      if (isCut(mesh, t)) continue;
      if (changedTri[t]) touched[i] = 1;
      for (int c = 0; c < 3; ++c) liveBox[i].add(dvec3(mesh.positions[mesh.indices[3 * t + c]]));
    }
  std::vector<uint32_t> touchedList;
  for (uint32_t i : order)
    if (touched[i]) touchedList.push_back(i);
  std::vector<uint64_t> pairs;
  if (touchedList.empty()) return pairs;
  std::vector<uint8_t> take(n, 0);
  for (uint32_t i : order) {
    if (liveBox[i].empty()) continue;
    for (uint32_t j : touchedList)
      if (liveBox[i].overlaps(liveBox[j])) {
        take[i] = 1;
        break;
      }
  }
  // The taken feathers' live triangles in mesh order, on their own vertices.
  TriMesh part;
  std::vector<uint32_t> triBack, vertOf(nv, UINT32_MAX);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    if (!take[mesh.featherId[tri[0]]] || isCut(mesh, t)) continue;
    for (int c = 0; c < 3; ++c) {
      uint32_t& w = vertOf[tri[c]];
      if (w == UINT32_MAX) {
        w = static_cast<uint32_t>(part.positions.size());
        part.positions.push_back(mesh.positions[tri[c]]);
        part.featherId.push_back(mesh.featherId[tri[c]]);
      }
      part.indices.push_back(w);
    }
    triBack.push_back(static_cast<uint32_t>(t));
  }
  for (uint64_t pr : intersectingTrianglePairsWith(part, touched, progress)) {
    const uint32_t t = triBack[pr >> 32], u = triBack[pr & 0xffffffffu];
    if (changedTri[t] || changedTri[u]) pairs.push_back((uint64_t(std::min(t, u)) << 32) | std::max(t, u));
  }
  return pairs;
}

detail::Box airReadBox(const Chart& C, double airRadius) {
  detail::Box b;
  const double depth = 0.25 * (C.nx - 1) * C.hx;
  for (int k : C.active) {
    const Node& nd = C.nodes[k];
    if (!nd.free) continue;
    const dvec3 r = depth * glm::abs(nd.n) + dvec3(airRadius * (1 + 1e-6) + 1e-9 * (1 + depth));
    b.add(nd.c - r);
    b.add(nd.c + r);
  }
  return b;
}

detail::Box readBoxOf(const Chart& C, const CoatTop& top, double airRadius) {
  detail::Box b = airReadBox(C, airRadius);
  for (uint32_t s : C.reqSamples) b.add(top.position(s));
  for (const Chart::Cover& cv : C.under) b.add(top.position(cv.sample));
  return b;
}

detail::Box writeBoxOf(const Chart& C, const CoatTop& top) {
  detail::Box b;
  for (const Chart::Cover& cv : C.under) b.add(top.position(cv.sample));
  for (int k : C.active) b.add(C.nodes[k].c + C.nodes[k].h * C.nodes[k].n);
  return b;
}

}  // namespace pteryla::coat::draping
