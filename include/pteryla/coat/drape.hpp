#pragma once
// Draped packing: every feather lies on the skin, following it, stacked on the feathers under it.
//
// The height-field packer (pack.hpp, thesis 6.3.2-6.3.3) turns each feather as a rigid body about its
// follicle until it clears what lies under its footprint. On a body that curves, a rigid feather must
// stand to clear concave skin and floats off convex skin, and it sees only the skin under its own
// footprint. Draping keeps the thesis' one-pass, ordered, deterministic layering but measures height
// over the skin instead of over the follicle's tangent plane (the "aim mesh" and "surface blend" of
// production systems, docs/packing.md):
//
//  1. Chart. Each feather's flat layout (elevation 0, local x along the shaft, y across the vane) is
//     mapped onto the skin by marching: along the shaft from the follicle, then across from each shaft
//     node, every step a closest-point projection within the step length of the previous surface point,
//     with the feather's direction transported into each new tangent plane. The chart is a small grid
//     of surface points, normals and directions per feather. Where the skin ends under the feather (a
//     step that barely advances), curves away with a radius under 0.15 x the feather's length (a rim, the
//     edge of a wing, fin or ear: a feather is stiffer than that) or has turned a quarter turn from the
//     follicle, the feather overhangs: it goes straight on, as a flight feather leaves the wing's edge.
//  2. Height. In layer order (bottom first), a node's required height over the skin is the highest
//     feather material already laid near its surface point (a hash over surface cells, split by normal
//     class so the far side of a thin part does not count), plus a gap. An overhanging node has no skin
//     under it: it clears the material already laid around the line through it along its normal. The feather's height
//     is the smallest function above those requirements whose slope over the skin is at most `maxSlope` (the upper
//     Lipschitz envelope): a stiff feather rides over what is under it instead of following each bump. Near the
//     follicle the height ramps from the skin over the calamus.
//  3. Mesh. Every vertex of the feather mesh (built at elevation 0) is moved to its chart point plus its
//     height along the chart normal; normals and tangents turn with the chart frame.
//  4. Guarantees. A feather never covers the follicle of a feather laid after it, and one whose chart
//     folds over a rim or into a crease is shortened first (scaled about its follicle). What still fails
//     is trimmed: triangles over a later follicle's root zone, cells on the skin that fold, nodes the
//     chart did not reach or whose lifted point sits in a fold of the skin, and then, with the
//     coat checker's own tests (check.hpp), every vertex inside the skin and, of every pair of crossing
//     triangles, the lower feather's. A draped coat has no skin penetration and no crossing triangles.
//     Trimmed and hidden feathers are counted.
#include <cstdint>
#include <memory>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/progress.hpp"
#include "pteryla/core/trimesh.hpp"

namespace pteryla::coat {

struct DrapeOptions {
  double gap = 0;  // scene units between stacked feathers and above the skin; 0 = auto (0.004 x median feather length)
  // Spacing of the coat's top, the samples over the skin that record how high the coat laid so far
  // reaches; 0 = auto (0.75 x the median chart cell). At most about 8 million samples either way.
  double spacing = 0;
  double maxSlope = 1.0;  // largest rise of a feather's height over the skin per unit length (tan 45 degrees)
  int gridAlong = 16;     // chart nodes along a feather (>= 2)
  int gridAcross = 9;     // chart nodes across it (>= 2)
  double baseAllowance =
      0.08;         // fraction of a feather's length around its follicle the checks exempt (PackOptions::baseAllowance)
  int threads = 0;  // 0 = all cores
  // drapeCarried: a feather whose chart and follicle frame a rigid piece of the posed skin carried (every
  // face under it, with its corners' normals, moved by one rotation and translation, within 1e-6 of the
  // skin's size) moves with the piece as it lay at rest, and only its pairs with feathers off the piece are
  // searched. False places every moved feather on its carried chart and searches all its pairs.
  bool rigidPieces = true;
  // Called on the calling thread with ("drape", fraction done) after each step and during the checker's
  // tests of the last two. Its answer is ignored: a caller stops the drape by throwing from it (the
  // mesh is then left half draped).
  ProgressFn progress;
};

struct DrapeStats {
  size_t draped = 0;            // feathers laid on the skin
  size_t trimmedFeathers = 0;   // feathers that lost triangles (over a later follicle, off or inside the skin)
  size_t hiddenFeathers = 0;    // feathers with no triangle left
  size_t trimmedTriangles = 0;  // triangles removed (collapsed to a point)
  size_t overhangingNodes = 0;  // chart nodes past the skin's edge (the feather goes straight on there)
  double gap = 0;               // the gap used (scene units)
  double seconds = 0;
  // With a DrapeCache: feathers laid afresh (their chart, what they read or the skin changed) and
  // feathers whose draped vertices were copied from the last drape (the rest of `draped`).
  // drapeOverMature: feathers placed on their mature chart, and feathers copied from the mature drape.
  size_t relaid = 0;
  size_t reused = 0;
  size_t rigid = 0;  // drapeCarried: of `reused`, feathers moved with a rigid piece of the skin
};

struct DrapeResult {
  // Per feather, radians: how steeply the shaft rises over the skin, atan(height / distance along the
  // skin), the largest over the shaft's chart nodes past the calamus. 0 for feathers not draped.
  std::vector<double> elevation;
  std::vector<uint8_t> trimmed;  // per feather: 1 when it lost triangles
  std::vector<uint8_t> hidden;   // per feather: 1 when it lost every triangle
  DrapeStats stats;
};

// What one drape keeps for the next (the timeline's frames): per feather its inputs (frame, the
// parameters the drape reads, its flat vertices and triangles), its chart, the coat's top it read and its
// draped vertices, and the crossing pairs. The next drape over the same skin and options lays again only
// the feathers whose inputs changed or whose reads of the coat under them differ, tests only their
// vertices against the skin and searches pairs only among changed triangles: the result is the one a
// drape without the cache gives, bit for bit (tests/coat/test_drape_cache.cpp). Any change of the skin,
// the options, the gap or the sample spacing (medians over the coat) lays everything again.
class DrapeCache {
 public:
  DrapeCache();
  ~DrapeCache();
  DrapeCache(DrapeCache&&) noexcept;
  DrapeCache& operator=(DrapeCache&&) noexcept;
  void clear();  // the next drape lays everything
  // A cache keeps nothing while the skin moves at every drape (an animated pose), unless told to keep
  // every drape (the mature coat's cache, which drapeOverMature reads).
  void keepEveryDrape();
  size_t bytes() const;  // roughly what the cache holds

