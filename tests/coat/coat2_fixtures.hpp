#pragma once
// Shared fixtures for the coat II tests (parameterization, key feathers, directions, ordering).
#include <glm/geometric.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/key_feathers.hpp"
#include "pteryla/coat/primitives.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"

namespace coat2test {

using namespace pteryla;
using namespace pteryla::coat;

inline Follicles scatterTracts(const SkinMesh& mesh, const std::vector<Tract>& tracts, size_t perTract,
                               uint64_t seed = 7) {
  Follicles all;
  for (uint32_t t = 0; t < tracts.size(); ++t) {
    ScatterOptions o;
    o.seed = seed + t;
    o.count = perTract;
    o.tractIndex = t;
    o.density.uniform = 1.0;
    all.append(scatterFollicles(mesh, tracts[t], o));
  }
  return all;
}

// Tract of the faces whose centroid satisfies pred.
template <class Pred>
Tract tractWhere(const SkinMesh& m, const std::string& name, Pred pred) {
  Tract t;
  t.name = name;
  for (uint32_t f = 0; f < m.faceCount(); ++f) {
    const auto& v = m.faces[f];
    const glm::dvec3 c = (m.positions[v[0]] + m.positions[v[1]] + m.positions[v[2]]) / 3.0;
    if (pred(c)) t.faces.push_back(f);
  }
  return t;
}

inline feather::FeatherParams testFeather(const std::string& name, double rachisLength, double barbLength,
                                          double curvature = 0.0) {
  feather::FeatherParams p;
  p.name = name;
  p.rachisLength = rachisLength;
  p.barbLength = barbLength;
  p.rachisLateralCurvature = curvature;
  return p;
}

inline FeatherLibrary testLibrary() {
  FeatherLibrary lib;
  lib["short"] = testFeather("short", 0.5, 0.1);
  lib["long"] = testFeather("long", 2.0, 0.4, 0.3);
  lib["mid"] = testFeather("mid", 1.0, 0.25, -0.2);
  lib["wide"] = testFeather("wide", 1.2, 0.6);
  return lib;
}

}  // namespace coat2test
