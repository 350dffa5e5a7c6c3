#pragma once
// Follicle relaxation: Lloyd's algorithm on the skin, restricted to one tract (Streit 2003, 6.1.1-6.1.5).
//
// Each iteration computes every follicle's restricted Voronoi cell (its Voronoi cell intersected with the
// tract's triangles, exactly, by clipping), moves every free follicle toward the (weighted) centroid of
// its cell and snaps it back onto the tract's faces; follicles migrate across triangles but never leave
// the tract or sit on its edges. Pinned follicles (6.1.5) and, by default, the follicles along the tract
// boundary (6.1.3) stay put but still own cells. Bias vectors (6.1.4) stretch the pattern into rows: near
// a vector, distance is measured in the metric I + (stretch^2 - 1) g(x) d d^T (g a Gaussian fall-off,
// constant per skin triangle), so rows along d come out up to `stretch` times closer than across. Without
// bias vectors (or with all stretches 1 and gains 0) the result is bit-identical to plain Lloyd.
//
// The CVT energy never rises from one iteration to the next: an over-relaxed step x + w (c - x) with
// 1 <= w < 2 lowers each cell's energy, and a projected step that would not is retried with w = 1 or
// skipped. Results are bit-identical for the same inputs and any thread count.
//
// Cells are grown over the tract's faces from the follicle's own face, so a cell is the part of the
// Voronoi cell connected to its follicle. When the spacing is small against the surface's feature size
// (the thesis' assumption, 6.1.3 and Fig. 6.4) that is the whole restricted cell. Where it is not (a
// band wrapping a thin wing edge), the far pieces are left out rather than claimed across the gap,
// RelaxResult::coverage drops below 1 and the energy may wobble by a few 1e-4 near convergence.
#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/progress.hpp"

namespace pteryla::coat {

struct BiasVector {
  glm::dvec3 origin{0.0};         // where the bias acts (scene units, on or near the skin)
  glm::dvec3 direction{1, 0, 0};  // row direction (sign irrelevant), projected onto the surface
  double sigma = 0.0;             // Gaussian fall-off radius, scene units; <= 0: no fall-off (whole tract)
  double stretch = 1.5;           // >= 1: spacing across rows / spacing along rows where the weight is 1
  double densityGain = 0.0;       // >= 0: extra follicle density near the vector (factor 1 + gain)
};

struct RelaxOptions {
  int iterations = 50;          // from random starts: hex fraction ~0.77, nn CV ~0.054
  double overRelaxation = 1.8;  // w in [1, 2): step x += w (c - x); 1 = textbook Lloyd
  bool fixBoundary = true;      // 6.1.3: follicles within boundaryBand of the tract edge do not move
  double boundaryBand = 0.5;    // in units of the mean follicle spacing
  double edgeMargin = 0.05;     // free follicles keep this distance from tract edges (spacing units)
  double tolerance = 0.0;       // stop when no follicle moves more than tolerance * spacing (0: off)
  DensityField density;         // relative density (only its shape matters); empty = uniform
  std::vector<BiasVector> bias;
  int64_t onlyTract = -1;  // relax only follicles whose tract == onlyTract; -1: all of them
  ProgressFn progress;     // stage "relax", fraction per iteration; returning false cancels
};

struct RelaxResult {
  // CVT energy sum_i integral over cell i of w(y) |y - x_i|_M^2 dA, normalised by area / integral of w
  // (scene units^4), at the start of each iteration and after the last one: iterations + 1 values,
  // never increasing.
  std::vector<double> energy;
  std::vector<double> maxMove;  // largest follicle displacement per iteration, scene units
  int iterations = 0;           // iterations run
  size_t follicles = 0;         // sites taking part (free + fixed + pinned)
  size_t moved = 0;             // free follicles
  size_t fixedBoundary = 0;     // held because they lie along the tract boundary
  size_t pinned = 0;
  double spacing = 0.0;    // mean hexagonal spacing sqrt(2 A / (sqrt(3) n)), scene units
  double coverage = 0.0;   // share of the tract's area inside some cell after the last step
  bool converged = false;  // stopped by tolerance
  bool cancelled = false;  // stopped by the progress callback
  double seconds = 0.0;
};

// Relaxes the selected follicles of `follicles` (all, or those of options.onlyTract) over `tract`.
// Non-pinned follicles must lie on the tract's faces (Error otherwise). Updates face, bary, position and
// normal in place; ids, tract and pinned flags are unchanged.
RelaxResult relaxFollicles(const SkinMesh& mesh, const Tract& tract, Follicles& follicles,
                           const RelaxOptions& options = {});

}  // namespace pteryla::coat
