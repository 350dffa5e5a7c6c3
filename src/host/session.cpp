// The host API (include/pteryla/pteryla.hpp): a Session is a pipeline::Pipeline over a skin held in
// memory, with a typed set-up turned into the scene sections the pipeline already parses
// (session_setup.cpp), and the frame's results handed out as flat views.
#include "pteryla/pteryla.hpp"

#include <glm/vec3.hpp>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <set>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/pack.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/skin_binding.hpp"
#include "pteryla/core/json.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/feather/mesh_io.hpp"
#include "pteryla/moult/controls.hpp"
#include "pteryla/moult/schedule.hpp"
#include "pteryla/exchange/coat_export.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/render/image.hpp"
#include "pteryla/render/osmesa_context.hpp"
#include "pteryla/render/scene_view.hpp"
#include "session_setup.hpp"

namespace pteryla {
namespace {

static_assert(sizeof(glm::vec3) == 3 * sizeof(float) && sizeof(glm::vec2) == 2 * sizeof(float),
              "the coat mesh's vectors are handed out as flat float arrays");

// Thrown through the pipeline by the progress callback when the host cancels; caught by evaluate().
// Stages keep their dirty flag when their computation throws, so nothing half-done is cached.
struct Cancelled {};

using host::at;
using host::sceneFromSetup;
using host::skinFromArrays;

}  // namespace

const char* version() { return PTERYLA_VERSION; }

struct Session::Impl {
  std::unique_ptr<pipeline::Pipeline> pipeline;
  size_t vertices = 0, faces = 0;
  bool frameValid = false;
  Frame frame;
  std::vector<uint64_t> keys;
  std::vector<double> origins, normals, tangents, binormals;
  std::vector<FeatherRange> ranges;
  std::vector<Material> materials;

  // PoseMode::Follow: the host's pose is kept here, not given to the pipeline, which lays the coat on its
  // base skin (rest, or a scene skeleton's pose); the bindings carry that coat onto the pose.
  PoseMode poseMode = PoseMode::Repack;
  std::vector<glm::dvec3> followPose;  // empty: no host pose
  coat::SkinBinding vertexBinding, originBinding;
  std::vector<glm::dvec3> vertexNormalLocal, normalLocal, tangentLocal, binormalLocal;
  uint64_t boundMeshEvaluation = ~uint64_t(0);  // the mesh stage's evaluation count when bound
  coat::SkinMesh followSkin;                    // the base skin's connectivity at the host's pose
  std::vector<glm::vec3> followPositions, followNormals;
  // The frame's vertex normals and alphas as floats: the host API hands out float arrays, where the coat
  // mesh keeps 16-bit ones (core/packed.hpp).
  std::vector<glm::vec3> vertexNormals;
  std::vector<float> vertexAlphas;
  uint64_t decodedMeshEvaluation = ~uint64_t(0);  // the mesh evaluation they were decoded from
  std::vector<glm::dvec3> scratch;

  Progress progress;  // setProgress (or SceneFileOptions::progress): reports of every evaluation
  // The kept renderer: one off-screen context (resized when the image size changes) and the view that
  // holds the uploaded skin and coat. The view goes before the context.
  std::unique_ptr<render::OsMesaContext> context;
  std::unique_ptr<render::SceneView> view;

  // The renderer makes its own context current for every call and when it is destroyed, so several
  // sessions' renderers live side by side.
  void releaseRenderer() {
    view.reset();
    context.reset();
  }

  explicit Impl(std::unique_ptr<pipeline::Pipeline> p) : pipeline(std::move(p)) {
    // Read the skin, the feathers and the tracts now, so bad input fails here and not at evaluate().
    const coat::SkinMesh& rest = pipeline->restSkin();
    vertices = rest.vertexCount();
    faces = rest.faceCount();
    pipeline->tracts();
  }

