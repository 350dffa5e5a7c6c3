// What a DrapeCache keeps of a drape, and the drape of moult frames over the mature coat's
// (drape_internal.hpp).
#include "drape_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

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
  return flatLike(m, mesh, L, i, [&](size_t q, uint32_t v, bool hasN, bool hasT) {
    return m.flatPos[q] == mesh.positions[v] && (!hasN || m.flatNrm[q] == mesh.normals[v]) &&
           (!hasT || m.flatTan[q] == mesh.tangents[v]);
  });
}

void keepFlat(FeatherMemo& m, const TriMesh& mesh, const CoatLayout& L, uint32_t i) {
  const size_t nv = mesh.positions.size(), cnt = L.first[i + 1] - L.first[i], tc = L.trisOf[i + 1] - L.trisOf[i];
  const bool hasN = mesh.normals.size() == nv, hasT = mesh.tangents.size() == nv;
  m.flatPos.resize(cnt);
  m.flatNrm.resize(hasN ? cnt : 0);
  m.flatTan.resize(hasT ? cnt : 0);
  for (size_t l = 0; l < cnt; ++l) {
    const uint32_t v = L.verts[L.first[i] + l];
    m.flatPos[l] = mesh.positions[v];
    if (hasN) m.flatNrm[l] = mesh.normals[v];
    if (hasT) m.flatTan[l] = mesh.tangents[v];
  }
  m.flatTris.resize(3 * tc);
  for (size_t q = 0; q < tc; ++q)
    for (int c = 0; c < 3; ++c)
      m.flatTris[3 * q + c] = L.localVert[mesh.indices[3 * static_cast<size_t>(L.tris[L.trisOf[i] + q]) + c]];
}

void keepPlaced(FeatherMemo& m, const TriMesh& mesh, const CoatLayout& L, uint32_t i,
                const std::vector<glm::vec3>& surfacePoint, const std::vector<uint8_t>& bad) {
  const size_t nv = mesh.positions.size(), cnt = L.first[i + 1] - L.first[i];
  const bool hasN = mesh.normals.size() == nv, hasT = mesh.tangents.size() == nv;
  m.pos.resize(cnt);
  m.nrm.resize(hasN ? cnt : 0);
  m.tan.resize(hasT ? cnt : 0);
  m.surface.resize(cnt);
  m.bad.resize(cnt);
  for (size_t l = 0; l < cnt; ++l) {
    const uint32_t v = L.verts[L.first[i] + l];
    m.pos[l] = mesh.positions[v];
    if (hasN) m.nrm[l] = mesh.normals[v];
    if (hasT) m.tan[l] = mesh.tangents[v];
    m.surface[l] = surfacePoint[v];
    m.bad[l] = bad[v];
  }
}

void tally(DrapeResult& res, const std::vector<uint32_t>& order, const std::vector<size_t>& cut,
           const std::vector<size_t>& kept, const std::function<const Chart&(uint32_t)>& chartOf) {
  for (uint32_t i : order) {
    ++res.stats.draped;
    res.stats.overhangingNodes += chartOf(i).overhanging;
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

std::vector<PairMemo> pairMemos(const std::vector<uint64_t>& pairs, const TriMesh& mesh, const CoatLayout& L) {
  std::vector<PairMemo> out;
  out.reserve(pairs.size());
  for (uint64_t pr : pairs) {
    const uint32_t t = static_cast<uint32_t>(pr >> 32), u = static_cast<uint32_t>(pr & 0xffffffffu);
    const uint32_t ft = mesh.featherId[mesh.indices[3 * static_cast<size_t>(t)]],
                   fu = mesh.featherId[mesh.indices[3 * static_cast<size_t>(u)]];
    out.push_back({ft, L.localTri[t], fu, L.localTri[u]});
  }
  return out;
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
  if (mesh.featherId.size() != mesh.positions.size())
    throw Error("the coat mesh needs one featherId per vertex", {}, "featherId");
  if (coat.frames.size() != coat.size() || coat.params.size() != coat.size())
    throw Error("the coat needs one frame and one parameter set per feather", {}, "frames");
  if (!M.valid) throw Error("the mature coat has not been draped", {}, "mature");
  if (M.feathers.size() != coat.size())
    throw Error("the mature coat has " + std::to_string(M.feathers.size()) + " feathers, this frame " +
                    std::to_string(coat.size()),
                {}, "mature");
  if (!sameSkin(M.skin, skin)) throw Error("the mature coat was draped over another skin", {}, "mature");
  // The mature drape carried to its own skin: unchanged feathers copied, the others (growing) placed on
  // their mature charts, the guarantees enforced for them.
  return carry(skin, skin, coat, mesh, M, o, nullptr);
}

}  // namespace pteryla::coat::draping
