// Skin mesh validation, repair, adjacency and geometry (Streit 2003, 6: the polygonal model that tracts
// are formed from and follicles are distributed on). Closest-point-on-triangle after Ericson,
// Real-Time Collision Detection (2005), 5.1.5.
#include "pteryla/coat/skin.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "mesh_io.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"

namespace pteryla::coat {

double SkinMesh::totalArea() const {
  double a = 0;
  for (double x : faceAreas) a += x;
  return a;
}

bool SkinMesh::groupMatches(int32_t group, const std::string& name) const {
  if (group < 0 || static_cast<size_t>(group) >= groupNames.size()) return false;
  const std::string& g = groupNames[static_cast<size_t>(group)];
  if (g == name) return true;
  std::istringstream ss(g);
  std::string tok;
  while (ss >> tok)
    if (tok == name) return true;
  return false;
}

int32_t SkinMesh::findGroup(const std::string& name) const {
  for (size_t g = 0; g < groupNames.size(); ++g)
    if (groupNames[g] == name) return static_cast<int32_t>(g);
  for (size_t g = 0; g < groupNames.size(); ++g)
    if (groupMatches(static_cast<int32_t>(g), name)) return static_cast<int32_t>(g);
  return -1;
}

namespace {

std::string fmtVec(const glm::dvec3& v) {
  std::ostringstream os;
  os << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return os.str();
}

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

struct HalfEdge {
  uint64_t key;  // min(v0,v1) << 32 | max(v0,v1)
  uint32_t face;
  uint32_t corner;
};

std::vector<HalfEdge> sortedHalfEdges(const std::vector<std::array<uint32_t, 3>>& tris) {
  std::vector<HalfEdge> he(tris.size() * 3);
  for (size_t f = 0; f < tris.size(); ++f)
    for (uint32_t c = 0; c < 3; ++c) {
      const uint64_t a = tris[f][c], b = tris[f][(c + 1) % 3];
      he[f * 3 + c] = {(std::min(a, b) << 32) | std::max(a, b), static_cast<uint32_t>(f), c};
    }
  std::sort(he.begin(), he.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key != y.key ? x.key < y.key : (x.face != y.face ? x.face < y.face : x.corner < y.corner);
  });
  return he;
}

double triArea(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  return 0.5 * glm::length(glm::cross(b - a, c - a));
}

}  // namespace

