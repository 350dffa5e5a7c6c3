#pragma once
// CoatMesher: the pipeline's mesh stage as a stateful mesher (the one-off function beside it is meshing
// every feather with feather::appendFeatherMeshes). It keeps, per feather, the barb curves and LOD order
// generated from the packed parameters (and the age while growing), and where the feather sits in the
// last mesh, unplaced. An update regenerates the curves of feathers whose inputs changed, copies the
// triangles of feathers whose curves, level of detail and sheath are unchanged from the last mesh,
// meshes the others, and places every feather again. The result equals meshing every feather afresh,
// bit for bit: a feather's vertices and indices depend only on its own input and its position in the
// mesh, and placing later applies the same arithmetic (feather::placeFeatherVertices).
//
// Instancing (CoatMeshInput::instanceTolerance > 0, feather/instancing.hpp): a mature feather whose
// curves are within the tolerance of an earlier feather's mature curves (in feather index order: over
// every feather of a coat meshed from its interpolated parameters, so representatives hold still through
// a moult; over the present mature ones of a packed coat) is meshed from that feather's curves. Unplaced meshes that
// come out identical (the same representative at the same level of detail) are kept once: the unplaced store holds one
// copy per distinct mesh, and every feather is placed from its copy. With the tolerance at 0 every feather is meshed
// from its own curves, as without.
#include <cstdint>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/core/trimesh.hpp"
#include "pteryla/feather/barbs.hpp"
#include "pteryla/feather/bend.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/feather/lod.hpp"
#include "pteryla/feather/mesh.hpp"

namespace pteryla::pipeline {

// A growing feather whose shaft is full grown is packed (and meshed) as grown at its age; any other
// growing feather is packed mature and grown from its packed parameters when meshed. A feather whose
// generator grows it its own way (a helical feather: barbs rolled on the collar, reaching below the
// rachis) is packed as grown at every growing age, so the packer sees those barbs.
bool packedAsGrown(double age, const feather::GrowthSchedule& schedule, const feather::FeatherParams& p);

// One past the last index of a feather's ranges (its parts are contiguous, shaft first).
uint32_t indexEnd(const feather::FeatherMeshRanges& r);

// One frame's input to the mesher. Every pointer must be set and stay valid during update().
struct CoatMeshInput {
  const coat::CoatFeathers* coat = nullptr;        // the frame's coat: params, frames, ages, presence, layer order
  const coat::CoatFeathers* packedCoat = nullptr;  // the coat `packed` was packed from (coat, or it with grown params)
  const coat::PackResult* packed = nullptr;        // elevations; packed key barbs (none: mesh coat's params)
  double lod = 1;                                  // (0,1]
  // Per feather, multiplies lod; ignored unless it has one entry per feather.
  const std::vector<double>* featherLods = nullptr;
  // Per feather, the shaft bend of the dynamic chain (feather/bend.hpp); ignored unless it has one entry
  // per feather; rigid entries are placed as without.
  const std::vector<feather::ShaftBend>* bends = nullptr;
  // Instancing: the largest difference, as a fraction of a feather's extent, between a mature feather's
  // curves and those it is meshed from (feather::shareCurves); 0 = off.
  double instanceTolerance = 0;
};

// What the unplaced store of the last update holds (CoatMesher::instancing).
struct InstancingStats {
  size_t feathers = 0;         // present feathers meshed
  size_t representatives = 0;  // of them, meshed from their own curves (the rest share another's)
  size_t meshes = 0;           // distinct unplaced meshes kept
  size_t vertices = 0;         // vertices of the coat mesh
  size_t storedVertices = 0;   // vertices in the unplaced store (= vertices without instancing)
  // Bytes of the unplaced store, and what it would take with a copy per feather.
  size_t storedBytes() const;
  size_t unsharedBytes() const;
};

class CoatMesher {
 public:
  // Meshes the present feathers of in.coat, in layer order, into `out` (featherId = feather index).
  // `out` must hold what the last update() wrote, or be empty: reused feathers are copied from it. Its
  // positions, normals and tangents may have been rewritten since (every vertex is placed again); before
  // rewriting its indices, call keepIndices(out).
  void update(const CoatMeshInput& in, TriMesh& out);
  // Keeps `out`'s indices for the next update, which restores them first (a draped coat trims triangles
  // of the mesh it was given).
  void keepIndices(const TriMesh& out);
  // Forgets everything: the next update meshes every feather.
  void clear();

