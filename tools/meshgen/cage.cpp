// Quad cages and Catmull-Clark subdivision.
// Catmull & Clark 1978, "Recursively generated B-spline surfaces on arbitrary topological meshes";
// limit-position mask for quad meshes from Halstead, Kass & DeRose 1993 ("Efficient, fair
// interpolation using Catmull-Clark surfaces"), section 3: (n^2 v + 4 sum e_j + sum f_j) / (n (n+5)).
#include "meshgen.hpp"

#include "pteryla/core/error.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/type_precision.hpp>

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace pteryla::meshgen {

namespace {

uint64_t edgeKey(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(a) << 32) | b;
}

struct EdgeTable {
  std::vector<std::array<uint32_t, 2>> verts;
  std::vector<std::array<int64_t, 2>> faces;
  std::unordered_map<uint64_t, uint32_t> index;

  explicit EdgeTable(const QuadCage& c) {
    index.reserve(c.quads.size() * 2);
    for (size_t f = 0; f < c.quads.size(); ++f) {
      for (int j = 0; j < 4; ++j) {
        const uint32_t a = c.quads[f][j], b = c.quads[f][(j + 1) % 4];
        auto [it, inserted] = index.emplace(edgeKey(a, b), static_cast<uint32_t>(verts.size()));
        if (inserted) {
          verts.push_back({a, b});
          faces.push_back({static_cast<int64_t>(f), -1});
        } else {
          PTERYLA_CHECK(faces[it->second][1] < 0, "cage edge shared by more than two faces");
          faces[it->second][1] = static_cast<int64_t>(f);
        }
      }
    }
    for (const auto& f : faces) PTERYLA_CHECK(f[1] >= 0, "cage has a boundary edge; Catmull-Clark needs a closed cage");
  }
  uint32_t at(uint32_t a, uint32_t b) const {
    auto it = index.find(edgeKey(a, b));
    PTERYLA_CHECK(it != index.end(), "chain step is not a cage edge");
    return it->second;
  }
};

}  // namespace

uint32_t QuadCage::addVertex(const glm::dvec3& p) {
  positions.push_back(p);
  return static_cast<uint32_t>(positions.size() - 1);
}

void QuadCage::addQuad(const std::array<uint32_t, 4>& q, int part, const std::array<glm::dvec2, 4>& param) {
  quads.push_back(q);
  tags.push_back(FaceTag{part, param});
}

void orientOutward(QuadCage& cage) {
  const size_t nf = cage.quads.size();
  // Directed edge -> face, rebuilt as faces flip, via undirected adjacency.
  std::unordered_map<uint64_t, std::vector<uint32_t>> adj;
  for (uint32_t f = 0; f < nf; ++f)
    for (int j = 0; j < 4; ++j) adj[edgeKey(cage.quads[f][j], cage.quads[f][(j + 1) % 4])].push_back(f);
  auto usesDirected = [&](uint32_t f, uint32_t a, uint32_t b) {
    for (int j = 0; j < 4; ++j)
      if (cage.quads[f][j] == a && cage.quads[f][(j + 1) % 4] == b) return true;
    return false;
  };
  auto flip = [&](uint32_t f) {
    std::swap(cage.quads[f][1], cage.quads[f][3]);
    std::swap(cage.tags[f].param[1], cage.tags[f].param[3]);
  };
  std::vector<char> seen(nf, 0);
  std::vector<uint32_t> stack;
  for (uint32_t start = 0; start < nf; ++start) {
    if (seen[start]) continue;
    seen[start] = 1;
    stack.push_back(start);
    while (!stack.empty()) {
      const uint32_t f = stack.back();
      stack.pop_back();
      for (int j = 0; j < 4; ++j) {
        const uint32_t a = cage.quads[f][j], b = cage.quads[f][(j + 1) % 4];
        for (uint32_t g : adj[edgeKey(a, b)]) {
          if (g == f || seen[g]) continue;
          if (usesDirected(g, a, b)) flip(g);
          seen[g] = 1;
          stack.push_back(g);
        }
      }
    }
  }
  double volume = 0;
  for (const auto& q : cage.quads) {
    const glm::dvec3 &p0 = cage.positions[q[0]], &p1 = cage.positions[q[1]], &p2 = cage.positions[q[2]],
                     &p3 = cage.positions[q[3]];
    volume += glm::dot(p0, glm::cross(p1, p2)) + glm::dot(p0, glm::cross(p2, p3));
  }
  if (volume < 0)
    for (uint32_t f = 0; f < nf; ++f) flip(f);
}

