#pragma once
// The host API: what a program outside this repository (a DCC plug-in, a game tool, a script binding)
// uses to feather its own mesh. This header and what it includes (core/error.hpp, core/data_dir.hpp,
// export.hpp and the utilities below) are what `cmake --install` ships; they use standard C++17 only (no
// JSON, GL, TBB, CGAL, OpenMesh or GLM types), and the rest of the library stays behind them.
//
// A Session is stateful, in the style of geometry-central's solvers: build it once from the rest skin
// and a coat set-up, then each frame hand it the posed skin (setPose) and/or a time (setTime),
// evaluate(), and read the frame's flat arrays. Only what changed is recomputed: a new pose or time
// re-frames, re-packs and re-meshes the coat but never re-distributes follicles, which stay attached to
// the skin by (face, barycentric) coordinates.
//
//   pteryla::SkinArrays skin;            // the host's rest mesh
//   skin.positions = {...};              // x, y, z per vertex
//   skin.triangles = {...};              // 3 vertex indices per face, counter-clockwise from outside
//   pteryla::CoatSetup setup;            // defaults: one tract over the whole skin, contour feathers
//   pteryla::Session session(skin, setup);
//   for (each frame) {
//     session.setPose(posedPositions);   // same vertex count and order as skin.positions
//     if (!session.evaluate(progress)) break;   // the progress callback returned false
//     const pteryla::Frame& f = session.frame();
//     draw(f.positions, f.indices);
//   }
//
// Errors. Bad input (arrays, set-up, scene file, feather file) throws pteryla::Error with file() (""
// for in-memory input), element() (where: "positions", "vertex 17", "tracts[2].faces[5]"; set-up
// fields are named by their scene-format key where they have one, "tracts[0].feather_scale", else by
// the field, "tracts[0].featherFile") and detail(). A broken invariant inside the library throws
// pteryla::InternalError. A call that throws leaves the session as it was, except evaluate() and
// metrics(), after which frame() is unavailable until an evaluate() completes. The library never
// calls exit().
//
// Threads. A Session is not thread-safe: use it from one thread at a time (it runs TBB inside).
// Evaluating separate Sessions concurrently is not tested yet.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pteryla/core/data_dir.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/export.hpp"
// Utilities a host shares with the library (and the CLI uses): the memory ceiling and quiet output of
// the whole process, paths, SHA-256, files written through a temporary name, images and comparing them.
#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/limits.hpp"
#include "pteryla/core/memory.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/core/quiet.hpp"
#include "pteryla/core/sha256.hpp"
#include "pteryla/render/image.hpp"
#include "pteryla/render/image_diff.hpp"