  void setPose(std::vector<glm::dvec3> positions) {
    for (size_t v = 0; v < positions.size(); ++v)
      for (int c = 0; c < 3; ++c)
        if (!std::isfinite(positions[v][c]))
          throw Error("coordinate " + std::to_string(c) + " is not a finite number", "", "vertex " + std::to_string(v));
    if (poseMode == PoseMode::Follow) {
      // The pipeline's own check (docs/limits.md), without dirtying its stages.
      pipeline::checkSkinPose(pipeline->restSkin(), positions);
      followPose = std::move(positions);
    } else {
      pipeline->setSkinPose(std::move(positions));  // also checks the coordinate range
    }
    frameValid = false;
  }

  uint64_t meshEvaluations() { return pipeline->evaluations(pipeline::Stage::Mesh); }

  // Follow mode: carries the base coat (the pipeline's frame, already in the views' arrays) onto the host's
  // pose. Binds again only when the mesh stage produced a new coat.
  void follow() {
    pipeline::Pipeline& p = *pipeline;
    const coat::SkinMesh& base = p.posedSkin();
    const TriMesh& m = p.coatMesh().mesh;
    const size_t n = keys.size();
    auto gather = [&](const std::vector<double>& flat) -> const std::vector<glm::dvec3>& {
      scratch.resize(n);
      for (size_t i = 0; i < n; ++i) scratch[i] = {flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]};
      return scratch;
    };
    const uint64_t evaluation = meshEvaluations();
    if (evaluation != boundMeshEvaluation || vertexBinding.size() != m.positions.size() || originBinding.size() != n) {
      boundMeshEvaluation = ~uint64_t(0);
      vertexBinding.bind(base, m.positions);
      vertexNormalLocal = vertexBinding.localDirections(base, vertexNormals);
      // Follicles are on the skin already: bound by their own (face, barycentric) coordinates.
      const coat::Follicles& follicles = p.follicles();
      const coat::CoatFeathers& coat = p.feathers();
      std::vector<coat::SurfacePoint> onSkin(n);
      for (size_t i = 0; i < n; ++i) onSkin[i] = {follicles.face[coat.follicle[i]], follicles.bary[coat.follicle[i]]};
      originBinding.bind(base, std::move(onSkin));
      normalLocal = originBinding.localDirections(base, gather(normals));
      tangentLocal = originBinding.localDirections(base, gather(tangents));
      binormalLocal = originBinding.localDirections(base, gather(binormals));
      boundMeshEvaluation = evaluation;
    }
    if (followSkin.faces.size() != base.faces.size() || followSkin.positions.size() != base.positions.size())
      followSkin = base;
    followSkin.positions = followPose;
    coat::recomputeGeometry(followSkin);
    vertexBinding.deform(followSkin, followPositions);
    vertexBinding.carry(followSkin, vertexNormalLocal, followNormals);
    auto scatter = [&](std::vector<double>& flat) {
      for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) flat[3 * i + c] = scratch[i][c];
    };
    originBinding.deform(followSkin, scratch);
    scatter(origins);
    originBinding.carry(followSkin, normalLocal, scratch);
    scatter(normals);
    originBinding.carry(followSkin, tangentLocal, scratch);
    scatter(tangents);
    originBinding.carry(followSkin, binormalLocal, scratch);
    scatter(binormals);
    const size_t nv = followPositions.size();
    frame.positions = {nv ? &followPositions[0].x : nullptr, 3 * nv};
    frame.vertexNormals = {nv ? &followNormals[0].x : nullptr, 3 * nv};
  }

  bool following() const { return poseMode == PoseMode::Follow && !followPose.empty(); }

  // Runs `fn` with `report` (or, when empty, the session's progress) receiving the pipeline's reports; a
  // false answer unwinds `fn` with Cancelled. The pipeline reports nowhere afterwards.
  template <class Fn>
  auto withProgress(const Progress& report, Fn&& fn) {
    const Progress& use = report ? report : progress;
    pipeline->setProgress([&use](const std::string& stage, double fraction) {
      if (use && !use(stage, fraction)) throw Cancelled{};
      return true;
    });
    struct Restore {
      pipeline::Pipeline& p;
      ~Restore() { p.setProgress({}); }
    } restore{*pipeline};
    return fn();
  }
  // The same for the calls that return results (render, export, metrics): a cancel is an Error.
  template <class Fn>
  auto reporting(const char* what, Fn&& fn) {
    try {
      return withProgress({}, std::forward<Fn>(fn));
    } catch (const Cancelled&) {
      throw Error(std::string(what) + " cancelled: the progress callback returned false", "", "progress");
    }
  }

  // The kept renderer at width x height (made on the first call; libOSMesa is loaded then).
  render::SceneView& renderer(int width, int height) {
    if (!context) {
      context = std::make_unique<render::OsMesaContext>(width, height);
      view = std::make_unique<render::SceneView>(*context);
    } else if (context->framebufferSize() != glm::ivec2(width, height)) {
      context->resize(width, height);
    }
    return *view;
  }
  // render and renderImage: the frame drawn by the kept renderer. frame() stays valid if it was, also when
  // the draw fails (the view may set per-feather levels of detail, render.lod_by_screen_size: the views
  // are pointed at the frame as it is now). `path` is named when a Follow pose is refused.
  render::Image drawFrame(const std::array<int, 2>& size, const std::string& style, const std::string& path) {
    if (following())
      throw Error("rendering a coat carried onto a Follow pose is not supported yet: use PoseMode::Repack", path,
                  "poseMode");
    const bool hadFrame = frameValid;
    frameValid = false;
    render::Image image;
    try {
      image = reporting("the render",
                        [&] { return renderer(size[0], size[1]).render(*pipeline, size[0], size[1], style); });
    } catch (...) {
      if (hadFrame) fillFrame();
      throw;
    }
    if (hadFrame) fillFrame();
    return image;
  }

  // The frame's coat mesh as a TriMesh (exportMesh): the pipeline's, or carried onto a Follow pose.
  TriMesh frameMesh() {
    const TriMesh& m = pipeline->coatMesh().mesh;
    if (!following()) return m;
    TriMesh out = m;
    out.positions = followPositions;
    out.normals.assign(followNormals.begin(), followNormals.end());
    return out;
  }

  // Points the frame's views at the pipeline's results (and at the flattened frames).
  void fillFrame() {
    pipeline::Pipeline& p = *pipeline;
    const pipeline::CoatMesh& mesh = p.coatMesh();
    const coat::CoatFeathers& coat = p.feathers();
    const coat::Follicles& follicles = p.follicles();
    const std::vector<double>& elevation = p.elevations();
    const size_t n = coat.size();
    keys.resize(n);
    origins.resize(3 * n);
    normals.resize(3 * n);
    tangents.resize(3 * n);
    binormals.resize(3 * n);
    for (size_t i = 0; i < n; ++i) {
      keys[i] = follicles.id[coat.follicle[i]];
      const coat::FeatherFrame& f = coat.frames[i];
      for (int c = 0; c < 3; ++c) {
        origins[3 * i + c] = f.origin[c];
        normals[3 * i + c] = f.normal[c];
        tangents[3 * i + c] = f.tangent[c];
        binormals[3 * i + c] = f.binormal[c];
      }
    }
    ranges.resize(mesh.ranges.size());
    for (size_t k = 0; k < ranges.size(); ++k)
      ranges[k] = {mesh.ranges[k].feather, mesh.ranges[k].firstIndex, mesh.ranges[k].indexCount,
                   mesh.ranges[k].material};
    materials.resize(mesh.materials.size());
    for (size_t k = 0; k < materials.size(); ++k) {
      const pipeline::CoatMaterial& c = mesh.materials[k];
      materials[k] = {c.name, c.texture, c.alphaTexture, c.pattern, {{c.baseColor.x, c.baseColor.y, c.baseColor.z}},
                      c.uv};
    }
    PTERYLA_CHECK(coat.tract.size() == n && coat.present.size() == n && elevation.size() == n,
                  "per-feather results of different lengths");
    const TriMesh& m = mesh.mesh;
    const size_t nv = m.positions.size();
    PTERYLA_CHECK(m.normals.size() == nv && m.featherId.size() == nv &&
                      (m.uvGlobal.empty() || m.uvGlobal.size() == nv) && (m.alpha.empty() || m.alpha.size() == nv),
                  "coat mesh attributes of different lengths");
    Frame& fr = frame;
    fr.featherCount = n;
    fr.follicleKeys = {keys.data(), n};
    fr.tracts = {coat.tract.data(), n};
    fr.present = {coat.present.data(), n};
    fr.origins = {origins.data(), 3 * n};
    fr.normals = {normals.data(), 3 * n};
    fr.tangents = {tangents.data(), 3 * n};
    fr.binormals = {binormals.data(), 3 * n};
    fr.elevations = {elevation.data(), n};
    fr.positions = {nv ? &m.positions[0].x : nullptr, 3 * nv};
    // Decoded again only when the mesh stage ran: a step that changes no input costs nothing here.
    if (meshEvaluations() != decodedMeshEvaluation || vertexNormals.size() != m.normals.size() ||
        vertexAlphas.size() != m.alpha.size()) {
      vertexNormals.assign(m.normals.begin(), m.normals.end());
      vertexAlphas.assign(m.alpha.begin(), m.alpha.end());
      decodedMeshEvaluation = meshEvaluations();
    }
    fr.vertexNormals = {nv ? &vertexNormals[0].x : nullptr, 3 * nv};
    fr.uvs = {m.uvGlobal.empty() ? nullptr : &m.uvGlobal[0].x, 2 * m.uvGlobal.size()};
    fr.alphas = {vertexAlphas.empty() ? nullptr : vertexAlphas.data(), vertexAlphas.size()};
    fr.vertexFeathers = {m.featherId.data(), nv};
    fr.indices = {m.indices.data(), m.indices.size()};
    fr.ranges = {ranges.data(), ranges.size()};
    fr.materials = {materials.data(), materials.size()};
    if (following()) follow();
    frameValid = true;
  }
};