namespace detail {

SkinMesh buildSkinMesh(RawMesh raw, const MeshLoadOptions& opt, const std::string& file) {
  const bool repair = opt.repair;
  const size_t nv = raw.positions.size();
  const size_t np = raw.polygonCount();
  auto faceName = [&](uint32_t poly) {
    std::string s = "face " + std::to_string(poly);
    if (!raw.polyLine.empty() && poly < raw.polyLine.size()) s += " (line " + std::to_string(raw.polyLine[poly]) + ")";
    return s;
  };
  if (nv == 0) throw Error("mesh has no vertices", file, "mesh");
  if (np == 0) throw Error("mesh has no faces", file, "mesh");
  if (!raw.polyGroup.empty() && raw.polyGroup.size() != np)
    throw Error(
        "face group list has " + std::to_string(raw.polyGroup.size()) + " entries for " + std::to_string(np) + " faces",
        file, "groups");

  SkinMesh m;
  m.file = file;
  m.sourceFaceCount = np;

  // Index range and finiteness.
  for (uint32_t p = 0; p < np; ++p)
    for (uint32_t k = raw.polyOffsets[p]; k < raw.polyOffsets[p + 1]; ++k)
      if (raw.polyIndices[k] >= nv)
        throw Error("vertex index " + std::to_string(raw.polyIndices[k]) + " is out of range (" + std::to_string(nv) +
                        " vertices)",
                    file, faceName(p));
  std::vector<uint8_t> badVertex(nv, 0);
  for (size_t v = 0; v < nv; ++v) {
    if (finite(raw.positions[v])) continue;
    if (!repair)
      throw Error("coordinate is not finite " + fmtVec(raw.positions[v]) + " (load with repair to drop its faces)",
                  file, "vertex " + std::to_string(v));
    badVertex[v] = 1;
    raw.positions[v] = glm::dvec3(0);
  }

  // Texture coordinates and normals end up in exported meshes: no NaN or infinity.
  for (uint32_t p = 0; p < np && !raw.cornerUVs.empty(); ++p)
    for (uint32_t k = raw.polyOffsets[p]; k < raw.polyOffsets[p + 1]; ++k)
      if (!std::isfinite(raw.cornerUVs[k].x) || !std::isfinite(raw.cornerUVs[k].y) ||
          std::abs(raw.cornerUVs[k].x) > 1e12 || std::abs(raw.cornerUVs[k].y) > 1e12)
        throw Error("texture coordinate is not finite (or beyond +-1e12)", file, faceName(p));
  for (size_t v = 0; v < raw.vertexNormals.size(); ++v)
    if (!finite(raw.vertexNormals[v]))
      throw Error("normal is not finite " + fmtVec(raw.vertexNormals[v]), file, "vertex " + std::to_string(v));

  // Magnitude and precision. Feathers are meshed and rendered in 32-bit float: far from the origin, or
  // tiny next to their distance from it, triangles collapse (and spatial searches degenerate).
  {
    size_t far = nv;
    double farAbs = 0;
    for (size_t v = 0; v < nv; ++v) {
      if (badVertex[v]) continue;
      const glm::dvec3& q = raw.positions[v];
      const double a = std::max({std::abs(q.x), std::abs(q.y), std::abs(q.z)});
      if (a > farAbs) {
        farAbs = a;
        far = v;
      }
    }
    if (farAbs > kMaxMeshCoordinate) {
      std::ostringstream os;
      os << "coordinate " << fmtVec(raw.positions[far]) << " is beyond +-" << kMaxMeshCoordinate
         << " (the largest supported; move the mesh near the origin or change its units)";
      throw Error(os.str(), file, "vertex " + std::to_string(far));
    }
    std::vector<double> edges;
    edges.reserve(std::min<size_t>(np, 100000));
    const size_t step = std::max<size_t>(1, np / 100000);
    for (uint32_t p = 0; p < np; p += static_cast<uint32_t>(step)) {
      const uint32_t b = raw.polyOffsets[p], e = raw.polyOffsets[p + 1];
      if (e - b < 2) continue;
      const uint32_t v0 = raw.polyIndices[b], v1 = raw.polyIndices[b + 1];
      if (badVertex[v0] || badVertex[v1]) continue;
      const double len = glm::length(raw.positions[v1] - raw.positions[v0]);
      if (len > 0) edges.push_back(len);
    }
    if (!edges.empty()) {
      std::nth_element(edges.begin(), edges.begin() + static_cast<long>(edges.size() / 2), edges.end());
      const double typical = edges[edges.size() / 2];
      if (farAbs > kMaxMeshRange * typical) {
        std::ostringstream os;
        os << "vertex " << fmtVec(raw.positions[far]) << " lies " << farAbs / typical << " typical edge lengths ("
           << typical << ") from the origin, more than " << kMaxMeshRange
           << ": 32-bit float geometry cannot resolve feathers there (a mistyped vertex? otherwise move the mesh "
              "near the origin)";
        throw Error(os.str(), file, "vertex " + std::to_string(far));
      }
    }
  }

  // Bounding-box diagonal over finite vertices used by faces.
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (uint32_t v : raw.polyIndices)
    if (!badVertex[v]) {
      lo = glm::min(lo, raw.positions[v]);
      hi = glm::max(hi, raw.positions[v]);
    }
  const double diag = lo.x <= hi.x ? glm::length(hi - lo) : 0.0;

  // Weld (repair only): vertex v maps to the lowest-index vertex within tolerance.
  std::vector<uint32_t> remap(nv);
  std::iota(remap.begin(), remap.end(), 0u);
  if (repair && diag > 0) {
    const double tol = std::max(opt.weldTolerance * diag, std::numeric_limits<double>::min());
    const double inv = 1.0 / tol;
    std::unordered_map<uint64_t, std::vector<uint32_t>> cells;
    // Grid coordinates are clamped before the integer conversion: the bounds cover only vertices used by
    // faces, so an unused vertex far outside them (or any huge extent) gives cell numbers beyond int64
    // (undefined behaviour, found by tests/fuzz). Clamped vertices share edge cells; the distance test
    // below keeps the weld exact.
    auto cellCoord = [](double q, int d) {
      return static_cast<uint64_t>(static_cast<int64_t>(std::clamp(std::floor(q), -0x1p52, 0x1p52)) + d) & 0x1FFFFF;
    };
    auto cellOf = [&](const glm::dvec3& p, int dx, int dy, int dz) {
      const glm::dvec3 q = (p - lo) * inv;
      const uint64_t i = cellCoord(q.x, dx);
      const uint64_t j = cellCoord(q.y, dy);
      const uint64_t k = cellCoord(q.z, dz);
      return (i << 42) | (j << 21) | k;
    };
    for (uint32_t v = 0; v < nv; ++v) {
      if (badVertex[v]) continue;
      const glm::dvec3& p = raw.positions[v];
      uint32_t rep = v;
      for (int dx = -1; dx <= 1 && rep == v; ++dx)
        for (int dy = -1; dy <= 1 && rep == v; ++dy)
          for (int dz = -1; dz <= 1 && rep == v; ++dz) {
            const auto it = cells.find(cellOf(p, dx, dy, dz));
            if (it == cells.end()) continue;
            for (uint32_t r : it->second)
              if (glm::length(raw.positions[r] - p) <= tol) {
                rep = r;
                break;
              }
          }
      if (rep != v) {
        remap[v] = rep;
        ++m.repairs.weldedVertices;
      } else {
        cells[cellOf(p, 0, 0, 0)].push_back(v);
      }
    }
  }

  // Triangulate (after weld so quads pick their diagonal on final positions).
  std::vector<std::array<uint32_t, 3>> tris;
  std::vector<uint32_t> triSrc;
  std::vector<std::array<glm::dvec2, 3>> triUV;
  const bool hasUV = !raw.cornerUVs.empty();
  tris.reserve(raw.polyIndices.size());
  for (uint32_t p = 0; p < np; ++p) {
    const uint32_t b = raw.polyOffsets[p], e = raw.polyOffsets[p + 1];
    const uint32_t n = e - b;
    if (n < 3) {
      if (!repair) throw Error("polygon has " + std::to_string(n) + " vertices (at least 3 needed)", file, faceName(p));
      ++m.repairs.droppedShortPolygons;
      continue;
    }
    bool bad = false;
    for (uint32_t k = b; k < e; ++k) bad |= badVertex[raw.polyIndices[k]] != 0;
    if (bad) {
      ++m.repairs.droppedNonFinite;
      continue;
    }
    auto add = [&](uint32_t i0, uint32_t i1, uint32_t i2) {
      tris.push_back({remap[raw.polyIndices[b + i0]], remap[raw.polyIndices[b + i1]], remap[raw.polyIndices[b + i2]]});
      triSrc.push_back(p);
      if (hasUV) triUV.push_back({raw.cornerUVs[b + i0], raw.cornerUVs[b + i1], raw.cornerUVs[b + i2]});
    };
    if (n == 4) {
      const auto& P = raw.positions;
      const double d02 = glm::length(P[raw.polyIndices[b]] - P[raw.polyIndices[b + 2]]);
      const double d13 = glm::length(P[raw.polyIndices[b + 1]] - P[raw.polyIndices[b + 3]]);
      if (d13 < d02) {
        add(0, 1, 3);
        add(1, 2, 3);
      } else {
        add(0, 1, 2);
        add(0, 2, 3);
      }
    } else {
      for (uint32_t k = 1; k + 1 < n; ++k) add(0, k, k + 1);
    }
  }

  // Degenerate faces.
  const double areaTol = opt.degenerateTolerance * diag * diag;
  std::vector<uint8_t> keep(tris.size(), 1);
  for (size_t t = 0; t < tris.size(); ++t) {
    const auto& f = tris[t];
    std::string why;
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      const uint32_t r = f[0] == f[1] || f[0] == f[2] ? f[0] : f[1];
      why = "is degenerate: it uses vertex " + std::to_string(r) + " twice";
    } else {
      const double a = triArea(raw.positions[f[0]], raw.positions[f[1]], raw.positions[f[2]]);
      if (!(a > areaTol)) {
        std::ostringstream os;
        os << "is degenerate: zero area (" << a << ", vertices " << f[0] << ", " << f[1] << ", " << f[2] << ")";
        why = os.str();
      }
    }
    if (why.empty()) continue;
    if (!repair) throw Error(why + " (load with repair to drop degenerate faces)", file, faceName(triSrc[t]));
    keep[t] = 0;
    ++m.repairs.droppedDegenerate;
  }