namespace pteryla {

// The library's version (PROJECT_VERSION of its CMakeLists.txt), e.g. "0.1.0".
PTERYLA_API const char* version();

// The rest skin, held by the caller. A triangle mesh that is finite, free of degenerate faces,
// edge-manifold and consistently oriented (docs/limits.md for the coordinate limits); `repair` instead
// drops or fixes what is not (vertex indices are never renumbered, so poses stay aligned).
struct SkinArrays {
  std::vector<double> positions;        // x, y, z per vertex (scene units)
  std::vector<uint32_t> triangles;      // 3 vertex indices per face, counter-clockwise seen from outside
  std::vector<std::string> groupNames;  // optional face groups, selected by TractSetup::groups
  std::vector<int32_t> faceGroups;      // empty, or per face: index into groupNames (-1 = none)
  bool repair = false;                  // repair instead of refusing (docs/scene-format.md "mesh_repair")
};

// A feather tract (Streit 2003, 6.1): a set of skin faces carrying one kind of feather.
struct TractSetup {
  std::string name;                 // required, unique
  std::vector<std::string> groups;  // faces of these groups, united with `faces`;
  std::vector<uint32_t> faces;      // ... these faces (triangle indices). Neither: the whole skin
  size_t count = 0;                 // exact number of follicles, or
  double density = 0;               // follicles per unit area (count 0). Both 0: 3,000 x area share
  std::string featherFile;          // feather definition (docs/feather-format.md); "" = bundled contour
  double featherScale = 0;          // multiplies every feather length; 0 = "auto": mean length =
  double featherSpacings = 3.5;     //   featherSpacings x the follicle spacing
  int relaxIterations = 40;         // Lloyd relaxation of the follicles (6.1)
  std::optional<uint64_t> seed;     // this tract's own follicle seed: changing it re-scatters only this
                                    //   tract; unset = derived from CoatSetup::seed and the tract's index
  bool moult = true;                // false: this tract keeps its feathers when CoatSetup::moult is enabled
};

// Feather replacement over time (Streit 2003, 8.2; docs/moult.md, where each key is explained): a window
// moves through each tract's feathers from `start` to `start + duration`; feathers in it are lost, then
// regrow. Tracts with TractSetup::moult false keep their feathers.
struct MoultSetup {
  bool enabled = false;                 // off: no feather is ever lost
  double start = 0;                     // time the window enters the order
  double duration = 1;                  // time until the last feather is renewed (> 0)
  double window = 0.2;                  // (0, 1]: feathers moulting at once, as a fraction of the tract
  std::string sequence = "centre_out";  // docs/moult.md: centre_out, boundary_in, increasing_u, radial, random ...
  double gap = 0.05;                    // [0, 1): fraction of a feather's window with no feather
  double random = 0;                    // [0, 1]: jitter of the order
  uint64_t seed = 1;                    // of sequence "random" and the jitter
};

// One key of an expressive control's animation (docs/controls.md): the attributes it sets at time t, each
// in [0, 1]; each attribute is its own track (unset: no key of that track here).
struct ControlKey {
  double t = 0;
  std::optional<double> lift, aim, direction, random, dynamic;
  std::optional<std::array<double, 3>> offset;  // displacement of the control off the skin
};

// An expressive control (Grier 2019, "AnimFur"; docs/controls.md): placed on the skin at `at`, it binds
// the feathers within `radius` and raises (lift), aims, turns (direction), twists (random) and lags
// (dynamic) them as its keys say. Raises need a packed coat (CoatSetup::Packing::HeightField: the rest
// of the coat is packed against the raised feathers); a draped coat takes the turns only.
struct ControlSetup {
  std::string name;
  std::array<double, 3> at{{0, 0, 0}};   // rest coordinates, snapped to the skin
  double radius = 0;                     // > 0
  double falloff = 0;                    // [0, 1]: outer fraction of the radius where the weight fades
  std::vector<std::string> tracts;       // tracts it may bind (empty: any)
  std::vector<ControlKey> keys;          // at least one
  std::string interpolation = "linear";  // "linear", "smooth" or "step" between keys
  uint64_t seed = 1;                     // random twist multipliers
  double twistAngleDeg = 45;             // twist at random = 1, [0, 180]
  double maxLiftDeg = 90;                // elevation at lift = 1, [0, 90]
};

// The coat set-up a Session is built from. It covers what maps cleanly onto the scene format; the
// rest (key feathers and interpolation, pinned follicles, density bias, label files and tract set
// operations, styling vectors, per-tract directions, packer knobs and styling, per-tract moult
// schedules, skeleton, control springs) is only reachable through a scene file: Session::fromSceneFile.
struct CoatSetup {
  std::vector<TractSetup> tracts;  // empty: one tract "all" over the whole skin
  // Body axis, head to tail (>= 2 distinct points): feathers point along it (6.3.1) and, with
  // Ordering::Axis, are layered along it like roof tiles. Empty: the longest axis of the skin's
  // bounding box, as for a bare mesh.
  std::vector<std::array<double, 3>> axis;
  enum class Ordering { Axis, Tracts, Flow };  // layer order for packing (docs/coat.md)
  Ordering ordering = Ordering::Axis;
  std::vector<std::string> tractOrder;        // Ordering::Tracts: tract names, bottom layer first
  enum class Packing { Drape, HeightField };  // docs/packing.md
  Packing packing = Packing::Drape;
  uint64_t seed = 1;                   // same skin + set-up + seed = same coat, bit for bit
  MoultSetup moult;                    // off by default
  std::vector<ControlSetup> controls;  // expressive controls (none by default)
};

// Progress of evaluate(): stage name ("distribute", "interpolate", "pack", "mesh"; the skin and the
// feathers are read by the constructor) and fraction in [0, 1]. Return false to cancel.
using Progress = std::function<bool(const std::string& stage, double fraction)>;

// How a pose given to Session::setPose moves the coat.
enum class PoseMode {
  // Re-frame, repack and re-drape the coat on the posed skin (Streit 2003, 8.3): the packing's guarantees
  // hold at every pose; a pose costs a full evaluation of the time stages.
  Repack,
  // Lay the coat once on the base skin (the rest skin, or a scene skeleton's pose at the session's time)
  // and let the posed skin carry it: every coat vertex and follicle keeps its offset in the local frame of
  // its nearest base-skin point (coat/skin_binding.hpp). Elevations and drape stay as laid on the base
  // ("fixed elevations"); feathers bend with the skin. A pose costs one pass over the coat's vertices
  // (docs/architecture.md, "Host API", has the numbers). frame()'s origins, normals, tangents, binormals, positions and
  // vertexNormals are the carried ones; elevations are the base's.
  Follow,
};

// A read-only view of an array the Session owns.
template <class T>
struct View {
  const T* data = nullptr;
  size_t size = 0;
  const T& operator[](size_t i) const { return data[i]; }
  const T* begin() const { return data; }
  const T* end() const { return data + size; }
  bool empty() const { return size == 0; }
};

// The triangles of feather `feather` in Frame::indices: [firstIndex, firstIndex + indexCount).
struct FeatherRange {
  uint32_t feather = 0;
  uint32_t firstIndex = 0, indexCount = 0;
  uint32_t material = 0;  // index into Frame::materials
};

// What a host needs to shade one kind of feather: one per feather definition the coat uses.
struct Material {
  std::string name;          // the feather definition's name (its scene key, or its file's stem)
  std::string texture;       // absolute path of the colour texture, "" = none (use baseColor)
  std::string alphaTexture;  // absolute path of the alpha texture, "" = none (use Frame::alphas)
  std::string pattern;       // procedural pattern name, "" = none
  std::array<float, 3> baseColor{{0.8f, 0.7f, 0.55f}};  // linear RGB
  std::string uv = "global";  // which texture coordinates the colour texture uses: "global" (Frame::uvs),
                              //   "barb" or "growth" (Streit 7.1.1; not in Frame yet: render() uses them)
};

// One evaluated frame. Every view stays valid until the next non-const call on the Session.
// Feathers are indexed 0..featherCount-1 in a fixed order for the life of the session.
struct Frame {
  size_t featherCount = 0;
  // Per feather.
  View<uint64_t> follicleKeys;  // stable key of the feather's follicle: the same across poses, times
                                //   and sessions built from the same skin, set-up and seed
  View<uint32_t> tracts;        // tract index (CoatSetup::tracts order, or the scene's)
  View<uint8_t> present;        // 0 = moulted out at this time (no triangles)
  View<double> origins;         // 3 per feather: the follicle on the posed skin
  View<double> normals;         // 3 per feather: N, unit skin normal
  View<double> tangents;        // 3 per feather: T, unit feather direction in the tangent plane
  View<double> binormals;       // 3 per feather: B = N x T (docs/architecture.md "Frames")
  View<double> elevations;      // radians: the rotation about B the feather was placed at (0 = flat
                                //   along T); a draped coat is placed flat and bent over the skin
  // The coat mesh: all present feathers, bottom layer first.
  View<float> positions;          // 3 per vertex
  View<float> vertexNormals;      // 3 per vertex, unit
  View<float> uvs;                // 2 per vertex: feather-global texture coordinates (Streit 7.1.1)
  View<float> alphas;             // 1 per vertex: opacity (7.1.2), or empty
  View<uint32_t> vertexFeathers;  // feather index per vertex
  View<uint32_t> indices;         // 3 per triangle
  View<FeatherRange> ranges;      // one per present feather, bottom layer first
  View<Material> materials;       // indexed by FeatherRange::material
};

// The independent checker's numbers (pteryla check; docs/packing.md). Unset = not measured.
struct Metrics {
  std::optional<size_t> follicles, feathers;
  std::optional<double> hexFraction, nnCv;              // follicle layout: hexagonal cells, spacing CV
  std::optional<size_t> intersectingPairs;              // triangle pairs of different feathers
  std::optional<size_t> intersectingPairsUnpacked;      // ... of the coat before packing
  std::optional<size_t> intersectingPairsProxy;         // ... of the packed coat meshed like that one
  std::optional<size_t> skinPenetrations;               // coat vertices under the skin
  std::optional<double> coverage;                       // fraction of tract area under feathers
  std::optional<double> elevationP50, elevationP90;     // degrees
  std::optional<size_t> fixedFeathers, hiddenFeathers;  // draped coats: trimmed, and left empty
  // The feathers (Frame indices) with a triangle crossing another feather's, and with a vertex under the
  // skin; ascending (empty when intersectingPairs / skinPenetrations is 0 or unset).
  std::vector<uint32_t> intersectingFeathers, penetratingFeathers;
};

// Export for other tools (docs/export.md); the format follows the extension of the path: .glb, .gltf
// (glTF 2.0), .usda (USD), .obj, .ply.
struct ExportSettings {
  std::string coatAs = "curves";  // USD coat: "curves" (BasisCurves), "cards" (Mesh), "instances" (PointInstancer)
  std::vector<double> times;      // empty: the session's time; else one frame per time, increasing (not OBJ/PLY)
  double fps = 24;                // frames per unit of time: the animation timing of `times`
  double metersPerUnit = 1;       // USD metersPerUnit
};
struct ExportSummary {
  size_t bytes = 0;  // size of the file written
  size_t frames = 0;
  size_t feathers = 0;      // in the last frame written
  size_t triangles = 0;     // coat and skin triangles of the last frame (cards, glTF, OBJ, PLY)
  size_t curves = 0;        // USD curves: rachis and barb curves of the last frame
  size_t instances = 0;     // USD instances: feathers instanced, and
  size_t prototypes = 0;    //   the prototype feathers they share
  double seconds = 0;       // evaluating the frames and writing
  double writeSeconds = 0;  // of which writing the file
};
// The times of a frame range from..to (inclusive) at `fps` frames per unit of time, as `pteryla export
// --from --to --fps` and `pteryla frames` sample it. Throws pteryla::Error naming "from", "to" or "fps"
// for a non-finite value, from > to or fps <= 0.
PTERYLA_API std::vector<double> exportFrameTimes(double from, double to, double fps);
// Refuses, before anything is evaluated, what Session::exportTo would refuse for these settings: an
// unknown extension, a coat form the format cannot carry, several times in an OBJ or PLY file, a bad
// metersPerUnit or fps, times not increasing. Throws pteryla::Error naming the path or the setting.
PTERYLA_API void checkExportSettings(const std::string& path, const ExportSettings& settings);

// Session::render: an image of the frame through Mesa's off-screen OpenGL (llvmpipe; no display or GPU).
struct RenderSettings {
  int width = 0, height = 0;  // pixels, each in [1, 16384]; 0 and 0 = the scene's render.size (960x720)
  std::string style;          // "" = the scene's render.style; "shaded" or "scratchboard" (docs/render.md)
};
// What Session::render drew.
struct RenderSummary {
  int width = 0, height = 0;
  size_t feathers = 0;   // feathers drawn (present at the frame's time)
  size_t triangles = 0;  // coat triangles drawn
};

// Seconds each stage of the pipeline took the last time it ran (0 for a stage that has not run), for
// profiling a host's set-up (`pteryla bench` prints them).
struct StageSeconds {
  double skin = 0, tracts = 0, distribute = 0, interpolate = 0, directions = 0, pack = 0, controls = 0, mesh = 0;
};

// Session::fromSceneFile's options.
struct SceneFileOptions {
  std::optional<uint64_t> seed;  // replaces the scene's master seed (the file's "seed")
  // Replaces the scene's render.lod_by_screen_size (default true: render and renderImage mesh each
  // feather at lod() times a fraction that follows its size on screen, so lod() is the cap; false: every
  // feather at lod(), a fixed level; docs/render.md). evaluate() before any render meshes every feather at
  // lod(); after a render, frame() is the coat that render drew.
  std::optional<bool> lodByScreenSize;
  // Replaces the scene's render.instance_tolerance (default 0, off): mature feathers whose barb curves are
  // within this fraction of their extent of an earlier feather's are meshed from that feather's curves, so
  // identical unplaced meshes are kept once (docs/limits.md, "Instancing"). In [0, 0.1].
  std::optional<double> instanceTolerance;
  Progress progress;  // reports of reading the skin and tracts, and then of every evaluation
                      // until setProgress replaces it (see setProgress)
};

// One feather definition file (docs/feather-format.md) on its own, as `pteryla feather` makes it: built
// at a growth age and a level of detail, written as a mesh (.obj, .ply) or rendered (.png, width x height,
// through Mesa's off-screen OpenGL). The output's directory is created once the feather is built, so a
// bad file leaves nothing behind. Throws pteryla::Error naming the file or setting. Returns the triangles.
struct FeatherOutput {
  double age = 1;                 // growth age: (0, 1] grows (Streit 8.1), above 1 wears
  double lod = 1;                 // fraction of barbs meshed, (0, 1]
  int width = 512, height = 512;  // .png only, each in [1, 16384]
};
PTERYLA_API size_t writeFeather(const std::string& featherFile, const std::string& out,
                                const FeatherOutput& output = {});

// A feather measured from a flatbed scan (Streit 2003, 5.2.3; docs/feather-format.md, "Feathers from
// scans"), as `pteryla feather --from-scan` makes it: writes the feather file `out` (.json) and, unless
// told not to, the scan resampled into the feather's texture space as its colour texture beside it.
struct ScanSettings {
  std::vector<std::array<double, 2>> rachis;  // pixels (x right, y down), base to tip; empty = found
  double pixelsPerUnit = 0;  // scan pixels per scene unit; 0 = the image's resolution (per cm), else 300 dpi
  std::string texture;       // the texture file (.png); "" = out's name + "_texture.png"
  bool writeTexture = true;  // false: no texture (the feather keeps its default look)
};
struct ScanSummary {
  bool rachisDetected = false;                    // the rachis was found, not given
  double pixelsPerUnit = 0;                       // what the measurement used, and where it came from:
  std::string resolution;                         // "pixelsPerUnit", "the image's resolution" or "300 dpi assumed"
  double rachisLength = 0, lateralCurvature = 0;  // scene units, radians
  double spacingBase = 0, spacingTip = 0;         // barb spacing (scene units)
  double leftBaseAngle = 0, leftTipAngle = 0, rightBaseAngle = 0, rightTipAngle = 0;  // radians
  std::string texture;                                                                // the texture written ("" = none)
  std::vector<std::string> notes;  // what could not be measured and which default was kept
};
// Throws pteryla::Error naming the file and "scan", "rachis", "pixelsPerUnit", "texture" or "out".
PTERYLA_API ScanSummary writeFeatherFromScan(const std::string& scanImage, const std::string& out,
                                             const ScanSettings& settings = {});

class PTERYLA_API Session {
 public:
  // Checks the skin (pteryla::Error naming "positions", "triangles", "vertex 5", "face 17", ...) and the
  // set-up (its tracts' faces and groups, its feather files) before returning.
  Session(const SkinArrays& skin, const CoatSetup& setup);
  // A scene file (docs/scene-format.md) or a bare mesh (.obj/.ply/.off/.stl): the only door through
  // which the library reads JSON from the caller. Paths inside resolve against the file.
  static Session fromSceneFile(const std::string& path, const SceneFileOptions& options = {});

