// Follicle relaxation: Lloyd's algorithm restricted to a tract (Streit 2003, 6.1.1 and 6.1.3), with bias
// vectors (6.1.4) and pinned follicles (6.1.5).
//
// Each follicle's cell is its restricted Voronoi cell V_i ∩ tract, computed exactly: starting from the
// follicle's face, tract triangles are clipped by the bisector planes of its nearest follicles and the
// clipped polygons integrated (area, first and second moments); neighbours are added until the cell is
// provably complete (security radius, as in Yan, Levy, Liu, Sun, Wang, "Isotropic remeshing with fast and
// exact computation of restricted Voronoi diagram", SGP 2009 / geogram's RVD). The centroid is projected
// back onto the tract by a closest-point walk over its faces. Weighted centroids follow Secord, "Weighted
// Voronoi stippling" (NPAR 2002); the density weight is rho^2 so follicle density ends up proportional to
// rho (CVT point density ~ rho^(d/(d+2)), Du, Faber, Gunzburger, SIAM Review 1999); weighted moments use
// Dunavant's degree-4 triangle rule. Bias vectors use the anisotropic metric I + k d d^T (the lloyd.md
// section 8 alternative), constant per skin triangle so bisectors stay planar. Over-relaxed steps
// x + w (c - x), 1 <= w < 2, keep each cell's energy decreasing since E(x) = E(c) + (x-c)^T H (x-c).
#include "pteryla/coat/relax.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include "pteryla/core/error.hpp"
#include "spatial_hash.hpp"

namespace pteryla::coat {
namespace {

using detail::CellGrid;
constexpr double kSqrt3 = 1.7320508075688772;

enum SiteKind : uint8_t { kFree = 0, kFixedBoundary = 1, kPinned = 2 };

// Per tract face: bary limits that keep free follicles off the tract's edges and corners.
struct FaceLimits {
  std::array<double, 3> lo{0, 0, 0}, hi{1, 1, 1};
  bool any = false;
};

// Polygon with, per vertex j, the label of edge j -> j+1: the triangle edge (0..2) it lies on, or -1 for
// a piece of a bisector.
struct Poly {
  std::vector<glm::dvec3> v;  // storage; the polygon is v[0 .. n)
  std::vector<int8_t> label;
  size_t n = 0;
  void fit(size_t m) {
    if (v.size() < m) {
      v.resize(m);
      label.resize(m);
    }
  }
  void setTriangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    fit(3);
    v[0] = a, v[1] = b, v[2] = c;
    label[0] = 0, label[1] = 1, label[2] = 2;
    n = 3;
  }
};

struct ThreadScratch {
  std::vector<uint32_t> stamp;
  uint32_t epoch = 0;
  std::vector<uint32_t> queue, shell;
  std::vector<std::pair<double, uint32_t>> knn;
  Poly polyA, polyB;
  std::vector<glm::dvec3> q, candPos;
  std::vector<double> qq;
  std::vector<uint32_t> cand;
  std::vector<double> f;

  void resetStamps(size_t n) {
    if (stamp.size() != n) {
      stamp.assign(n, 0);
      epoch = 0;
    }
    if (++epoch == 0) {
      std::fill(stamp.begin(), stamp.end(), 0);
      epoch = 1;
    }
  }
};

// Moments of one restricted Voronoi cell about its site (relative coordinates).
struct Cell {
  double area = 0;    // plain area
  double mass = 0;    // integral of the weight
  glm::dvec3 m1{0};   // integral of weight * y
  glm::dmat3 H{0.0};  // integral of weight * M (metric only)
  glm::dvec3 hm1{0};  // integral of weight * M y (metric only)
  double energy = 0;  // integral of weight * y^T M y
};

// Dunavant (1985) degree-4 rule on a triangle: barycentric points and weights (sum 1).
constexpr double kQa = 0.445948490915965, kQb = 0.108103018168070, kQc = 0.091576213509771, kQd = 0.816847572980459;
constexpr double kWa = 0.223381589678011, kWc = 0.109951743655322;
constexpr double kQuad[6][4] = {{kQb, kQa, kQa, kWa}, {kQa, kQb, kQa, kWa}, {kQa, kQa, kQb, kWa},
                                {kQd, kQc, kQc, kWc}, {kQc, kQd, kQc, kWc}, {kQc, kQc, kQd, kWc}};

class Relaxer {
 public:
  Relaxer(const SkinMesh& mesh, const Tract& tract, Follicles& fol, const RelaxOptions& opt)
      : mesh_(mesh), tract_(tract), fol_(fol), opt_(opt) {}

