// Follicle scattering (Streit 2003, 6.1: area-weighted random points per tract with a fixed table of random
// barycentric coordinates; 6.1.5 manual placement).
#include "pteryla/coat/follicles.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"

namespace pteryla::coat {

double DensityField::at(const SkinMesh& mesh, uint32_t face, const glm::dvec3& b) const {
  double d = uniform;
  if (!perVertex.empty()) {
    const auto& f = mesh.faces[face];
    d = b.x * perVertex[f[0]] + b.y * perVertex[f[1]] + b.z * perVertex[f[2]];
  }
  if (multiplier) {
    const double m = multiplier(face, b);
    if (!std::isfinite(m) || m < 0)
      throw Error("density multiplier returned " + std::to_string(m) + " (must be finite and >= 0)", mesh.file,
                  "face " + std::to_string(face));
    d *= m;
  }
  return d;
}

void Follicles::reserve(size_t n) {
  face.reserve(n);
  bary.reserve(n);
  position.reserve(n);
  normal.reserve(n);
  tract.reserve(n);
  pinned.reserve(n);
  id.reserve(n);
}

void Follicles::clear() { *this = Follicles(); }

size_t Follicles::push(const SkinMesh& mesh, uint32_t f, const glm::dvec3& b, uint32_t t, uint64_t i, bool pin) {
  PTERYLA_CHECK(f < mesh.faces.size(), "follicle face out of range");
  face.push_back(f);
  bary.push_back(b);
  position.push_back(pointAt(mesh, f, b));
  normal.push_back(normalAt(mesh, f, b));
  tract.push_back(t);
  pinned.push_back(pin ? 1 : 0);
  id.push_back(i);
  return face.size() - 1;
}

void Follicles::append(const Follicles& o) {
  face.insert(face.end(), o.face.begin(), o.face.end());
  bary.insert(bary.end(), o.bary.begin(), o.bary.end());
  position.insert(position.end(), o.position.begin(), o.position.end());
  normal.insert(normal.end(), o.normal.begin(), o.normal.end());
  tract.insert(tract.end(), o.tract.begin(), o.tract.end());
  pinned.insert(pinned.end(), o.pinned.begin(), o.pinned.end());
  id.insert(id.end(), o.id.begin(), o.id.end());
}

namespace {

void checkDensity(const SkinMesh& mesh, const DensityField& d) {
  if (!std::isfinite(d.uniform) || d.uniform < 0)
    throw Error("density must be finite and >= 0 (got " + std::to_string(d.uniform) + ")", mesh.file, "density");
  if (!d.perVertex.empty()) {
    if (d.perVertex.size() != mesh.positions.size())
      throw Error("per-vertex density has " + std::to_string(d.perVertex.size()) + " values for " +
                      std::to_string(mesh.positions.size()) + " vertices",
                  mesh.file, "density");
    for (size_t v = 0; v < d.perVertex.size(); ++v)
      if (!std::isfinite(d.perVertex[v]) || d.perVertex[v] < 0)
        throw Error("density must be finite and >= 0 (got " + std::to_string(d.perVertex[v]) + ")", mesh.file,
                    "vertex " + std::to_string(v));
  }
}

// Integrated density per tract face (exact for the linear per-vertex field; multiplier at the centroid).
std::vector<double> faceWeights(const SkinMesh& mesh, const Tract& tract, const DensityField& d) {
  checkDensity(mesh, d);
  std::vector<double> w(tract.faces.size());
  for (size_t k = 0; k < tract.faces.size(); ++k) {
    const uint32_t f = tract.faces[k];
    double rho = d.uniform;
    if (!d.perVertex.empty()) {
      const auto& t = mesh.faces[f];
      rho = (d.perVertex[t[0]] + d.perVertex[t[1]] + d.perVertex[t[2]]) / 3.0;
    }
    if (d.multiplier) {
      const double m = d.multiplier(f, glm::dvec3(1.0 / 3.0));
      if (!std::isfinite(m) || m < 0)
        throw Error("density multiplier returned " + std::to_string(m) + " (must be finite and >= 0)", mesh.file,
                    "face " + std::to_string(f));
      rho *= m;
    }
    w[k] = rho * mesh.faceAreas[f];
  }
  return w;
}

}  // namespace

size_t expectedFollicleCount(const SkinMesh& mesh, const Tract& tract, const DensityField& density) {
  const auto w = faceWeights(mesh, tract, density);
  double total = 0;
  for (double x : w) total += x;
  return static_cast<size_t>(std::llround(total));
}

Follicles scatterFollicles(const SkinMesh& mesh, const Tract& tract, const ScatterOptions& opt) {
  if (tract.faces.empty())
    throw Error("tract '" + tract.name + "' has no faces", mesh.file, "tract '" + tract.name + "'");
  // With an explicit count a uniform density only needs to be "uniform": weight faces by area.
  DensityField shape = opt.density;
  if (opt.count > 0 && shape.perVertex.empty() && shape.uniform == 0.0) shape.uniform = 1.0;
  const auto w = faceWeights(mesh, tract, shape);
  std::vector<double> cdf(w.size());
  double total = 0;
  for (size_t k = 0; k < w.size(); ++k) {
    total += w[k];
    cdf[k] = total;
  }
  size_t n = opt.count;
  if (n == 0) {
    if (!(total > 0))
      throw Error("follicle density integrates to zero over tract '" + tract.name + "' (set a density or a count)",
                  mesh.file, "tract '" + tract.name + "'");
    n = static_cast<size_t>(std::llround(total));
  } else if (!(total > 0)) {
    throw Error("follicle density is zero everywhere on tract '" + tract.name + "'", mesh.file,
                "tract '" + tract.name + "'");
  }
  constexpr size_t kMaxFollicles = 50'000'000;
  if (n > kMaxFollicles)
    throw Error("tract '" + tract.name + "' would get " + std::to_string(n) + " follicles (limit " +
                    std::to_string(kMaxFollicles) + "): density too high for the mesh units?",
                mesh.file, "tract '" + tract.name + "'");

  const uint64_t base = opt.firstId == kAutoFollicleId ? (static_cast<uint64_t>(opt.tractIndex) << 40) : opt.firstId;
  Follicles out;
  out.face.resize(n);
  out.bary.resize(n);
  out.position.resize(n);
  out.normal.resize(n);
  out.tract.assign(n, opt.tractIndex);
  out.pinned.assign(n, 0);
  out.id.resize(n);
  const bool linear = !opt.density.perVertex.empty();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k) {
      // Follicle k's own stream: its draws depend only on (seed, k).
      Rng rng(opt.seed, k);
      const double u = rng.uniform() * total;
      size_t fi = static_cast<size_t>(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin());
      if (fi >= cdf.size()) fi = cdf.size() - 1;
      while (w[fi] <= 0 && fi > 0) --fi;  // never land on a zero-weight face via rounding
      const uint32_t f = tract.faces[fi];
      glm::dvec3 b;
      double rmax = 0;
      if (linear) {
        const auto& t = mesh.faces[f];
        rmax = std::max({opt.density.perVertex[t[0]], opt.density.perVertex[t[1]], opt.density.perVertex[t[2]]});
      }
      for (int attempt = 0;; ++attempt) {
        // Uniform on the triangle; keep clear of the edges (6.1.3: follicles never lie on an edge).
        const double s = std::sqrt(std::clamp(rng.uniform(), 1e-12, 1.0 - 1e-12));
        const double v = std::clamp(rng.uniform(), 1e-9, 1.0 - 1e-9);
        b = glm::dvec3(1.0 - s, s * (1.0 - v), s * v);
        if (!linear || attempt >= 64) break;
        const auto& t = mesh.faces[f];
        const double rho =
            b.x * opt.density.perVertex[t[0]] + b.y * opt.density.perVertex[t[1]] + b.z * opt.density.perVertex[t[2]];
        if (rng.uniform() * rmax <= rho) break;
      }
      out.face[k] = f;
      out.bary[k] = b;
      out.position[k] = pointAt(mesh, f, b);
      out.normal[k] = normalAt(mesh, f, b);
      out.id[k] = base + k;
    }
  });
  return out;
}

