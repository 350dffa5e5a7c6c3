#pragma once
// Regularity of a follicle distribution (Streit 2003, 6.1: "a rough regular hexagonal pattern"). Measures
// from /work/shared/reference/lloyd.md: share of follicles with exactly six Delaunay neighbours, the
// coefficient of variation of nearest-neighbour distance, nearest-neighbour distance relative to a
// perfect hexagonal lattice of the same density, and the bond-orientational order |psi6|.
//
// Delaunay neighbours on the surface: each follicle's nearest neighbours are projected onto its tangent
// plane and its Voronoi cell is clipped from their bisectors; neighbours are added until the cell is
// provably complete (security radius), so the result equals the local 2-D Delaunay triangulation.
// Follicles whose normal faces away (n_i . n_j < 0) are on another sheet of the surface (the far side
// of a thin wing) and are not neighbours.
// Follicles closer than interiorBand spacings to the tract boundary are not measured (they are still
// neighbours of the others). Spacing = sqrt(2 A / (sqrt(3) n)) for tract area A and n follicles.
#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"

namespace pteryla::coat {

struct MetricsOptions {
  double interiorBand = 1.5;  // follicles nearer than this many spacings to the tract edge are skipped
};

struct DistributionMetrics {
  size_t follicles = 0;    // all follicles considered (sites)
  size_t interior = 0;     // measured follicles
  double spacing = 0;      // hexagonal spacing for this density, scene units
  double hexFraction = 0;  // share of interior follicles with exactly 6 Delaunay neighbours
  double nnCv = 0;         // std / mean of nearest-neighbour distance (interior follicles)
  double nnMean = 0;       // mean nearest-neighbour distance / spacing
  double nnMin = 0;        // minimum nearest-neighbour distance / spacing
  double meanDegree = 0;   // mean Delaunay degree
  double psi6 = 0;         // mean |psi6| bond order
};

// Delaunay neighbours on the surface for every follicle (CSR), computed in each tangent plane.
struct FollicleNeighbours {
  std::vector<uint32_t> offsets;  // size n + 1
  std::vector<uint32_t> indices;
  std::vector<uint8_t> complete;  // 0 when the follicle's local cell was unbounded (open boundary)
};
FollicleNeighbours delaunayNeighbours(const Follicles& follicles, double spacing);

DistributionMetrics measureDistribution(const SkinMesh& mesh, const Tract& tract, const Follicles& follicles,
                                        const MetricsOptions& options = {});
double hexFraction(const SkinMesh& mesh, const Tract& tract, const Follicles& follicles,
                   const MetricsOptions& options = {});
double nnCv(const SkinMesh& mesh, const Tract& tract, const Follicles& follicles, const MetricsOptions& options = {});

// Mean Delaunay-edge length of interior follicles within 30 degrees of `direction` (projected onto each
// tangent plane) and within 30 degrees of perpendicular to it. Stretched distributions (bias vectors)
// have along < across.
struct DirectionalSpacing {
  double along = 0, across = 0;  // scene units
  size_t alongEdges = 0, acrossEdges = 0;
};
DirectionalSpacing directionalSpacing(const SkinMesh& mesh, const Tract& tract, const Follicles& follicles,
                                      const glm::dvec3& direction, const MetricsOptions& options = {});

}  // namespace pteryla::coat
