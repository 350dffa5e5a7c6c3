// Layer order for packing. Streit 2003, 6.3 (feathers are packed bottom to top in an order derived from the
// tract's parameterization) and 9.2.1 (a global order across tracts, by tract order or by projection onto a
// body axis).
#include "pteryla/coat/ordering.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "pteryla/core/error.hpp"
#include "spatial.hpp"

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

std::vector<double> flowPotential(const std::vector<glm::dvec3>& x, const std::vector<glm::dvec3>& dir,
                                  int neighbours) {
  const size_t n = x.size();
  PTERYLA_CHECK_EQ(dir.size(), n, "flowPotential: one direction per point");
  std::vector<double> phi(n, 0.0);
  if (n < 2) return phi;
  const size_t k = static_cast<size_t>(std::clamp(neighbours, 1, 64));
  // Typical spacing from a deterministic sample of nearest-neighbour distances.
  std::vector<double> nn;
  const size_t stride = std::max<size_t>(1, n / 256);
  for (size_t i = 0; i < n; i += stride) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < n; ++j)
      if (j != i) best = std::min(best, glm::length(x[j] - x[i]));
    if (best > 0 && std::isfinite(best)) nn.push_back(best);
  }
  detail::Box box;
  for (const auto& p : x) box.add(p);
  const double diag = std::max(1e-12, glm::length(box.hi - box.lo));
  double h = diag / std::sqrt(static_cast<double>(n));
  if (!nn.empty()) {
    std::nth_element(nn.begin(), nn.begin() + nn.size() / 2, nn.end());
    h = std::max(nn[nn.size() / 2], 1e-9 * diag);
  }
  detail::PointGrid grid;
  grid.build(x, 2 * h);
  // Edges i < j from each point's k nearest neighbours (ties by index), deduplicated.
  std::vector<uint64_t> edges;
  std::vector<std::pair<double, uint32_t>> found;
  for (size_t i = 0; i < n; ++i) {
    double r = 2 * h;
    for (;;) {
      found.clear();
      grid.query(x[i] - glm::dvec3(r), x[i] + glm::dvec3(r), [&](uint32_t j) {
        if (j == i) return;
        const double d = glm::length(x[j] - x[i]);
        if (d <= r) found.push_back({d, j});
      });
      if (found.size() >= k || r > diag) break;
      r *= 2;
    }
    const size_t m = std::min(k, found.size());
    std::partial_sort(found.begin(), found.begin() + m, found.end());
    for (size_t q = 0; q < m; ++q) {
      const uint64_t a = std::min<uint64_t>(i, found[q].second), b = std::max<uint64_t>(i, found[q].second);
      edges.push_back(a << 32 | b);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  // Normal equations of sum_e w_e (phi_j - phi_i - g_e)^2 + lambda sum phi^2, w_e = 1 / |x_j - x_i|^2
  // (residuals in units of gradient), g_e = (x_j - x_i) . mean direction. Edges across opposed directions
  // (a parting) carry less weight.
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(4 * edges.size() + n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
  std::vector<double> diagSum(n, 0.0);
  for (uint64_t e : edges) {
    const auto i = static_cast<Eigen::Index>(e >> 32), j = static_cast<Eigen::Index>(e & 0xffffffffu);
    const glm::dvec3 d = x[j] - x[i];
    const double l2 = glm::dot(d, d);
    if (!(l2 > 0)) continue;
    const double agree = glm::dot(dir[i], dir[j]);
    const double w = std::max(0.05, agree) / l2;
    const double g = glm::dot(d, 0.5 * (dir[i] + dir[j]));
    trip.emplace_back(i, i, w);
    trip.emplace_back(j, j, w);
    trip.emplace_back(i, j, -w);
    trip.emplace_back(j, i, -w);
    b[i] -= w * g;
    b[j] += w * g;
    diagSum[i] += w;
    diagSum[j] += w;
  }
  double mean = 0;
  for (double v : diagSum) mean += v;
  mean /= static_cast<double>(n);
  const double lambda = 1e-9 * std::max(mean, 1e-300);
  for (size_t i = 0; i < n; ++i) trip.emplace_back(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i), lambda);
  Eigen::SparseMatrix<double> A(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg;
  cg.setTolerance(1e-10);
  cg.setMaxIterations(static_cast<Eigen::Index>(std::max<size_t>(2000, 4 * n)));
  cg.compute(A);
  const Eigen::VectorXd sol = cg.solve(b);
  double avg = 0;
  for (size_t i = 0; i < n; ++i) avg += sol[static_cast<Eigen::Index>(i)];
  avg /= static_cast<double>(n);
  for (size_t i = 0; i < n; ++i) phi[i] = sol[static_cast<Eigen::Index>(i)] - avg;
  return phi;
}

OrderResult orderLayers(const SkinMesh& rest, const std::vector<Tract>& tracts,
                        const std::vector<TractParameterization>& params, const Follicles& follicles,
                        const SurfaceDirections& directions, const OrderOptions& options, CoatFeathers& coat) {
  const size_t n = coat.size();
  OrderResult res;
  res.key.assign(n, 0.0);
  // Tract ranks: the listed tracts first (bottom), in the listed order. Tracts: each unlisted tract follows
  // in index order. Axis and Flow: the unlisted tracts share one rank, ordered by the global key.
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
    if (r == UINT32_MAX) r = options.method == OrderMethod::Tracts ? rank++ : rank;
  // Axis and Flow without a tract list need no tracts at all: one group.
  std::vector<uint32_t> group(n, 0);
  if (options.method == OrderMethod::Tracts || !options.tractOrder.empty())
    for (size_t i = 0; i < n; ++i) {
      PTERYLA_CHECK(coat.tract[i] < tracts.size(), "feather of an unknown tract");
      group[i] = res.tractRank[coat.tract[i]];
    }
  if (options.method == OrderMethod::Axis) {
    if (options.axis.size() < 2)
      throw Error("ordering by axis needs an \"axis\" polyline (head to tail)", {}, "ordering.axis");
    for (size_t i = 0; i < n; ++i) res.key[i] = axisArcLength(options.axis, follicles.position[coat.follicle[i]]);
  } else if (options.method == OrderMethod::Flow) {
    PTERYLA_CHECK_EQ(coat.frames.size(), n, "orderLayers: flow ordering needs the feather frames");
    std::vector<glm::dvec3> x(n), d(n);
    for (size_t i = 0; i < n; ++i) {
      x[i] = coat.frames[i].origin;
      d[i] = coat.frames[i].tangent;
    }
    res.key = flowPotential(x, d, options.neighbours);
  } else {
    PTERYLA_CHECK_EQ(params.size(), tracts.size(), "orderLayers: one parameterization per tract");
    PTERYLA_CHECK_EQ(directions.faceCoords.size(), follicles.size(), "orderLayers: directions of other follicles");

    // Per feather: (u,v) position and direction; per tract: the mean direction.
    std::vector<glm::dvec2> uv(n), duv(n);
    res.tractFlow.assign(tracts.size(), glm::dvec2(0.0));
    for (size_t i = 0; i < n; ++i) {
      const uint32_t f = coat.follicle[i], t = coat.tract[i];
      PTERYLA_CHECK(t < params.size(), "feather of an unknown tract");
      const TractParameterization& p = params[t];
      const auto it = std::lower_bound(p.follicles.begin(), p.follicles.end(), f);
      PTERYLA_CHECK(it != p.follicles.end() && *it == f,
                    "feather's follicle missing from its tract's parameterization");
      uv[i] = p.follicleUv[static_cast<size_t>(it - p.follicles.begin())];
      glm::dvec2 d(0.0);  // a hand-made parameterization without corner (u,v) contributes no direction
      if (!p.faces.empty()) {
        const auto& c = p.faceUv(follicles.face[f]);
        d = directions.faceCoords[f].x * (c[1] - c[0]) + directions.faceCoords[f].y * (c[2] - c[0]);
      }
      const double len = glm::length(d);
      duv[i] = len > 0 ? d / len : glm::dvec2(0.0);
      res.tractFlow[t] += duv[i];
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
  const std::string method = r.oneOf("method", "tracts", {"tracts", "axis", "flow"});
  o.method = method == "axis" ? OrderMethod::Axis : (method == "flow" ? OrderMethod::Flow : OrderMethod::Tracts);
  if (r.has("neighbours")) {
    const double k = r.number("neighbours");
    if (!(k >= 1 && k <= 64 && k == std::floor(k))) r.fail("neighbours", "expected an integer in [1, 64]");
    o.neighbours = static_cast<int>(k);
  }
  if (r.has("tracts")) {
    const Json& a = r.raw("tracts");
    if (!a.is_array()) r.fail("tracts", "expected an array of tract names, bottom layer first");
    for (size_t i = 0; i < a.size(); ++i) {
      if (!a[i].is_string())
        throw Error("expected a tract name", r.file(), r.pathOf("tracts") + "[" + std::to_string(i) + "]");
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
  if (o.method == OrderMethod::Axis && o.axis.empty())
    r.fail("axis", "\"method\": \"axis\" needs an \"axis\" polyline");
  r.finish();
  return o;
}

}  // namespace pteryla::coat
