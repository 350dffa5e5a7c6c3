// Regularity metrics for follicle distributions (Streit 2003, 6.1 "rough regular hexagonal pattern";
// measures as in /work/shared/reference/lloyd.md section 7). Local Voronoi cells are clipped in each
// follicle's tangent plane from neighbour bisectors, with the security-radius test of Levy and Bonneel,
// "Variational anisotropic surface meshing with Voronoi parallel linear enumeration" (IMR 2012) to know
// when enough neighbours have been seen.
#include "pteryla/coat/metrics.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"
#include "spatial_hash.hpp"

namespace pteryla::coat {
namespace {

constexpr double kSqrt3 = 1.7320508075688772;
constexpr size_t kMaxDegree = 32;

struct LocalCell {
  std::array<uint32_t, kMaxDegree> nb{};
  uint32_t degree = 0;
  bool complete = false;
  double nn = 0;  // nearest-neighbour distance (3-D)
  double psi6 = 0;
};

struct V2 {
  double x, y;
};

void tangentBasis(const glm::dvec3& n, glm::dvec3& t1, glm::dvec3& t2) {
  const glm::dvec3 a = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  t1 = glm::normalize(glm::cross(n, a));
  t2 = glm::cross(n, t1);
}

class CellBuilder {
 public:
  CellBuilder(const Follicles& f, double spacing) : f_(f), spacing_(spacing) {
    glm::dvec3 lo(std::numeric_limits<double>::max());
    glm::dvec3 hi(-std::numeric_limits<double>::max());
    for (const auto& p : f.position) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 0.0});
    // Cells of a few times the follicles' own spacing (points on a surface spanning `extent`: a dozen
    // neighbours within one shell), even when the spacing asked for is far smaller (a small tract's
    // spacing measured over every follicle): the neighbour search is exact whatever the cell size, but
    // tiny cells make it walk thousands of empty shells per follicle. (On the bird's 19 tracts, 0.5, 1
    // and 2 x extent / sqrt(n) took 1.9, 1.8 and 1.4 s on a busy machine.)
    const double own = f.size() > 0 ? 2.0 * extent / std::sqrt(static_cast<double>(f.size())) : 0.0;
    const double h = std::max({spacing, extent / 1.0e6, own});
    grid_ = detail::CellGrid(lo - glm::dvec3(2 * h), h > 0 ? h : 1.0);
    grid_.build(f.position.data(), f.size());
  }

  LocalCell build(size_t i) const {
    LocalCell out;
    const glm::dvec3 p = f_.position[i];
    glm::dvec3 n = f_.normal[i];
    if (!(glm::length(n) > 0)) n = glm::dvec3(0, 0, 1);
    n = glm::normalize(n);
    glm::dvec3 t1, t2;
    tangentBasis(n, t1, t2);
    std::vector<std::pair<double, uint32_t>> knn;
    std::vector<V2> poly, next;
    std::vector<int64_t> lab, nextLab;
    for (size_t k = 12;; k *= 2) {
      double next2 = 0;
      grid_.kNearest(f_.position.data(), p, static_cast<uint32_t>(i), k, knn, &next2);
      if (knn.empty()) return out;
      out.nn = std::sqrt(knn.front().first);
      const double R0 = 10.0 * std::max(std::sqrt(knn.back().first), spacing_);
      poly = {{-R0, -R0}, {R0, -R0}, {R0, R0}, {-R0, R0}};
      lab = {-1, -1, -1, -1};
      for (const auto& [d2, q] : knn) {
        // A follicle facing away lies on another sheet of the surface (other side of a thin wing).
        if (glm::dot(f_.normal[q], n) < 0) continue;
        const glm::dvec3 d = f_.position[q] - p;
        const V2 v{glm::dot(d, t1), glm::dot(d, t2)};
        const double c = 0.5 * (v.x * v.x + v.y * v.y);
        if (!(c > 0)) continue;  // coincident in the tangent plane
        next.clear();
        nextLab.clear();
        const size_t m = poly.size();
        for (size_t j = 0; j < m; ++j) {
          const V2 a = poly[j], b = poly[(j + 1) % m];
          const double fa = v.x * a.x + v.y * a.y - c, fb = v.x * b.x + v.y * b.y - c;
          if (fa <= 0) {
            next.push_back(a);
            nextLab.push_back(lab[j]);
          }
          if ((fa <= 0) != (fb <= 0)) {
            const double t = fa / (fa - fb);
            next.push_back({a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t});
            nextLab.push_back(fa <= 0 ? static_cast<int64_t>(q) : lab[j]);
          }
        }
        poly.swap(next);
        lab.swap(nextLab);
        if (poly.empty()) break;
      }
      double rmax2 = 0;
      for (const V2& v : poly) rmax2 = std::max(rmax2, v.x * v.x + v.y * v.y);
      const bool secure = 4.0 * rmax2 < next2;
      bool open = false;
      for (int64_t l : lab) open |= l < 0;
      if (secure || knn.size() < k || k >= 96) {
        out.complete = !open && !poly.empty();
        break;
      }
    }
    // Distinct neighbours owning an edge of non-negligible length.
    const double eps = 1e-9 * spacing_;
    std::complex<double> psi(0, 0);
    const size_t m = poly.size();
    for (size_t j = 0; j < m; ++j) {
      if (lab[j] < 0) continue;
      const V2 a = poly[j], b = poly[(j + 1) % m];
      if (std::hypot(b.x - a.x, b.y - a.y) <= eps) continue;
      const uint32_t q = static_cast<uint32_t>(lab[j]);
      bool seen = false;
      for (uint32_t k = 0; k < out.degree; ++k) seen |= out.nb[k] == q;
      if (seen || out.degree >= kMaxDegree) continue;
      out.nb[out.degree++] = q;
      const glm::dvec3 d = f_.position[q] - p;
      psi += std::polar(1.0, 6.0 * std::atan2(glm::dot(d, t2), glm::dot(d, t1)));
    }
    if (out.degree > 0) out.psi6 = std::abs(psi) / out.degree;
    return out;
  }