size_t addPinnedFollicle(Follicles& follicles, const SkinMesh& mesh, const SurfacePoint& at, uint32_t tract,
                         uint64_t id) {
  if (at.face >= mesh.faces.size())
    throw Error("pinned follicle face " + std::to_string(at.face) + " is out of range (" +
                    std::to_string(mesh.faces.size()) + " faces)",
                mesh.file, "follicle " + std::to_string(id));
  const glm::dvec3 b = at.bary;
  const double s = b.x + b.y + b.z;
  if (!(b.x >= 0 && b.y >= 0 && b.z >= 0) || !(std::abs(s - 1.0) < 1e-6))
    throw Error("barycentric coordinates must be >= 0 and sum to 1", mesh.file, "follicle " + std::to_string(id));
  return follicles.push(mesh, at.face, b / s, tract, id, true);
}

size_t addPinnedFollicleNear(Follicles& follicles, const SkinMesh& mesh, const Tract& tract, const glm::dvec3& position,
                             uint32_t tractIndex, uint64_t id) {
  if (tract.faces.empty()) throw Error("tract '" + tract.name + "' has no faces", mesh.file);
  const SurfacePoint p = closestSurfacePoint(mesh, position, &tract.faces);
  return follicles.push(mesh, p.face, p.bary, tractIndex, id, true);
}

void updateFollicleGeometry(const SkinMesh& mesh, Follicles& f) {
  f.position.resize(f.size());
  f.normal.resize(f.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, f.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      f.position[i] = pointAt(mesh, f.face[i], f.bary[i]);
      f.normal[i] = normalAt(mesh, f.face[i], f.bary[i]);
    }
  });
}

}  // namespace pteryla::coat
