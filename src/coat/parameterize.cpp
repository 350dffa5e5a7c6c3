// Tract parameterization. Streit 2003, 6.2.1 (imposed parameterization: a grid projected from screen space
// onto each tract) and 9.1.2 (its distortion, and the suggestion to use automatic low-distortion mesh
// parameterizations instead). The automatic methods are CGAL's least-squares conformal maps (Levy et al.
// 2002) and as-rigid-as-possible (Liu et al. 2008) parameterizers, run on a disk-like tract.
#include "pteryla/coat/parameterize.hpp"

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/ARAP_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/LSCM_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>

#include "pteryla/core/error.hpp"

namespace pteryla::coat {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using VertexD = CgalMesh::Vertex_index;
using HalfedgeD = CgalMesh::Halfedge_index;
namespace SMP = CGAL::Surface_mesh_parameterization;

constexpr int kMaxSeamBranches = 8;
constexpr double kSeamBranchFraction = 0.3;  // branch when the farthest vertex is this far (x first seam length)

std::string where(const Tract& t) { return "tracts." + t.name; }

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Global vertex -> local index over the tract's faces; `vertices` ascending.
struct LocalVertices {
  std::vector<uint32_t> vertices;
  std::vector<int32_t> local;  // per skin vertex, -1 = not in the tract
};

LocalVertices localVertices(const SkinMesh& skin, const Tract& tract) {
  LocalVertices lv;
  lv.local.assign(skin.vertexCount(), -1);
  for (uint32_t f : tract.faces)
    for (uint32_t v : skin.faces[f]) lv.local[v] = 0;
  for (uint32_t v = 0; v < lv.local.size(); ++v)
    if (lv.local[v] == 0) {
      lv.local[v] = static_cast<int32_t>(lv.vertices.size());
      lv.vertices.push_back(v);
    }
  return lv;
}

void normaliseUv(std::vector<glm::dvec2>& uv) {
  glm::dvec2 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
  for (const auto& p : uv) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const double ext = std::max(hi.x - lo.x, hi.y - lo.y);
  const double inv = ext > 0 ? 1.0 / ext : 1.0;
  for (auto& p : uv) p = (p - lo) * inv;
}

double signedArea(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
  return 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

glm::dvec3 meanNormal(const SkinMesh& skin, const Tract& tract) {
  glm::dvec3 n(0.0);
  for (uint32_t f : tract.faces) n += skin.faceNormals[f] * skin.faceAreas[f];
  return n;
}

// Corners of the tract's faces grouped into wedges: one wedge per skin vertex, or several where seams cut
// the faces around a vertex apart. wedgeVertex[w] is the skin vertex of wedge w.
struct Wedges {
  std::vector<uint32_t> corner;  // 3 per tract face
  std::vector<uint32_t> wedgeVertex;
};

Wedges plainWedges(const SkinMesh& skin, const Tract& tract, const LocalVertices& lv) {
  Wedges w;
  w.wedgeVertex = lv.vertices;
  w.corner.reserve(3 * tract.faces.size());
  for (uint32_t f : tract.faces)
    for (uint32_t v : skin.faces[f]) w.corner.push_back(static_cast<uint32_t>(lv.local[v]));
  return w;
}

uint64_t edgeKey(uint32_t a, uint32_t b) { return (uint64_t(std::min(a, b)) << 32) | std::max(a, b); }

// Wedges after cutting along `seams` (edge keys of skin vertices, sorted): around each vertex, faces
// connected across uncut interior edges incident to it share a wedge.
Wedges cutWedges(const SkinMesh& skin, const Tract& tract, const std::vector<uint8_t>& inTract,
                 const std::vector<uint32_t>& slot, const LocalVertices& lv, const std::vector<uint64_t>& seams) {
  Wedges w;
  w.corner.assign(3 * tract.faces.size(), UINT32_MAX);
  std::vector<uint32_t> around, stack;
  for (uint32_t v : lv.vertices) {
    around.clear();
    for (uint32_t j = skin.vertexFaceOffsets[v]; j < skin.vertexFaceOffsets[v + 1]; ++j)
      if (inTract[skin.vertexFaces[j]]) around.push_back(skin.vertexFaces[j]);
    auto cornerOf = [&](uint32_t f) -> uint32_t& {
      const auto& t = skin.faces[f];
      const int c = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      return w.corner[3 * size_t(slot[f]) + size_t(c)];
    };
    for (uint32_t start : around) {
      if (cornerOf(start) != UINT32_MAX) continue;
      const uint32_t id = static_cast<uint32_t>(w.wedgeVertex.size());
      w.wedgeVertex.push_back(v);
      stack.assign(1, start);
      cornerOf(start) = id;
      while (!stack.empty()) {
        const uint32_t f = stack.back();
        stack.pop_back();
        for (int c = 0; c < 3; ++c) {
          const uint32_t a = skin.faces[f][c], b = skin.faces[f][(c + 1) % 3];
          if (a != v && b != v) continue;
          const int32_t g = skin.faceNeighbors[f][c];
          if (g < 0 || !inTract[uint32_t(g)]) continue;
          if (std::binary_search(seams.begin(), seams.end(), edgeKey(a, b))) continue;
          uint32_t& cg = cornerOf(uint32_t(g));
          if (cg == UINT32_MAX) cg = id, stack.push_back(uint32_t(g));
        }
      }
    }
  }
  return w;
}

// Seams that make a connected genus-0 tract a disk: shortest edge paths (Dijkstra, 3D edge lengths)
// joining the boundary loops one after another; for a closed tract, a shortest path between two far
// vertices (a double sweep). Returns sorted edge keys.
std::vector<uint64_t> genusZeroSeams(const SkinMesh& skin, const Tract& tract, const LocalVertices& lv,
                                     const std::vector<int32_t>& loopOf) {
  const size_t n = lv.vertices.size();
  // Vertex adjacency (CSR) over tract edges.
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for (uint32_t f : tract.faces)
    for (int c = 0; c < 3; ++c) {
      const uint32_t a = uint32_t(lv.local[skin.faces[f][c]]), b = uint32_t(lv.local[skin.faces[f][(c + 1) % 3]]);
      pairs.emplace_back(a, b), pairs.emplace_back(b, a);
    }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  std::vector<uint32_t> off(n + 1, 0);
  for (const auto& p : pairs) ++off[p.first + 1];
  for (size_t i = 0; i < n; ++i) off[i + 1] += off[i];
  auto len = [&](uint32_t a, uint32_t b) {
    return glm::length(skin.positions[lv.vertices[a]] - skin.positions[lv.vertices[b]]);
  };

  std::vector<double> dist(n);
  std::vector<int32_t> prev(n);
  // Dijkstra from `sources`; stops at the first popped vertex for which stop(v) holds (returns it), or
  // runs to completion and returns the farthest vertex.
  auto dijkstra = [&](const std::vector<uint32_t>& sources, const auto& stop) -> uint32_t {
    std::fill(dist.begin(), dist.end(), std::numeric_limits<double>::infinity());
    std::fill(prev.begin(), prev.end(), -1);
    using Item = std::pair<double, uint32_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
    for (uint32_t s : sources) dist[s] = 0, q.emplace(0.0, s);
    uint32_t last = sources.front();
    while (!q.empty()) {
      const auto [d, v] = q.top();
      q.pop();
      if (d > dist[v]) continue;
      last = v;
      if (stop(v)) return v;
      for (uint32_t j = off[v]; j < off[v + 1]; ++j) {
        const uint32_t u = pairs[j].second;
        const double nd = d + len(v, u);
        if (nd < dist[u]) dist[u] = nd, prev[u] = int32_t(v), q.emplace(nd, u);
      }
    }
    return last;
  };
  std::vector<uint64_t> seams;
  auto addPath = [&](uint32_t end, std::vector<uint32_t>* onPath) {
    for (uint32_t v = end; prev[v] >= 0; v = uint32_t(prev[v])) {
      seams.push_back(edgeKey(lv.vertices[v], lv.vertices[uint32_t(prev[v])]));
      if (onPath) onPath->push_back(uint32_t(prev[v]));
    }
  };
  int32_t loops = 0;
  for (int32_t l : loopOf) loops = std::max(loops, l + 1);
  if (loops == 0) {
    // A closed tract: a seam tree. First a path between two far vertices, then branches to the vertex
    // farthest from the seam while it is far (extremities such as head, tail, wing tips), which lowers
    // the distortion of the conformal map around the seam's ends.
    const auto never = [](uint32_t) { return false; };
    const uint32_t a = dijkstra({0u}, never);
    const uint32_t b = dijkstra({a}, never);
    const double length = dist[b];
    std::vector<uint32_t> sources{b};
    addPath(b, &sources);
    for (int branch = 0; branch < kMaxSeamBranches; ++branch) {
      const uint32_t far = dijkstra(sources, never);
      if (!(dist[far] > kSeamBranchFraction * length)) break;
      addPath(far, &sources);
      sources.push_back(far);
    }
  } else {
    std::vector<uint8_t> joined(size_t(loops), 0);
    joined[0] = 1;
    std::vector<uint32_t> sources;
    for (uint32_t v = 0; v < n; ++v)
      if (loopOf[v] == 0) sources.push_back(v);
    for (int32_t k = 1; k < loops; ++k) {
      const uint32_t hit = dijkstra(sources, [&](uint32_t v) { return loopOf[v] >= 0 && !joined[size_t(loopOf[v])]; });
      PTERYLA_CHECK(loopOf[hit] >= 0 && !joined[size_t(loopOf[hit])], "seam search did not reach a boundary loop");
      addPath(hit, &sources);
      joined[size_t(loopOf[hit])] = 1;
      for (uint32_t v = 0; v < n; ++v)
        if (loopOf[v] == loopOf[hit]) sources.push_back(v);
    }
  }
  std::sort(seams.begin(), seams.end());
  seams.erase(std::unique(seams.begin(), seams.end()), seams.end());
  return seams;
}

// Orthographic projection of each wedge's vertex onto the screen plane of a camera looking along `view`.
void projectWedges(const SkinMesh& skin, const Wedges& w, glm::dvec3 view, glm::dvec3 up, std::vector<glm::dvec2>& uv) {
  view = glm::normalize(view);
  if (glm::length(up) == 0) up = std::abs(view.y) > 0.99 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
  glm::dvec3 right = glm::cross(view, up);
  if (glm::length(right) < 1e-9)
    right = glm::cross(view, std::abs(view.y) > 0.99 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0));
  right = glm::normalize(right);
  const glm::dvec3 screenUp = glm::cross(right, view);
  uv.resize(w.wedgeVertex.size());
  for (size_t i = 0; i < w.wedgeVertex.size(); ++i) {
    const glm::dvec3& p = skin.positions[w.wedgeVertex[i]];
    uv[i] = {glm::dot(p, right), glm::dot(p, screenUp)};
  }
}

double backfacingFraction(const SkinMesh& skin, const Tract& tract, const glm::dvec3& view) {
  double back = 0, total = 0;
  for (uint32_t f : tract.faces) {
    total += skin.faceAreas[f];
    if (glm::dot(skin.faceNormals[f], view) >= 0) back += skin.faceAreas[f];
  }
  return total > 0 ? back / total : 1.0;
}

void cgalParameterize(const SkinMesh& skin, const Tract& tract, const Wedges& w, ParamMethod method,
                      const ParameterizeOptions& opt, std::vector<glm::dvec2>& uv) {
  CgalMesh sm;
  sm.reserve(static_cast<CgalMesh::size_type>(w.wedgeVertex.size()), 0,
             static_cast<CgalMesh::size_type>(tract.faces.size()));
  for (uint32_t v : w.wedgeVertex) {
    const glm::dvec3& p = skin.positions[v];
    sm.add_vertex(Kernel::Point_3(p.x, p.y, p.z));
  }
  for (size_t k = 0; k < tract.faces.size(); ++k) {
    const auto fd = sm.add_face(VertexD(w.corner[3 * k]), VertexD(w.corner[3 * k + 1]), VertexD(w.corner[3 * k + 2]));
    if (fd == CgalMesh::null_face())
      throw Error("tract '" + tract.name + "' is not a manifold surface at face " + std::to_string(tract.faces[k]) +
                      "; split the tract or use \"method\": \"projection\"",
                  skin.file, where(tract));
  }
  HalfedgeD border;
  size_t borderLoops = 0;
  {
    std::vector<uint8_t> seen(sm.number_of_halfedges(), 0);
    for (HalfedgeD h : sm.halfedges()) {
      if (!sm.is_border(h) || seen[h.idx()]) continue;
      if (borderLoops++ == 0) border = h;
      for (HalfedgeD g = h; !seen[g.idx()]; g = sm.next(g)) seen[g.idx()] = 1;
    }
  }
  PTERYLA_CHECK(borderLoops == 1, "cut tract is not a disk (" + std::to_string(borderLoops) + " border loops)");
  auto uvMap = sm.add_property_map<VertexD, Kernel::Point_2>("v:uv").first;
  SMP::Error_code err = SMP::OK;
  if (method == ParamMethod::Lscm) {
    err = SMP::parameterize(sm, SMP::LSCM_parameterizer_3<CgalMesh>(), border, uvMap);
  } else {
    using Arap = SMP::ARAP_parameterizer_3<CgalMesh>;
    Arap arap(Arap::Border_parameterizer(), Arap::Solver_traits(), 1000.0,
              static_cast<unsigned>(std::max(1, opt.arapIterations)), 1e-6);
    err = SMP::parameterize(sm, arap, border, uvMap);
  }
  if (err != SMP::OK)
    throw Error(std::string("automatic parameterization of tract '") + tract.name + "' failed (" +
                    SMP::get_error_message(err) + "); split the tract or use \"method\": \"projection\"",
                skin.file, where(tract));
  uv.resize(w.wedgeVertex.size());
  for (VertexD v : sm.vertices()) {
    const auto& q = uvMap[v];
    uv[v.idx()] = {q.x(), q.y()};
  }
}

std::string topologyText(const TractTopology& t) {
  return std::to_string(t.components) + " component(s), " + std::to_string(t.boundaryLoops) +
         " boundary loop(s), Euler characteristic " + std::to_string(t.eulerCharacteristic()) +
         (t.nonManifold ? ", non-manifold vertices" : "");
}

struct TractAnalysis {
  LocalVertices lv;
  std::vector<uint8_t> inTract;  // per skin face
  std::vector<uint32_t> slot;    // per skin face: index in tract.faces
  TractTopology topo;
  std::vector<int32_t> loopOf;  // per local vertex: boundary loop id, -1 = interior
};

TractAnalysis analyse(const SkinMesh& skin, const Tract& tract) {
  TractAnalysis an;
  TractTopology& topo = an.topo;
  topo.faces = tract.faces.size();
  if (tract.faces.empty()) return an;
  an.lv = localVertices(skin, tract);
  const LocalVertices& lv = an.lv;
  topo.vertices = lv.vertices.size();
  std::vector<uint8_t>& inTract = an.inTract;
  inTract.assign(skin.faceCount(), 0);
  for (uint32_t f : tract.faces) inTract[f] = 1;

  // Edges: interior edges are seen from two tract faces, boundary edges from one (the skin is edge-manifold).
  size_t halfEdges = 0, boundaryEdges = 0;
  UnionFind faceSets(tract.faces.size());
  std::vector<uint32_t>& slot = an.slot;
  slot.assign(skin.faceCount(), 0);
  for (uint32_t k = 0; k < tract.faces.size(); ++k) slot[tract.faces[k]] = k;
  // Outgoing boundary half-edges per local vertex (a -> b with the tract face on the left).
  std::vector<int32_t> boundaryNext(lv.vertices.size(), -1);
  std::vector<uint32_t> boundaryOut(lv.vertices.size(), 0);
  for (uint32_t k = 0; k < tract.faces.size(); ++k) {
    const uint32_t f = tract.faces[k];
    for (int c = 0; c < 3; ++c) {
      ++halfEdges;
      const int32_t g = skin.faceNeighbors[f][c];
      if (g >= 0 && inTract[static_cast<uint32_t>(g)]) {
        faceSets.unite(k, slot[static_cast<uint32_t>(g)]);
      } else {
        ++boundaryEdges;
        const int32_t a = lv.local[skin.faces[f][c]], b = lv.local[skin.faces[f][(c + 1) % 3]];
        boundaryNext[static_cast<size_t>(a)] = b;
        ++boundaryOut[static_cast<size_t>(a)];
      }
    }
  }
  topo.edges = (halfEdges - boundaryEdges) / 2 + boundaryEdges;
  for (uint32_t k = 0; k < tract.faces.size(); ++k)
    if (faceSets.find(k) == k) ++topo.components;

  // Vertex manifoldness: the tract faces around each vertex form one edge-connected fan.
  std::vector<uint32_t> around, label;
  for (size_t i = 0; i < lv.vertices.size(); ++i) {
    const uint32_t v = lv.vertices[i];
    if (boundaryOut[i] > 1) topo.nonManifold = true;
    around.clear();
    for (uint32_t j = skin.vertexFaceOffsets[v]; j < skin.vertexFaceOffsets[v + 1]; ++j)
      if (inTract[skin.vertexFaces[j]]) around.push_back(skin.vertexFaces[j]);
    if (around.size() < 2) continue;
    // Flood the fan from its first face across edges incident to v.
    label.assign(around.size(), 0);
    label[0] = 1;
    for (bool grew = true; grew;) {
      grew = false;
      for (size_t a = 0; a < around.size(); ++a) {
        if (!label[a]) continue;
        const uint32_t f = around[a];
        for (int c = 0; c < 3; ++c) {
          if (skin.faces[f][c] != v && skin.faces[f][(c + 1) % 3] != v) continue;
          const int32_t g = skin.faceNeighbors[f][c];
          if (g < 0) continue;
          for (size_t b = 0; b < around.size(); ++b)
            if (!label[b] && around[b] == static_cast<uint32_t>(g)) label[b] = 1, grew = true;
        }
      }
    }
    for (uint32_t l : label)
      if (!l) topo.nonManifold = true;
  }
  // Boundary loops (only meaningful without non-manifold vertices; counted anyway for the message).
  an.loopOf.assign(lv.vertices.size(), -1);
  for (size_t i = 0; i < lv.vertices.size(); ++i) {
    if (boundaryOut[i] == 0 || an.loopOf[i] >= 0) continue;
    const int32_t id = static_cast<int32_t>(topo.boundaryLoops++);
    size_t cur = i;
    while (an.loopOf[cur] < 0 && boundaryNext[cur] >= 0) {
      an.loopOf[cur] = id;
      cur = static_cast<size_t>(boundaryNext[cur]);
    }
  }
  return an;
}

}  // namespace