 private:
  const Follicles& f_;
  double spacing_;
  detail::CellGrid grid_;
};

double hexSpacing(double area, size_t n) { return n ? std::sqrt(2.0 * area / (kSqrt3 * static_cast<double>(n))) : 0.0; }

std::vector<uint8_t> interiorMask(const SkinMesh& mesh, const Tract& tract, const Follicles& f, double band) {
  std::vector<uint8_t> in(f.size(), 1);
  const auto segs = tractBoundarySegments(mesh, tract);
  if (segs.empty() || band <= 0) return in;
  const detail::SegmentDistance dist(segs, band);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, f.size(), 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) in[i] = dist(f.position[i]) >= band ? 1 : 0;
  });
  return in;
}

}  // namespace

FollicleNeighbours delaunayNeighbours(const Follicles& follicles, double spacing) {
  FollicleNeighbours out;
  const size_t n = follicles.size();
  out.offsets.assign(n + 1, 0);
  out.complete.assign(n, 0);
  if (n == 0) return out;
  const CellBuilder cb(follicles, spacing > 0 ? spacing : 1.0);
  std::vector<LocalCell> cells(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) cells[i] = cb.build(i);
  });
  for (size_t i = 0; i < n; ++i) {
    out.offsets[i + 1] = out.offsets[i] + cells[i].degree;
    out.complete[i] = cells[i].complete;
  }
  out.indices.resize(out.offsets[n]);
  for (size_t i = 0; i < n; ++i)
    std::copy_n(cells[i].nb.begin(), cells[i].degree, out.indices.begin() + out.offsets[i]);
  return out;
}

DistributionMetrics measureDistribution(const SkinMesh& mesh, const Tract& tract, const Follicles& f,
                                        const MetricsOptions& opt) {
  DistributionMetrics m;
  m.follicles = f.size();
  if (f.size() < 2) return m;
  m.spacing = hexSpacing(tractArea(mesh, tract), f.size());
  const auto interior = interiorMask(mesh, tract, f, opt.interiorBand * m.spacing);
  const CellBuilder cb(f, m.spacing);
  std::vector<LocalCell> cells(f.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, f.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i)
      if (interior[i]) cells[i] = cb.build(i);
  });
  double sum = 0, mn = std::numeric_limits<double>::infinity(), deg = 0, psi = 0;
  size_t six = 0, cnt = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    if (!interior[i] || !cells[i].complete) continue;
    ++cnt;
    six += cells[i].degree == 6;
    sum += cells[i].nn;
    mn = std::min(mn, cells[i].nn);
    deg += cells[i].degree;
    psi += cells[i].psi6;
  }
  m.interior = cnt;
  if (cnt == 0) return m;
  const double mean = sum / cnt;
  double var = 0;
  for (size_t i = 0; i < f.size(); ++i)
    if (interior[i] && cells[i].complete) var += (cells[i].nn - mean) * (cells[i].nn - mean);
  var /= cnt;
  m.hexFraction = static_cast<double>(six) / cnt;
  m.nnCv = mean > 0 ? std::sqrt(var) / mean : 0;
  m.nnMean = mean / m.spacing;
  m.nnMin = mn / m.spacing;
  m.meanDegree = deg / cnt;
  m.psi6 = psi / cnt;
  return m;
}

double hexFraction(const SkinMesh& mesh, const Tract& tract, const Follicles& follicles,
                   const MetricsOptions& options) {
  return measureDistribution(mesh, tract, follicles, options).hexFraction;
}

double nnCv(const SkinMesh& mesh, const Tract& tract, const Follicles& follicles, const MetricsOptions& options) {
  return measureDistribution(mesh, tract, follicles, options).nnCv;
}

DirectionalSpacing directionalSpacing(const SkinMesh& mesh, const Tract& tract, const Follicles& f,
                                      const glm::dvec3& direction, const MetricsOptions& opt) {
  DirectionalSpacing out;
  if (f.size() < 2) return out;
  const double spacing = hexSpacing(tractArea(mesh, tract), f.size());
  const auto interior = interiorMask(mesh, tract, f, opt.interiorBand * spacing);
  const auto nb = delaunayNeighbours(f, spacing);
  const double cos30 = std::cos(3.14159265358979323846 / 6.0);
  double along = 0, across = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    if (!interior[i] || !nb.complete[i]) continue;
    const glm::dvec3 n = glm::normalize(f.normal[i]);
    glm::dvec3 d = direction - glm::dot(direction, n) * n;
    if (!(glm::length(d) > 1e-12)) continue;
    d = glm::normalize(d);
    for (uint32_t k = nb.offsets[i]; k < nb.offsets[i + 1]; ++k) {
      const glm::dvec3 e = f.position[nb.indices[k]] - f.position[i];
      glm::dvec3 et = e - glm::dot(e, n) * n;
      const double len = glm::length(et);
      if (!(len > 0)) continue;
      const double c = std::abs(glm::dot(et / len, d));
      if (c >= cos30) {
        along += glm::length(e);
        ++out.alongEdges;
      } else if (c <= 0.5 + 1e-9) {
        across += glm::length(e);
        ++out.acrossEdges;
      }
    }
  }
  if (out.alongEdges) out.along = along / out.alongEdges;
  if (out.acrossEdges) out.across = across / out.acrossEdges;
  return out;
}

}  // namespace pteryla::coat