  auto compact = [&]() {
    size_t w = 0;
    for (size_t t = 0; t < tris.size(); ++t) {
      if (!keep[t]) continue;
      tris[w] = tris[t];
      triSrc[w] = triSrc[t];
      if (hasUV) triUV[w] = triUV[t];
      ++w;
    }
    tris.resize(w);
    triSrc.resize(w);
    if (hasUV) triUV.resize(w);
    keep.assign(w, 1);
  };
  compact();

  // Non-manifold edges: more than two faces on one edge.
  {
    const auto he = sortedHalfEdges(tris);
    for (size_t i = 0; i < he.size();) {
      size_t j = i;
      while (j < he.size() && he[j].key == he[i].key) ++j;
      if (j - i > 2) {
        const uint32_t a = static_cast<uint32_t>(he[i].key >> 32), b = static_cast<uint32_t>(he[i].key & 0xFFFFFFFFu);
        if (!repair) {
          std::string list;
          for (size_t k = i; k < j; ++k) list += (k > i ? ", " : "") + std::to_string(triSrc[he[k].face]);
          throw Error("edge (" + std::to_string(a) + ", " + std::to_string(b) + ") is shared by " +
                          std::to_string(j - i) + " faces (" + list +
                          "): non-manifold edge (load with repair to drop the extra faces)",
                      file, faceName(triSrc[he[i + 2].face]));
        }
        for (size_t k = i + 2; k < j; ++k)
          if (keep[he[k].face]) {
            keep[he[k].face] = 0;
            ++m.repairs.droppedNonManifold;
          }
      }
      i = j;
    }
    // Dropping a face can only lower edge counts; one more pass keeps the invariant simple to see.
    compact();
  }
  if (tris.empty()) throw Error("mesh has no valid faces left after repair", file, "mesh");

