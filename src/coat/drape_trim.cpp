// The draped packer's trims over later follicles, the crossing pairs near changed triangles, and the
// boxes a chart reads and writes (drape_internal.hpp).
#include "drape_internal.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
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

namespace {

// Do feathers i and j (neither touched) need their pairs searched: are they on different pieces?
bool apart(const std::vector<int32_t>* piece, uint32_t i, uint32_t j) { return piece && (*piece)[i] != (*piece)[j]; }

// The feathers a search for the changed triangles' crossing pairs needs: `touched` those with a changed
// live triangle, `take` every feather whose live bounds meet a touched one's or one on a moved piece
// (`piece` >= 1; either meets its own). False when there is nothing to search.
bool featherReach(const TriMesh& mesh, const std::vector<uint32_t>& order, const std::vector<uint32_t>& trisOf,
                  const std::vector<uint32_t>& tris, const std::vector<uint8_t>& changedTri,
                  const std::vector<int32_t>* piece, std::vector<uint8_t>& touched, std::vector<uint8_t>& take) {
  const size_t n = trisOf.size() - 1;
  touched.assign(n, 0);
  take.assign(n, 0);
  std::vector<detail::Box> liveBox(n);  // per feather, its live triangles' bounds
  tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const uint32_t i = order[k];
      for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) {
        const size_t t = tris[q];
        if (isCut(mesh, t)) continue;
        if (changedTri[t]) touched[i] = 1;
        for (int c = 0; c < 3; ++c) liveBox[i].add(dvec3(mesh.positions[mesh.indices[3 * t + c]]));
      }
    }
  });
  std::vector<uint32_t> touchedList, all;
  std::vector<detail::Box> touchedBox, allBox;
  for (uint32_t i : order) {
    if ((touched[i] || (piece && (*piece)[i] >= 1)) && !liveBox[i].empty()) {
      touchedList.push_back(i);
      touchedBox.push_back(liveBox[i]);
    }
    if (!liveBox[i].empty()) {
      all.push_back(i);
      allBox.push_back(liveBox[i]);
    }
  }
  if (touchedList.empty()) return false;
  std::vector<dvec3> cAll, cTouched;
  std::vector<uint32_t> iAll, iTouched;
  detail::TriangleBvh allTree, touchedTree;
  detail::buildBoxTree(allBox, cAll, iAll, allTree);
  detail::buildBoxTree(touchedBox, cTouched, iTouched, touchedTree);
  allTree.overlappingPairs(touchedTree, [&](uint32_t a, uint32_t b) {
    const uint32_t i = all[a];
    if (!take[i] && liveBox[i].overlaps(liveBox[touchedList[b]])) take[i] = 1;
  });
  return true;
}

}  // namespace

std::vector<uint64_t> pairsWithChanged(const TriMesh& mesh, const std::vector<uint32_t>& order,
                                       const std::vector<uint32_t>& trisOf, const std::vector<uint32_t>& tris,
                                       const std::vector<uint8_t>& changedTri, const ProgressFn& progress,
                                       const std::vector<int32_t>* piece) {
  const size_t nt = mesh.triangleCount(), nv = mesh.positions.size();
  std::vector<uint8_t> touched, take;
  std::vector<uint64_t> pairs;
  if (!featherReach(mesh, order, trisOf, tris, changedTri, piece, touched, take)) return pairs;
  // The search below finds every pair with a triangle of a marked feather: touched, or on a moved piece.
  std::vector<uint8_t> marked = touched;
  if (piece)
    for (uint32_t i : order)
      if ((*piece)[i] >= 1) marked[i] = 1;
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
  for (uint64_t pr : intersectingTrianglePairsWith(part, marked, progress)) {
    const uint32_t t = triBack[pr >> 32], u = triBack[pr & 0xffffffffu];
    if (changedTri[t] || changedTri[u] ||
        apart(piece, mesh.featherId[mesh.indices[3 * size_t(t)]], mesh.featherId[mesh.indices[3 * size_t(u)]]))
      pairs.push_back((uint64_t(std::min(t, u)) << 32) | std::max(t, u));
  }
  return pairs;
}