  // Of the last update: the feather of each range (layer order, present feathers) and its index ranges.
  const std::vector<uint32_t>& feathers() const { return which_; }
  const std::vector<feather::FeatherMeshRanges>& ranges() const { return ranges_; }
  // Feathers whose barb curves were generated (present ones; with instancing of an unpacked coat, absent
  // ones' mature curves too).
  size_t regenerated() const { return regenerated_; }
  size_t reused() const { return reused_; }  // present feathers copied from the last mesh
  const InstancingStats& instancing() const { return stats_; }
  // Per feather of the last update: the feather whose mature curves it is meshed from when mature (itself
  // without instancing).
  const std::vector<uint32_t>& representatives() const { return rep_; }

 private:
  // Where a feather sits in the mesh and what it was meshed from.
  struct Slice {
    bool valid = false;
    uint32_t rep = 0;      // the feather whose curves it was meshed from (itself without instancing)
    uint64_t version = 0;  // of those curves: curvesVersion_ while growing, else matureVersion_
    bool growing = false;  // meshed from the grown curves (else the mature ones)
    double lod = 0, shed = 0;
    uint32_t v0 = 0, vn = 0, i0 = 0, in = 0;
    uint32_t u0 = 0;                    // its unplaced vertices: localPos_[u0 .. u0 + vn)
    uint64_t hash = 0;                  // of those vertices (unplacedHash)
    feather::FeatherMeshRanges ranges;  // absolute, in the mesh
  };

  static std::vector<Slice> locate(const std::vector<feather::FeatherMeshInput>& inputs,
                                   const std::vector<feather::FeatherMeshRanges>& ranges, const TriMesh& mesh);
  void resize(size_t n);
  void updateCurves(const CoatMeshInput& in, std::vector<uint8_t>& grown, std::vector<double>& shed);
  void assemble(const std::vector<feather::FeatherMeshInput>& placed, const std::vector<double>& shed, TriMesh& out);
  void updateRepresentatives(const CoatMeshInput& in, const std::vector<uint8_t>& grown);
  static bool clustersEveryFeather(const CoatMeshInput& in);
  // Rebuilds the unplaced store: every slice of `next` from the last store (reused[k]) or from `fresh`'s
  // positions, normals and tangents at src[k].v0, identical meshes kept once. Sets next[k].u0 and .hash.
  // When every slice is fresh and distinct, in order, it takes fresh's arrays (swapped, not copied).
  void storeUnplaced(const std::vector<uint8_t>& reused, const std::vector<Slice>& src, TriMesh& fresh,
                     std::vector<Slice>& next);
  // With the layout unchanged (slices_ is the last update's, as next's vertex ranges are): writes each
  // remeshed slice (changedAt, from freshMesh_ at src[k].v0) over its stored mesh when it alone holds it,
  // setting next[k].u0 and .hash; false (nothing written) when any is shared.
  bool writeStoreInPlace(const std::vector<size_t>& changedAt, const std::vector<Slice>& src, std::vector<Slice>& next);

  // Per feather: the packed parameters the mature curves and LOD order were generated from, and the age
  // (NaN = none) and packed grown parameters of the grown (pin feather) curves.
  std::vector<feather::FeatherParams> meshParams_, grownParams_;
  std::vector<uint8_t> matureValid_;
  std::vector<double> grownAge_;
  std::vector<feather::FeatherCurves> matureCurves_, grownCurves_;
  std::vector<feather::LodOrder> lodOrders_, grownOrders_;
  std::vector<uint64_t> curvesVersion_;  // bumped whenever a feather's curves are regenerated
  std::vector<uint64_t> matureVersion_;  // bumped whenever its mature curves are
  std::vector<Slice> slices_;
  // The unplaced store: positions, normals and tangents of each distinct unplaced mesh of the last update
  // (Slice::u0). No spare copy of the coat mesh is kept: an update writes changed slices in place when the
  // layout is unchanged, else builds the new mesh beside the last one and frees the last; the store is
  // built again only when a feather was meshed (docs/limits.md, bytes per triangle).
  std::vector<glm::vec3> localPos_;
  std::vector<PackedDir> localNrm_, localTan_;
  size_t meshVertices_ = 0;  // vertices of the last update's mesh
  // Instancing: the tolerance of the last update, and per feather the one whose curves it is meshed from.
  double tolerance_ = 0;
  std::vector<uint32_t> rep_;
  std::vector<uint64_t> repKey_;  // what rep_ was computed from: per feather, curvesVersion_ if clustered, else 0
  InstancingStats stats_;
  TriMesh freshMesh_;  // the changed feathers, unplaced, during an update (empty between updates)
  std::vector<uint32_t> keptIndices_;
  std::vector<uint32_t> which_;
  std::vector<feather::FeatherMeshRanges> ranges_;
  const std::vector<feather::ShaftBend>* bends_ = nullptr;  // of the current update (null: none)
  size_t regenerated_ = 0, reused_ = 0;
};

}  // namespace pteryla::pipeline