Session::Session(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Session::Session(const SkinArrays& skin, const CoatSetup& setup) {
  coat::SkinMesh mesh = skinFromArrays(skin);
  impl_ = std::make_unique<Impl>(std::make_unique<pipeline::Pipeline>(sceneFromSetup(setup), std::move(mesh)));
}

Session Session::fromSceneFile(const std::string& path, const SceneFileOptions& options) {
  pipeline::Scene scene = pipeline::loadScene(path);
  if (options.seed) scene.seed = *options.seed;
  if (options.lodByScreenSize) scene.render.lodByScreenSize = *options.lodByScreenSize;
  if (options.instanceTolerance) {
    const double t = *options.instanceTolerance;
    if (!(t >= 0 && t <= 0.1))
      throw Error("expected an instance tolerance in [0, 0.1], got " + std::to_string(t), path, "instanceTolerance");
    scene.render.instanceTolerance = t;
  }
  // The constructor reads the skin and the tracts: their reports go to the options' callback.
  const Progress& report = options.progress;
  auto impl = std::make_unique<Impl>(std::make_unique<pipeline::Pipeline>(
      std::move(scene), [&report, &path](const std::string& stage, double fraction) {
        if (report && !report(stage, fraction)) throw Error("reading the scene cancelled", path, "progress");
        return true;
      }));
  impl->pipeline->setProgress({});
  impl->progress = options.progress;
  return Session(std::move(impl));
}

Session::Session(Session&&) noexcept = default;
Session& Session::operator=(Session&&) noexcept = default;
Session::~Session() = default;

size_t Session::vertexCount() const { return impl_->vertices; }
size_t Session::faceCount() const { return impl_->faces; }

void Session::setPose(const std::vector<double>& positions) {
  if (positions.size() != 3 * impl_->vertices)
    throw Error("expected 3 x " + std::to_string(impl_->vertices) + " = " + std::to_string(3 * impl_->vertices) +
                    " values (the rest skin's vertices), got " + std::to_string(positions.size()),
                "", "positions");
  std::vector<glm::dvec3> p(impl_->vertices);
  for (size_t v = 0; v < p.size(); ++v) p[v] = {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]};
  impl_->setPose(std::move(p));
}

