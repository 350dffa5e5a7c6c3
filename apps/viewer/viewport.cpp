// The viewer's 3D view (viewport.hpp): the Renderer (src/render) does the scene's GL into its off-screen
// target; the view keeps the last frame in a texture drawn behind the panels, re-rendering only when the
// camera, the uploaded results or the look change. It calls no GL itself: the texture is a
// render::ImageTexture, the wireframe a RenderSettings flag, the window's clear Renderer::clearWindow.
#include "viewport.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "glfw_context.hpp"
#include "navigation.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/render/scene_view.hpp"
#include "pteryla/render/scratchboard.hpp"

namespace pteryla::viewer {

Viewport::Viewport(Document& doc, ViewState& view, CameraController& camera)
    : doc_(doc), view_(view), camera_(camera) {}

Viewport::~Viewport() = default;

void Viewport::attach(GlfwContext& context) {
  context_ = &context;
  renderer_ = std::make_unique<render::Renderer>(context);
}

void Viewport::releaseGl() {
  viewTexture_.reset();  // each deletes its GL objects in the window's context
  renderer_.reset();
  navRenderer_.reset();
}

void Viewport::clearWindow(int fbw, int fbh, const glm::vec3& colour) { renderer_->clearWindow(fbw, fbh, colour); }

void Viewport::layout(glm::ivec2 windowSize, glm::ivec2 fbSize, float menuHeight) {
  windowSize_ = windowSize;
  fbSize_ = fbSize;
  const float panel = view_.hidePanels ? 0.0f : std::clamp(view_.panelWidth, 260.0f, 0.7f * float(windowSize_.x));
  view_.viewOrigin = {panel, menuHeight};
  view_.viewSize = {std::max(1, int(float(windowSize_.x) - panel)),
                    std::max(1, int(float(windowSize_.y) - menuHeight - kStatusHeight))};
  const float sx = windowSize_.x > 0 ? float(fbSize_.x) / float(windowSize_.x) : 1.0f;
  const float sy = windowSize_.y > 0 ? float(fbSize_.y) / float(windowSize_.y) : 1.0f;
  viewPixels_ = {int(std::lround(float(view_.viewSize.x) * sx)), int(std::lround(float(view_.viewSize.y) * sy))};
}

void Viewport::initCamera() {
  const Snapshot& s = doc_.snapshot();
  const glm::ivec2 vs = view_.viewSize;
  const float aspect = float(vs.x) / float(vs.y);
  camera_.set(render::sceneCamera(doc_.scene(), s.skin, TriMesh{}, vs.x, vs.y));
  if (doc_.scene().camera.autoFrame) camera_.frame(s.skinLo, s.skinHi, aspect);
  const float diag = glm::length(s.skinHi - s.skinLo);
  if (diag > 0) {
    view_.brushRadius = diag * 0.05f;
    view_.paintRadius = diag * 0.05f;
    view_.controlRadius = diag * 0.1f;
    view_.biasSigma = diag * 0.1f;
  }
  cameraReady_ = true;
  cameraMoved_ = false;
}

void Viewport::frameAll() {
  const Snapshot& s = doc_.snapshot();
  glm::vec3 lo = s.skinLo, hi = s.skinHi;
  if (s.haveCoat) {
    lo = glm::min(lo, s.coatLo);
    hi = glm::max(hi, s.coatHi);
  }
  camera_.frame(lo, hi, float(view_.viewSize.x) / float(view_.viewSize.y));
}

void Viewport::frameBox(const glm::vec3& lo, const glm::vec3& hi) {
  camera_.frame(lo, hi, float(view_.viewSize.x) / float(view_.viewSize.y));
  cameraMoved_ = true;
}

void Viewport::frameSelection() {
  const Snapshot& s = doc_.snapshot();
  const int f = view_.selectedFeather;
  if (f < 0 || size_t(f) >= s.featherOrigin.size()) {
    frameAll();
    return;
  }
  const float r = size_t(f) < s.featherLength.size() ? std::max(s.featherLength[size_t(f)], 1e-4f) : 0.1f;
  const glm::vec3 c = s.featherOrigin[size_t(f)] + 0.5f * r * s.featherTangent[size_t(f)];
  frameBox(c - glm::vec3(r), c + glm::vec3(r));
}

void Viewport::forgetScene() {
  renderer_->setSkin(TriMesh{});
  renderer_->setCoat(TriMesh{}, {});
  navReady_ = false;
  syncedResult_ = ~0ull;
  uploadedSkin_ = 0;
  meshEvals_ = ~0ull;
  ++uploadVersion_;
  cameraReady_ = cameraFramedCoat_ = false;
  materialsStale_ = true;
}

bool Viewport::resultOnScreen() const {
  return doc_.upToDate() && doc_.resultVersion() == syncedResult_ && !viewImage_.empty();
}

// Results to the renderer: the skin as soon as a job publishes it (progressive display), the coat and
// its materials once the evaluation is complete.
void Viewport::sync() {
  if (!doc_.hasScene()) return;
  const Snapshot& s = doc_.snapshot();
  if (s.skinVersion != uploadedSkin_ && !s.skin.empty()) {
    context_->makeCurrent();
    renderer_->setSkin(s.skin);
    if (navRenderer_) navRenderer_->setSkin(s.skin);
    uploadedSkin_ = s.skinVersion;
    ++uploadVersion_;
  }
  if (!cameraReady_ && !s.skin.empty()) initCamera();
  uploadResults();
  if (cameraReady_ && !cameraFramedCoat_ && s.haveCoat) {
    if (!cameraMoved_ && doc_.scene().camera.autoFrame) frameAll();
    cameraFramedCoat_ = true;
  }
}

void Viewport::uploadResults() {
  const pipeline::Scene& scene = doc_.scene();
  const Snapshot& snap = doc_.snapshot();
  pipeline::Pipeline* p = doc_.idlePipeline();
  if (p && doc_.upToDate() && doc_.resultVersion() != syncedResult_) {
    // The pipeline is idle and clean: reading its coat does not evaluate anything.
    const uint64_t meshEvals = p->evaluations(pipeline::Stage::Mesh);
    if (meshEvals != meshEvals_) {
      const pipeline::CoatMesh& coat = p->coatMesh();
      context_->makeCurrent();
      updateColouring();
      renderer_->setCoat(coat.mesh, drawRangesFor(coat.ranges));
      uploadedMaterials_ = coat.materials;  // the ranges index these: set together, never the snapshot's
      meshEvals_ = meshEvals;
      materialsStale_ = true;
      ++uploadVersion_;
      navNeeded_ = true;
    }
    syncedResult_ = doc_.resultVersion();
  }
  if (view_.navigationChanged) {
    view_.navigationChanged = false;
    navNeeded_ = true;
  }
  // A new colour mode (or a check finishing under "problems"): the same coat with other ranges.
  if (p && doc_.upToDate() && doc_.resultVersion() == syncedResult_ && updateColouring()) {
    context_->makeCurrent();
    renderer_->setCoat(p->coatMesh().mesh, drawRangesFor(p->coatMesh().ranges));
    uploadedMaterials_ = p->coatMesh().materials;
    materialsStale_ = true;
    navNeeded_ = true;
    ++uploadVersion_;
  }
  if (navNeeded_ && p && doc_.upToDate() && doc_.resultVersion() == syncedResult_) {
    navNeeded_ = false;
    buildNavigationCoat(p->coatMesh());
  }
  // The materials of the coat the renderer holds (its draw ranges index them): a snapshot published by
  // a later job can list other materials (a changed coat blends other key feathers) before that job's
  // coat is uploaded, and drawing the old ranges with them failed.
  if (snap.haveCoat && meshEvals_ != ~0ull &&
      (materialsStale_ || lastBrdfD_ != scene.render.brdfD || lastBrdfH_ != scene.render.brdfH ||
       lastMaterials_ != uploadedMaterials_)) {
    pipeline::CoatMesh materialsOnly;
    materialsOnly.materials = uploadedMaterials_;
    const auto materials =
        view_.colourBy == ColourBy::Material ? render::sceneMaterials(scene, materialsOnly) : paletteMaterials();
    renderer_->setMaterials(materials);
    if (navRenderer_) navRenderer_->setMaterials(materials);
    lastBrdfD_ = scene.render.brdfD;
    lastBrdfH_ = scene.render.brdfH;
    lastMaterials_ = uploadedMaterials_;
    materialsStale_ = false;
    ++uploadVersion_;
  }
}

void Viewport::buildNavigationCoat(const pipeline::CoatMesh& coat) {
  navReady_ = false;
  navTriangles_ = 0;
  navStride_ = 1;
  if (!view_.fastNavigation) return;
  NavigationCoat nav = makeNavigationCoat(coat, size_t(std::max(view_.navigationBudget, 1)));
  if (nav.mesh.empty()) return;  // the whole coat fits the budget
  context_->makeCurrent();
  const bool fresh = !navRenderer_;
  if (fresh) navRenderer_ = std::make_unique<render::Renderer>(*context_);
  if (fresh || uploadedSkin_ != 0) navRenderer_->setSkin(doc_.snapshot().skin);
  navRenderer_->setCoat(nav.mesh, drawRangesFor(nav.ranges));
  materialsStale_ = true;  // both renderers get the materials on the next upload
  navTriangles_ = nav.mesh.triangleCount();
  navStride_ = nav.stride;
  navReady_ = true;
}

// Everything the 3D image depends on; the view is re-rendered when it changes.
std::vector<float> Viewport::viewKey() const {
  const render::Camera& c = camera_.camera();
  const pipeline::Scene& s = doc_.scene();
  std::vector<float> k = {float(viewPixels_.x),
                          float(viewPixels_.y),
                          c.eye.x,
                          c.eye.y,
                          c.eye.z,
                          c.target.x,
                          c.target.y,
                          c.target.z,
                          c.up.x,
                          c.up.y,
                          c.up.z,
                          c.fovYDegrees,
                          c.zNear,
                          c.zFar,
                          float(uploadVersion_),  // kUploadKeyIndex
                          float(view_.showSkin),
                          float(view_.showCoat),
                          float(view_.wireframe),
                          float(s.render.ambient),
                          float(s.render.background.x),
                          float(s.render.background.y),
                          float(s.render.background.z),
                          float(s.render.skinColor.x),
                          float(s.render.skinColor.y),
                          float(s.render.skinColor.z),
                          float(s.render.shadows),
                          float(s.render.shadowStrength),
                          float(s.render.msaa),
                          float(s.render.exposure),
                          float(s.render.tone == "filmic"),
                          float(s.render.lightRig == "studio"),
                          float(s.render.ground),
                          float(s.render.groundColor.x),
                          float(s.render.groundColor.y),
                          float(s.render.groundColor.z)};
  for (const auto& l : s.lights)
    for (float v : {float(l.direction.x), float(l.direction.y), float(l.direction.z), float(l.color.x),
                    float(l.color.y), float(l.color.z), float(l.intensity)})
      k.push_back(v);
  return k;
}

void Viewport::showImage(const render::Image& image) {
  if (!viewTexture_) viewTexture_ = std::make_unique<render::ImageTexture>(*context_);
  viewImage_ = image;
  viewTexture_->upload(viewImage_);
  lastViewKey_.clear();  // the live view is rendered again when the evaluation catches up
}

Viewport::Drawn Viewport::render(bool moving, int benchPass, bool playing) {
  // A new coat or view size invalidates the measured full-coat time (adaptive navigation).
  const float fullKey[3] = {float(uploadVersion_), float(viewPixels_.x), float(viewPixels_.y)};
  if (!std::equal(fullKey, fullKey + 3, movingFullKey_)) {
    std::copy(fullKey, fullKey + 3, movingFullKey_);
    movingFullMs_ = -1.0;
  }
  const bool fixedPass = benchPass == 0 || benchPass == 1;  // benchmark passes fix the coat drawn
  const bool navChoice = fixedPass ? benchPass == 0
                                   : useNavigationCoat(view_.forceNavigation, view_.adaptiveNavigation, movingFullMs_,
                                                       view_.fullCoatBudgetMs);
  const bool nav = navReady_ && view_.fastNavigation && moving && navRenderer_ && navChoice;
  // Playing at rest: every feather, drawn as cheaply as a moving view is (below).
  const bool fastPlay = playing && !moving && view_.fastPlayback;
  // While moving, fewer pixels as well: the coat's fragments cost as much as its triangles on llvmpipe.
  const int scale = (moving && view_.fastNavigation) || fastPlay ? std::clamp(view_.navigationScale, 1, 8) : 1;
  std::vector<float> key = viewKey();
  key.push_back(nav ? 1.0f : 0.0f);
  key.push_back(float(scale));
  key.push_back(fastPlay ? 1.0f : 0.0f);
  if (key == lastViewKey_ && viewTexture_ && viewTexture_->id()) {
    drawnResult_ = syncedResult_;  // the view on screen shows the synced result
    return Drawn::Nothing;
  }
  render::Renderer& renderer = nav ? *navRenderer_ : *renderer_;
  const pipeline::Scene& scene = doc_.scene();
  render::RenderSettings settings =
      render::sceneSettings(scene, std::max(1, viewPixels_.x / scale), std::max(1, viewPixels_.y / scale));
  settings.drawSkin = view_.showSkin;
  settings.drawCoat = view_.showCoat;
  settings.wireframe = view_.wireframe;  // also turns off shadows and sub-pixel culling
  // Multisampling costs most of a frame on llvmpipe: only at rest (and not for fast playback).
  if (moving || fastPlay) settings.msaaSamples = 0;
  // The navigation coat shows every k-th feather: colour the skin like the coat looked (the mean of
  // the last full view) so the body reads as feathered rather than bare while the camera moves.
  if (nav && navSkinColor_.x >= 0.0f) settings.skinColor = navSkinColor_;
  const auto t0 = std::chrono::steady_clock::now();
  viewImage_ = renderer.renderImage(camera_.camera(), render::sceneLights(scene), settings);
  if (!viewTexture_) viewTexture_ = std::make_unique<render::ImageTexture>(*context_);
  viewTexture_->upload(viewImage_);
  lastRenderSeconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!nav && moving && view_.fastNavigation) movingFullMs_ = smoothFrameMs(movingFullMs_, 1000.0 * lastRenderSeconds_);
  if (!nav && scale == 1 && view_.showCoat) {
    const glm::vec4 bg = settings.background * 255.0f;
    glm::dvec3 sum(0.0);
    size_t count = 0;
    for (size_t i = 0; i + 3 < viewImage_.rgba.size(); i += 4 * 5) {
      const uint8_t* p = &viewImage_.rgba[i];
      if (std::abs(p[0] - bg.r) + std::abs(p[1] - bg.g) + std::abs(p[2] - bg.b) < 12.0f) continue;
      sum += glm::dvec3(p[0], p[1], p[2]);
      ++count;
    }
    if (count > 0) navSkinColor_ = glm::clamp(glm::vec3(sum / (255.0 * double(count))) * 1.15f, 0.0f, 1.0f);
  }
  lastViewKey_ = std::move(key);
  drawnResult_ = syncedResult_;
  if (fastPlay) return Drawn::Playback;
  return !nav && !moving && scale == 1 ? Drawn::Full : Drawn::Reduced;
}