  RelaxResult run() {
    const auto t0 = std::chrono::steady_clock::now();
    validateOptions();
    selectSites();
    RelaxResult res;
    res.follicles = n_;
    if (n_ == 0) return res;
    area_ = tractArea(mesh_, tract_);
    spacing_ = std::sqrt(2.0 * area_ / (kSqrt3 * static_cast<double>(n_)));
    res.spacing = spacing_;
    selectBias();
    setupTract();
    classifyBoundary();
    for (uint8_t k : kind_) {
      res.moved += k == kFree;
      res.fixedBoundary += k == kFixedBoundary;
      res.pinned += k == kPinned;
    }

    std::vector<glm::dvec3> newPos(n_), newBary(n_);
    std::vector<uint32_t> newFace(n_);
    std::vector<double> cellEnergy(n_), move(n_);
    for (int it = 0; it < opt_.iterations; ++it) {
      step(&newPos, &newFace, &newBary, cellEnergy, move);
      res.energy.push_back(totalEnergy(cellEnergy));
      double mx = 0;
      for (double d : move) mx = std::max(mx, d);
      res.maxMove.push_back(mx);
      pos_.swap(newPos);
      face_.swap(newFace);
      bary_.swap(newBary);
      res.iterations = it + 1;
      if (opt_.tolerance > 0 && mx < opt_.tolerance * spacing_) {
        res.converged = true;
        break;
      }
      if (!report(opt_.progress, "relax", double(it + 1) / opt_.iterations)) {
        res.cancelled = true;
        break;
      }
    }
    step(nullptr, nullptr, nullptr, cellEnergy, move);
    res.energy.push_back(totalEnergy(cellEnergy));
    double covered = 0;
    for (double a : cellArea_) covered += a;
    res.coverage = area_ > 0 ? covered / area_ : 0.0;

    tbb::parallel_for(tbb::blocked_range<size_t>(0, n_, 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        if (kind_[i] != kFree) continue;
        const size_t f = sel_[i];
        fol_.face[f] = face_[i];
        fol_.bary[f] = bary_[i];
        fol_.position[f] = pos_[i];
        fol_.normal[f] = normalAt(mesh_, face_[i], bary_[i]);
      }
    });
    res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
  }

 private:
  [[noreturn]] void fail(const std::string& what, const std::string& element) const {
    throw Error(what, mesh_.file, element);
  }

  void validateOptions() {
    if (opt_.iterations < 0) fail("iterations must be >= 0", "relax.iterations");
    if (!(opt_.overRelaxation >= 1.0 && opt_.overRelaxation < 2.0))
      fail("overRelaxation must be in [1, 2)", "relax.overRelaxation");
    if (!(opt_.boundaryBand >= 0 && std::isfinite(opt_.boundaryBand)))
      fail("boundaryBand must be >= 0", "relax.boundaryBand");
    if (!(opt_.edgeMargin >= 0 && opt_.edgeMargin < 0.5)) fail("edgeMargin must be in [0, 0.5)", "relax.edgeMargin");
    if (!(opt_.tolerance >= 0 && std::isfinite(opt_.tolerance))) fail("tolerance must be >= 0", "relax.tolerance");
    if (!opt_.density.perVertex.empty() && opt_.density.perVertex.size() != mesh_.positions.size())
      fail("per-vertex density has " + std::to_string(opt_.density.perVertex.size()) + " values for " +
               std::to_string(mesh_.positions.size()) + " vertices",
           "relax.density");
    for (size_t v = 0; v < opt_.density.perVertex.size(); ++v)
      if (!(opt_.density.perVertex[v] >= 0) || !std::isfinite(opt_.density.perVertex[v]))
        fail("density must be finite and >= 0", "vertex " + std::to_string(v));
    for (size_t j = 0; j < opt_.bias.size(); ++j) {
      const BiasVector& b = opt_.bias[j];
      const std::string el = "bias[" + std::to_string(j) + "]";
      if (!(b.stretch >= 1.0 && std::isfinite(b.stretch))) fail("stretch must be >= 1", el);
      if (!(b.densityGain >= 0.0 && std::isfinite(b.densityGain))) fail("densityGain must be >= 0", el);
      if (!std::isfinite(b.sigma)) fail("sigma must be finite", el);
      if (!std::isfinite(b.origin.x) || !std::isfinite(b.origin.y) || !std::isfinite(b.origin.z))
        fail("origin must be finite", el);
      if (b.stretch > 1.0 && !(glm::length(b.direction) > 0)) fail("direction must be non-zero", el);
    }
  }