std::vector<uint64_t> pairsWithChanged(const TriMesh& mesh, const std::vector<uint32_t>& order,
                                       const std::vector<uint32_t>& trisOf, const std::vector<uint32_t>& tris,
                                       const std::vector<uint8_t>& changedTri, PairTrees& cache,
                                       const std::vector<int32_t>* piece) {
  const size_t n = trisOf.size() - 1;
  std::vector<uint8_t> touched, take;
  std::vector<uint64_t> pairs;
  if (!featherReach(mesh, order, trisOf, tris, changedTri, piece, touched, take)) return pairs;
  const std::lock_guard<std::mutex> hold(cache.lock);
  if (cache.tree.size() != n) {
    cache.tree.assign(n, detail::TriangleBvh{});
    cache.count.assign(n, 0);
  }
  // Per taken feather its triangles' current corners (collapsed ones too: a refitted tree leaves them
  // out) and shapes, and its tree: the cached one refitted, or built again if its triangle count changed.
  std::vector<uint32_t> taken, base(n, 0);
  size_t slots = 0;
  for (uint32_t i : order)
    if (take[i]) {
      taken.push_back(i);
      base[i] = static_cast<uint32_t>(slots);
      slots += trisOf[i + 1] - trisOf[i];
    }
  std::vector<uint32_t> idx(3 * slots);
  // What the triangle test reads of a slot, together: its corners, its shape, its triangle and whether
  // it changed.
  struct Slot {
    dvec3 v[3];
    detail::TriangleShape shape;
    uint32_t tri;
    uint8_t changed;
  };
  std::vector<Slot> slot(slots);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, taken.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t z = r.begin(); z < r.end(); ++z) {
      const uint32_t i = taken[z];
      const uint32_t tc = trisOf[i + 1] - trisOf[i];
      for (uint32_t q = 0; q < tc; ++q) {
        const size_t t = tris[trisOf[i] + q], s = base[i] + q;
        Slot& sl = slot[s];
        for (int c = 0; c < 3; ++c) {
          idx[3 * s + c] = mesh.indices[3 * t + c];
          sl.v[c] = dvec3(mesh.positions[idx[3 * s + c]]);
        }
        sl.tri = static_cast<uint32_t>(t);
        sl.changed = changedTri[t];
        if (!isCut(mesh, t)) sl.shape = detail::triangleShape(sl.v[0], sl.v[1], sl.v[2]);
      }
      detail::TriangleBvh& tree = cache.tree[i];
      if (cache.count[i] != tc || tree.empty()) {
        tree.build(mesh.positions.data(), idx.data() + 3 * static_cast<size_t>(base[i]), tc);
        tree.makePrimBoxes();
        cache.count[i] = tc;
      }
      tree.refit(mesh.positions.data(), idx.data() + 3 * static_cast<size_t>(base[i]));
    }
  });
  // The taken feathers whose trees hold a live triangle, and the pairs of them whose bounds meet with a
  // touched one: every crossing pair the search over the whole coat finds with a changed triangle.
  std::vector<uint32_t> group;
  std::vector<detail::Box> groupBox;
  for (uint32_t i : taken) {
    glm::vec3 lo, hi;
    if (!cache.tree[i].bounds(lo, hi) || lo.x > hi.x) continue;
    group.push_back(i);
    groupBox.emplace_back();
    groupBox.back().add(dvec3(lo));
    groupBox.back().add(dvec3(hi));
  }
  std::vector<std::pair<uint32_t, uint32_t>> tasks;
  if (!group.empty()) {
    std::vector<dvec3> corners;
    std::vector<uint32_t> boxIdx;
    detail::TriangleBvh top;
    detail::buildBoxTree(groupBox, corners, boxIdx, top);
    top.overlappingPairs(top, [&](uint32_t g, uint32_t h) {
      if (g < h && (touched[group[g]] || touched[group[h]] || apart(piece, group[g], group[h])))
        tasks.emplace_back(group[g], group[h]);
    });
  }
  tbb::combinable<std::vector<uint64_t>> found;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, tasks.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<uint64_t>& mine = found.local();
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const uint32_t f = tasks[k].first, g = tasks[k].second;
      const Slot *sf = slot.data() + base[f], *sg = slot.data() + base[g];
      const bool every = apart(piece, f, g);  // on different pieces: every pair of theirs
      cache.tree[f].overlappingPairs(cache.tree[g], [&](uint32_t a, uint32_t b) {
        const Slot *x = sf + a, *y = sg + b;
        if (!every && !x->changed && !y->changed) return;
        // Moeller's test on the lower triangle index first, as the search over the whole coat runs it.
        if (y->tri < x->tri) std::swap(x, y);
        if (detail::trianglesIntersect(x->v[0], x->v[1], x->v[2], x->shape, y->v[0], y->v[1], y->v[2], y->shape))
          mine.push_back((uint64_t(x->tri) << 32) | y->tri);
      });
    }
  });
  found.combine_each([&](const std::vector<uint64_t>& v) { pairs.insert(pairs.end(), v.begin(), v.end()); });
  std::sort(pairs.begin(), pairs.end());
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
