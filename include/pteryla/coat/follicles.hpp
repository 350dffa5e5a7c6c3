#pragma once
// Follicles: where feathers grow (Streit 2003, 6.1). Stored as (face, barycentric) so they ride the skin
// when it deforms; position/normal are caches refreshed by updateFollicleGeometry().
//
// Scattering (6.1: "random points within each triangle of the set of polygons defining a given tract ...
// area weighting ... A large table of random barycentric coordinates are generated once initially to
// preserve consistency when adding follicles"): follicle k's random draws depend only on (seed, k), so
// asking for more follicles keeps the first ones exactly where they were.
#include <glm/vec3.hpp>

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"

namespace pteryla::coat {

// Follicle density over the skin, in follicles per unit area (scene units^-2).
struct DensityField {
  double uniform = 0.0;           // used when perVertex is empty
  std::vector<double> perVertex;  // one value per mesh vertex (>= 0), linear across each face
  // Optional factor >= 0 on top (e.g. a painted density texture sampled through uvAt). Scattering
  // evaluates it at face centroids (it picks faces, not points inside them); relaxation at quadrature
  // points, from several threads at once (it must be thread-safe and deterministic).
  std::function<double(uint32_t face, const glm::dvec3& bary)> multiplier;

  bool isUniform() const { return perVertex.empty() && !multiplier; }
  // Density at a surface point (throws Error for negative or non-finite values).
  double at(const SkinMesh& mesh, uint32_t face, const glm::dvec3& bary) const;
};

struct Follicles {
  std::vector<uint32_t> face;
  std::vector<glm::dvec3> bary;
  std::vector<glm::dvec3> position;  // cache of pointAt(face, bary)
  std::vector<glm::dvec3> normal;    // cache of normalAt(face, bary)
  std::vector<uint32_t> tract;       // index into the caller's tract list
  std::vector<uint8_t> pinned;       // 1 = placed by hand (6.1.5): never moved by relaxation
  std::vector<uint64_t> id;          // stable identifier (survives relaxation and re-scattering)

  size_t size() const { return face.size(); }
  bool empty() const { return face.empty(); }
  void reserve(size_t n);
  void clear();
  // Appends one follicle (position and normal evaluated on `mesh`); returns its index.
  size_t push(const SkinMesh& mesh, uint32_t face, const glm::dvec3& bary, uint32_t tract, uint64_t id,
              bool pinned = false);
  void append(const Follicles& other);
  SurfacePoint surfacePoint(size_t i) const { return {face[i], bary[i]}; }
};

// Default ids: (tract << 40) + k for the k-th scattered follicle of a tract.
constexpr uint64_t kAutoFollicleId = std::numeric_limits<uint64_t>::max();

struct ScatterOptions {
  uint64_t seed = 1;
  DensityField density;                // follicles per unit area
  size_t count = 0;                    // > 0: exactly this many (density then only shapes where they go)
  uint32_t tractIndex = 0;             // stored in Follicles::tract
  uint64_t firstId = kAutoFollicleId;  // follicle k gets firstId + k
};

// Expected number of follicles for a density over a tract: round(integral of density over the tract).
size_t expectedFollicleCount(const SkinMesh& mesh, const Tract& tract, const DensityField& density);

// Random follicles over the tract: face chosen by integrated density (area-weighted), point inside the
// face uniform (or linear in per-vertex density). Deterministic in (seed, k); never on a face edge.
Follicles scatterFollicles(const SkinMesh& mesh, const Tract& tract, const ScatterOptions& options);

// Manual placement (6.1.5, flight feathers): a pinned follicle at a surface point, or at the point of the
// tract closest to `position`. Returns the new index. Pinned follicles never move and act as Lloyd sites.
size_t addPinnedFollicle(Follicles& follicles, const SkinMesh& mesh, const SurfacePoint& at, uint32_t tract,
                         uint64_t id);
size_t addPinnedFollicleNear(Follicles& follicles, const SkinMesh& mesh, const Tract& tract, const glm::dvec3& position,
                             uint32_t tractIndex, uint64_t id);

// Re-evaluates position and normal from (face, bary) after the skin deformed (recomputeGeometry first).
void updateFollicleGeometry(const SkinMesh& mesh, Follicles& follicles);

}  // namespace pteryla::coat
