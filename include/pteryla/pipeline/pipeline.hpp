#pragma once
// Pipeline: evaluates a Scene through cached stages (StageGraph). The CLI, the viewer and the tests all
// go through it. Stages and what they depend on:
//
//   skin ──> tracts ──> distribute ──> interpolate ──> directions ──┐
//                                                                   ├─> pose(t) ─> ages(t) ─> controls(t) ─> pack ─>
//                                                                   mesh
//   time ───────────────────────────────────────────────────────────┘
//
// Edits dirty only what is downstream (`invalidate`), so a packing change repacks without re-relaxing
// follicles, and a timeline scrub (setTime) re-evaluates pose, ages, controls, pack and mesh only.
// Which stage each scene section feeds: scene_stages.hpp (earliestChangedStage).
// Results are pure functions of (scene, time, lod): evaluating t=5 then t=2 equals evaluating t=2 fresh.
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pteryla/core/progress.hpp"
#include "pteryla/core/trimesh.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/pipeline/stage.hpp"

namespace pteryla::feather {
struct FeatherParams;
}
namespace pteryla::coat {
struct SkinMesh;
struct Tract;
struct Follicles;
struct CoatFeathers;
struct PackingSettings;
}  // namespace pteryla::coat

namespace pteryla::pipeline {

// What the renderer needs to draw one feather of the coat mesh (mirrors render::FeatherDrawRange
// without depending on the render module).
struct CoatDrawRange {
  uint32_t feather = 0;  // index into Pipeline::feathers()
  uint32_t firstIndex = 0, indexCount = 0;
  uint32_t material = 0;  // index into CoatMesh::materials
  glm::vec3 origin{0}, axisX{1, 0, 0}, axisY{0, 1, 0};
  uint32_t partCount[4] = {0, 0, 0, 0};  // shaft, left vane, right vane, afterfeather
};

// Materials blend between key feathers in steps of 1 / kMaterialWeightSteps of weight (issue #30 item 2;
// docs/feather-format.md, "Material blending").
inline constexpr int kMaterialWeightSteps = 8;

struct MaterialWeight {
  uint32_t material = 0;  // index into CoatMesh::materials: a feather definition's own material
  double weight = 0;      // a multiple of 1 / kMaterialWeightSteps in (0, 1)
  bool operator==(const MaterialWeight& o) const { return material == o.material && weight == o.weight; }
};

struct CoatMaterial {
  std::string name;                            // feather definition name (a blend: "a 3/8 + b 5/8")
  std::string texture, alphaTexture, pattern;  // absolute paths / pattern name ("" = none)
  glm::vec3 baseColor{0.8f, 0.7f, 0.55f};
  std::string uv = "global";           // colour texture mapping: "global", "barb" or "growth" (feather material.uv)
  std::optional<double> brdfD, brdfH;  // feather material.brdf (unset: the scene's render.brdf)
  // Non-empty: this material is the blend of these feather definitions' materials (at least two
  // different looks, ascending indices, weights summing to 1), the look of a feather interpolated from
  // key feathers. The fields above then hold the heaviest part's texture, pattern, uv and brdf and the
  // blended base colour, for consumers that do not blend (exporters, hosts).
  std::vector<MaterialWeight> blend;
  bool operator==(const CoatMaterial& o) const {
    return name == o.name && texture == o.texture && alphaTexture == o.alphaTexture && pattern == o.pattern &&
           baseColor == o.baseColor && uv == o.uv && brdfD == o.brdfD && brdfH == o.brdfH && blend == o.blend;
  }
};

// Whether a feather definition's name marks it as down: its barb alpha mask is then the sparse, fluffy
// one when its material has no alpha texture (render::sceneMaterials).
bool isDownName(const std::string& name);
// Whether two materials look the same: every field but the name, and the name's isDownName.
bool sameLook(const CoatMaterial& a, const CoatMaterial& b);

struct CoatMesh {
  TriMesh mesh;                       // all feathers, featherId per vertex
  std::vector<CoatDrawRange> ranges;  // one per present feather, in layer order
  std::vector<CoatMaterial> materials;
};

struct QualityMetrics {
  std::optional<size_t> follicles, feathers;
  std::optional<double> hexFraction, nnCv;
  std::optional<size_t> intersectingPairs, intersectingPairsUnpacked, skinPenetrations;
  // Same-geometry comparison for the unpacked count: the packed coat meshed like the unpacked one.
  std::optional<size_t> intersectingPairsProxy;
  std::optional<double> coverage;
  // Median and 90th percentile of how steeply feathers rise, degrees (packed elevation; for a draped
  // coat, the rise of the shaft over the skin).
  std::optional<double> elevationP50, elevationP90;
  // Draped coats: feathers the drape's guarantees trimmed (material over a later follicle, off or inside
  // the skin) and feathers left with no triangle.
  std::optional<size_t> fixedFeathers, hiddenFeathers;
  // Which feathers (indices into Pipeline::feathers(), the coat mesh's featherId) have a triangle that
  // intersects another feather's, and which have a vertex under the skin; ascending, each set with
  // intersectingPairs / skinPenetrations (empty when those are 0 or not computed).
  std::vector<uint32_t> intersectingFeathers, penetratingFeathers;
  // Per posed-skin triangle: the coverage samples on it and how many of them no feather covers (the
  // tracts' faces only; others have 0 samples). Bare skin is where faceUncovered is a large share.
  std::vector<uint32_t> faceSamples, faceUncovered;
};

// The unpacked coat `check` compares against: every feather at this elevation (degrees) with its own,
// unflattened barbs, from the input alone.
inline constexpr double kUnpackedElevationDeg = 10.0;

// How the last evaluation of the pack and mesh stages reused earlier work (diagnostics for tests and
// benchmarks; results never depend on it).
struct FrameReuse {
  bool naturalPacked = false;       // the controls packed the frame without its raises
  bool naturalIncremental = false;  // ... by repacking (or reusing) an earlier natural pack
  size_t naturalChanged = 0, naturalRecomputed = 0;
  bool packIncremental = false;  // the frame's pack repacked (or reused) an earlier pack
  size_t packChanged = 0;        // feathers whose packing input differed from the seed pack's
  size_t packRecomputed = 0;     // feathers whose packing was computed (0: the earlier pack was reused)
  // Moult frames: the pack* fields describe the mature coat's pack; the lost and growing feathers are
  // packed over it (coat::packOver).
  bool moult = false;
  size_t moultChanged = 0;     // lost and growing feathers
  size_t moultRecomputed = 0;  // feathers packed over the mature pack (0: the last one was reused)
  size_t meshRegenerated = 0;  // feathers whose barb curves the mesh stage generated (present ones; with
                               // instancing of a draped coat, absent ones' mature curves too)
  size_t meshReused = 0;       // present feathers whose triangles were copied from the last mesh
  // Instancing (scene render.instance_tolerance): of the meshFeathers present feathers meshed, those meshed
  // from their own curves (the others share an earlier feather's), the distinct unplaced meshes kept, and
  // the vertices of that store against the coat mesh's (equal without instancing; 24 bytes each).
  size_t meshFeathers = 0, meshRepresentatives = 0, meshDistinct = 0, meshStoredVertices = 0, meshVertices = 0;
  // Posed frames (coat::packDeformed from the rest pose's pack; packing.pose_tolerance): packs made that
  // way this frame, and over them the feathers whose surroundings moved (relative to them) beyond the
  // tolerance and the feathers packed again (those and what packs over a changed one).
  size_t deformedPacks = 0, poseMoved = 0, poseRepacked = 0;
  // Draped coats (coat::DrapeCache): feathers laid again by the mesh stage's drape, and feathers whose
  // draped vertices it copied from the last drape.
  size_t drapeRelaid = 0, drapeReused = 0;
  // Posed frames of a draped coat (packing.posed_drape "carry"): the coat was carried from the rest pose's
  // drape this frame (a moult frame: the mature coat's), with this many feathers placed on their carried
  // charts (moved by the pose, or growing); the others were copied, `drapeCarriedRigid` of them moved with
  // a rigidly moving piece of the skin (coat::DrapeOptions::rigidPieces).
  bool drapeCarried = false;
  size_t drapeCarriedMoved = 0, drapeCarriedRigid = 0;
};

// Checks a posed skin given by a caller against the rest skin: one position per rest vertex, each
// coordinate finite and within coat::kMaxMeshCoordinate. Throws pteryla::Error naming "pose" (a wrong
// count) or "vertex v". Pipeline::setSkinPose calls it; so does a host that keeps a pose itself.
void checkSkinPose(const coat::SkinMesh& rest, const std::vector<glm::dvec3>& positions);

// The least fraction of the level of detail a feather gets by screen size (render::screenSizeLods; scene
// render.lod_by_screen_size): what the memory estimate before packing assumes when rendering by size.
inline constexpr double kMinScreenLodFraction = 0.1;

class Pipeline {
 public:
  explicit Pipeline(Scene scene, ProgressFn progress = {});
  // A pipeline over a skin held in memory (the host API's Session): `skin` is the rest skin and the
  // scene's mesh path and mesh_repair are not read. Build `skin` with coat::makeSkinMesh, which checks it.
  Pipeline(Scene scene, coat::SkinMesh skin, ProgressFn progress = {});
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  const Scene& scene() const;
  // The scene's "packing" section as the pipeline reads it (parsed once per edit of the section; defaults
  // when it is empty). Throws pteryla::Error with the scene file and key path when it is malformed.
  const coat::PackingSettings& packingSettings();
  // Edits the scene and dirties `from` and everything downstream of it.
  void editScene(Stage from, const std::function<void(Scene&)>& edit);
  void invalidate(Stage from);
  void setProgress(ProgressFn progress);

