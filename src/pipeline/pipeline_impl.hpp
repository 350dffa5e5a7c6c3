#pragma once
// Pipeline::Impl: the state of a Pipeline, shared by pipeline.cpp (the stage graph, the time stages and
// the public API) and rest_stages.cpp (the rest stages, skin to directions).
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "coat_materials.hpp"
#include "coat_mesher.hpp"
#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/directions.hpp"
#include "pteryla/coat/drape.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/key_feathers.hpp"
#include "pteryla/coat/ordering.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/parameterize.hpp"
#include "pteryla/coat/relax.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/feather/growth.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "scene_settings.hpp"
#include "stage_graph.hpp"
#include "time_stages.hpp"

namespace pteryla::pipeline {

// Memory of a coat's geometry at level `lod` (times featherLods[f] when it has one per feather), of the
// present feathers (all when `present` is null), checked against the memory ceiling before meshing
// (docs/limits.md): barbs on both vanes and afterfeathers, 16 triangles each, 200 bytes a triangle.
// Throws pteryla::Error naming `file` and the feather with the most barbs; `what` opens the message.
void requireCoatMemory(const std::vector<feather::FeatherParams>& params, const std::vector<uint8_t>* present,
                       double lod, const std::vector<double>* featherLods, const std::string& what,
                       const std::string& file);

struct Pipeline::Impl {
  Scene scene;
  SceneSettings settings;  // the scene's sections, typed (updated with every edit of `scene`)
  ProgressFn progress;
  double time = 0, lod = 1;
  std::vector<double> featherLods;  // per feather, multiplies lod (empty: 1 for all)
  StageGraph graph;                 // node int(s) is stage s

  std::optional<coat::SkinMesh> memorySkin;   // the rest skin when given in memory (else scene.meshPath)
  std::vector<glm::dvec3> skinPose;           // the caller's posed positions (empty: skeleton / rest)
  std::map<uint64_t, double> hostElevations;  // setFixedElevations: follicle id -> radians