void Viewport::requestScreenshot(const std::string& path, bool withUi) {
  shot_.path = path;
  shot_.wanted = true;
  shot_.withUi = withUi;
}

Viewport::Capture Viewport::capture(int fbw, int fbh, bool afterUi, bool waitFrames) {
  if (!shot_.wanted || afterUi != shot_.withUi) return {};
  // Scripted and --screenshot captures wait for the evaluation (and its upload) to finish.
  if (doc_.hasScene() && !resultOnScreen()) {
    if (doc_.failed() || doc_.halted()) {
      shot_.wanted = false;
      return {Capture::NotEvaluated, ""};
    }
    return {};
  }
  if (waitFrames) return {};
  // A view drawn while the camera moved has a reduced resolution: wait for the full one (unless the
  // navigation view is forced on, which never stops "moving": capture what it shows).
  if (!afterUi && viewImage_.width != viewPixels_.x && doc_.scene().render.style != "scratchboard" &&
      !view_.forceNavigation)
    return {};
  shot_.wanted = false;
  try {
    render::Image img;
    if (afterUi) {
      img = renderer_->readPixels(fbw, fbh);
    } else if (doc_.scene().render.style == "scratchboard" && doc_.idlePipeline()) {
      pipeline::Pipeline& p = *doc_.idlePipeline();
      render::ScratchboardSettings ss;
      ss.width = viewPixels_.x;
      ss.height = viewPixels_.y;
      img = render::renderScratchboard(p.coatMesh().mesh, p.skinTriMesh(), camera_.camera(),
                                       render::sceneLights(p.scene()), ss);
    } else {
      img = viewImage_;  // exactly the 3D view on screen, without the panels
    }
    render::saveImage(shot_.path, img);
    std::fprintf(stderr, "pteryla-viewer: wrote %s (%dx%d)\n", shot_.path.c_str(), img.width, img.height);
    return {Capture::Written, shot_.path};
  } catch (const Error& e) {
    return {Capture::Failed, e.what()};
  }
}

}  // namespace pteryla::viewer