  // Orientation: across every interior edge the two faces must traverse it in opposite directions.
  auto he = sortedHalfEdges(tris);
  auto directed = [&](const HalfEdge& h) { return tris[h.face][h.corner]; };  // start vertex
  {
    bool inconsistent = false;
    for (size_t i = 0; i + 1 < he.size(); ++i) {
      if (he[i].key != he[i + 1].key) continue;
      if (directed(he[i]) == directed(he[i + 1])) {
        if (!repair) {
          const uint32_t a = static_cast<uint32_t>(he[i].key >> 32), b = static_cast<uint32_t>(he[i].key & 0xFFFFFFFFu);
          throw Error("faces " + std::to_string(triSrc[he[i].face]) + " and " + std::to_string(triSrc[he[i + 1].face]) +
                          " are oriented inconsistently across edge (" + std::to_string(a) + ", " + std::to_string(b) +
                          ") (load with repair to re-orient)",
                      file, faceName(triSrc[he[i + 1].face]));
        }
        inconsistent = true;
      }
      ++i;
    }
    // Neighbour lists (orientation-independent) for BFS.
    std::vector<std::array<int32_t, 3>> nb(tris.size(), {-1, -1, -1});
    for (size_t i = 0; i + 1 < he.size(); ++i) {
      if (he[i].key != he[i + 1].key) continue;
      nb[he[i].face][he[i].corner] = static_cast<int32_t>(he[i + 1].face);
      nb[he[i + 1].face][he[i + 1].corner] = static_cast<int32_t>(he[i].face);
      ++i;
    }
    if (repair) {
      // BFS per component: flip neighbours that traverse the shared edge in the same direction.
      std::vector<int8_t> state(tris.size(), -1);  // -1 unvisited, 0 keep, 1 flip
      std::vector<uint32_t> queue, comp;
      auto edgeDir = [&](uint32_t f, uint32_t c, bool flipped, uint32_t& from, uint32_t& to) {
        from = tris[f][c];
        to = tris[f][(c + 1) % 3];
        if (flipped) std::swap(from, to);
      };
      for (uint32_t seed = 0; seed < tris.size(); ++seed) {
        if (state[seed] >= 0) continue;
        state[seed] = 0;
        queue.assign(1, seed);
        comp.clear();
        bool closed = true;
        for (size_t qi = 0; qi < queue.size(); ++qi) {
          const uint32_t f = queue[qi];
          comp.push_back(f);
          for (uint32_t c = 0; c < 3; ++c) {
            const int32_t g = nb[f][c];
            if (g < 0) {
              closed = false;
              continue;
            }
            uint32_t a0, a1;
            edgeDir(f, c, state[f] == 1, a0, a1);
            // Find the corner of g holding the same edge.
            uint32_t cg = 0;
            for (; cg < 3; ++cg)
              if (nb[g][cg] == static_cast<int32_t>(f)) {
                const uint32_t u = tris[g][cg], v = tris[g][(cg + 1) % 3];
                if ((u == a0 && v == a1) || (u == a1 && v == a0)) break;
              }
            if (cg == 3) continue;
            const uint32_t u = tris[g][cg];
            // g keeps its orientation iff it runs the edge a1 -> a0.
            const int8_t want = (u == a1) ? 0 : 1;
            if (state[g] < 0) {
              state[g] = want;
              queue.push_back(static_cast<uint32_t>(g));
            } else if (state[g] != want) {
              throw Error("mesh is not orientable (Moebius-like strip through this face)", file,
                          faceName(triSrc[static_cast<size_t>(g)]));
            }
          }
        }
        // Closed components face outward: positive signed volume.
        if (closed) {
          double vol = 0;
          for (uint32_t f : comp) {
            const auto& t = tris[f];
            const glm::dvec3 a = raw.positions[t[0]] - lo, b = raw.positions[t[1]] - lo, c = raw.positions[t[2]] - lo;
            const double v = glm::dot(a, glm::cross(b, c));
            vol += state[f] == 1 ? -v : v;
          }
          if (vol < 0)
            for (uint32_t f : comp) state[f] = static_cast<int8_t>(1 - state[f]);
        }
      }
      for (size_t f = 0; f < tris.size(); ++f)
        if (state[f] == 1) {
          std::swap(tris[f][1], tris[f][2]);
          if (hasUV) std::swap(triUV[f][1], triUV[f][2]);
          ++m.repairs.flippedFaces;
        }
      if (m.repairs.flippedFaces > 0) he = sortedHalfEdges(tris);
    }
    (void)inconsistent;
  }

