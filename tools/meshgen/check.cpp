// Mesh validation, OBJ reading/writing and the JSON side files (skeleton, axes).
#include "meshgen.hpp"

#include "pteryla/core/error.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <unordered_map>

namespace pteryla::meshgen {

namespace {

constexpr double kPi = 3.14159265358979323846;

uint64_t directedKey(uint32_t a, uint32_t b) { return (static_cast<uint64_t>(a) << 32) | b; }

double triangleMinAngleDeg(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  auto angle = [](const glm::dvec3& p, const glm::dvec3& q, const glm::dvec3& r) {
    const glm::dvec3 u = q - p, v = r - p;
    const double lu = glm::length(u), lv = glm::length(v);
    if (lu <= 0 || lv <= 0) return 0.0;
    return std::acos(std::clamp(glm::dot(u, v) / (lu * lv), -1.0, 1.0)) * 180.0 / kPi;
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
}

// Segment pq against triangle abc, excluding touching at the ends (tolerance eps in parameters).
bool segmentHitsTriangle(const glm::dvec3& p, const glm::dvec3& q, const glm::dvec3& a, const glm::dvec3& b,
                         const glm::dvec3& c) {
  const double eps = 1e-9;
  const glm::dvec3 d = q - p, e1 = b - a, e2 = c - a;
  const glm::dvec3 h = glm::cross(d, e2);
  const double det = glm::dot(e1, h);
  if (std::abs(det) < 1e-18) return false;
  const double inv = 1.0 / det;
  const glm::dvec3 s = p - a;
  const double u = glm::dot(s, h) * inv;
  if (u < eps || u > 1 - eps) return false;
  const glm::dvec3 qv = glm::cross(s, e1);
  const double v = glm::dot(d, qv) * inv;
  if (v < eps || u + v > 1 - eps) return false;
  const double t = glm::dot(e2, qv) * inv;
  return t > eps && t < 1 - eps;
}

size_t countSelfIntersections(const GroupedMesh& m) {
  const size_t nt = m.triangles.size();
  std::vector<glm::dvec3> lo(nt), hi(nt);
  std::vector<uint32_t> order(nt);
  for (size_t t = 0; t < nt; ++t) {
    const auto& tri = m.triangles[t];
    lo[t] = glm::min(glm::min(m.positions[tri[0]], m.positions[tri[1]]), m.positions[tri[2]]);
    hi[t] = glm::max(glm::max(m.positions[tri[0]], m.positions[tri[1]]), m.positions[tri[2]]);
    order[t] = static_cast<uint32_t>(t);
  }
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return lo[a].x < lo[b].x || (lo[a].x == lo[b].x && a < b); });
  size_t hits = 0;
  for (size_t i = 0; i < nt; ++i) {
    const uint32_t A = order[i];
    for (size_t j = i + 1; j < nt && lo[order[j]].x <= hi[A].x; ++j) {
      const uint32_t B = order[j];
      if (lo[B].y > hi[A].y || hi[B].y < lo[A].y || lo[B].z > hi[A].z || hi[B].z < lo[A].z) continue;
      const auto& ta = m.triangles[A];
      const auto& tb = m.triangles[B];
      int shared = 0;
      for (uint32_t va : ta)
        for (uint32_t vb : tb) shared += (va == vb);
      if (shared >= 2) continue;
      bool hit = false;
      auto edgesAgainst = [&](const std::array<uint32_t, 3>& s, const std::array<uint32_t, 3>& t) {
        for (int k = 0; k < 3 && !hit; ++k) {
          const uint32_t e0 = s[k], e1 = s[(k + 1) % 3];
          if (std::find(t.begin(), t.end(), e0) != t.end() || std::find(t.begin(), t.end(), e1) != t.end()) continue;
          hit = segmentHitsTriangle(m.positions[e0], m.positions[e1], m.positions[t[0]], m.positions[t[1]],
                                    m.positions[t[2]]);
        }
      };
      edgesAgainst(ta, tb);
      edgesAgainst(tb, ta);
      hits += hit;
    }
  }
  return hits;
}

std::string fmt(const char* f, double a) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, a);
  return buf;
}

}  // namespace