  // Keeps the bias vectors that change anything: stretch > 1 or gain > 0, and within 3 sigma of the
  // tract's bounding box (the Gaussian is cut off there). Without any, the plain Lloyd code runs.
  void selectBias() {
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (uint32_t f : tract_.faces)
      for (uint32_t v : mesh_.faces[f]) {
        lo = glm::min(lo, mesh_.positions[v]);
        hi = glm::max(hi, mesh_.positions[v]);
      }
    for (const BiasVector& b : opt_.bias) {
      if (!(b.stretch > 1.0 || b.densityGain > 0.0)) continue;
      if (b.sigma > 0) {
        const glm::dvec3 d = glm::max(glm::max(lo - b.origin, b.origin - hi), glm::dvec3(0));
        if (glm::dot(d, d) > 9.0 * b.sigma * b.sigma) continue;
      }
      if (b.stretch > 1.0) {
        metric_ = true;
        lambdaBound_ += b.stretch * b.stretch - 1.0;
      }
      if (b.densityGain > 0.0) gain_ = true;
      activeBias_.push_back(b);
    }
    weighted_ = !opt_.density.isUniform() || gain_;
  }

  void selectSites() {
    const size_t total = fol_.size();
    PTERYLA_CHECK(fol_.bary.size() == total && fol_.tract.size() == total && fol_.pinned.size() == total &&
                      fol_.position.size() == total && fol_.normal.size() == total && fol_.id.size() == total,
                  "Follicles arrays have different lengths");
    const auto mask = tractFaceMask(mesh_, tract_);
    for (size_t f = 0; f < total; ++f) {
      if (opt_.onlyTract >= 0 && static_cast<int64_t>(fol_.tract[f]) != opt_.onlyTract) continue;
      if (fol_.face[f] >= mesh_.faces.size())
        fail("face " + std::to_string(fol_.face[f]) + " is out of range", "follicle " + std::to_string(fol_.id[f]));
      const bool pinned = fol_.pinned[f] != 0;
      if (!pinned && !mask[fol_.face[f]])
        fail("follicle lies on face " + std::to_string(fol_.face[f]) + ", outside tract '" + tract_.name + "'",
             "follicle " + std::to_string(fol_.id[f]));
      sel_.push_back(f);
      kind_.push_back(pinned ? kPinned : kFree);
      face_.push_back(fol_.face[f]);
      bary_.push_back(fol_.bary[f]);
      pos_.push_back(pointAt(mesh_, fol_.face[f], fol_.bary[f]));
    }
    n_ = sel_.size();
  }

  double biasWeight(const BiasVector& b, const glm::dvec3& p) const {
    if (b.sigma <= 0) return 1.0;
    const glm::dvec3 d = p - b.origin;
    const double r2 = glm::dot(d, d);
    const double s2 = b.sigma * b.sigma;
    if (r2 > 9.0 * s2) return 0.0;  // 3 sigma cut-off
    return std::exp(-0.5 * r2 / s2);
  }

