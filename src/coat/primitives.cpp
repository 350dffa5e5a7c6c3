// Generated skin meshes (icosphere, grid patch, torus, open cylinder) for tests and benchmarks.
#include "pteryla/coat/primitives.hpp"

#include <cmath>
#include <functional>
#include <map>
#include <utility>

#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"

namespace pteryla::coat {

SkinMesh makeIcosphere(int subdivisions, double radius, const glm::dvec3& center) {
  if (subdivisions < 0 || subdivisions > 9) throw Error("icosphere subdivisions must be in [0, 9]");
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<glm::dvec3> p = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                               {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& v : p) v = glm::normalize(v);
  std::vector<std::array<uint32_t, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back(glm::normalize(p[a] + p[b]));
      const uint32_t id = static_cast<uint32_t>(p.size() - 1);
      mid.emplace(key, id);
      return id;
    };
    std::vector<std::array<uint32_t, 3>> g;
    g.reserve(f.size() * 4);
    for (const auto& tri : f) {
      const uint32_t a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f = std::move(g);
  }
  for (auto& v : p) v = center + radius * v;
  return makeSkinMesh(std::move(p), std::move(f));
}

SkinMesh makeGridPatch(int nx, int ny, double sizeX, double sizeY) {
  if (nx < 1 || ny < 1) throw Error("grid patch needs at least 1 x 1 cells");
  std::vector<glm::dvec3> p;
  std::vector<std::array<uint32_t, 3>> f;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) p.emplace_back(sizeX * i / nx, sizeY * j / ny, 0.0);
  auto id = [&](int i, int j) { return static_cast<uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        f.push_back({a, b, c});
        f.push_back({a, c, d});
      } else {
        f.push_back({a, b, d});
        f.push_back({b, c, d});
      }
    }
  return makeSkinMesh(std::move(p), std::move(f));
}

namespace {
SkinMesh sweep(int nu, int nv, bool closedV, const std::function<glm::dvec3(double, double)>& at) {
  std::vector<glm::dvec3> p;
  std::vector<std::array<uint32_t, 3>> f;
  const int rows = closedV ? nv : nv + 1;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < nu; ++i) p.push_back(at(double(i) / nu, double(j) / nv));
  auto id = [&](int i, int j) { return static_cast<uint32_t>((j % rows) * nu + (i % nu)); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const uint32_t a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      f.push_back({a, b, c});
      f.push_back({a, c, d});
    }
  return makeSkinMesh(std::move(p), std::move(f));
}
}  // namespace

SkinMesh makeTorus(int nu, int nv, double R, double r) {
  if (nu < 3 || nv < 3) throw Error("torus needs at least 3 x 3 cells");
  const double tau = 6.283185307179586;
  // u around the z axis, v around the tube; (u, v) order gives outward normals.
  return sweep(nu, nv, true, [&](double u, double v) {
    const double cu = std::cos(tau * u), su = std::sin(tau * u), cv = std::cos(tau * v), sv = std::sin(tau * v);
    return glm::dvec3((R + r * cv) * cu, (R + r * cv) * su, r * sv);
  });
}

SkinMesh makeCylinder(int nu, int nv, double radius, double height) {
  if (nu < 3 || nv < 1) throw Error("cylinder needs at least 3 x 1 cells");
  const double tau = 6.283185307179586;
  return sweep(nu, nv, false, [&](double u, double v) {
    return glm::dvec3(radius * std::cos(tau * u), radius * std::sin(tau * u), height * v);
  });
}

}  // namespace pteryla::coat