QuadCage subdivideCatmullClark(const QuadCage& c) {
  const EdgeTable et(c);
  const size_t nv = c.positions.size(), ne = et.verts.size(), nf = c.quads.size();
  std::vector<glm::dvec3> facePt(nf);
  for (size_t f = 0; f < nf; ++f) {
    glm::dvec3 s(0.0);
    for (uint32_t v : c.quads[f]) s += c.positions[v];
    facePt[f] = s * 0.25;
  }
  std::vector<glm::dvec3> edgePt(ne);
  for (size_t e = 0; e < ne; ++e)
    edgePt[e] =
        (c.positions[et.verts[e][0]] + c.positions[et.verts[e][1]] + facePt[et.faces[e][0]] + facePt[et.faces[e][1]]) *
        0.25;

  std::vector<glm::dvec3> faceSum(nv, glm::dvec3(0.0)), edgeMidSum(nv, glm::dvec3(0.0));
  std::vector<int> faceCount(nv, 0), edgeCount(nv, 0);
  for (size_t f = 0; f < nf; ++f)
    for (uint32_t v : c.quads[f]) {
      faceSum[v] += facePt[f];
      ++faceCount[v];
    }
  for (size_t e = 0; e < ne; ++e) {
    const glm::dvec3 mid = (c.positions[et.verts[e][0]] + c.positions[et.verts[e][1]]) * 0.5;
    for (uint32_t v : et.verts[e]) {
      edgeMidSum[v] += mid;
      ++edgeCount[v];
    }
  }

  QuadCage out;
  out.positions.resize(nv + ne + nf);
  for (size_t v = 0; v < nv; ++v) {
    const double n = edgeCount[v];
    PTERYLA_CHECK(n >= 3 && faceCount[v] == edgeCount[v], "cage vertex is not an interior manifold vertex");
    const glm::dvec3 q = faceSum[v] / double(faceCount[v]), r = edgeMidSum[v] / n;
    out.positions[v] = (q + 2.0 * r + (n - 3.0) * c.positions[v]) / n;
  }
  for (size_t e = 0; e < ne; ++e) out.positions[nv + e] = edgePt[e];
  for (size_t f = 0; f < nf; ++f) out.positions[nv + ne + f] = facePt[f];

  out.quads.reserve(nf * 4);
  out.tags.reserve(nf * 4);
  for (size_t f = 0; f < nf; ++f) {
    const auto& q = c.quads[f];
    const auto& p = c.tags[f].param;
    const uint32_t fp = static_cast<uint32_t>(nv + ne + f);
    const glm::dvec2 pc = c.tags[f].center();
    for (int j = 0; j < 4; ++j) {
      const int jn = (j + 1) % 4, jp = (j + 3) % 4;
      const uint32_t en = static_cast<uint32_t>(nv + et.at(q[j], q[jn]));
      const uint32_t ep = static_cast<uint32_t>(nv + et.at(q[jp], q[j]));
      out.addQuad({q[j], en, fp, ep}, c.tags[f].part, {p[j], (p[j] + p[jn]) * 0.5, pc, (p[jp] + p[j]) * 0.5});
    }
  }
  for (const auto& chain : c.chains) {
    std::vector<uint32_t> fine;
    for (size_t i = 0; i < chain.size(); ++i) {
      fine.push_back(chain[i]);
      if (i + 1 < chain.size()) fine.push_back(static_cast<uint32_t>(nv + et.at(chain[i], chain[i + 1])));
    }
    out.chains.push_back(std::move(fine));
  }
  return out;
}

void projectToLimit(QuadCage& c) {
  const size_t nv = c.positions.size();
  std::vector<glm::dvec3> sum(nv, glm::dvec3(0.0));
  std::vector<int> valence(nv, 0);
  // Each quad corner v sees its two edge neighbours (each edge is seen from two quads, hence
  // weight 4/2 per sighting) and its diagonal vertex.
  for (const auto& q : c.quads) {
    for (int j = 0; j < 4; ++j) {
      const uint32_t v = q[j];
      sum[v] += 2.0 * (c.positions[q[(j + 1) % 4]] + c.positions[q[(j + 3) % 4]]) + c.positions[q[(j + 2) % 4]];
      ++valence[v];
    }
  }
  std::vector<glm::dvec3> limit(nv);
  for (size_t v = 0; v < nv; ++v) {
    const double n = valence[v];
    limit[v] = (n * n * c.positions[v] + sum[v]) / (n * (n + 5.0));
  }
  c.positions = std::move(limit);
}

uint32_t GroupedMesh::groupIndex(const std::string& name) {
  for (size_t i = 0; i < groupNames.size(); ++i)
    if (groupNames[i] == name) return static_cast<uint32_t>(i);
  groupNames.push_back(name);
  return static_cast<uint32_t>(groupNames.size() - 1);
}