  void setupTract() {
    const size_t nf = tract_.faces.size();
    local_.assign(mesh_.faces.size(), -1);
    for (size_t k = 0; k < nf; ++k) local_[tract_.faces[k]] = static_cast<int32_t>(k);
    const auto bits = tractBoundaryEdgeBits(mesh_, tract_);
    std::vector<uint8_t> boundaryVertex(mesh_.positions.size(), 0);
    for (size_t k = 0; k < nf; ++k)
      for (int c = 0; c < 3; ++c)
        if (bits[k] & (1u << c)) {
          boundaryVertex[mesh_.faces[tract_.faces[k]][c]] = 1;
          boundaryVertex[mesh_.faces[tract_.faces[k]][(c + 1) % 3]] = 1;
        }
    const double margin = opt_.edgeMargin * spacing_;
    limits_.assign(nf, FaceLimits());
    if (metric_) metric_faces_.assign(nf, glm::dmat3(1.0));
    for (size_t k = 0; k < nf; ++k) {
      const uint32_t fi = tract_.faces[k];
      const auto& f = mesh_.faces[fi];
      FaceLimits& L = limits_[k];
      for (int c = 0; c < 3 && margin > 0; ++c) {
        // Height of corner c over the opposite edge (c+1, c+2).
        const glm::dvec3 a = mesh_.positions[f[(c + 1) % 3]], b = mesh_.positions[f[(c + 2) % 3]];
        const double edge = glm::length(b - a);
        const double h = edge > 0 ? 2.0 * mesh_.faceAreas[fi] / edge : 0.0;
        const double m = h > 0 ? std::min(margin / h, 0.3) : 0.3;
        if (bits[k] & (1u << ((c + 1) % 3))) {
          L.lo[c] = m;
          L.any = true;
        }  // edge opposite corner c
        if (boundaryVertex[f[c]]) {
          L.hi[c] = 1.0 - m;
          L.any = true;
        }
      }
      if (metric_) {
        // Metric of the face, evaluated at its centroid with directions in the face plane.
        const glm::dvec3 ctr = (mesh_.positions[f[0]] + mesh_.positions[f[1]] + mesh_.positions[f[2]]) / 3.0;
        const glm::dvec3 n = mesh_.faceNormals[fi];
        glm::dmat3 M(1.0);
        for (const auto& bv : activeBias_) {
          if (bv.stretch <= 1.0) continue;
          const double w = biasWeight(bv, ctr);
          if (w <= 0) continue;
          glm::dvec3 d = bv.direction - glm::dot(bv.direction, n) * n;
          const double len = glm::length(d);
          if (!(len > 1e-12 * glm::length(bv.direction))) continue;
          d /= len;
          M += (w * (bv.stretch * bv.stretch - 1.0)) * glm::outerProduct(d, d);
        }
        metric_faces_[k] = M;
      }
    }
    // Grid over the sites: cells of two spacings, so the 27 around a site usually hold its neighbours.
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (uint32_t f : tract_.faces)
      for (uint32_t v : mesh_.faces[f]) {
        lo = glm::min(lo, mesh_.positions[v]);
        hi = glm::max(hi, mesh_.positions[v]);
      }
    for (const auto& p : pos_) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
    double h = std::max(2.0 * spacing_, extent / 1.0e6);
    if (!(h > 0)) h = 1.0;
    grid_ = CellGrid(lo - glm::dvec3(2.0 * h), h);
    // Total weight of the tract, for a fixed energy normalisation.
    if (weighted_) {
      double W = 0;
      for (uint32_t fi : tract_.faces) {
        const auto& f = mesh_.faces[fi];
        const glm::dvec3 a = mesh_.positions[f[0]], b = mesh_.positions[f[1]], c = mesh_.positions[f[2]];
        for (const auto& q : kQuad) W += mesh_.faceAreas[fi] * q[3] * weightAt(fi, q[0] * a + q[1] * b + q[2] * c);
      }
      if (!(W > 0)) fail("relaxation density is zero over the whole tract", "tract '" + tract_.name + "'");
      weightNorm_ = area_ / W;
    }
  }

  // Sample weight rho^2 (1 + gain)^2 at a point of face fi.
  double weightAt(uint32_t fi, const glm::dvec3& y) const {
    double rho = 1.0;
    const auto& d = opt_.density;
    if (!d.perVertex.empty() || d.multiplier) {
      const auto& f = mesh_.faces[fi];
      const glm::dvec3 a = mesh_.positions[f[0]];
      const glm::dvec3 e1 = mesh_.positions[f[1]] - a, e2 = mesh_.positions[f[2]] - a, r = y - a;
      const double g11 = glm::dot(e1, e1), g12 = glm::dot(e1, e2), g22 = glm::dot(e2, e2);
      const double det = g11 * g22 - g12 * g12;
      double u = (g22 * glm::dot(r, e1) - g12 * glm::dot(r, e2)) / det;
      double v = (g11 * glm::dot(r, e2) - g12 * glm::dot(r, e1)) / det;
      u = std::clamp(u, 0.0, 1.0);
      v = std::clamp(v, 0.0, 1.0 - u);
      const glm::dvec3 b(1.0 - u - v, u, v);
      if (!d.perVertex.empty()) rho = b.x * d.perVertex[f[0]] + b.y * d.perVertex[f[1]] + b.z * d.perVertex[f[2]];
      if (d.multiplier) {
        const double m = d.multiplier(fi, b);
        if (!std::isfinite(m) || m < 0)
          throw Error("density multiplier returned " + std::to_string(m) + " (must be finite and >= 0)", mesh_.file,
                      "face " + std::to_string(fi));
        rho *= m;
      }
    }
    double g = 0;
    if (gain_)
      for (const auto& bv : activeBias_)
        if (bv.densityGain > 0) g += bv.densityGain * biasWeight(bv, y);
    const double w = rho * (1.0 + g);
    return w * w;
  }