MeshCheck checkMesh(const GroupedMesh& m, bool expectClosed) {
  MeshCheck r;
  r.vertices = m.positions.size();
  r.faces = m.triangles.size();
  auto problem = [&](const std::string& s) { r.problems.push_back(s); };
  if (m.faceGroup.size() != m.triangles.size()) problem("faceGroup size differs from face count");

  for (const auto& p : m.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) ++r.nonFinite;

  std::vector<char> used(m.positions.size(), 0);
  std::unordered_map<uint64_t, uint32_t> directed;  // directed edge -> count
  directed.reserve(m.triangles.size() * 4);
  r.groups.resize(m.groupNames.size());
  for (size_t g = 0; g < m.groupNames.size(); ++g) r.groups[g].name = m.groupNames[g];
  double minSum = 0;
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    const auto& tri = m.triangles[t];
    bool badIndex = false;
    for (uint32_t v : tri) badIndex |= v >= m.positions.size();
    if (badIndex || tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      ++r.degenerateFaces;
      continue;
    }
    for (uint32_t v : tri) used[v] = 1;
    const glm::dvec3 &a = m.positions[tri[0]], &b = m.positions[tri[1]], &c = m.positions[tri[2]];
    const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
    const double minAngle = triangleMinAngleDeg(a, b, c);
    if (!(area > 1e-12) || !(minAngle > 1e-3)) ++r.degenerateFaces;
    r.area += area;
    r.volume += glm::dot(a, glm::cross(b, c)) / 6.0;
    r.minAngleDeg = std::min(r.minAngleDeg, minAngle);
    minSum += minAngle;
    r.facesBelow20Deg += minAngle < 20.0;
    r.facesBelow10Deg += minAngle < 10.0;
    if (t < m.faceGroup.size() && m.faceGroup[t] < r.groups.size()) {
      ++r.groups[m.faceGroup[t]].faces;
      r.groups[m.faceGroup[t]].area += area;
      r.groups[m.faceGroup[t]].facesBelow20Deg += minAngle < 20.0;
    } else {
      problem("face " + std::to_string(t) + " has no valid group");
    }
    for (int k = 0; k < 3; ++k) ++directed[directedKey(tri[k], tri[(k + 1) % 3])];
  }
  if (!m.triangles.empty()) r.meanMinAngleDeg = minSum / double(m.triangles.size());
  for (char u : used) r.unusedVertices += !u;

  // Edge classification: each undirected edge must be a->b once and (closed) b->a once.
  std::unordered_map<uint32_t, std::vector<uint32_t>> boundaryNext;
  for (const auto& [key, count] : directed) {
    const uint32_t a = static_cast<uint32_t>(key >> 32), b = static_cast<uint32_t>(key & 0xffffffffu);
    if (count > 1) ++r.misorientedEdges;
    auto rev = directed.find(directedKey(b, a));
    const uint32_t revCount = rev == directed.end() ? 0 : rev->second;
    if (a < b || revCount == 0) ++r.edges;
    if (count + revCount > 2) ++r.nonManifoldEdges;
    if (revCount == 0) {
      ++r.boundaryEdges;
      boundaryNext[b].push_back(a);  // boundary loops run opposite to the faces
    }
  }
  // Vertex fans: the link of every vertex is one cycle (interior) or one path (boundary).
  std::vector<std::vector<std::array<uint32_t, 2>>> link(m.positions.size());
  for (const auto& tri : m.triangles) {
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
    for (int k = 0; k < 3; ++k) link[tri[k]].push_back({tri[(k + 1) % 3], tri[(k + 2) % 3]});
  }
  for (size_t v = 0; v < link.size(); ++v) {
    auto& L = link[v];
    if (L.empty()) continue;
    std::unordered_map<uint32_t, uint32_t> next;
    std::unordered_map<uint32_t, int> indeg;
    bool bad = false;
    for (const auto& e : L) {
      bad |= !next.emplace(e[0], e[1]).second;
      ++indeg[e[1]];
    }
    uint32_t start = L[0][0];
    int starts = 0;
    for (const auto& e : L)
      if (!indeg.count(e[0])) {
        start = e[0];
        ++starts;
      }
    bad |= starts > 1;
    size_t steps = 0;
    uint32_t cur = start;
    while (!bad && next.count(cur) && steps <= L.size()) {
      cur = next[cur];
      ++steps;
      if (cur == start) break;
    }
    if (bad || steps != L.size()) ++r.nonManifoldVertices;
  }
  if (r.boundaryEdges > 0 && r.nonManifoldEdges == 0) {
    std::unordered_map<uint32_t, char> visited;
    for (const auto& [v, outs] : boundaryNext) {
      if (visited.count(v)) continue;
      ++r.boundaryLoops;
      uint32_t cur = v;
      while (!visited.count(cur)) {
        visited[cur] = 1;
        auto it = boundaryNext.find(cur);
        if (it == boundaryNext.end() || it->second.size() != 1) break;
        cur = it->second[0];
      }
    }
  }
  r.selfIntersections = countSelfIntersections(m);

  if (r.nonFinite) problem(std::to_string(r.nonFinite) + " vertices with non-finite coordinates");
  if (r.degenerateFaces) problem(std::to_string(r.degenerateFaces) + " degenerate faces");
  if (r.unusedVertices) problem(std::to_string(r.unusedVertices) + " unused vertices");
  if (r.misorientedEdges)
    problem(std::to_string(r.misorientedEdges) + " edges used twice in one direction (inconsistent orientation)");
  if (r.nonManifoldEdges) problem(std::to_string(r.nonManifoldEdges) + " non-manifold edges");
  if (r.nonManifoldVertices) problem(std::to_string(r.nonManifoldVertices) + " non-manifold vertices");
  if (r.selfIntersections) problem(std::to_string(r.selfIntersections) + " self-intersecting face pairs");
  if (expectClosed) {
    if (r.boundaryEdges) problem(std::to_string(r.boundaryEdges) + " boundary edges in a mesh that must be closed");
    if (!(r.volume > 0)) problem("enclosed volume " + fmt("%g", r.volume) + " is not positive (normals point inward)");
  } else if (r.boundaryEdges == 0) {
    problem("open mesh expected but it has no boundary");
  }
  for (const auto& g : r.groups)
    if (g.faces == 0) problem("group '" + g.name + "' is empty");
  return r;
}