GroupedMesh triangulate(const QuadCage& c, const Classifier& classify, const std::vector<std::string>& groupOrder) {
  GroupedMesh m;
  m.positions = c.positions;
  std::vector<uint32_t> rawGroup;
  std::vector<std::string> used;
  for (size_t f = 0; f < c.quads.size(); ++f) {
    const auto& q = c.quads[f];
    const glm::dvec3 centroid = (c.positions[q[0]] + c.positions[q[1]] + c.positions[q[2]] + c.positions[q[3]]) * 0.25;
    const std::string g = classify(c.tags[f], centroid);
    auto it = std::find(used.begin(), used.end(), g);
    const uint32_t gi = static_cast<uint32_t>(it - used.begin());
    if (it == used.end()) used.push_back(g);
    const double d02 = glm::length(c.positions[q[0]] - c.positions[q[2]]);
    const double d13 = glm::length(c.positions[q[1]] - c.positions[q[3]]);
    if (d02 <= d13) {
      m.triangles.push_back({q[0], q[1], q[2]});
      m.triangles.push_back({q[0], q[2], q[3]});
    } else {
      m.triangles.push_back({q[0], q[1], q[3]});
      m.triangles.push_back({q[1], q[2], q[3]});
    }
    rawGroup.push_back(gi);
    rawGroup.push_back(gi);
  }
  for (const auto& g : groupOrder)
    if (std::find(used.begin(), used.end(), g) != used.end()) m.groupIndex(g);
  for (const auto& g : used) m.groupIndex(g);
  m.faceGroup.reserve(rawGroup.size());
  for (uint32_t g : rawGroup) m.faceGroup.push_back(m.groupIndex(used[g]));
  return m;
}

size_t improveByFlips(GroupedMesh& m, double maxDihedralDeg) {
  auto minAngle = [&](uint32_t a, uint32_t b, uint32_t c) {
    const glm::dvec3 &p = m.positions[a], &q = m.positions[b], &r = m.positions[c];
    auto ang = [](const glm::dvec3& o, const glm::dvec3& u, const glm::dvec3& v) {
      return std::acos(std::clamp(glm::dot(glm::normalize(u - o), glm::normalize(v - o)), -1.0, 1.0));
    };
    return std::min({ang(p, q, r), ang(q, r, p), ang(r, p, q)});
  };
  auto normal = [&](uint32_t a, uint32_t b, uint32_t c) {
    return glm::normalize(glm::cross(m.positions[b] - m.positions[a], m.positions[c] - m.positions[a]));
  };
  const double cosLimit = std::cos(maxDihedralDeg * 3.14159265358979323846 / 180.0);
  size_t total = 0;
  for (int pass = 0; pass < 20; ++pass) {
    // Directed edge -> (triangle, corner of the edge's start).
    std::unordered_map<uint64_t, std::pair<uint32_t, int>> dir;
    dir.reserve(m.triangles.size() * 3);
    for (uint32_t t = 0; t < m.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) dir[(uint64_t(m.triangles[t][k]) << 32) | m.triangles[t][(k + 1) % 3]] = {t, k};
    std::vector<char> touched(m.triangles.size(), 0);
    size_t flips = 0;
    for (uint32_t t0 = 0; t0 < m.triangles.size(); ++t0) {
      for (int k = 0; k < 3 && !touched[t0]; ++k) {
        const uint32_t a = m.triangles[t0][k], b = m.triangles[t0][(k + 1) % 3], c = m.triangles[t0][(k + 2) % 3];
        auto it = dir.find((uint64_t(b) << 32) | a);
        if (it == dir.end()) continue;
        const uint32_t t1 = it->second.first;
        if (touched[t1] || m.faceGroup[t0] != m.faceGroup[t1]) continue;
        const uint32_t d = m.triangles[t1][(it->second.second + 2) % 3];
        if (c == d || dir.count((uint64_t(c) << 32) | d) || dir.count((uint64_t(d) << 32) | c)) continue;
        const glm::dvec3 n0 = normal(a, b, c), n1 = normal(b, a, d);
        if (glm::dot(n0, n1) < cosLimit) continue;
        const double before = std::min(minAngle(a, b, c), minAngle(b, a, d));
        const double after = std::min(minAngle(a, d, c), minAngle(d, b, c));
        if (after <= before + 1e-9) continue;
        const glm::dvec3 avg = n0 + n1;
        if (glm::dot(normal(a, d, c), avg) <= 0 || glm::dot(normal(d, b, c), avg) <= 0) continue;
        m.triangles[t0] = {a, d, c};
        m.triangles[t1] = {d, b, c};
        touched[t0] = touched[t1] = 1;
        dir[(uint64_t(c) << 32) | d] = {t1, 0};
        dir[(uint64_t(d) << 32) | c] = {t0, 0};
        ++flips;
      }
    }
    total += flips;
    if (!flips) break;
  }
  return total;
}

