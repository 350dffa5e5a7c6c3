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

#include "pteryla/core/error.hpp"

namespace pteryla::coat {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using VertexD = CgalMesh::Vertex_index;
using HalfedgeD = CgalMesh::Halfedge_index;
namespace SMP = CGAL::Surface_mesh_parameterization;

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

// Orthographic projection onto the screen plane of a camera looking along `view`.
void projectVertices(const SkinMesh& skin, const LocalVertices& lv, glm::dvec3 view, glm::dvec3 up,
                     std::vector<glm::dvec2>& uv) {
  view = glm::normalize(view);
  if (glm::length(up) == 0) up = std::abs(view.y) > 0.99 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
  glm::dvec3 right = glm::cross(view, up);
  if (glm::length(right) < 1e-9) right = glm::cross(view, std::abs(view.y) > 0.99 ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0));
  right = glm::normalize(right);
  const glm::dvec3 screenUp = glm::cross(right, view);
  uv.resize(lv.vertices.size());
  for (size_t i = 0; i < lv.vertices.size(); ++i) {
    const glm::dvec3& p = skin.positions[lv.vertices[i]];
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

void cgalParameterize(const SkinMesh& skin, const Tract& tract, const LocalVertices& lv, ParamMethod method,
                      const ParameterizeOptions& opt, std::vector<glm::dvec2>& uv) {
  CgalMesh sm;
  sm.reserve(static_cast<CgalMesh::size_type>(lv.vertices.size()), 0, static_cast<CgalMesh::size_type>(tract.faces.size()));
  for (uint32_t v : lv.vertices) {
    const glm::dvec3& p = skin.positions[v];
    sm.add_vertex(Kernel::Point_3(p.x, p.y, p.z));
  }
  for (uint32_t f : tract.faces) {
    const auto& t = skin.faces[f];
    const auto fd = sm.add_face(VertexD(static_cast<uint32_t>(lv.local[t[0]])), VertexD(static_cast<uint32_t>(lv.local[t[1]])),
                                VertexD(static_cast<uint32_t>(lv.local[t[2]])));
    if (fd == CgalMesh::null_face())
      throw Error("tract '" + tract.name + "' is not a manifold surface at face " + std::to_string(f) +
                      "; split the tract or use \"method\": \"projection\"",
                  skin.file, where(tract));
  }
  HalfedgeD border;
  for (HalfedgeD h : sm.halfedges())
    if (sm.is_border(h)) {
      border = h;
      break;
    }
  PTERYLA_CHECK(border != CgalMesh::null_halfedge(), "disk-like tract without a border halfedge");
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
  uv.resize(lv.vertices.size());
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

}  // namespace

const char* paramMethodName(ParamMethod m) {
  switch (m) {
    case ParamMethod::Projection: return "projection";
    case ParamMethod::Lscm: return "lscm";
    case ParamMethod::Arap: return "arap";
    case ParamMethod::Auto: return "auto";
  }
  return "?";
}

glm::dvec2 TractParameterization::uvOfVertex(uint32_t globalVertex) const {
  const auto it = std::lower_bound(vertices.begin(), vertices.end(), globalVertex);
  PTERYLA_CHECK(it != vertices.end() && *it == globalVertex, "vertex not in the parameterized tract");
  return vertexUv[static_cast<size_t>(it - vertices.begin())];
}

TractTopology tractTopology(const SkinMesh& skin, const Tract& tract) {
  TractTopology topo;
  topo.faces = tract.faces.size();
  if (tract.faces.empty()) return topo;
  const LocalVertices lv = localVertices(skin, tract);
  topo.vertices = lv.vertices.size();
  std::vector<uint8_t> inTract(skin.faceCount(), 0);
  for (uint32_t f : tract.faces) inTract[f] = 1;

  // Edges: interior edges are seen from two tract faces, boundary edges from one (the skin is edge-manifold).
  size_t halfEdges = 0, boundaryEdges = 0;
  UnionFind faceSets(tract.faces.size());
  std::vector<uint32_t> slot(skin.faceCount(), 0);
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
  std::vector<uint8_t> seen(lv.vertices.size(), 0);
  for (size_t i = 0; i < lv.vertices.size(); ++i) {
    if (boundaryOut[i] == 0 || seen[i]) continue;
    ++topo.boundaryLoops;
    size_t cur = i;
    while (!seen[cur] && boundaryNext[cur] >= 0) {
      seen[cur] = 1;
      cur = static_cast<size_t>(boundaryNext[cur]);
    }
  }
  return topo;
}

TractParameterization parameterizeTract(const SkinMesh& skin, const Tract& tract, uint32_t tractIndex,
                                        const Follicles& follicles, const ParameterizeOptions& options) {
  if (tract.faces.empty()) throw Error("tract '" + tract.name + "' has no faces to parameterize", skin.file, where(tract));
  for (uint32_t f : tract.faces)
    if (f >= skin.faceCount()) throw Error("tract face " + std::to_string(f) + " is out of range", skin.file, where(tract));
  TractParameterization out;
  const LocalVertices lv = localVertices(skin, tract);
  out.vertices = lv.vertices;

  ParamMethod method = options.method;
  glm::dvec3 view = options.viewDirection;
  if (method != ParamMethod::Projection) {
    const TractTopology topo = tractTopology(skin, tract);
    if (!topo.isDisk()) {
      const glm::dvec3 mean = meanNormal(skin, tract);
      const double total = tractArea(skin, tract);
      const bool flat = glm::length(mean) > 1e-9 * total &&
                        backfacingFraction(skin, tract, -mean) <= options.autoMaxBackfacing;
      if (method == ParamMethod::Auto && flat) {
        method = ParamMethod::Projection;
        view = -mean;
        out.note = "not a topological disk (" + topologyText(topo) + "): projected along the mean normal";
      } else {
        throw Error("tract '" + tract.name + "' is not a topological disk (" + topologyText(topo) +
                        "; needed: 1 component, 1 boundary loop, Euler characteristic 1), so " +
                        (method == ParamMethod::Auto ? std::string("it cannot be parameterized automatically")
                                                     : std::string(paramMethodName(method)) + " cannot flatten it") +
                        ": split it into disk-like tracts, or use \"method\": \"projection\" with a view_direction",
                    skin.file, where(tract));
      }
    } else if (method == ParamMethod::Auto) {
      method = ParamMethod::Lscm;
      out.note = "disk-like tract: least-squares conformal map";
    }
  }
  out.method = method;

  std::vector<glm::dvec2> uv;
  if (method == ParamMethod::Projection) {
    if (glm::length(view) == 0) {
      view = -meanNormal(skin, tract);
      if (glm::length(view) <= 1e-9 * tractArea(skin, tract))
        throw Error("tract '" + tract.name + "' has no dominant facing direction (closed or folded); give the "
                    "projection a view_direction or split the tract",
                    skin.file, where(tract));
    }
    if (!std::isfinite(view.x + view.y + view.z))
      throw Error("projection view_direction must be finite and non-zero", skin.file, where(tract) + ".parameterization");
    out.viewDirection = glm::normalize(view);
    projectVertices(skin, lv, out.viewDirection, options.up, uv);
  } else {
    cgalParameterize(skin, tract, lv, method, options, uv);
  }

  // Orientation: counter-clockwise in (u,v) seen from the normal side. Mirror in u when most area is flipped.
  double positive = 0, negative = 0;
  for (uint32_t f : tract.faces) {
    const auto& t = skin.faces[f];
    const double a = signedArea(uv[static_cast<size_t>(lv.local[t[0]])], uv[static_cast<size_t>(lv.local[t[1]])],
                                uv[static_cast<size_t>(lv.local[t[2]])]);
    (a >= 0 ? positive : negative) += std::abs(a);
  }
  if (negative > positive)
    for (auto& p : uv) p.x = -p.x;
  normaliseUv(uv);
  // Scale: scene units per normalised (u,v) unit, measured from areas (LSCM's own scale is arbitrary).
  {
    double area3 = 0, areaUv = 0;
    for (uint32_t f : tract.faces) {
      const auto& t = skin.faces[f];
      area3 += skin.faceAreas[f];
      areaUv += std::abs(signedArea(uv[static_cast<size_t>(lv.local[t[0]])], uv[static_cast<size_t>(lv.local[t[1]])],
                                    uv[static_cast<size_t>(lv.local[t[2]])]));
    }
    if (!(areaUv > 1e-300) || !std::isfinite(areaUv))
      throw Error("tract '" + tract.name + "' maps to a degenerate (u,v) region (seen edge-on?)", skin.file, where(tract));
    out.scale = std::sqrt(area3 / areaUv);
  }
  for (uint32_t f : tract.faces) {
    const auto& t = skin.faces[f];
    if (signedArea(uv[static_cast<size_t>(lv.local[t[0]])], uv[static_cast<size_t>(lv.local[t[1]])],
                   uv[static_cast<size_t>(lv.local[t[2]])]) <= 0)
      ++out.flippedFaces;
  }
  out.vertexUv = std::move(uv);

  // Follicles of this tract.
  for (uint32_t i = 0; i < follicles.size(); ++i) {
    if (follicles.tract[i] != tractIndex) continue;
    const uint32_t f = follicles.face[i];
    if (f >= skin.faceCount() || !tract.contains(f))
      throw Error("follicle " + std::to_string(i) + " lies on face " + std::to_string(f) + ", outside tract '" +
                      tract.name + "'",
                  skin.file, where(tract));
    const auto& t = skin.faces[f];
    const glm::dvec3& b = follicles.bary[i];
    const glm::dvec2 p = b.x * out.vertexUv[static_cast<size_t>(lv.local[t[0]])] +
                         b.y * out.vertexUv[static_cast<size_t>(lv.local[t[1]])] +
                         b.z * out.vertexUv[static_cast<size_t>(lv.local[t[2]])];
    out.follicles.push_back(i);
    out.follicleUv.push_back(p);
  }
  return out;
}

std::vector<double> uvFaceAreas(const SkinMesh& skin, const Tract& tract, const TractParameterization& param) {
  std::vector<double> a;
  a.reserve(tract.faces.size());
  for (uint32_t f : tract.faces) {
    const auto& t = skin.faces[f];
    a.push_back(signedArea(param.uvOfVertex(t[0]), param.uvOfVertex(t[1]), param.uvOfVertex(t[2])));
  }
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
  r.finish();
  return o;
}

}  // namespace pteryla::coat
