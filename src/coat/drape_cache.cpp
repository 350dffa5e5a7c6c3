// What a DrapeCache keeps of a drape, and the drape of moult frames over the mature coat's
// (drape_internal.hpp).
#include "drape_internal.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <chrono>

namespace pteryla::coat {

using glm::dvec3;
using namespace draping;

DrapeCache::DrapeCache() : state_(std::make_unique<State>()) {}
DrapeCache::~DrapeCache() = default;
DrapeCache::DrapeCache(DrapeCache&&) noexcept = default;
DrapeCache& DrapeCache::operator=(DrapeCache&&) noexcept = default;
void DrapeCache::clear() {
  const bool keepAlways = state_->keepAlways;
  state_ = std::make_unique<State>();
  state_->keepAlways = keepAlways;
}
void DrapeCache::keepEveryDrape() { state_->keepAlways = true; }
size_t DrapeCache::bytes() const {
  const State& s = *state_;
  size_t b = s.skin.positions.capacity() * sizeof(dvec3) * 3 + s.skin.faces.capacity() * 16 +
             s.pairs.capacity() * sizeof(PairMemo) + (s.top ? s.top->bytes() : 0);
  for (const FeatherMemo& f : s.feathers) {
    b += sizeof(FeatherMemo) + (f.flatPos.capacity() + f.flatNrm.capacity() + f.flatTan.capacity() + f.pos.capacity() +
                                f.nrm.capacity() + f.tan.capacity() + f.surface.capacity()) *
                                   sizeof(glm::vec3);
    b += f.flatTris.capacity() * 4 + f.reads.capacity() * 8 + f.chart.nodes.capacity() * sizeof(Node) +
         f.chart.reqSamples.capacity() * 4 + f.chart.under.capacity() * sizeof(Chart::Cover) + f.chart.fine.capacity() +
         f.bad.capacity() * 2 + f.overFollicle.capacity() * 2;
  }
  return b;
}

}  // namespace pteryla::coat

namespace pteryla::coat::draping {

using glm::dvec3;

void insideSkinFor(const SkinMesh& skin, const TriMesh& mesh, const CoatLayout& L,
                   const std::vector<uint32_t>& feathers, const CheckOptions& co, std::vector<uint8_t>& inside) {
  if (feathers.empty()) return;
  TriMesh part;
  std::vector<uint32_t> back;
  for (uint32_t i : feathers)
    for (uint32_t q = L.first[i]; q < L.first[i + 1]; ++q) {
      back.push_back(L.verts[q]);
      part.positions.push_back(mesh.positions[L.verts[q]]);
      part.featherId.push_back(i);
    }
  const std::vector<uint8_t> in = verticesInsideSkin(skin, part, co);
  if (in.size() != back.size()) throw Error("the drape was cancelled", {}, "drape");
  for (size_t k = 0; k < back.size(); ++k) inside[back[k]] = in[k];
}

bool sameFlat(const FeatherMemo& m, const TriMesh& mesh, const CoatLayout& L, uint32_t i) {
  const uint32_t* vs = L.verts.data() + L.first[i];
  const size_t cnt = L.first[i + 1] - L.first[i], tc = L.trisOf[i + 1] - L.trisOf[i];
  const bool hasN = mesh.normals.size() == mesh.positions.size(), hasT = mesh.tangents.size() == mesh.positions.size();
  if (m.flatPos.size() != cnt || m.flatTris.size() != 3 * tc) return false;
  if ((hasN && m.flatNrm.size() != cnt) || (hasT && m.flatTan.size() != cnt)) return false;
  for (size_t q = 0; q < cnt; ++q)
    if (m.flatPos[q] != mesh.positions[vs[q]] || (hasN && m.flatNrm[q] != mesh.normals[vs[q]]) ||
        (hasT && m.flatTan[q] != mesh.tangents[vs[q]]))
      return false;
  for (size_t q = 0; q < tc; ++q)
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = mesh.indices[3 * static_cast<size_t>(L.tris[L.trisOf[i] + q]) + c];
      if (mesh.featherId[v] != i || m.flatTris[3 * q + c] != L.localVert[v]) return false;
    }
  return true;
}