namespace {

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
glm::dvec3 closestOnTriangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const glm::dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const glm::dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

struct TriangleGrid {
  std::vector<std::array<glm::dvec3, 3>> tris;
  std::vector<glm::dvec3> normals;
  glm::dvec3 lo{0.0};
  double cell = 1;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells;

  uint64_t key(int64_t i, int64_t j, int64_t k) const {
    return (static_cast<uint64_t>(i & 0x1fffff) << 42) | (static_cast<uint64_t>(j & 0x1fffff) << 21) |
           static_cast<uint64_t>(k & 0x1fffff);
  }
  glm::i64vec3 index(const glm::dvec3& p) const {
    const glm::dvec3 q = (p - lo) / cell;
    return {static_cast<int64_t>(std::floor(q.x)), static_cast<int64_t>(std::floor(q.y)),
            static_cast<int64_t>(std::floor(q.z))};
  }
  void build(double cellSize) {
    cell = cellSize;
    lo = glm::dvec3(1e30);
    for (const auto& t : tris)
      for (const auto& p : t) lo = glm::min(lo, p);
    for (uint32_t i = 0; i < tris.size(); ++i) {
      const auto& t = tris[i];
      const glm::i64vec3 a = index(glm::min(glm::min(t[0], t[1]), t[2])),
                         b = index(glm::max(glm::max(t[0], t[1]), t[2]));
      for (int64_t x = a.x; x <= b.x; ++x)
        for (int64_t y = a.y; y <= b.y; ++y)
          for (int64_t z = a.z; z <= b.z; ++z) cells[key(x, y, z)].push_back(i);
    }
  }
  // Closest point among triangles within one cell of p whose normal agrees with n.
  bool closest(const glm::dvec3& p, const glm::dvec3& n, glm::dvec3& out) const {
    const glm::i64vec3 c = index(p);
    double best = 1e30;
    for (int64_t x = c.x - 1; x <= c.x + 1; ++x)
      for (int64_t y = c.y - 1; y <= c.y + 1; ++y)
        for (int64_t z = c.z - 1; z <= c.z + 1; ++z) {
          auto it = cells.find(key(x, y, z));
          if (it == cells.end()) continue;
          for (uint32_t t : it->second) {
            if (glm::dot(normals[t], n) < 0.3) continue;
            const glm::dvec3 q = closestOnTriangle(p, tris[t][0], tris[t][1], tris[t][2]);
            const double d = glm::dot(q - p, q - p);
            if (d < best) {
              best = d;
              out = q;
            }
          }
        }
    return best < 1e30;
  }
};

}  // namespace

void relaxOnSurface(GroupedMesh& m, const QuadCage& reference, int iterations, double step) {
  TriangleGrid grid;
  double edgeSum = 0;
  for (const auto& q : reference.quads) {
    const glm::dvec3 &a = reference.positions[q[0]], &b = reference.positions[q[1]], &c = reference.positions[q[2]],
                     &d = reference.positions[q[3]];
    grid.tris.push_back({a, b, c});
    grid.tris.push_back({a, c, d});
    edgeSum += glm::length(b - a);
  }
  for (const auto& t : grid.tris) {
    const glm::dvec3 n = glm::cross(t[1] - t[0], t[2] - t[0]);
    const double l = glm::length(n);
    grid.normals.push_back(l > 0 ? n / l : glm::dvec3(0.0));
  }
  grid.build(4.0 * edgeSum / double(std::max<size_t>(1, reference.quads.size())));

  const size_t nv = m.positions.size();
  std::vector<std::vector<uint32_t>> nbr(nv);
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      auto& l = nbr[t[k]];
      for (uint32_t o : {t[(k + 1) % 3], t[(k + 2) % 3]})
        if (std::find(l.begin(), l.end(), o) == l.end()) l.push_back(o);
    }
  for (int it = 0; it < iterations; ++it) {
    std::vector<glm::dvec3> normal(nv, glm::dvec3(0.0));
    for (const auto& t : m.triangles) {
      const glm::dvec3 n = glm::cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]);
      for (uint32_t v : t) normal[v] += n;
    }
    std::vector<glm::dvec3> next = m.positions;
    for (size_t v = 0; v < nv; ++v) {
      if (nbr[v].empty()) continue;
      const glm::dvec3 n = glm::normalize(normal[v]);
      glm::dvec3 mean(0.0);
      for (uint32_t o : nbr[v]) mean += m.positions[o];
      const glm::dvec3 lap = mean / double(nbr[v].size()) - m.positions[v];
      const glm::dvec3 moved = m.positions[v] + step * (lap - glm::dot(lap, n) * n);
      glm::dvec3 onSurface;
      if (grid.closest(moved, n, onSurface)) next[v] = onSurface;
    }
    m.positions = std::move(next);
  }
}

}  // namespace pteryla::meshgen