  void classifyBoundary() {
    if (!opt_.fixBoundary || opt_.boundaryBand <= 0) return;
    const auto segs = tractBoundarySegments(mesh_, tract_);
    if (segs.empty()) return;
    const double band = opt_.boundaryBand * spacing_;
    const detail::SegmentDistance dist(segs, band);
    for (size_t i = 0; i < n_; ++i)
      if (kind_[i] == kFree && dist(pos_[i]) < band) kind_[i] = kFixedBoundary;
  }

  // Keeps the part of polygon `a` with n.y <= d (Sutherland-Hodgman), result in `a` (using `b` and `f` as
  // scratch); returns false when nothing is left.
  enum ClipResult { kEmpty, kUnchanged, kClipped };
  static ClipResult clip(Poly& a, Poly& b, std::vector<double>& f, const glm::dvec3& n, double d) {
    const size_t m = a.n;
    if (f.size() < m) f.resize(m);
    double* fv = f.data();
    const glm::dvec3* av = a.v.data();
    bool anyOut = false, anyIn = false;
    for (size_t j = 0; j < m; ++j) {
      fv[j] = glm::dot(n, av[j]) - d;
      if (fv[j] > 0)
        anyOut = true;
      else
        anyIn = true;
    }
    if (!anyOut) return kUnchanged;
    if (!anyIn) return kEmpty;
    b.fit(m + 1);  // a convex polygon gains at most one vertex per cut
    glm::dvec3* bv = b.v.data();
    int8_t* bl = b.label.data();
    const int8_t* al = a.label.data();
    size_t k = 0;
    size_t prev = m - 1;
    for (size_t j = 0; j < m; ++j) {
      const double fa = fv[prev], fb = fv[j];
      if ((fa <= 0) != (fb <= 0)) {
        bv[k] = av[prev] + (av[j] - av[prev]) * (fa / (fa - fb));
        bl[k++] = fa <= 0 ? int8_t(-1) : al[prev];  // leaving: along the bisector
      }
      if (fb <= 0) {
        bv[k] = av[j];
        bl[k++] = al[j];
      }
      prev = j;
    }
    b.n = k;
    std::swap(a, b);
    return a.n >= 3 ? kClipped : kEmpty;
  }

  static double maxNorm2(const Poly& a) {
    double r2 = 0;
    for (size_t j = 0; j < a.n; ++j) r2 = std::max(r2, glm::dot(a.v[j], a.v[j]));
    return r2;
  }

  void integrate(const Poly& poly, uint32_t fi, size_t lf, const glm::dvec3& site, Cell& cell) const {
    const glm::dvec3& a = poly.v[0];
    for (size_t j = 1; j + 1 < poly.n; ++j) {
      const glm::dvec3& b = poly.v[j];
      const glm::dvec3& c = poly.v[j + 1];
      const double A = 0.5 * glm::length(glm::cross(b - a, c - a));
      if (!(A > 0)) continue;
      cell.area += A;
      if (!weighted_) {
        const glm::dvec3 s = a + b + c;
        const glm::dvec3 m1 = (A / 3.0) * s;
        cell.mass += A;
        cell.m1 += m1;
        if (metric_) {
          const glm::dmat3& M = metric_faces_[lf];
          cell.H += A * M;
          cell.hm1 += M * m1;
          cell.energy += A / 12.0 * (glm::dot(a, M * a) + glm::dot(b, M * b) + glm::dot(c, M * c) + glm::dot(s, M * s));
        } else {
          cell.energy += A / 12.0 * (glm::dot(a, a) + glm::dot(b, b) + glm::dot(c, c) + glm::dot(s, s));
        }
      } else {
        for (const auto& q : kQuad) {
          const glm::dvec3 y = q[0] * a + q[1] * b + q[2] * c;
          const double w = A * q[3] * weightAt(fi, site + y);
          cell.mass += w;
          cell.m1 += w * y;
          if (metric_) {
            const glm::dmat3& M = metric_faces_[lf];
            const glm::dvec3 My = M * y;
            cell.H += w * M;
            cell.hm1 += w * My;
            cell.energy += w * glm::dot(y, My);
          } else {
            cell.energy += w * glm::dot(y, y);
          }
        }
      }
    }
  }

