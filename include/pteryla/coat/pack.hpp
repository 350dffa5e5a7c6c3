#pragma once
// Feather packing after Streit 2003, 6.3.2-6.3.4, 6.4 and 8.3: feathers are laid bottom to top in layer
// order; each shaft is rotated down about its bitangent B as far as the already packed feathers (and the
// skin) under it allow, then its key barbs are elevated where a neighbour would pass through them.
//
// Terms (docs/packing.md has the full description):
//  - elevation e: rotation about B from the surface tangent T (e = 0 lies flat) toward the normal N
//    (e = pi/2 stands up); docs/architecture.md "Placement with elevation e".
//  - footprint: the box the feather covers in its follicle frame, x along T from the follicle to the
//    farthest reach of shaft and barbs, y across the widest vane extent; its points are the candidates.
//  - shaft height field: candidate points projected to the NT (shaft slicing) plane, kept as the largest
//    polar angle (plus clearance) per radius bin; the smallest e that keeps the shaft polyline, extended
//    past the tip along its tangent to the footprint's reach, above it.
//  - barb height field: per key barb, candidates on the barb's side of the shaft between the neighbouring
//    key barbs' slicing planes, projected to the barb slicing plane (barb direction x dorsal) and binned
//    along the barb; the key barb's control vertices are raised in that plane only (lateral curvature kept)
//    by one flattening fraction (never past flat, so no inverse curvature) and, only if flattening cannot
//    clear the field, a rotation of the barb about its root.
//
// Each feather's key barbs are first refined: keyBarbsPerVane key barbs at uniform rp are inserted with
// the interpolated shape (the feather's shape is unchanged; the default tip barb becomes a real key barb),
// so the vane is packed at that resolution.
//
// Determinism: results are bit-identical for any thread count and between full and incremental packing.
// A feather's result depends only on its own input and on the packed points of the feathers before it
// whose reach can touch its footprint (the dependency graph); threads work on feathers whose
// dependencies are done.
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/style.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/feather/params.hpp"