  // Cached stage results.
  coat::SkinMesh rest, posed;
  coat::FeatherLibrary library;
  std::vector<std::string> materialNames;
  std::vector<TractSettings> tractSettings;
  std::shared_ptr<const feather::GrowthSchedule> sceneGrowth;  // the scene's "growth" (null: none)
  std::vector<coat::Tract> tracts;
  coat::Follicles follicles, posedFollicles;
  std::vector<coat::RelaxResult> relaxResults;
  std::vector<coat::TractParameterization> params;
  coat::CoatFeathers coatRest;  // interpolated + rest frames + order
  CoatMaterials restMaterials;  // the coat's materials, per feather of coatRest (blends of key feathers' looks)
  coat::SurfaceDirections directions;
  coat::DirectionOptions directionOptions;
  coat::OrderOptions orderOptions;
  coat::PackOptions packOptions;      // the scene's "packing" knobs (PackingSettings::options)
  coat::PackConstraints constraints;  // the frame's per-feather constraints: fixedElevation below, and
                                      // the styling's minimum elevations and shaft bands
  bool moultOver = true;              // PackingSettings::moultOver
  bool carryPosedDrape = true;        // PackingSettings::carryPosedDrape
  coat::CoatFeathers coatNow;         // at the current time: posed frames, ages, presence
  coat::CoatFeathers packCoat;        // coatNow with growing feathers as grown (the pack input when any grows)
  // Makes packCoat and packGrownAge from coatNow; returns the pack input (coatNow when nothing grows).
  const coat::CoatFeathers& grownPackInput();
  std::vector<double> packGrownAge;  // per feather, the age packCoat's parameters are grown to (empty = none)
  TimeState timeState;
  std::vector<double> fixedElevation;
  const coat::PackResult* packed = nullptr;        // timeState.frame.result() once packed
  const coat::CoatFeathers* packedCoat = nullptr;  // the coat `packed` was packed from (coatNow or packCoat)
  // Draped packing (packing.method "drape"): the pack stage lays nothing (every elevation 0, `flatPack`)
  // and the mesh stage drapes the assembled mesh; `drape` is its last result.
  coat::PackResult flatPack;
  coat::DrapeResult drape;
  coat::DrapeCache drapeCache;  // the last drape, for the next frame's (its result is the same bits)
  // A timeline's drape takes its gap and sample spacing from the rest coat, mature and whole, meshed at
  // the same level of detail (drapeReference): a moult or a pose does not change them frame to frame.
  struct DrapeReference {
    InputKey rest;
    double lod = 0, gap = 0, maxSlope = 0, baseAllowance = 0;
    std::vector<double> featherLods;
    coat::DrapeSpacing spacing;
  };
  std::optional<DrapeReference> drapeRef;
  // Moult frames of a draped coat are laid over the mature coat's drape (moultOver): its own flat layout,
  // mesher, mesh and drape cache.
  coat::PackResult matureFlat;
  CoatMesher matureMesher;
  TriMesh matureMesh;
  // A drape cache that keeps every drape (another drape reads it).
  static coat::DrapeCache keptDrapes() {
    coat::DrapeCache c;
    c.keepEveryDrape();
    return c;
  }
  coat::DrapeCache matureDrapeCache = keptDrapes();
  // What the mature drape was made from; an equal next one is not meshed or draped again.
  struct MatureDrapeKey {
    InputKey rest;
    double lod = 0, gap = 0, spacing = 0, maxSlope = 0, baseAllowance = 0;
    std::vector<double> featherLods;
    std::vector<coat::FeatherFrame> frames;
    std::vector<glm::dvec3> skin;
    double instanceTolerance = 0;  // scene render.instance_tolerance (CoatMeshInput)
    bool operator==(const MatureDrapeKey& o) const;
  };
  std::optional<MatureDrapeKey> matureDrapeKey;
  // Posed frames of a draped coat are carried from the rest pose's drape (coat::drapeCarried): the coat
  // (or the mature coat of a moult frame) with its rest frames, meshed and draped over the rest skin by a
  // mesher and a drape cache of their own. The cache reuses what did not change from frame to frame.
  struct RestDrape {
    coat::CoatFeathers coat;  // with the pose reference's frames
    CoatMesher mesher;
    TriMesh mesh;
    coat::DrapeCache cache = keptDrapes();
    std::optional<MatureDrapeKey> key;  // of its last drape (with its coat's params, ages and presence)
  };
  RestDrape restDrape;
  std::vector<coat::FeatherFrame> restTurned;  // the reference's frames turned by this frame's controls
  std::optional<size_t> carried;               // this frame's mesh stage carried a drape: the feathers it placed
  size_t carriedRigid = 0;                     // and those it moved with a rigid piece of the skin
  // Drapes `frame` (this frame's coat, meshed flat into `posedMesh`) by carrying the rest pose's drape of
  // `reference` (the same feathers, or a moult frame's mature coat) meshed with `in`.
  coat::DrapeResult carryFromRest(const coat::CoatFeathers& reference, const CoatMeshInput& in,
                                  const coat::CoatFeathers& frame, TriMesh& posedMesh, const coat::DrapeOptions& o);
  const coat::DrapeSpacing& drapeReference(const coat::DrapeOptions& options);
  CoatMesh mesh;
  CoatMesher mesher;  // mesh.mesh is its last result
  // Caches of time-stage results are keyed by the rest state they were made from (restKey(): the number
  // of evaluations of the directions stage, downstream of every rest stage) and the settings sections
  // they read (SceneSettings revisions): one InputKey each.
  InputKey coatNowKey;  // the rest state coatNow was copied from coatRest at
  InputKey posedKey;    // the rest state `posed` is an untouched copy of `rest` at (empty: it is not)
  // check(): the last unpacked proxy coat and its intersecting pair count. The unpacked coat comes from
  // the input alone, so checks after edits that leave it as it was (packing, pose-free edits, LOD)
  // reuse the count instead of searching the same mesh again.
  TriMesh lastUnpacked;
  std::optional<size_t> lastUnpackedPairs;

  static StageGraph::Id id(Stage s) { return static_cast<StageGraph::Id>(s); }
  uint64_t restGeneration() const { return graph.evaluations(id(Stage::Directions)); }
  InputKey restKey() const { return {restGeneration()}; }

  void build();
  void computeSkin();
  void computeTracts();
  void computeDistribute();
  void redistributeOverlaps(uint64_t& nextId);
  void removeFollicles();  // each tract's "removed_follicles", after relaxation
  void computeInterpolate();
  coat::TractParameterization boxParameterization(uint32_t tract) const;
  void computeDirections();
  void computePose();
  void computeAges();
  void computeControls();
  void computePack();
  void computeMesh();
  bool timeMatters() const;
};

}  // namespace pteryla::pipeline