void Session::setPose(const float* xyz, size_t vertexCount) {
  if (vertexCount != impl_->vertices)
    throw Error("expected " + std::to_string(impl_->vertices) + " vertices (the rest skin's), got " +
                    std::to_string(vertexCount),
                "", "positions");
  if (!xyz) throw Error("no positions given", "", "positions");
  std::vector<glm::dvec3> p(vertexCount);
  for (size_t v = 0; v < p.size(); ++v) p[v] = {xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]};
  impl_->setPose(std::move(p));
}

void Session::clearPose() {
  impl_->pipeline->setSkinPose({});
  impl_->followPose.clear();
  impl_->frameValid = false;
}

void Session::setFixedElevations(const std::vector<uint64_t>& follicleKeys, const std::vector<double>& elevations) {
  Impl& m = *impl_;
  if (follicleKeys.size() != elevations.size())
    throw Error("expected one elevation per follicle key (" + std::to_string(follicleKeys.size()) + "), got " +
                    std::to_string(elevations.size()),
                "", "elevations");
  if (!follicleKeys.empty()) {
    if (m.pipeline->packingSettings().options.method == coat::PackMethod::Drape)
      throw Error("fixed elevations need a packed coat (packing height_field): a draped coat is laid along the skin",
                  "", "packing");
  }
  std::map<uint64_t, double> byKey;
  if (!follicleKeys.empty()) {
    const coat::Follicles& f = m.pipeline->follicles();  // distributes first if needed
    std::set<uint64_t> known(f.id.begin(), f.id.end());
    for (size_t k = 0; k < follicleKeys.size(); ++k) {
      if (!known.count(follicleKeys[k]))
        throw Error("no follicle has the key " + std::to_string(follicleKeys[k]), "", at("follicleKeys", k));
      if (!std::isfinite(elevations[k]) || elevations[k] < 0 || elevations[k] > 1.5707963267948966)
        throw Error("elevation must be in [0, pi/2] radians, got " + std::to_string(elevations[k]), "",
                    at("elevations", k));
      byKey[follicleKeys[k]] = elevations[k];
    }
  }
  if (byKey == m.pipeline->fixedElevations()) return;
  m.pipeline->setFixedElevations(std::move(byKey));
  m.frameValid = false;
}