namespace pteryla::coat {

namespace detail {
struct PackSkinSamples;  // the skin samples of a pack (pack_setup.cpp), kept by coat::Packer, shared with packOver
}

// How the pipeline lays the coat (pack() itself is always the height-field method):
//  - Drape (the default): every feather lies on the skin along a surface chart, stacked over what lies
//    under it by height over the skin (drape.hpp); styling elevations, expressive lifts and moult packing
//    over the mature coat are not applied;
//  - HeightField: Streit's rigid shaft rotation and barb elevation against height fields (pack()); the
//    bundled scenes use it.
enum class PackMethod { Drape, HeightField };

struct PackOptions {
  PackMethod method = PackMethod::Drape;
  double drapeMaxSlopeDeg = 45;  // drape: steepest rise of a feather over the skin, degrees
  double clearance =
      0;  // scene units kept between a feather and what is under it; 0 = auto (0.25 x median rachis width)
  double skinClearance = 0;                  // scene units kept above the skin; 0 = auto (= clearance)
  double minElevation = 0;                   // radians; lower bound for every computed elevation
  double maxElevation = 1.5707963267948966;  // radians; upper bound (pi/2 = upright)
  double conflictElevation =
      1.3962634015954636;   // radians (80 deg): height-field bins asking for more are
                            // layer-order conflicts and are ignored instead of standing the feather up
  double openingAge = 0.8;  // feathers with age < openingAge are unopened: straight shaft only, no barb elevation (8.3)
  double baseAllowance = 0.08;  // fraction of the feather's total length around the follicle where the shaft may sink
                                // into the skin (the calamus sits in the follicle); clearance ramps up over it
  double shaftBand = 1.0;       // the shaft packs against candidates within this fraction of the vane half-width
                                // of the shaft (1 = the whole vane, as in the thesis); the barbs handle the rest
  int keyBarbsPerVane = 5;      // key barbs inserted per vane at uniform rp (>= 2)
  int barbSamples = 6;          // points per key barb handed to later feathers
  int shaftSamples = 12;        // rachis segments of the shaft polyline
  int heightFieldBins = 48;     // radius bins of the shaft height field
  int barbFieldBins = 16;       // bins along a key barb of its height field
  double maxFlatten = 1.0;      // flattening fraction limit (1 = flat; up to 2 allows reverse curvature)
  bool keepBarbArcLength = false;  // a flattened key barb is scaled about its root back to its arc length (6.4)
  double maxBarbLift = 1.0;        // radians a key barb may rotate up about its root when flattening is not enough
  bool elevateBarbs = true;        // 6.3.3 barb elevation
  bool extendShaft = true;         // extend the shaft past its tip along the tip tangent to the footprint reach
  bool skin = true;                // pack against the skin surface
  double skinSampleSpacing = 0;    // scene units between skin samples; 0 = auto (0.05 x median feather reach)
  int threads = 0;                 // 0 = all available, 1 = sequential
  bool captureFields = false;      // keep every key barb height field in PackResult::barbFields (tests, debugging)
};

// Per-feather constraints on a pack, resolved outside the packer: styling selections
// (styleConstraints, style.hpp), a host's fixed elevations, expressive controls. Each vector is empty
// (no constraint) or has one entry per feather, NaN where that feather has none.
struct PackConstraints {
  std::vector<double> fixedElevation;  // radians: the feather is placed at this elevation, not packed
  std::vector<double> minElevation;    // radians: a lower bound on its packed elevation (with PackOptions')
  std::vector<double> shaftBand;       // replaces PackOptions::shaftBand for this feather
};

// The scene file's "packing" object (docs/packing.md): the packer's knobs, the styling selections the
// pipeline resolves into PackConstraints, and how the pipeline packs a moult frame.
struct PackingSettings {
  PackOptions options;
  std::vector<StyleSelection> styling;
  // Moult frames (docs/moult.md): true = the lost and growing feathers over the mature coat (packOver,
  // fast), false = a full repack of every feather (tighter).
  bool moultOver = true;
  // Posed frames (a skeleton moving the skin): packDeformed from the rest-pose pack with this tolerance, a
  // fraction of the clearance; 0 = pack every posed frame in full (docs/packing.md, "pose_tolerance").
  double poseTolerance = 0.25;
  // Posed frames of a draped coat: true = carried from the rest pose's drape (drapeCarried: every feather
  // moves with the skin under it), false = draped in full on the posed skin (docs/packing.md, "posed_drape").
  bool carryPosedDrape = true;
};

// One binned height field along an axis: h[b] is the largest height seen in [origin + b cell,
// origin + (b+1) cell); -infinity for an empty bin.
struct HeightField1D {
  double origin = 0, cell = 1;
  std::vector<float> h;
  double at(double s) const;  // value of the bin holding s (-inf outside)
};

// A captured barb height field (captureFields): feather, vane, key barb index in the packed key barbs,
// the slicing frame in world coordinates (root, along = barb direction, up = dorsal) and the field of
// raw candidate heights (without clearance) along `along`.
struct BarbField {
  uint32_t feather = 0;
  uint8_t vane = 0;
  uint16_t key = 0;
  glm::dvec3 root{0}, along{1, 0, 0}, up{0, 0, 1};
  double length = 0;  // extent of the field along the barb
  HeightField1D field;
};

struct PackStats {
  size_t packed = 0;           // feathers packed (present and in layer order)
  size_t recomputed = 0;       // feathers whose packing was computed (the rest were reused: repack)
  size_t fixed = 0;            // feathers with a fixed elevation
  size_t unopened = 0;         // packed as straight shafts (age < openingAge)
  size_t free = 0;             // no candidate constrained the shaft (rested at the skin/minimum elevation)
  size_t shaftClamped = 0;     // the height field asked for more than maxElevation
  size_t conflicts = 0;        // feathers with height-field bins above conflictElevation (ignored)
  size_t barbsElevated = 0;    // key barbs raised by flattening
  size_t barbsLifted = 0;      // key barbs that also needed the rotation fallback
  size_t barbsUnresolved = 0;  // key barbs still below their height field at the limits
  size_t candidatePoints = 0;  // candidate points examined (feather + skin)
  size_t dependencies = 0;     // edges in the dependency graph
  size_t skinSamples = 0;
  double seconds = 0;
};

namespace detail {
// Blocks of at least kHugeBlockMin bytes: 2 MiB-aligned anonymous memory advised as transparent huge pages
// (on this VM a fresh 4 KiB page costs ~13 us, a huge page ~3.5 ms per 2 MiB), from and back to a
// process-wide pool of freed blocks (src/coat/arena.cpp). Thread-safe.
inline constexpr size_t kHugeBlockMin = size_t(4) << 20;
void* allocateHugeBlock(size_t bytes);
void freeHugeBlock(void* block);
}  // namespace detail

// An allocator that leaves default-constructed values uninitialised: PackResult::points is sized before
// the feathers are packed and every slot is then written once, so zero-filling it first only touched ~19 MB
// of fresh memory twice (serially) on the bird. Buffers of 4 MiB or more are whole huge pages
// (detail::allocateHugeBlock), so none of their pages is faulted in 4 KiB at a time.
template <class T>
struct UninitializedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  UninitializedAllocator() = default;
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  T* allocate(size_t n) {
    if (n * sizeof(T) >= detail::kHugeBlockMin) return static_cast<T*>(detail::allocateHugeBlock(n * sizeof(T)));
    return std::allocator<T>::allocate(n);
  }
  void deallocate(T* p, size_t n) noexcept {
    if (n * sizeof(T) >= detail::kHugeBlockMin)
      detail::freeHugeBlock(p);
    else
      std::allocator<T>::deallocate(p, n);
  }
  template <class U, class... A>
  void construct(U* p, A&&... a) {
    if constexpr (sizeof...(A) == 0)
      ::new (static_cast<void*>(p)) U;
    else
      ::new (static_cast<void*>(p)) U(std::forward<A>(a)...);
  }
};
using PackedPoints = std::vector<glm::vec4, UninitializedAllocator<glm::vec4>>;
using PackedGroupBounds = std::vector<glm::vec4, UninitializedAllocator<glm::vec4>>;