  static constexpr size_t kFirstK = 10;

  // The kFirstK nearest sites of site i from the candidates of its 3x3x3 cell block (sc.cand), when the
  // block is large enough to be sure; the same list grid_.kNearest would give (ties by index).
  bool nearestFromBlock(size_t i, ThreadScratch& sc, double& next2) const {
    sc.knn.clear();
    const glm::dvec3 p = sites_[i];
    for (size_t q = 0; q < sc.cand.size(); ++q) {
      if (sc.cand[q] == i) continue;
      const glm::dvec3 d = sc.candPos[q] - p;
      sc.knn.emplace_back(glm::dot(d, d), sc.cand[q]);
    }
    if (sc.knn.size() < kFirstK + 1) return false;
    std::nth_element(sc.knn.begin(), sc.knn.begin() + kFirstK, sc.knn.end());
    const double h = grid_.cellSize();
    if (!(sc.knn[kFirstK].first <= h * h)) return false;
    std::sort(sc.knn.begin(), sc.knn.begin() + kFirstK);
    next2 = sc.knn[kFirstK].first;
    sc.knn.resize(kFirstK);
    return true;
  }

  // Restricted Voronoi cell of site i, exact; empty when the site is not on a tract face.
  Cell computeCell(size_t i, ThreadScratch& sc) const {
    Cell cell;
    const int32_t startLocal = local_[face_[i]];
    if (startLocal < 0) return cell;
    const glm::dvec3 p = pos_[i];
    const double secure = metric_ ? (1.0 + std::sqrt(1.0 + lambdaBound_)) : 2.0;
    const double lambda = 1.0 + lambdaBound_;  // bound on the metric's largest eigenvalue
    for (size_t k = kFirstK;; k *= 2) {
      double next2 = 0;
      if (k != kFirstK || !nearestFromBlock(i, sc, next2))
        grid_.kNearest(sites_.data(), p, static_cast<uint32_t>(i), k, sc.knn, &next2, sc.shell);
      sc.q.clear();
      sc.qq.clear();
      for (const auto& [d2, j] : sc.knn) {
        if (d2 == 0 && j < i) return cell;  // coincident sites: the lower index owns the cell
        if (d2 > 0) {
          sc.q.push_back(sites_[j] - p);
          sc.qq.push_back(d2);
        }
      }
      cell = Cell();
      double r2max = 0;
      sc.resetStamps(tract_.faces.size());
      sc.queue.clear();
      sc.queue.push_back(face_[i]);
      sc.stamp[static_cast<size_t>(startLocal)] = sc.epoch;
      for (size_t qi = 0; qi < sc.queue.size(); ++qi) {
        const uint32_t fi = sc.queue[qi];
        const size_t lf = static_cast<size_t>(local_[fi]);
        const auto& t = mesh_.faces[fi];
        sc.polyA.setTriangle(mesh_.positions[t[0]] - p, mesh_.positions[t[1]] - p, mesh_.positions[t[2]] - p);
        bool alive = true;
        double r2 = maxNorm2(sc.polyA);
        for (size_t j = 0; j < sc.q.size(); ++j) {
          // A bisector at distance |q|/2 cannot reach a polygon within r of the site when
          // sqrt(lambda) r <= |q|/2; neighbours are sorted by distance, so neither can the later ones.
          if (4.0 * lambda * r2 <= sc.qq[j]) break;
          const glm::dvec3& q = sc.q[j];
          ClipResult res;
          if (metric_) {
            const glm::dvec3 n = metric_faces_[lf] * q;
            res = clip(sc.polyA, sc.polyB, sc.f, n, 0.5 * glm::dot(q, n));
          } else {
            res = clip(sc.polyA, sc.polyB, sc.f, q, 0.5 * sc.qq[j]);
          }
          if (res == kEmpty) {
            alive = false;
            break;
          }
          if (res == kClipped) r2 = maxNorm2(sc.polyA);
        }
        if (!alive) continue;
        r2max = std::max(r2max, r2);
        integrate(sc.polyA, fi, lf, p, cell);
        // Grow across the triangle edges the cell actually crosses (a stretch of non-zero length).
        uint8_t crossed = 0;
        const size_t pm = sc.polyA.n;
        for (size_t j = 0; j < pm; ++j) {
          const int8_t l = sc.polyA.label[j];
          if (l >= 0 && sc.polyA.v[j] != sc.polyA.v[(j + 1) % pm]) crossed |= static_cast<uint8_t>(1u << l);
        }
        for (int c = 0; c < 3; ++c) {
          if (!(crossed & (1u << c))) continue;
          const int32_t g = mesh_.faceNeighbors[fi][c];
          if (g < 0) continue;
          const int32_t lg = local_[static_cast<size_t>(g)];
          if (lg < 0 || sc.stamp[static_cast<size_t>(lg)] == sc.epoch) continue;
          sc.stamp[static_cast<size_t>(lg)] = sc.epoch;
          sc.queue.push_back(static_cast<uint32_t>(g));
        }
      }
      // Complete when no site beyond the k nearest can reach the cell.
      if (sc.knn.size() < k || secure * secure * r2max < next2) break;
    }
    return cell;
  }