const char* paramMethodName(ParamMethod m) {
  switch (m) {
    case ParamMethod::Projection:
      return "projection";
    case ParamMethod::Lscm:
      return "lscm";
    case ParamMethod::Arap:
      return "arap";
    case ParamMethod::Auto:
      return "auto";
  }
  return "?";
}

glm::dvec2 gridDisplacement(const std::vector<GridDistortion>& handles, const glm::dvec2& q) {
  glm::dvec2 d(0.0);
  for (const GridDistortion& h : handles) {
    const glm::dvec2 e = q - h.at;
    const double s2 = glm::dot(e, e) / (h.radius * h.radius);
    if (s2 < 1) d += (1 - s2) * (1 - s2) * h.move;
  }
  return d;
}

glm::dvec2 undistortUv(const std::vector<GridDistortion>& handles, const glm::dvec2& g, const std::string& where) {
  if (handles.empty()) return g;
  // q = g - D(q) contracts while D's Lipschitz constant is under 1 (one handle: 1.54 |move| / radius).
  glm::dvec2 q = g;
  for (int it = 0; it < 200; ++it) {
    const glm::dvec2 next = g - gridDisplacement(handles, q);
    const double step = glm::length(next - q);
    q = next;
    if (step <= 1e-14 * (1 + glm::length(g))) return q;
  }
  throw Error("the grid distortion folds the parameterization near (" + std::to_string(g.x) + ", " +
                  std::to_string(g.y) +
                  "): overlapping handles move too far (keep each |move| under 0.6 x radius "
                  "and spread overlapping ones)",
              "", where);
}

