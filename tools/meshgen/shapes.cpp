// Simple test meshes: unit spheres with near-uniform triangles (Streit 2003, Fig. 9.13 uses 250-
// and 1,600-triangle spheres) and a gently curved open patch.
// Sphere: spherical Fibonacci point set (golden-angle spiral), relaxed by a few umbrella steps, and
// triangulated as its convex hull (= the spherical Delaunay triangulation of the points).
#include "cage_build.hpp"

#include "pteryla/core/error.hpp"

#include <map>
#include <unordered_map>

namespace pteryla::meshgen {

namespace {

uint64_t dkey(uint32_t a, uint32_t b) { return (static_cast<uint64_t>(a) << 32) | b; }

// Incremental convex hull of points that all lie on the unit sphere (so every point is a hull
// vertex). Returns outward-oriented triangles.
std::vector<std::array<uint32_t, 3>> sphereHull(const std::vector<glm::dvec3>& pts) {
  const size_t n = pts.size();
  PTERYLA_CHECK(n >= 4, "hull needs four points");
  std::vector<std::array<uint32_t, 3>> faces;
  // Start: points 0 and n-1 (the poles of the spiral) and two spread-out points.
  std::array<uint32_t, 4> t = {0, static_cast<uint32_t>(n / 3), static_cast<uint32_t>(2 * n / 3),
                               static_cast<uint32_t>(n - 1)};
  const glm::dvec3 inside = (pts[t[0]] + pts[t[1]] + pts[t[2]] + pts[t[3]]) * 0.25;
  auto orient = [&](std::array<uint32_t, 3> f) {
    const glm::dvec3 nrm = glm::cross(pts[f[1]] - pts[f[0]], pts[f[2]] - pts[f[0]]);
    if (glm::dot(nrm, pts[f[0]] - inside) < 0) std::swap(f[1], f[2]);
    return f;
  };
  faces.push_back(orient({t[0], t[1], t[2]}));
  faces.push_back(orient({t[0], t[1], t[3]}));
  faces.push_back(orient({t[0], t[2], t[3]}));
  faces.push_back(orient({t[1], t[2], t[3]}));
  std::vector<char> inHull(n, 0);
  for (uint32_t v : t) inHull[v] = 1;
  for (uint32_t p = 0; p < n; ++p) {
    if (inHull[p]) continue;
    std::vector<std::array<uint32_t, 3>> keep;
    std::unordered_map<uint64_t, char> visibleEdges;
    std::vector<std::array<uint32_t, 2>> visibleList;
    for (const auto& f : faces) {
      const glm::dvec3 nrm = glm::cross(pts[f[1]] - pts[f[0]], pts[f[2]] - pts[f[0]]);
      if (glm::dot(nrm, pts[p] - pts[f[0]]) > 1e-12) {
        for (int k = 0; k < 3; ++k) {
          visibleEdges[dkey(f[k], f[(k + 1) % 3])] = 1;
          visibleList.push_back({f[k], f[(k + 1) % 3]});
        }
      } else {
        keep.push_back(f);
      }
    }
    PTERYLA_CHECK(!visibleList.empty(), "sphere point inside the hull");
    for (const auto& e : visibleList)
      if (!visibleEdges.count(dkey(e[1], e[0]))) keep.push_back({e[0], e[1], p});
    faces = std::move(keep);
    inHull[p] = 1;
  }
  return faces;
}

}  // namespace

Generated makeSphere(int pointCount, const std::string& name) {
  const size_t n = static_cast<size_t>(pointCount);
  std::vector<glm::dvec3> pts(n);
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < n; ++i) {
    const double y = 1.0 - (2.0 * i + 1.0) / double(n);
    const double r = std::sqrt(std::max(0.0, 1.0 - y * y));
    const double phi = golden * double(i);
    pts[i] = {r * std::cos(phi), y, r * std::sin(phi)};
  }
  std::vector<std::array<uint32_t, 3>> tris;
  for (int iter = 0; iter < 12; ++iter) {
    tris = sphereHull(pts);
    // Umbrella step towards the mean of the neighbours, back onto the sphere.
    std::vector<glm::dvec3> sum(n, glm::dvec3(0.0));
    std::vector<int> cnt(n, 0);
    for (const auto& t : tris)
      for (int k = 0; k < 3; ++k) {
        sum[t[k]] += pts[t[(k + 1) % 3]];
        ++cnt[t[k]];
      }
    for (size_t i = 0; i < n; ++i) pts[i] = glm::normalize(glm::mix(pts[i], sum[i] / double(cnt[i]), 0.5));
  }
  tris = sphereHull(pts);
  Generated g;
  g.name = name;
  g.mesh.positions = pts;
  g.mesh.triangles = tris;
  g.mesh.faceGroup.assign(tris.size(), g.mesh.groupIndex("sphere"));
  return g;
}

Generated makePatch(int cells) {
  Generated g;
  g.name = "patch";
  g.closed = false;
  const int n = cells;
  auto id = [&](int i, int j) { return static_cast<uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = -1.0 + 2.0 * i / n, z = -1.0 + 2.0 * j / n;
      // Gentle saddle-free dome: 0.12 rise at the centre, slightly more curved along x.
      const double y = 0.12 * (1.0 - 0.6 * x * x - 0.4 * z * z);
      g.mesh.positions.push_back({x, y, z});
    }
  const uint32_t grp = g.mesh.groupIndex("patch");
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      // Alternate the diagonal so the triangulation has no preferred direction. Faces wind so the
      // normal points +Y (edge +z then +x).
      if ((i + j) % 2 == 0) {
        g.mesh.triangles.push_back({a, c, b});
        g.mesh.triangles.push_back({a, d, c});
      } else {
        g.mesh.triangles.push_back({a, d, b});
        g.mesh.triangles.push_back({b, d, c});
      }
      g.mesh.faceGroup.push_back(grp);
      g.mesh.faceGroup.push_back(grp);
    }
  return g;
}

}  // namespace pteryla::meshgen