std::string formatCheck(const std::string& title, const MeshCheck& c) {
  std::ostringstream o;
  o << title << ": " << c.vertices << " vertices, " << c.faces << " triangles, " << c.edges << " edges";
  if (c.boundaryEdges) o << ", " << c.boundaryEdges << " boundary edges in " << c.boundaryLoops << " loop(s)";
  o << "\n  area " << fmt("%.4f", c.area);
  if (!c.boundaryEdges) o << ", volume " << fmt("%.4f", c.volume);
  o << ", min angle " << fmt("%.1f", c.minAngleDeg) << " deg, mean min angle " << fmt("%.1f", c.meanMinAngleDeg)
    << " deg, " << c.facesBelow20Deg << " faces < 20 deg, " << c.facesBelow10Deg << " < 10 deg\n";
  for (const auto& g : c.groups) {
    char line[160];
    std::snprintf(line, sizeof line, "  g %-26s %6zu faces  area %8.4f  (%zu < 20 deg)\n", g.name.c_str(), g.faces,
                  g.area, g.facesBelow20Deg);
    o << line;
  }
  o << (c.ok() ? "  OK: closed/manifold checks passed\n" : "  FAILED:\n");
  for (const auto& p : c.problems) o << "    - " << p << "\n";
  return o.str();
}

void writeObj(const GroupedMesh& m, const std::string& path, const std::string& comment) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw Error("cannot open for writing", path);
  std::fprintf(f, "# %s\n", comment.c_str());
  std::fprintf(f, "# %zu vertices, %zu triangles, %zu groups\n", m.positions.size(), m.triangles.size(),
               m.groupNames.size());
  for (const auto& p : m.positions) std::fprintf(f, "v %.6f %.6f %.6f\n", p.x, p.y, p.z);
  for (uint32_t g = 0; g < m.groupNames.size(); ++g) {
    std::fprintf(f, "g %s\n", m.groupNames[g].c_str());
    for (size_t t = 0; t < m.triangles.size(); ++t)
      if (m.faceGroup[t] == g)
        std::fprintf(f, "f %u %u %u\n", m.triangles[t][0] + 1, m.triangles[t][1] + 1, m.triangles[t][2] + 1);
  }
  if (std::fclose(f) != 0) throw Error("write failed", path);
}