// Every feather's packed key barbs in a few flat arrays (the bird's 110k key barbs used to be as many
// small vectors in per-feather FeatherParams copies: ~23 MB of fresh memory in 4 KB pages, faulted in one
// by one in every first pack). Feather i's key barbs are k = keyOffset[i] .. keyOffset[i+1]: the left
// vane's first (leftKeys[i] of them), each vane by ascending rp, the afterfeather's not included; key k
// lies at rp[k] with control vertices cvs[cvOffset[k] .. cvOffset[k+1]) (barb-local unit frame, as
// feather::KeyBarb::cvs). replaced[i] = 0 for feathers that keep their input key barbs (not packed:
// absent, or unopened and packed as a straight shaft); they have no keys here. packedParams() below
// rebuilds a feather's parameters from these and the coat that was packed.
struct PackedKeyBarbs {
  std::vector<uint32_t> keyOffset;                         // feathers + 1
  std::vector<uint32_t> leftKeys;                          // per feather
  std::vector<uint8_t> replaced;                           // per feather
  std::vector<double, UninitializedAllocator<double>> rp;  // per key barb
  std::vector<uint32_t> cvOffset;                          // key barbs + 1
  std::vector<glm::dvec3, UninitializedAllocator<glm::dvec3>> cvs;
};