  // Closest point of the tract to t, walking from `startFace` over tract faces within |t - xOld|.
  void project(const glm::dvec3& t, uint32_t startFace, const glm::dvec3& xOld, ThreadScratch& sc, uint32_t& outFace,
               glm::dvec3& outBary, glm::dvec3& outPos) const {
    sc.resetStamps(tract_.faces.size());
    const glm::dvec3 dOld = t - xOld;
    const double R2 = glm::dot(dOld, dOld) * (1.0 + 1e-9) + 1e-300;
    double best = std::numeric_limits<double>::infinity();
    sc.queue.clear();
    sc.queue.push_back(startFace);
    sc.stamp[static_cast<size_t>(local_[startFace])] = sc.epoch;
    constexpr size_t kMaxVisits = 4096;
    for (size_t qi = 0; qi < sc.queue.size() && qi < kMaxVisits; ++qi) {
      const uint32_t f = sc.queue[qi];
      const auto& tri = mesh_.faces[f];
      glm::dvec3 b;
      const glm::dvec3 q =
          closestPointOnTriangle(t, mesh_.positions[tri[0]], mesh_.positions[tri[1]], mesh_.positions[tri[2]], &b);
      const glm::dvec3 d = q - t;
      const double dd = glm::dot(d, d);
      if (dd < best) {
        best = dd;
        outFace = f;
        outBary = b;
        outPos = q;
      }
      if (dd > R2 && qi > 0) continue;
      for (int c = 0; c < 3; ++c) {
        const int32_t g = mesh_.faceNeighbors[f][c];
        if (g < 0) continue;
        const int32_t lg = local_[static_cast<size_t>(g)];
        if (lg < 0 || sc.stamp[static_cast<size_t>(lg)] == sc.epoch) continue;
        sc.stamp[static_cast<size_t>(lg)] = sc.epoch;
        sc.queue.push_back(static_cast<uint32_t>(g));
      }
    }
    // Keep clear of tract edges and corners (6.1.3).
    const FaceLimits& L = limits_[static_cast<size_t>(local_[outFace])];
    if (L.any) {
      glm::dvec3 b = outBary;
      for (int pass = 0; pass < 3; ++pass) {
        for (int c = 0; c < 3; ++c) b[c] = std::clamp(b[c], L.lo[c], L.hi[c]);
        b /= (b.x + b.y + b.z);
      }
      if (b != outBary) {
        outBary = b;
        outPos = pointAt(mesh_, outFace, b);
      }
    }
  }