  void setTime(double t);
  double time() const;
  // The posed skin's vertex positions, given by the caller (a host's own deformation), one per rest
  // vertex, finite. It replaces the scene's skeleton pose at every time; empty = back to the skeleton
  // (or the rest skin). Follicles keep their (face, barycentric) coordinates, so nothing is
  // re-distributed: only pose and later stages are dirtied. Throws pteryla::Error naming the vertex for
  // a wrong count or a non-finite coordinate.
  void setSkinPose(std::vector<glm::dvec3> positions);
  const std::vector<glm::dvec3>& skinPose() const;
  // Fixed elevations from the caller (a host's animator): follicle id (coat::Follicles::id) -> radians in
  // [0, pi/2]. They replace what packing and styling would give those feathers (PackOptions::
  // fixedElevation; controls still raise on top); ids the coat does not have are ignored. A packed
  // (height_field) coat only: a draped coat is laid along the skin. Dirties controls, pack and mesh.
  void setFixedElevations(std::map<uint64_t, double> elevations);
  const std::map<uint64_t, double>& fixedElevations() const;
  void setLod(double fraction);  // (0,1]
  double lod() const;
  // Per-feather levels of detail (indexed like feathers()), each in (0,1], multiplying lod(): feather i
  // is meshed at lod() * fractions[i] (screen-size LOD, render::screenSizeLods). Empty, or a size other
  // than the feather count (the coat changed since), meshes every feather at lod(). Throws
  // pteryla::Error naming the feather for a value outside (0,1]. Dirties only the mesh stage.
  void setFeatherLods(std::vector<double> fractions);
  const std::vector<double>& featherLods() const;