struct PackResult {
  std::vector<uint32_t> order;        // layer order used (copy of CoatFeathers::layerOrder)
  std::vector<double> elevation;      // radians per feather (0 for feathers not packed)
  PackedKeyBarbs packedKeys;          // per feather: the elevated key barbs (packedParams())
  std::vector<uint8_t> barbsChanged;  // 1 when fitting raised any of feather i's key barbs
  std::vector<uint8_t> recomputed;    // 1 when this call computed feather i (else reused)
  // Packed geometry handed to later feathers, world coordinates: xyz and a thickness radius (shaft
  // points carry the shaft radius, barb points 0). Points of feather i: points[pointOffset[i] .. [i+1]).
  std::vector<uint32_t> pointOffset;
  PackedPoints points;
  std::vector<glm::dvec4> bounds;  // per feather: sphere (centre, radius) around its points
  // Point groups (the shaft, then each key barb's samples) with bounding spheres, for culling: the groups
  // of feather i are groupOffset[i] .. [i+1]; group g holds points groupPoint[g] .. groupPoint[g+1].
  std::vector<uint32_t> groupOffset, groupPoint;
  PackedGroupBounds groupBounds;
  std::vector<BarbField> barbFields;  // captureFields only
  PackStats stats;
  // The automatic values this pack resolved (the options' own values when they were given): scene-unit
  // clearances and the median feather reach that sizes the skin sample spacing. packOver packs with them.
  double clearance = 0, skinClearance = 0, medianReach = 0;
  // The skin samples (and their patches) this pack used, for packOver and coat::Packer on the same skin.
  std::shared_ptr<const detail::PackSkinSamples> skinSamples;
};

// The free functions below are a coat::Packer (packer.hpp) used once. A caller that packs one skin again
// and again holds a Packer instead: it keeps the skin samples and its last result while they fit.

// Packs every present feather of `coat` (in coat.layerOrder, or index order when it is empty) against
// the feathers packed before it and the skin. Throws Error for inconsistent input (array sizes, indices).
PackResult pack(const SkinMesh& skin, const CoatFeathers& coat, const PackOptions& options = {},
                const PackConstraints& constraints = {});

// Incremental repack after a small change: `changed` lists the feathers whose input differs from the
// one `previous` was computed from (frame, params, age, presence or fixed elevation). Only feathers whose
// dependency chain reaches a changed feather are recomputed; the result equals pack() bit for bit. Falls
// back to a full pack when the layer order or feather count changed. The skin, the options and the
// constraints (other than fixed elevations, whose changes belong in `changed`) must be those `previous`
// was packed with (a `previous` packed on another skin gives a full pack); after a skin deformation every
// frame changes: call pack(). When the changes move the clearances or the median reach resolved over the
// whole coat, every feather is recomputed.
PackResult repack(const SkinMesh& skin, const CoatFeathers& coat, const PackResult& previous,
                  const std::vector<uint32_t>& changed, const PackOptions& options = {},
                  const PackConstraints& constraints = {});

// Packs only the feathers in `changed` over `base`: every other present feather keeps its pose, barbs and
// points from `base` exactly, and the changed ones are packed in layer order against what lies under them
// (base's feathers, and the changed feathers packed before them), with base's clearances and skin
// samples. Absent feathers (coat.present) are left out: nothing packs against them. This is the moult's
// pack (docs/moult.md): `base` is the pack of the coat with every feather mature, `changed` the lost and
// growing feathers, so a lost feather leaves a gap and a growing one fills in under the feathers over it.
// Unlike repack(), feathers over a changed one are not repacked, so the result is not a full pack's; it
// is a function of (skin, coat, base, changed set, options) only. `base` must come from pack()/repack()
// on the same skin with the same options and feather count, and every present feather of `coat` must be
// packed in `base` in the same relative layer order; else Error.
PackResult packOver(const SkinMesh& skin, const CoatFeathers& coat, const PackResult& base,
                    const std::vector<uint32_t>& changed, const PackOptions& options = {},
                    const PackConstraints& constraints = {});

// What packDeformed did: feathers whose surroundings moved relative to them by more than the tolerance,
// feathers packed (those and what packs over a changed one; the rest were carried from the reference),
// and the tolerance in scene units.
struct DeformedPackStats {
  size_t moved = 0, repacked = 0;
  double toleranceUnits = 0;
};