void Session::setPoseMode(PoseMode mode) {
  Impl& m = *impl_;
  if (mode == m.poseMode) return;
  // The pose the host gave moves to where the new mode keeps it.
  if (mode == PoseMode::Follow) {
    m.followPose = m.pipeline->skinPose();
    m.pipeline->setSkinPose({});
  } else {
    m.pipeline->setSkinPose(std::move(m.followPose));
    m.followPose.clear();
  }
  m.poseMode = mode;
  m.frameValid = false;
}
PoseMode Session::poseMode() const { return impl_->poseMode; }

void Session::setTime(double t) {
  if (!std::isfinite(t)) throw Error("time must be a finite number", "", "time");
  if (t == impl_->pipeline->time()) return;
  impl_->pipeline->setTime(t);
  impl_->frameValid = false;
}
double Session::time() const { return impl_->pipeline->time(); }

void Session::setLod(double fraction) {
  if (!(fraction > 0 && fraction <= 1)) throw Error("level of detail must be in (0, 1]", "", "lod");
  if (fraction == impl_->pipeline->lod()) return;
  impl_->pipeline->setLod(fraction);
  impl_->frameValid = false;
}
double Session::lod() const { return impl_->pipeline->lod(); }

void Session::setInstanceTolerance(double fraction) {
  if (!(fraction >= 0 && fraction <= 0.1))
    throw Error("expected an instance tolerance in [0, 0.1], got " + std::to_string(fraction), "", "instanceTolerance");
  if (fraction == instanceTolerance()) return;
  impl_->pipeline->editScene(pipeline::Stage::Mesh, [&](pipeline::Scene& s) { s.render.instanceTolerance = fraction; });
  impl_->frameValid = false;
}
double Session::instanceTolerance() const { return impl_->pipeline->scene().render.instanceTolerance; }

bool Session::evaluate(const Progress& progress) {
  Impl& m = *impl_;
  m.frameValid = false;
  // The host's callback sees every report; a false answer unwinds the stage that is running.
  try {
    m.withProgress(progress, [&] { m.fillFrame(); });
  } catch (const Cancelled&) {
    return false;
  }
  return true;
}

