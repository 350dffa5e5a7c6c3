#pragma once
// Navigation coat: while the camera moves, the viewer may draw a light stand-in for the coat so orbiting
// stays fluid on software GL (llvmpipe draws roughly a million feather triangles a second on two cores);
// the full coat is drawn again as soon as the camera stops. The longest feathers are kept whole (flight
// and tail feathers make the silhouette: those in the top tenth by length, within half the budget); every
// other feather becomes a card, a strip along its shaft through its outermost vertices on either side,
// so the body stays covered (#28: dropping all but every 27th feather left the bird bald while
// orbiting). Only when even two-triangle cards exceed the budget is every k-th card kept. Layer order is
// kept.
#include <cstddef>
#include <vector>

#include "pteryla/core/trimesh.hpp"
#include "pteryla/pipeline/pipeline.hpp"

namespace pteryla::viewer {

inline constexpr size_t kMaxCardBins = 6;

struct NavigationCoat {
  TriMesh mesh;                                 // vertices and triangles of the kept feathers only
  std::vector<pipeline::CoatDrawRange> ranges;  // their draw ranges, re-based onto `mesh`
  size_t stride = 1;                            // every stride-th card kept (1: every feather)
  size_t longKept = 0;                          // long feathers kept whole
  size_t cards = 0;                             // feathers drawn as cards
  int cardBins = 0;                             // rows of a card (2 (cardBins - 1) triangles)
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