// The coat packed on a deformed skin (a posed frame, Streit 2003 8.3) from a reference pack `ref`: the pack
// (pack() or repack()) of the same coat, options and constraints with the feathers' frames `refFrames` on
// `refSkin` (the rest skin, same topology as `skin`). Each feather's motion is the rigid motion taking its
// reference frame to coat.frames[i]. A feather whose skin (the reference skin within its reach) and whose
// feathers under it (reference or posed dependencies) all moved with its own motion to within
// `tolerance` x the pack's clearance keeps its reference packing (elevation and key barbs, follicle-frame
// values) with its points carried by that motion. The others are packed again on `skin`, in layer order,
// with every feather that packs against one whose points moved more than the tolerance from the carried
// reference. The result is a function of its arguments only (not of any earlier frame). tolerance 0, a
// reference that does not fit the coat, or options.captureFields: a full pack(). Error for a tolerance
// that is negative or not finite, or frames or skins that do not match the coat.
PackResult packDeformed(const SkinMesh& skin, const CoatFeathers& coat, const SkinMesh& refSkin,
                        const std::vector<FeatherFrame>& refFrames, const PackResult& ref, double tolerance,
                        const PackOptions& options = {}, const PackConstraints& constraints = {},
                        DeformedPackStats* stats = nullptr);

// Feathers whose packing input differs between two coats of equal size (frame, params, age, presence),
// plus those whose fixed elevation differs between two constraint sets.
std::vector<uint32_t> changedFeathers(const CoatFeathers& before, const CoatFeathers& after,
                                      const std::vector<double>& fixedBefore = {},
                                      const std::vector<double>& fixedAfter = {});

// Placement (docs/architecture.md): world position of feather-local point p for frame f and elevation e.
glm::dvec3 placePoint(const FeatherFrame& f, double elevation, const glm::dvec3& p);
// World direction of feather-local direction d.
glm::dvec3 placeDirection(const FeatherFrame& f, double elevation, const glm::dvec3& d);

// Feather i's parameters as packed: coat.params[i] with its vanes' key barbs replaced by the packed ones
// (coat must be the coat `result` was packed from, or one with the same parameters). `Into` reuses out's
// storage; `Equal` compares without building them; `all` gives every feather's (e.g. for proxyCoatMesh).
feather::FeatherParams packedParams(const CoatFeathers& coat, const PackResult& result, uint32_t feather);
void packedParamsInto(const CoatFeathers& coat, const PackResult& result, uint32_t feather,
                      feather::FeatherParams& out);
bool packedParamsEqual(const feather::FeatherParams& p, const CoatFeathers& coat, const PackResult& result,
                       uint32_t feather);
std::vector<feather::FeatherParams> allPackedParams(const CoatFeathers& coat, const PackResult& result);

// World-space control vertices of every key barb of feather i as packed (effective key barbs of
// packedParams(coat, result, i), placed with result.elevation[i]): one vector per key barb, left vane first.
struct PlacedKeyBarb {
  uint8_t vane = 0;
  double rp = 0;
  std::vector<glm::dvec3> cvs;                      // world coordinates
  glm::dvec3 root{0}, along{1, 0, 0}, up{0, 0, 1};  // barb slicing frame (world)
  double length = 0;                                // barb length (scene units)
};
std::vector<PlacedKeyBarb> placedKeyBarbs(const CoatFeathers& coat, const PackResult& result, uint32_t feather);

// Reads a scene's "packing" object (docs/packing.md). Unknown keys are errors.
PackingSettings parsePackingSettings(JsonReader& r);
Json packingSettingsToJson(const PackingSettings& s);
// `o` with the packer's default sampling (key barbs per vane, barb and shaft samples, field bins, skin
// sample spacing) and everything else (clearances, styling, threads...) kept: what a scene's denser
// sampling costs (bench_pack, pack_digest).
PackOptions withDefaultSampling(PackOptions o);

}  // namespace pteryla::coat