void Session::setProgress(Progress progress) { impl_->progress = std::move(progress); }

Session::MeshStore Session::meshStore() const {
  const pipeline::FrameReuse r = impl_->pipeline->frameReuse();
  MeshStore m;
  m.feathers = r.meshFeathers;
  m.representatives = r.meshRepresentatives;
  m.distinctMeshes = r.meshDistinct;
  m.storedVertices = r.meshStoredVertices;
  m.vertices = r.meshVertices;
  return m;
}

StageSeconds Session::stageSeconds() const {
  const pipeline::Pipeline& p = *impl_->pipeline;
  using pipeline::Stage;
  StageSeconds s;
  s.skin = p.lastSeconds(Stage::Skin);
  s.tracts = p.lastSeconds(Stage::Tracts);
  s.distribute = p.lastSeconds(Stage::Distribute);
  s.interpolate = p.lastSeconds(Stage::Interpolate);
  s.directions = p.lastSeconds(Stage::Directions);
  s.pack = p.lastSeconds(Stage::Pack);
  s.controls = p.lastSeconds(Stage::Controls);
  s.mesh = p.lastSeconds(Stage::Mesh);
  return s;
}

double Session::timeFullPack(int repeats) {
  if (repeats < 1) throw Error("expected at least one repeat, got " + std::to_string(repeats), "", "repeats");
  Impl& m = *impl_;
  return m.reporting("timing the pack", [&] { return m.pipeline->timeFullPack(repeats); });
}

std::array<int, 2> Session::sceneImageSize() const {
  const auto& r = impl_->pipeline->scene().render;
  return {{r.width, r.height}};
}

void Session::releaseRenderer() { impl_->releaseRenderer(); }

const Frame& Session::frame() const {
  if (!impl_->frameValid)
    throw Error(
        "no evaluated frame: the inputs changed, or the last evaluate() was cancelled or failed; call evaluate()", "",
        "frame");
  return impl_->frame;
}

void Session::exportMesh(const std::string& path) const {
  frame();  // throws when there is no evaluated frame
  feather::writeMesh(path, impl_->frameMesh());
}

std::vector<double> exportFrameTimes(double from, double to, double fps) { return exchange::frameTimes(from, to, fps); }

namespace {

exchange::ExportOptions exportOptions(const std::string& path, const ExportSettings& settings) {
  const exchange::Format format = exchange::formatOf(path);
  exchange::ExportOptions opt;
  opt.as = exchange::coatAsOf(settings.coatAs);
  for (size_t k = 0; k < settings.times.size(); ++k)
    if (!std::isfinite(settings.times[k]) || (k > 0 && !(settings.times[k] > settings.times[k - 1])))
      throw Error("times must be finite and increasing", "", "times[" + std::to_string(k) + "]");
  if ((format == exchange::Format::Obj || format == exchange::Format::Ply) && settings.times.size() > 1)
    throw Error("OBJ and PLY hold one frame: export several times as .glb, .gltf or .usda", path, "times");
  if (!(settings.fps > 0 && std::isfinite(settings.fps))) throw Error("fps must be a positive number", path, "fps");
  if (!(settings.metersPerUnit > 0 && std::isfinite(settings.metersPerUnit)))
    throw Error("metersPerUnit must be a positive number", path, "metersPerUnit");
  opt.times = settings.times;
  opt.fps = settings.fps;
  opt.metersPerUnit = settings.metersPerUnit;
  return opt;
}

// Image size and style of a render, checked.
std::array<int, 2> renderSize(const pipeline::Pipeline& p, const RenderSettings& settings, const std::string& path) {
  const bool sceneSize = settings.width == 0 && settings.height == 0;
  const int width = sceneSize ? p.scene().render.width : settings.width;
  const int height = sceneSize ? p.scene().render.height : settings.height;
  for (const auto& [v, name] : {std::pair{width, "width"}, {height, "height"}})
    if (v < 1 || v > 16384)
      throw Error(std::string(name) + " must be in [1, 16384], got " + std::to_string(v), path, name);
  if (!settings.style.empty() && settings.style != "shaded" && settings.style != "scratchboard")
    throw Error("style must be \"\", \"shaded\" or \"scratchboard\", got \"" + settings.style + "\"", path, "style");
  return {{width, height}};
}

}  // namespace