  // Final adjacency across edges.
  m.faceNeighbors.assign(tris.size(), {-1, -1, -1});
  for (size_t i = 0; i + 1 < he.size(); ++i) {
    if (he[i].key != he[i + 1].key) continue;
    m.faceNeighbors[he[i].face][he[i].corner] = static_cast<int32_t>(he[i + 1].face);
    m.faceNeighbors[he[i + 1].face][he[i + 1].corner] = static_cast<int32_t>(he[i].face);
    ++i;
  }

  m.positions = std::move(raw.positions);
  m.faces = std::move(tris);
  m.sourceFace = std::move(triSrc);
  if (hasUV) m.faceUVs = std::move(triUV);
  m.groupNames = std::move(raw.groupNames);
  m.faceGroup.resize(m.faces.size(), -1);
  if (!raw.polyGroup.empty())
    for (size_t t = 0; t < m.faces.size(); ++t) {
      const int32_t g = raw.polyGroup[m.sourceFace[t]];
      m.faceGroup[t] = (g >= 0 && static_cast<size_t>(g) < m.groupNames.size()) ? g : -1;
    }

  // Vertex -> faces (CSR, faces in increasing order).
  m.vertexFaceOffsets.assign(nv + 1, 0);
  for (const auto& f : m.faces)
    for (uint32_t v : f) ++m.vertexFaceOffsets[v + 1];
  for (size_t v = 0; v < nv; ++v) m.vertexFaceOffsets[v + 1] += m.vertexFaceOffsets[v];
  m.vertexFaces.resize(m.vertexFaceOffsets[nv]);
  {
    std::vector<uint32_t> fill(m.vertexFaceOffsets.begin(), m.vertexFaceOffsets.end() - 1);
    for (uint32_t f = 0; f < m.faces.size(); ++f)
      for (uint32_t v : m.faces[f]) m.vertexFaces[fill[v]++] = f;
  }