void tally(DrapeResult& res, const std::vector<uint32_t>& order, const std::vector<size_t>& cut,
           const std::vector<size_t>& kept, const std::function<const Chart&(uint32_t)>& chartOf) {
  for (uint32_t i : order) {
    ++res.stats.draped;
    for (const Node& nd : chartOf(i).nodes) res.stats.overhangingNodes += nd.free && nd.active;
    if (cut[i]) {
      res.trimmed[i] = 1;
      ++res.stats.trimmedFeathers;
      res.stats.trimmedTriangles += cut[i];
      if (!kept[i]) {
        res.hidden[i] = 1;
        ++res.stats.hiddenFeathers;
      }
    }
  }
}

bool sameSkin(const SkinMesh& a, const SkinMesh& b) {
  return a.positions.size() == b.positions.size() && a.faces.size() == b.faces.size() &&
         std::equal(a.positions.begin(), a.positions.end(), b.positions.begin()) &&
         std::equal(a.faces.begin(), a.faces.end(), b.faces.begin()) &&
         std::equal(a.vertexNormals.begin(), a.vertexNormals.end(), b.vertexNormals.begin(), b.vertexNormals.end()) &&
         std::equal(a.faceNormals.begin(), a.faceNormals.end(), b.faceNormals.begin(), b.faceNormals.end());
}

bool sameFrame(const FeatherFrame& a, const FeatherFrame& b) {
  return a.origin == b.origin && a.normal == b.normal && a.tangent == b.tangent && a.binormal == b.binormal;
}