GroupedMesh readObj(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error("cannot open OBJ file", path);
  GroupedMesh m;
  uint32_t group = UINT32_MAX;
  std::string line;
  size_t lineNo = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    const std::string where = "line " + std::to_string(lineNo);
    std::istringstream ls(line);
    std::string tok;
    if (!(ls >> tok) || tok[0] == '#') continue;
    if (tok == "v") {
      glm::dvec3 p;
      if (!(ls >> p.x >> p.y >> p.z)) throw Error("vertex needs three numbers", path, where);
      m.positions.push_back(p);
    } else if (tok == "g" || tok == "o") {
      std::string name;
      ls >> name;
      if (tok == "g") group = m.groupIndex(name.empty() ? "default" : name);
    } else if (tok == "f") {
      std::vector<uint32_t> idx;
      std::string ref;
      while (ls >> ref) {
        long v = 0;
        try {
          v = std::stol(ref.substr(0, ref.find('/')));
        } catch (const std::exception&) {
          throw Error("bad face index '" + ref + "'", path, where);
        }
        if (v < 0) v += static_cast<long>(m.positions.size()) + 1;
        if (v < 1 || v > static_cast<long>(m.positions.size()))
          throw Error(
              "face index " + ref + " out of range (" + std::to_string(m.positions.size()) + " vertices so far)", path,
              where);
        idx.push_back(static_cast<uint32_t>(v - 1));
      }
      if (idx.size() < 3) throw Error("face needs at least three vertices", path, where);
      if (group == UINT32_MAX) group = m.groupIndex("default");
      for (size_t k = 1; k + 1 < idx.size(); ++k) {
        m.triangles.push_back({idx[0], idx[k], idx[k + 1]});
        m.faceGroup.push_back(group);
      }
    }
  }
  return m;
}

namespace {
std::string num(double x) {
  if (std::abs(x) < 5e-7) x = 0;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}
std::string vec(const glm::dvec3& p) { return "[" + num(p.x) + ", " + num(p.y) + ", " + num(p.z) + "]"; }
}  // namespace

void writeSkeletonJson(const Skeleton& s, const std::string& path) {
  std::ofstream o(path, std::ios::binary);
  if (!o) throw Error("cannot open for writing", path);
  o << "{\n  \"joints\": [\n";
  for (size_t j = 0; j < s.joints.size(); ++j)
    o << "    {\"name\": \"" << s.joints[j].name << "\", \"parent\": " << s.joints[j].parent
      << ", \"position\": " << vec(s.joints[j].position) << "}" << (j + 1 < s.joints.size() ? "," : "") << "\n";
  o << "  ],\n  \"weights\": [\n";
  for (size_t i = 0; i < s.weights.size(); ++i) {
    char buf[80];
    std::snprintf(buf, sizeof buf, "    [%u, %u, %.5f]%s\n", s.weights[i].vertex, s.weights[i].joint,
                  s.weights[i].weight, i + 1 < s.weights.size() ? "," : "");
    o << buf;
  }
  o << "  ]\n}\n";
  if (!o) throw Error("write failed", path);
}

void writeAxesJson(const std::vector<Polyline>& lines, const std::string& path) {
  std::ofstream o(path, std::ios::binary);
  if (!o) throw Error("cannot open for writing", path);
  o << "{\n";
  for (size_t l = 0; l < lines.size(); ++l) {
    o << "  \"" << lines[l].name << "\": [\n";
    for (size_t i = 0; i < lines[l].points.size(); ++i)
      o << "    " << vec(lines[l].points[i]) << (i + 1 < lines[l].points.size() ? "," : "") << "\n";
    o << "  ]" << (l + 1 < lines.size() ? "," : "") << "\n";
  }
  o << "}\n";
  if (!o) throw Error("write failed", path);
}

}  // namespace pteryla::meshgen
