#pragma once
// Navigation coat: while the camera moves, the viewer may draw a subset of the coat's feathers so
// orbiting stays fluid on software GL (llvmpipe draws roughly a million feather triangles a second on
// two cores); the full coat is drawn again as soon as the camera stops. The subset keeps the longest
// feathers first (flight and tail feathers make the silhouette: those in the top tenth by length, within
// half the budget), then every k-th of the others in layer order (k chosen so the subset fits the
// budget), so it is spread evenly over the body; layer order is kept.
#include <cstddef>
#include <vector>

#include "pteryla/core/trimesh.hpp"
#include "pteryla/pipeline/pipeline.hpp"

namespace pteryla::viewer {

struct NavigationCoat {
  TriMesh mesh;                                 // vertices and triangles of the kept feathers only
  std::vector<pipeline::CoatDrawRange> ranges;  // their draw ranges, re-based onto `mesh`
  size_t stride = 1;                            // every stride-th of the shorter feathers kept
  size_t longKept = 0;                          // long feathers kept whole
};

// Empty (stride 1, no mesh) when the coat already fits the budget. Feathers whose triangles index a
// vertex range shared with another feather are copied with that range (correct, if not minimal).
NavigationCoat makeNavigationCoat(const pipeline::CoatMesh& coat, size_t triangleBudget);

// Adaptive navigation: whether a moving view draws the navigation coat rather than every feather.
// `movingFullCoatMs` is the smoothed render time of the full coat while moving (< 0: not measured yet
// since the last upload or resize, so the full coat is tried first). `forced` (show navigation on)
// always draws the navigation coat; without `adaptive` the navigation coat is always drawn.
bool useNavigationCoat(bool forced, bool adaptive, double movingFullCoatMs, double budgetMs);

// Exponential smoothing of the measured moving full-coat time (the first sample is taken as it is).
double smoothFrameMs(double previousMs, double sampleMs);

}  // namespace pteryla::viewer