  Session(Session&&) noexcept;
  Session& operator=(Session&&) noexcept;
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  ~Session();

  size_t vertexCount() const;  // of the rest skin (what setPose expects)
  size_t faceCount() const;

  // The posed skin: x, y, z per vertex, the rest skin's vertex count and order, finite. Throws
  // pteryla::Error ("positions" for a wrong length, "vertex 17" for a bad coordinate) and keeps the
  // last pose. The pose replaces a scene skeleton's pose at every time.
  void setPose(const std::vector<double>& positions);
  void setPose(const float* xyz, size_t vertexCount);
  void clearPose();  // back to the rest skin (or the scene's skeleton)
  // Fixed elevations (an animator's choice): per follicle key (Frame::follicleKeys), radians in [0, pi/2]
  // above the skin's tangent plane, replacing what packing would give those feathers (expressive controls
  // of a scene file still raise on top). Replaces the whole set; empty = none. A packed coat only
  // (CoatSetup::Packing::HeightField): a draped coat is laid along the skin, and this throws. Throws
  // pteryla::Error naming "follicleKeys[i]" for a key the coat does not have, "elevations[i]" for a
  // value out of range, and keeps the last set.
  void setFixedElevations(const std::vector<uint64_t>& follicleKeys, const std::vector<double>& elevations);
  // PoseMode::Repack (default) or Follow. Switching keeps the pose the host gave.
  void setPoseMode(PoseMode mode);
  PoseMode poseMode() const;
  // Evaluation time (moult, skeleton and controls of a scene file; nothing changes with time otherwise).
  void setTime(double t);
  double time() const;
  // Fraction of barbs meshed, in (0, 1] (Streit 7.1.3). Only the mesh is redone.
  void setLod(double fraction);
  double lod() const;
  // Instancing (the scene's render.instance_tolerance; docs/limits.md, "Instancing"): mature feathers whose
  // barb curves are within this fraction of their extent of an earlier feather's are meshed from that
  // feather's curves, and identical unplaced meshes are stored once. In [0, 0.1]; 0 = off, every feather
  // meshed from its own curves. Only the mesh is redone.
  void setInstanceTolerance(double fraction);
  double instanceTolerance() const;