  recomputeGeometry(m);

  // File normals, when every used vertex has one.
  if (raw.vertexNormals.size() == nv) {
    bool all = true;
    for (size_t v = 0; v < nv && all; ++v) {
      if (m.vertexFaceOffsets[v] == m.vertexFaceOffsets[v + 1]) continue;
      const glm::dvec3& n = raw.vertexNormals[v];
      all = finite(n) && glm::length(n) > 0;
    }
    if (all) {
      for (size_t v = 0; v < nv; ++v)
        if (m.vertexFaceOffsets[v] != m.vertexFaceOffsets[v + 1])
          m.vertexNormals[v] = glm::normalize(raw.vertexNormals[v]);
      m.hasFileNormals = true;
    }
  }
  return m;
}

}  // namespace detail

SkinMesh loadSkinMesh(const std::string& path, const MeshLoadOptions& options) {
  const std::string ext = extensionOf(path);
  detail::RawMesh raw;
  if (ext == ".obj") {
    raw = detail::readObj(path);
  } else if (ext == ".ply" || ext == ".off" || ext == ".stl") {
    raw = detail::readWithOpenMesh(path);
  } else {
    throw Error("unsupported mesh format '" + ext + "' (expected .obj, .ply, .off or .stl)", path);
  }
  return detail::buildSkinMesh(std::move(raw), options, path);
}

SkinMesh makeSkinMesh(std::vector<glm::dvec3> positions, std::vector<std::array<uint32_t, 3>> faces,
                      std::vector<std::string> groupNames, std::vector<int32_t> faceGroup,
                      const MeshLoadOptions& options, const std::string& file) {
  detail::RawMesh raw;
  raw.positions = std::move(positions);
  raw.polyIndices.reserve(faces.size() * 3);
  raw.polyOffsets.reserve(faces.size() + 1);
  for (const auto& f : faces) {
    raw.polyIndices.insert(raw.polyIndices.end(), f.begin(), f.end());
    raw.polyOffsets.push_back(static_cast<uint32_t>(raw.polyIndices.size()));
  }
  if (!faceGroup.empty() && faceGroup.size() != faces.size())
    throw Error(
        "faceGroup has " + std::to_string(faceGroup.size()) + " entries for " + std::to_string(faces.size()) + " faces",
        file, "faceGroup");
  for (size_t f = 0; f < faceGroup.size(); ++f)
    if (faceGroup[f] >= static_cast<int32_t>(groupNames.size()))
      throw Error("group index " + std::to_string(faceGroup[f]) + " out of range (" +
                      std::to_string(groupNames.size()) + " groups)",
                  file, "face " + std::to_string(f));
  raw.groupNames = std::move(groupNames);
  raw.polyGroup = std::move(faceGroup);
  return detail::buildSkinMesh(std::move(raw), options, file);
}

void recomputeGeometry(SkinMesh& m) {
  const size_t nf = m.faces.size(), nv = m.positions.size();
  m.faceNormals.resize(nf);
  m.faceAreas.resize(nf);
  m.vertexNormals.resize(nv);
  std::vector<glm::dvec3> cross(nf);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, nf, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f != r.end(); ++f) {
      const auto& t = m.faces[f];
      const glm::dvec3 c = glm::cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]);
      const double len = glm::length(c);
      cross[f] = c;
      m.faceAreas[f] = 0.5 * len;
      m.faceNormals[f] = len > 0 ? c / len : glm::dvec3(0, 0, 1);
    }
  });
  const bool csr = m.vertexFaceOffsets.size() == nv + 1;
  PTERYLA_CHECK(csr, "SkinMesh without vertex-face adjacency (build it with makeSkinMesh/loadSkinMesh)");
  tbb::parallel_for(tbb::blocked_range<size_t>(0, nv, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v != r.end(); ++v) {
      glm::dvec3 n(0);
      for (uint32_t k = m.vertexFaceOffsets[v]; k < m.vertexFaceOffsets[v + 1]; ++k) n += cross[m.vertexFaces[k]];
      const double len = glm::length(n);
      if (len > 0) {
        m.vertexNormals[v] = n / len;
      } else if (m.vertexFaceOffsets[v] < m.vertexFaceOffsets[v + 1]) {
        m.vertexNormals[v] = m.faceNormals[m.vertexFaces[m.vertexFaceOffsets[v]]];
      } else {
        m.vertexNormals[v] = glm::dvec3(0);
      }
    }
  });
  m.hasFileNormals = false;
}