  // Results (each pulls its stage and everything upstream).
  const coat::SkinMesh& restSkin();
  const coat::SkinMesh& posedSkin();
  const std::vector<coat::Tract>& tracts();
  const coat::Follicles& follicles();
  const coat::CoatFeathers& feathers();     // interpolated, framed, aged (at the current time)
  const std::vector<double>& elevations();  // packed elevation per feather, radians
  const CoatMesh& coatMesh();
  TriMesh skinTriMesh();

  // Runs the independent checker (and an unpacked evaluation for intersecting_pairs_unpacked) on the
  // coat at full detail. The tracts' distribution metrics and the proxy coats' pair counts run as a TBB
  // task beside the full-detail mesh and the checker (the same numbers; it keeps an idle core busy).
  // Reports progress "check" through its parts on the calling thread (the mesh stage reports "mesh"
  // meanwhile); when the progress callback returns false (or throws) it stops early, after waiting for
  // that task, and returns the metrics computed so far (the rest empty).
  QualityMetrics check();

  FrameReuse frameReuse() const;

  // Packs the current frame's coat from scratch `repeats` times (coat::pack with the frame's options,
  // results discarded) and returns the fastest wall time in seconds: what a full pack costs once memory
  // is warm, without the first evaluation's page faults (pteryla bench "pack_repeat"). In a moult frame
  // it packs the mature coat (the frame's full pack; the moulting feathers are packed over it).
  double timeFullPack(int repeats);

  // Per stage (tests, benchmarks, and views that upload only what changed): completed evaluations since
  // construction, whether the next result that needs it recomputes it, the seconds of its last
  // evaluation and the seconds summed since the last resetTimings().
  uint64_t evaluations(Stage s) const;
  bool dirty(Stage s) const;
  double lastSeconds(Stage s) const;
  double stageSeconds(Stage s) const;
  void resetTimings();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pteryla::pipeline