glm::dvec2 TractParameterization::uvAt(uint32_t face, const glm::dvec3& bary) const {
  if (distortion.empty()) {
    const auto& c = faceUv(face);
    return bary.x * c[0] + bary.y * c[1] + bary.z * c[2];
  }
  const auto it = std::lower_bound(faces.begin(), faces.end(), face);
  PTERYLA_CHECK(it != faces.end() && *it == face, "face not in the parameterized tract");
  const auto& c = projectedCornerUv[static_cast<size_t>(it - faces.begin())];
  return undistortUv(distortion, bary.x * c[0] + bary.y * c[1] + bary.z * c[2], "parameterization.distortion");
}

const std::array<glm::dvec2, 3>& TractParameterization::faceUv(uint32_t face) const {
  const auto it = std::lower_bound(faces.begin(), faces.end(), face);
  PTERYLA_CHECK(it != faces.end() && *it == face, "face not in the parameterized tract");
  return cornerUv[static_cast<size_t>(it - faces.begin())];
}

TractTopology tractTopology(const SkinMesh& skin, const Tract& tract) { return analyse(skin, tract).topo; }

TractParameterization parameterizeTract(const SkinMesh& skin, const Tract& tract, uint32_t tractIndex,
                                        const Follicles& follicles, const ParameterizeOptions& options) {
  if (tract.faces.empty())
    throw Error("tract '" + tract.name + "' has no faces to parameterize", skin.file, where(tract));
  for (size_t k = 0; k < tract.faces.size(); ++k)
    if (tract.faces[k] >= skin.faceCount() || (k > 0 && tract.faces[k] <= tract.faces[k - 1]))
      throw Error("tract faces must be ascending indices below " + std::to_string(skin.faceCount()), skin.file,
                  where(tract));
  TractParameterization out;
  out.faces = tract.faces;
  const TractAnalysis an = analyse(skin, tract);
  Wedges wedges = plainWedges(skin, tract, an.lv);

  ParamMethod method = options.method;
  glm::dvec3 view = options.viewDirection;
  if (method != ParamMethod::Projection) {
    const TractTopology& topo = an.topo;
    const bool genusZero = topo.components == 1 && !topo.nonManifold &&
                           topo.eulerCharacteristic() == 2 - static_cast<long>(topo.boundaryLoops);
    if (topo.isDisk()) {
      if (method == ParamMethod::Auto)
        method = ParamMethod::Lscm, out.note = "disk-like tract: least-squares conformal map";
    } else if (method == ParamMethod::Auto && options.autoSeams && genusZero) {
      const std::vector<uint64_t> seams = genusZeroSeams(skin, tract, an.lv, an.loopOf);
      wedges = cutWedges(skin, tract, an.inTract, an.slot, an.lv, seams);
      out.seamEdges = seams.size();
      method = ParamMethod::Lscm;
      out.note = "not a topological disk (" + topologyText(topo) + "): cut open along " + std::to_string(seams.size()) +
                 " seam edges, then least-squares conformal map";
    } else {
      const glm::dvec3 mean = meanNormal(skin, tract);
      const double total = tractArea(skin, tract);
      const bool flat =
          glm::length(mean) > 1e-9 * total && backfacingFraction(skin, tract, -mean) <= options.autoMaxBackfacing;
      if (method == ParamMethod::Auto && flat) {
        method = ParamMethod::Projection;
        view = -mean;
        out.note = "not a topological disk (" + topologyText(topo) + "): projected along the mean normal";
      } else {
        std::string why = "split it into disk-like tracts, or use \"method\": \"projection\" with a view_direction";
        if (topo.components > 1)
          why = "define one tract per piece, or use \"method\": \"projection\" with a view_direction";
        throw Error("tract '" + tract.name + "' is not a topological disk (" + topologyText(topo) +
                        "; needed: 1 component, 1 boundary loop, Euler characteristic 1), so " +
                        (method == ParamMethod::Auto ? std::string("it cannot be parameterized automatically")
                                                     : std::string(paramMethodName(method)) + " cannot flatten it") +
                        ": " + why,
                    skin.file, where(tract));
      }
    }
  }
  out.method = method;

  std::vector<glm::dvec2> uv;  // per wedge
  if (method == ParamMethod::Projection) {
    if (glm::length(view) == 0) {
      view = -meanNormal(skin, tract);
      if (glm::length(view) <= 1e-9 * tractArea(skin, tract))
        throw Error("tract '" + tract.name +
                        "' has no dominant facing direction (closed or folded); give the "
                        "projection a view_direction or split the tract",
                    skin.file, where(tract));
    }
    if (!std::isfinite(view.x + view.y + view.z))
      throw Error("projection view_direction must be finite and non-zero", skin.file,
                  where(tract) + ".parameterization");
    out.viewDirection = glm::normalize(view);
    projectWedges(skin, wedges, out.viewDirection, options.up, uv);
  } else {
    cgalParameterize(skin, tract, wedges, method, options, uv);
  }

  // Orientation: counter-clockwise in (u,v) seen from the normal side. Mirror in u when most area is flipped.
  auto cornerArea = [&](size_t k) {
    return signedArea(uv[wedges.corner[3 * k]], uv[wedges.corner[3 * k + 1]], uv[wedges.corner[3 * k + 2]]);
  };
  double positive = 0, negative = 0;
  for (size_t k = 0; k < tract.faces.size(); ++k) {
    const double a = cornerArea(k);
    (a >= 0 ? positive : negative) += std::abs(a);
  }
  if (negative > positive)
    for (auto& p : uv) p.x = -p.x;
  normaliseUv(uv);
  // Scale: scene units per normalised (u,v) unit, measured from areas (LSCM's own scale is arbitrary).
  double area3 = 0, areaUv = 0;
  for (size_t k = 0; k < tract.faces.size(); ++k) {
    area3 += skin.faceAreas[tract.faces[k]];
    const double a = cornerArea(k);
    areaUv += std::abs(a);
    if (a <= 0) ++out.flippedFaces;
  }
  if (!(areaUv > 1e-300) || !std::isfinite(areaUv))
    throw Error("tract '" + tract.name + "' maps to a degenerate (u,v) region (seen edge-on?)", skin.file,
                where(tract));
  out.scale = std::sqrt(area3 / areaUv);
  out.cornerUv.resize(tract.faces.size());
  for (size_t k = 0; k < tract.faces.size(); ++k)
    for (size_t c = 0; c < 3; ++c) out.cornerUv[k][c] = uv[wedges.corner[3 * k + c]];
  if (!options.distortion.empty()) {
    out.distortion = options.distortion;
    out.projectedCornerUv = out.cornerUv;
    const std::string at = "tracts." + tract.name + ".parameterization.distortion";
    for (auto& corners : out.cornerUv)
      for (glm::dvec2& c : corners) c = undistortUv(out.distortion, c, at);
  }

  // Follicles of this tract.
  for (uint32_t i = 0; i < follicles.size(); ++i) {
    if (follicles.tract[i] != tractIndex) continue;
    const uint32_t f = follicles.face[i];
    if (f >= skin.faceCount() || !an.inTract[f])
      throw Error("follicle " + std::to_string(i) + " lies on face " + std::to_string(f) + ", outside tract '" +
                      tract.name + "'",
                  skin.file, where(tract));
    out.follicles.push_back(i);
    out.follicleUv.push_back(out.uvAt(f, follicles.bary[i]));
  }
  return out;
}