  struct State;

 private:
  std::unique_ptr<State> state_;
  friend struct DrapeAccess;
};

// Drapes `mesh`, the coat meshed with every feather at elevation 0 from `coat.frames` (featherId per
// vertex; feathers absent from coat.layerOrder are left alone), over `skin`. Rewrites positions, normals
// and tangents in place and collapses trimmed triangles to a point (index ranges stay valid).
// Throws Error for inconsistent input (featherId out of range or missing).
DrapeResult drapeCoatMesh(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh,
                          const DrapeOptions& options = {});
// A moult frame of a draped coat laid over its mature coat (packing "moult_pack": "over", the default,
// as the height-field packer lays a moult frame over the mature coat's pack): `mature` holds the drape of
// the same coat with every feather present and mature (drapeCoatMesh with a cache, over `skin`). A
// feather whose flat vertices are the mature drape's keeps its draped vertices; a growing feather (or any
// other whose flat mesh differs) is placed on its mature chart, at the mature coat's heights, so nothing
// laid over it moves while it grows; a lost feather leaves its place open. Then the guarantees run for
// what changed: vertices of placed feathers under the skin and their material over a later follicle are
// trimmed, and of every crossing pair with a placed triangle the lower feather's triangle goes, while the
// triangles the mature drape cut only because they crossed a feather lost now come back. Throws Error if
// `mature` is empty, was laid over another skin or coat size, or its layer order disagrees.
DrapeResult drapeOverMature(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh, const DrapeCache& mature,
                            const DrapeOptions& options = {});

// A posed frame's drape carried from the rest pose's (issue #26, docs/moult.md "Posed frames"):
// `reference` holds the last drape of this coat with its rest frames over `rest`; `coat` has this frame's
// frames over `posed` (the rest skin's mesh moved) and `mesh` is meshed flat from them. Every chart node
// moves with the skin point it was marched to, so a rigidly moving part of the skin carries its feathers
// rigidly and a bending part bends them with it; the feathers are placed on their carried charts. The
// drape's guarantees are enforced on the posed skin as a drape enforces them: material over a later
// follicle, vertices under the skin and the lower triangle of every crossing pair are trimmed. A feather
// whose skin, frame and flat mesh did not move is copied from the reference. The result depends on the
// reference, the posed skin and the frame's coat only. A feather on a rigidly moving piece of the skin
// (DrapeOptions::rigidPieces) is moved with it as it lay, and keeps its rest trims and its rest pairs with
// the feathers on that piece. With `out`, the carried drape is kept there
// (drapeOverMature can lay a moult over it; a later drapeCoatMesh with it lays everything). Throws Error
// when the reference is not a drape of this coat's feathers in this layer order over `rest`.
DrapeResult drapeCarried(const SkinMesh& rest, const SkinMesh& posed, const CoatFeathers& coat, TriMesh& mesh,
                         const DrapeCache& reference, const DrapeOptions& options = {}, DrapeCache* out = nullptr);

// The gap and sample spacing drapeCoatMesh would use with `options` (their "auto" values from this coat's
// charts, or the options' own). A timeline fixes them from its rest coat, so that a moult or a pose does
// not change them frame to frame (a change lays the whole coat again, DrapeCache).
struct DrapeSpacing {
  double gap = 0, spacing = 0;
};
DrapeSpacing drapeSpacing(const SkinMesh& skin, const CoatFeathers& coat, const TriMesh& mesh,
                          const DrapeOptions& options = {});

// The same, reusing what `cache` kept from its last drape where the inputs allow, and keeping this one's.
// The result equals drapeCoatMesh(skin, coat, mesh, options) bit for bit. If it throws (progress
// cancelled, bad input), the cache is cleared.
DrapeResult drapeCoatMesh(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh, const DrapeOptions& options,
                          DrapeCache& cache);

}  // namespace pteryla::coat
