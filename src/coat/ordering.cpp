// Layer order for packing. Streit 2003, 6.3 (feathers are packed bottom to top in an order derived from the
// tract's parameterization) and 9.2.1 (a global order across tracts, by tract order or by projection onto a
// body axis).
#include "pteryla/coat/ordering.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "pteryla/core/error.hpp"

namespace pteryla::coat {

double axisArcLength(const std::vector<glm::dvec3>& axis, const glm::dvec3& p) {
  double best = std::numeric_limits<double>::infinity(), s = 0, along = 0;
  for (size_t i = 0; i + 1 < axis.size(); ++i) {
    const glm::dvec3 a = axis[i], d = axis[i + 1] - a;
    const double len2 = glm::dot(d, d), len = std::sqrt(len2);
    if (len2 > 0) {
      const double t = std::clamp(glm::dot(p - a, d) / len2, 0.0, 1.0);
      const glm::dvec3 q = a + t * d - p;
      const double d2 = glm::dot(q, q);
      if (d2 < best) best = d2, s = along + t * len;
    }
    along += len;
  }
  return s;
}

OrderResult orderLayers(const SkinMesh& rest, const std::vector<Tract>& tracts,
                        const std::vector<TractParameterization>& params, const Follicles& follicles,
                        const SurfaceDirections& directions, const OrderOptions& options, CoatFeathers& coat) {
  const size_t n = coat.size();
  OrderResult res;
  res.key.assign(n, 0.0);
  std::vector<uint32_t> group(n, 0);
  if (options.method == OrderMethod::Axis) {
    if (options.axis.size() < 2) throw Error("ordering by axis needs an \"axis\" polyline (head to tail)", {}, "ordering.axis");
    for (size_t i = 0; i < n; ++i) res.key[i] = axisArcLength(options.axis, follicles.position[coat.follicle[i]]);
  } else {
    PTERYLA_CHECK(params.size() == tracts.size(), "orderLayers: one parameterization per tract");
    PTERYLA_CHECK(directions.faceCoords.size() == follicles.size(), "orderLayers: directions of other follicles");
    res.tractRank.assign(tracts.size(), UINT32_MAX);
    uint32_t rank = 0;
    for (size_t k = 0; k < options.tractOrder.size(); ++k) {
      const std::string& name = options.tractOrder[k];
      bool found = false;
      for (size_t t = 0; t < tracts.size(); ++t)
        if (tracts[t].name == name) {
          found = true;
          if (res.tractRank[t] != UINT32_MAX)
            throw Error("tract '" + name + "' is listed twice", {}, "ordering.tracts[" + std::to_string(k) + "]");
          res.tractRank[t] = rank++;
        }
      if (!found) throw Error("no tract named '" + name + "'", {}, "ordering.tracts[" + std::to_string(k) + "]");
    }
    for (auto& r : res.tractRank)
      if (r == UINT32_MAX) r = rank++;

    // Per feather: (u,v) position and direction; per tract: the mean direction.
    std::vector<glm::dvec2> uv(n), duv(n);
    res.tractFlow.assign(tracts.size(), glm::dvec2(0.0));
    for (size_t i = 0; i < n; ++i) {
      const uint32_t f = coat.follicle[i], t = coat.tract[i];
      PTERYLA_CHECK(t < params.size(), "feather of an unknown tract");
      const TractParameterization& p = params[t];
      const auto it = std::lower_bound(p.follicles.begin(), p.follicles.end(), f);
      PTERYLA_CHECK(it != p.follicles.end() && *it == f, "feather's follicle missing from its tract's parameterization");
      uv[i] = p.follicleUv[static_cast<size_t>(it - p.follicles.begin())];
      glm::dvec2 d(0.0);  // a hand-made parameterization without corner (u,v) contributes no direction
      if (!p.faces.empty()) {
        const auto& c = p.faceUv(follicles.face[f]);
        d = directions.faceCoords[f].x * (c[1] - c[0]) + directions.faceCoords[f].y * (c[2] - c[0]);
      }
      const double len = glm::length(d);
      duv[i] = len > 0 ? d / len : glm::dvec2(0.0);
      res.tractFlow[t] += duv[i];
      group[i] = res.tractRank[t];
    }
    for (auto& fl : res.tractFlow) {
      const double len = glm::length(fl);
      fl = len > 1e-12 ? fl / len : glm::dvec2(1.0, 0.0);
    }
    for (size_t i = 0; i < n; ++i) res.key[i] = glm::dot(uv[i], res.tractFlow[coat.tract[i]]);
  }
  coat.layerOrder.resize(n);
  std::iota(coat.layerOrder.begin(), coat.layerOrder.end(), 0u);
  std::sort(coat.layerOrder.begin(), coat.layerOrder.end(), [&](uint32_t a, uint32_t b) {
    if (group[a] != group[b]) return group[a] < group[b];
    if (res.key[a] != res.key[b]) return res.key[a] > res.key[b];
    const uint64_t ia = follicles.id[coat.follicle[a]], ib = follicles.id[coat.follicle[b]];
    if (ia != ib) return ia < ib;
    return a < b;
  });
  return res;
}

OrderOptions parseOrdering(JsonReader& r) {
  OrderOptions o;
  o.method = r.oneOf("method", "tracts", {"tracts", "axis"}) == "axis" ? OrderMethod::Axis : OrderMethod::Tracts;
  if (r.has("tracts")) {
    const Json& a = r.raw("tracts");
    if (!a.is_array()) r.fail("tracts", "expected an array of tract names, bottom layer first");
    for (size_t i = 0; i < a.size(); ++i) {
      if (!a[i].is_string()) throw Error("expected a tract name", r.file(), r.pathOf("tracts") + "[" + std::to_string(i) + "]");
      o.tractOrder.push_back(a[i].get<std::string>());
    }
  }
  if (r.has("axis")) {
    const Json& a = r.raw("axis");
    const std::string base = r.pathOf("axis");
    if (!a.is_array()) r.fail("axis", "expected an array of [x,y,z] points, head to tail");
    for (size_t i = 0; i < a.size(); ++i) {
      const std::string p = base + "[" + std::to_string(i) + "]";
      if (!a[i].is_array() || a[i].size() != 3) throw Error("expected [x,y,z]", r.file(), p);
      o.axis.emplace_back(jsonNumber(a[i][0], r.file(), p + "[0]"), jsonNumber(a[i][1], r.file(), p + "[1]"),
                          jsonNumber(a[i][2], r.file(), p + "[2]"));
      if (i > 0 && o.axis[i] == o.axis[i - 1]) throw Error("consecutive axis points coincide", r.file(), p);
    }
    if (o.axis.size() < 2) r.fail("axis", "needs at least two points (head to tail)");
  }
  if (o.method == OrderMethod::Axis && o.axis.empty()) r.fail("axis", "\"method\": \"axis\" needs an \"axis\" polyline");
  r.finish();
  return o;
}

}  // namespace pteryla::coat