std::vector<double> uvFaceAreas(const TractParameterization& param) {
  std::vector<double> a;
  a.reserve(param.faces.size());
  for (const auto& c : param.cornerUv) a.push_back(signedArea(c[0], c[1], c[2]));
  return a;
}

ParameterizeOptions parseParameterization(JsonReader& r) {
  ParameterizeOptions o;
  const std::string m = r.oneOf("method", "auto", {"auto", "projection", "lscm", "arap"});
  o.method = m == "projection" ? ParamMethod::Projection
             : m == "lscm"     ? ParamMethod::Lscm
             : m == "arap"     ? ParamMethod::Arap
                               : ParamMethod::Auto;
  if (r.has("view_direction")) {
    o.viewDirection = r.vec3("view_direction");
    if (glm::length(o.viewDirection) == 0) r.fail("view_direction", "must be non-zero");
  }
  o.up = r.vec3("up", glm::dvec3(0.0));
  o.arapIterations = static_cast<int>(r.integer("arap_iterations", 50, 1, 10000));
  o.autoMaxBackfacing = r.number("auto_max_backfacing", 0.01, 0.0, 1.0);
  o.autoSeams = r.boolean("auto_seams", true);
  std::vector<JsonReader> handles = r.objects("distortion");
  for (JsonReader& h : handles) {
    GridDistortion d;
    d.at = h.vec2("at");
    d.move = h.vec2("move");
    d.radius = h.number("radius", 0.1, 1e-6, 10.0);
    if (glm::length(d.move) > 0.6 * d.radius)
      h.fail("move", "must be at most 0.6 x radius (a larger move folds the grid)");
    h.finish();
    o.distortion.push_back(d);
  }
  r.finish();
  return o;
}

}  // namespace pteryla::coat