DrapeResult drapeOver(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh, const DrapeCache::State& M,
                      const DrapeOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t n = coat.size(), nv = mesh.positions.size();
  if (mesh.featherId.size() != nv) throw Error("the coat mesh needs one featherId per vertex", {}, "featherId");
  if (coat.frames.size() != n || coat.params.size() != n)
    throw Error("the coat needs one frame and one parameter set per feather", {}, "frames");
  if (!M.valid) throw Error("the mature coat has not been draped", {}, "mature");
  if (M.feathers.size() != n)
    throw Error(
        "the mature coat has " + std::to_string(M.feathers.size()) + " feathers, this frame " + std::to_string(n), {},
        "mature");
  if (!sameSkin(M.skin, skin)) throw Error("the mature coat was draped over another skin", {}, "mature");
  DrapeResult res;
  res.elevation.assign(n, 0.0);
  res.trimmed.assign(n, 0);
  res.hidden.assign(n, 0);
  res.stats.gap = M.gap;
  if (nv == 0) return res;
  const CoatLayout L(coat, mesh);
  const std::vector<uint32_t>&first = L.first, &verts = L.verts, &trisOf = L.trisOf, &tris = L.tris;
  const std::vector<int64_t>& rank = L.rank;
  const std::vector<uint32_t>& order = L.order;
  for (uint32_t i : order)
    if (!M.feathers[i].laid) throw Error("feather " + std::to_string(i) + " has no mature drape", {}, "mature");
  {
    // This frame's layers keep the mature coat's order.
    size_t k = 0;
    for (uint32_t i : M.order)
      if (k < order.size() && order[k] == i) ++k;
    if (k != order.size()) throw Error("the frame's layer order differs from the mature coat's", {}, "layerOrder");
  }
  const size_t nt = mesh.triangleCount();
  const bool hasN = mesh.normals.size() == nv, hasT = mesh.tangents.size() == nv;
  report(o.progress, "drape", 0);
  // Per feather: its flat mesh is the mature drape's (copied), else placed on its mature chart.
  std::vector<uint8_t> placed(n, 0);
  std::vector<glm::vec3> surfacePoint(nv);
  std::vector<uint8_t> bad(nv, 0), inside(nv, 0), overFollicle(nt, 0);
  detail::inArena(o.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        const uint32_t i = order[k];
        const FeatherMemo& m = M.feathers[i];
        const uint32_t* vs = verts.data() + first[i];
        const size_t cnt = first[i + 1] - first[i], tc = trisOf[i + 1] - trisOf[i];
        const bool same = sameFrame(m.frame, coat.frames[i]) && sameFlat(m, mesh, L, i);
        if (same) {
          for (size_t l = 0; l < cnt; ++l) {
            const uint32_t v = vs[l];
            mesh.positions[v] = m.pos[l];
            if (hasN) mesh.normals[v] = m.nrm[l];
            if (hasT) mesh.tangents[v] = m.tan[l];
            surfacePoint[v] = m.surface[l];
            bad[v] = m.bad[l];
            inside[v] = m.inside[l];
          }
          for (size_t q = 0; q < tc; ++q) overFollicle[tris[trisOf[i] + q]] = m.overFollicle[q];
          res.elevation[i] = m.elevation;
        } else {
          placed[i] = 1;
          res.elevation[i] = placeOnChart(m.chart, coat.frames[i], mesh, vs, cnt, hasN, hasT, surfacePoint, bad);
        }
      }
    });
  });
  std::vector<uint32_t> placedList;
  for (uint32_t i : order)
    if (placed[i]) placedList.push_back(i);
  report(o.progress, "drape", 0.3);
  // Placed feathers' material over a later follicle of this frame.
  {
    std::vector<dvec3> origins;
    std::vector<double> rootZone(n, 0.0);
    double reachMax = 0;
    for (uint32_t i : order) {
      origins.push_back(coat.frames[i].origin);
      rootZone[i] = M.feathers[i].rootZone;
      reachMax = std::max(reachMax, rootZone[i]);
    }
    detail::PointGrid grid;
    grid.build(origins, std::max(reachMax, 1e-12));
    const RootZones zones{order, coat, rootZone, reachMax, grid};
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, placedList.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<LaterZone> later;
        for (size_t z = r.begin(); z < r.end(); ++z) {
          const uint32_t i = placedList[z];
          trimOverFollicles(zones, static_cast<size_t>(rank[i]), mesh, tris.data() + trisOf[i],
                            trisOf[i + 1] - trisOf[i], surfacePoint, bad, overFollicle, later);
        }
      });
    });
  }
  // Placed feathers' vertices under the skin.
  if (!placedList.empty()) {
    CheckOptions co;
    setFeatherBases(co, coat, o.baseAllowance);
    insideSkinFor(skin, mesh, L, placedList, co, inside);
  }
  report(o.progress, "drape", 0.6);
  for (uint32_t v = 0; v < nv; ++v)
    if (inside[v]) bad[v] = 1;
  std::vector<size_t> kept(n, 0), cut(n, 0);
  auto collapse = [&](size_t t) { collapseTriangle(mesh, t, cut); };
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    if (overFollicle[t] || bad[tri[0]] || bad[tri[1]] || bad[tri[2]]) collapse(t);
  }
  for (uint32_t v = 0; v < nv; ++v)
    if (bad[v]) mesh.positions[v] = glm::vec3(coat.frames[mesh.featherId[v]].origin);
  // Crossing pairs: the mature drape's pairs of two copied feathers' live triangles, and those of the
  // placed feathers' triangles searched here. A pair with a lost feather is gone, and its lower triangle
  // stays.
  std::vector<uint64_t> pairs;
  for (const PairMemo& pm : M.pairs) {
    if (rank[pm.fa] < 0 || rank[pm.fb] < 0 || placed[pm.fa] || placed[pm.fb]) continue;
    const uint32_t t = tris[trisOf[pm.fa] + pm.ta], u = tris[trisOf[pm.fb] + pm.tb];
    if (isCut(mesh, t) || isCut(mesh, u)) continue;
    pairs.push_back((uint64_t(std::min(t, u)) << 32) | std::max(t, u));
  }
  {
    std::vector<uint8_t> changedTri(nt, 0);
    for (uint32_t i : placedList)
      for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) changedTri[tris[q]] = 1;
    const std::vector<uint64_t> found = pairsWithChanged(mesh, order, trisOf, tris, changedTri, {});
    pairs.insert(pairs.end(), found.begin(), found.end());
  }
  for (uint64_t pr : pairs) {
    const size_t t = pr >> 32, u = pr & 0xffffffffu;
    const uint32_t ft = mesh.featherId[mesh.indices[3 * t]], fu = mesh.featherId[mesh.indices[3 * u]];
    collapse(rank[ft] < rank[fu] ? t : u);
  }
  for (size_t t = 0; t < nt; ++t)
    if (!isCut(mesh, t)) ++kept[mesh.featherId[mesh.indices[3 * t]]];
  tally(res, order, cut, kept, [&](uint32_t i) -> const Chart& { return M.feathers[i].chart; });
  res.stats.relaid = placedList.size();
  res.stats.reused = order.size() - placedList.size();
  report(o.progress, "drape", 1);
  res.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace pteryla::coat::draping