void checkExportSettings(const std::string& path, const ExportSettings& settings) { exportOptions(path, settings); }

ExportSummary Session::exportTo(const std::string& path, const ExportSettings& settings) {
  Impl& m = *impl_;
  if (m.following())
    throw Error(
        "exporting a coat carried onto a Follow pose is not supported yet: exportMesh() writes this frame, "
        "or use PoseMode::Repack",
        path, "poseMode");
  const exchange::ExportOptions opt = exportOptions(path, settings);
  const bool hadFrame = m.frameValid;
  m.frameValid = false;
  // An export carries every feather at lod(), also after a render set levels by screen size; the render's
  // levels come back for the frame.
  const std::vector<double> levels = m.pipeline->featherLods();
  m.pipeline->setFeatherLods({});
  exchange::ExportResult r;
  try {
    r = m.reporting("the export", [&] { return exchange::exportCoat(*m.pipeline, path, opt); });
  } catch (...) {
    m.pipeline->setFeatherLods(levels);
    throw;
  }
  m.pipeline->setFeatherLods(levels);
  if (hadFrame) m.fillFrame();  // the export evaluated other times: point the views at this one again
  ExportSummary out;
  out.bytes = r.bytes;
  out.frames = r.frames;
  out.feathers = r.feathers;
  out.triangles = r.triangles;
  out.curves = r.curves;
  out.instances = r.instances;
  out.prototypes = r.prototypes;
  out.seconds = r.seconds;
  out.writeSeconds = r.writeSeconds;
  return out;
}

render::Image Session::renderImage(const RenderSettings& settings) {
  return impl_->drawFrame(renderSize(*impl_->pipeline, settings, ""), settings.style, "");
}

RenderSummary Session::render(const std::string& path, const RenderSettings& settings) {
  Impl& m = *impl_;
  const std::array<int, 2> size = renderSize(*m.pipeline, settings, path);
  const render::Image image = m.drawFrame(size, settings.style, path);
  const pipeline::CoatMesh& drawn = m.pipeline->coatMesh();  // evaluated by the render: no work
  const RenderSummary summary{size[0], size[1], drawn.ranges.size(), drawn.mesh.triangleCount()};
  render::saveImage(path, image);  // a failed write keeps the frame the host had (drawFrame refilled it)
  return summary;
}

Metrics Session::metrics() {
  Impl& m = *impl_;
  if (m.following())
    throw Error(
        "the checker measures the coat the pipeline laid, not one carried onto a Follow pose: clear the "
        "pose or use PoseMode::Repack to check a pose",
        "", "poseMode");
  pipeline::QualityMetrics q;
  const double lod = m.pipeline->lod();
  const bool hadFrame = m.frameValid;
  m.frameValid = false;
  try {
    q = m.reporting("the check", [&] { return m.pipeline->check(); });
  } catch (...) {
    m.pipeline->setLod(lod);  // check() meshes at lod 1 and restores the level only when it completes
    throw;
  }
  // check() meshes at full detail: point the views at the frame's own level again (meshing it anew),
  // only for a host that had a frame.
  if (hadFrame) m.fillFrame();
  Metrics r;
  r.follicles = q.follicles;
  r.feathers = q.feathers;
  r.hexFraction = q.hexFraction;
  r.nnCv = q.nnCv;
  r.intersectingPairs = q.intersectingPairs;
  r.intersectingPairsUnpacked = q.intersectingPairsUnpacked;
  r.intersectingPairsProxy = q.intersectingPairsProxy;
  r.skinPenetrations = q.skinPenetrations;
  r.coverage = q.coverage;
  r.elevationP50 = q.elevationP50;
  r.elevationP90 = q.elevationP90;
  r.fixedFeathers = q.fixedFeathers;
  r.hiddenFeathers = q.hiddenFeathers;
  r.intersectingFeathers = q.intersectingFeathers;
  r.penetratingFeathers = q.penetratingFeathers;
  return r;
}

}  // namespace pteryla