  // Brings the frame up to date. Returns true when done; false when `progress` returned false, which
  // stops evaluation at once: the session keeps every stage completed before the cancel, frame() is
  // unavailable until an evaluate() completes, and the next evaluate() carries on from there.
  [[nodiscard]] bool evaluate(const Progress& progress = {});
  // The last complete evaluation. Throws pteryla::Error when an input changed since (call evaluate()).
  const Frame& frame() const;
  // Runs the independent checker on the current frame at full detail (evaluates first if needed).
  // frame() stays valid if it was (a session that only checks never meshes at its own level of detail).
  // Throws with a PoseMode::Follow pose set (it checks what the pipeline laid). Costs more than an
  // evaluation: it also meshes and checks the unpacked coat.
  Metrics metrics();
  // Writes the last complete evaluation's coat mesh (frame()) as Wavefront OBJ or PLY, chosen by the
  // extension of `path` (".obj", ".ply"); PLY carries every vertex attribute (feather/mesh_io.hpp). Throws
  // pteryla::Error like frame() when there is no evaluated frame, and naming the file when it cannot
  // be written or the extension is neither.
  void exportMesh(const std::string& path) const;

  // Writes the coat and the skin at the session's pose to `path` (ExportSettings), evaluating each time
  // of settings.times (the session's time is kept). Not for a PoseMode::Follow pose yet (throws; use
  // exportMesh for the frame). The file is written to a temporary and renamed: a
  // failure throws pteryla::Error naming the file or setting and keeps any previous file. frame() stays
  // valid if it was.
  ExportSummary exportTo(const std::string& path, const ExportSettings& settings = {});