TriMesh toTriMesh(const SkinMesh& m) {
  TriMesh t;
  if (m.faceUVs.empty()) {
    t.positions.reserve(m.positions.size());
    t.normals.reserve(m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v) {
      t.positions.emplace_back(m.positions[v]);
      t.normals.emplace_back(m.vertexNormals[v]);
    }
    t.indices.reserve(m.faces.size() * 3);
    for (const auto& f : m.faces) t.indices.insert(t.indices.end(), f.begin(), f.end());
  } else {
    const size_t n = m.faces.size() * 3;
    t.positions.reserve(n);
    t.normals.reserve(n);
    t.uvGlobal.reserve(n);
    t.indices.reserve(n);
    for (size_t f = 0; f < m.faces.size(); ++f)
      for (int c = 0; c < 3; ++c) {
        t.indices.push_back(static_cast<uint32_t>(t.positions.size()));
        t.positions.emplace_back(m.positions[m.faces[f][c]]);
        t.normals.emplace_back(m.vertexNormals[m.faces[f][c]]);
        t.uvGlobal.emplace_back(m.faceUVs[f][c]);
      }
  }
  return t;
}

glm::dvec3 pointAt(const SkinMesh& m, uint32_t face, const glm::dvec3& b) {
  const auto& f = m.faces[face];
  return b.x * m.positions[f[0]] + b.y * m.positions[f[1]] + b.z * m.positions[f[2]];
}

glm::dvec3 normalAt(const SkinMesh& m, uint32_t face, const glm::dvec3& b) {
  const auto& f = m.faces[face];
  const glm::dvec3 n = b.x * m.vertexNormals[f[0]] + b.y * m.vertexNormals[f[1]] + b.z * m.vertexNormals[f[2]];
  const double len = glm::length(n);
  return len > 1e-12 ? n / len : m.faceNormals[face];
}

glm::dvec2 uvAt(const SkinMesh& m, uint32_t face, const glm::dvec3& b) {
  PTERYLA_CHECK(!m.faceUVs.empty(), "uvAt on a mesh without texture coordinates");
  const auto& t = m.faceUVs[face];
  return b.x * t[0] + b.y * t[1] + b.z * t[2];
}

glm::dvec3 closestPointOnTriangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c,
                                  glm::dvec3* bary) {
  auto out = [&](double u, double v, double w) {
    if (bary) *bary = {u, v, w};
    return u * a + v * b + w * c;
  };
  const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return out(1, 0, 0);
  const glm::dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return out(0, 1, 0);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return out(1 - v, v, 0);
  }
  const glm::dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return out(0, 0, 1);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return out(1 - w, 0, w);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return out(0, 1 - w, w);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return out(1 - v - w, v, w);
}

SurfacePoint closestSurfacePoint(const SkinMesh& m, const glm::dvec3& p, const std::vector<uint32_t>* faces) {
  SurfacePoint best;
  double bestD = std::numeric_limits<double>::infinity();
  auto visit = [&](uint32_t f) {
    glm::dvec3 b;
    const auto& t = m.faces[f];
    const glm::dvec3 q = closestPointOnTriangle(p, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]], &b);
    const glm::dvec3 d = q - p;
    const double dd = glm::dot(d, d);
    if (dd < bestD) {
      bestD = dd;
      best = {f, b};
    }
  };
  if (faces) {
    for (uint32_t f : *faces) visit(f);
  } else {
    for (uint32_t f = 0; f < m.faces.size(); ++f) visit(f);
  }
  PTERYLA_CHECK(std::isfinite(bestD), "closestSurfacePoint on an empty face set");
  return best;
}

}  // namespace pteryla::coat