  // One Lloyd step (or, with newPos == nullptr, only the cell energies at the current positions).
  void step(std::vector<glm::dvec3>* newPos, std::vector<uint32_t>* newFace, std::vector<glm::dvec3>* newBary,
            std::vector<double>& cellEnergy, std::vector<double>& move) {
    sites_ = pos_;
    cellArea_.resize(n_);
    grid_.build(sites_.data(), n_);
    const double omega = opt_.overRelaxation;
    const auto& runKeys = grid_.runKeys();
    const auto& runBegin = grid_.runBegin();
    const auto& order = grid_.order();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, runKeys.size(), 8), [&](const tbb::blocked_range<size_t>& r) {
      ThreadScratch& sc = scratch_.local();
      for (size_t run = r.begin(); run != r.end(); ++run) {
        // Candidates shared by all sites of this grid cell: the sites of the 27 cells around it.
        const auto c = CellGrid::unpack(runKeys[run]);
        sc.cand.clear();
        sc.candPos.clear();
        for (int64_t di = -1; di <= 1; ++di)
          for (int64_t dj = -1; dj <= 1; ++dj)
            for (int64_t dk = -1; dk <= 1; ++dk) {
              const auto [b, e] = grid_.cell(c[0] + di, c[1] + dj, c[2] + dk);
              for (uint32_t q = b; q < e; ++q) {
                sc.cand.push_back(order[q]);
                sc.candPos.push_back(sites_[order[q]]);
              }
            }
        for (uint32_t oi = runBegin[run]; oi < runBegin[run + 1]; ++oi) {
          const size_t i = order[oi];
          const glm::dvec3 x = pos_[i];
          move[i] = 0;
          if (newPos) {
            (*newPos)[i] = x;
            (*newFace)[i] = face_[i];
            (*newBary)[i] = bary_[i];
          }
          const Cell cell = computeCell(i, sc);
          cellEnergy[i] = cell.energy;
          cellArea_[i] = cell.area;
          if (!newPos || kind_[i] != kFree || !(cell.mass > 0)) continue;
          const glm::dvec3 cRel = metric_ ? glm::inverse(cell.H) * cell.hm1 : cell.m1 / cell.mass;
          const glm::dvec3 c = x + cRel;
          auto cost = [&](const glm::dvec3& v) { return metric_ ? glm::dot(v, cell.H * v) : glm::dot(v, v); };
          const double current = cost(x - c);
          const double omegas[2] = {omega, 1.0};
          for (int attempt = 0; attempt < (omega > 1.0 ? 2 : 1); ++attempt) {
            const glm::dvec3 target = x + omegas[attempt] * (c - x);
            uint32_t f = face_[i];
            glm::dvec3 bb = bary_[i], p = x;
            project(target, face_[i], x, sc, f, bb, p);
            if (cost(p - c) <= current) {
              (*newPos)[i] = p;
              (*newFace)[i] = f;
              (*newBary)[i] = bb;
              move[i] = glm::length(p - x);
              break;
            }
          }
        }
      }
    });
  }

  double totalEnergy(const std::vector<double>& cellEnergy) const {
    double e = 0;
    for (double x : cellEnergy) e += x;
    return e * weightNorm_;
  }

  const SkinMesh& mesh_;
  const Tract& tract_;
  Follicles& fol_;
  const RelaxOptions& opt_;

  std::vector<BiasVector> activeBias_;
  bool metric_ = false, gain_ = false, weighted_ = false;
  double lambdaBound_ = 0.0;  // bound on (largest metric eigenvalue - 1)

  std::vector<int32_t> local_;  // mesh face -> index in tract.faces, -1 outside
  std::vector<FaceLimits> limits_;
  std::vector<glm::dmat3> metric_faces_;
  std::vector<size_t> sel_;
  std::vector<uint8_t> kind_;
  std::vector<uint32_t> face_;
  std::vector<glm::dvec3> bary_, pos_, sites_;
  std::vector<double> cellArea_;
  size_t n_ = 0;
  double area_ = 0, spacing_ = 0, weightNorm_ = 1.0;
  CellGrid grid_;
  tbb::enumerable_thread_specific<ThreadScratch> scratch_;
};

}  // namespace

RelaxResult relaxFollicles(const SkinMesh& mesh, const Tract& tract, Follicles& follicles,
                           const RelaxOptions& options) {
  Relaxer r(mesh, tract, follicles, options);
  return r.run();
}

}  // namespace pteryla::coat