  // Renders the frame (evaluating first if needed) with the scene's camera (a typed set-up's frames the
  // skin), lights and feather materials, as `pteryla render` does, and writes it to `path` (.png, .jpg,
  // .tif, .exr) through a temporary file renamed on success. libOSMesa is loaded on the first call:
  // without it, or for a bad size, style or path, throws pteryla::Error naming it. Not for a
  // PoseMode::Follow pose yet (throws). frame() stays valid if it was. With screen-size levels of detail
  // (the scene's render.lod_by_screen_size, default on; SceneFileOptions::lodByScreenSize) it first sets
  // each feather's level from its size in this image and meshes the coat once at those levels.
  RenderSummary render(const std::string& path, const RenderSettings& settings = {});
  // The same image, in memory.
  render::Image renderImage(const RenderSettings& settings = {});
  // The off-screen context and the uploaded coat are kept between renders of the same size (a sequence
  // renders each frame without compiling shaders or uploading an unchanged skin again); this frees them.
  void releaseRenderer();
  // The image size renders default to: the scene's render.size (960x720 for a typed set-up).
  std::array<int, 2> sceneImageSize() const;

  // Reports of every evaluation the session runs from now on: evaluate() without a callback of its own,
  // render, renderImage, exportTo and metrics. A false answer cancels: evaluate() returns false, the
  // others throw pteryla::Error ("cancelled"). An empty function reports nowhere.
  void setProgress(Progress progress);

  // Profiling: seconds of each stage's last run, and the best of `repeats` full packs of the current
  // coat with warm memory (what a packing edit costs; leaves every result as it was).
  StageSeconds stageSeconds() const;
  double timeFullPack(int repeats);
  // The mesh stage's store of unplaced feather meshes at its last run (instancing shrinks it).
  struct MeshStore {
    size_t feathers = 0;         // present feathers meshed
    size_t representatives = 0;  // of them, meshed from their own curves (the rest share another's)
    size_t distinctMeshes = 0;   // unplaced meshes kept
    size_t storedVertices = 0;   // their vertices (24 bytes each), against
    size_t vertices = 0;         // the coat mesh's (what a copy per feather would hold)
  };
  MeshStore meshStore() const;

 private:
  struct Impl;
  explicit Session(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace pteryla
