#include "document.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/follicles.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/coat/tracts.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/core/paths.hpp"
#include "pteryla/pipeline/scene_stages.hpp"
#include "pteryla/render/scene_view.hpp"
#include "scene_edit.hpp"

namespace pteryla::viewer {

using pipeline::Pipeline;
using pipeline::Scene;
using pipeline::Stage;

namespace {

// Thrown from the progress callback to abandon a job; the stage that was running stays dirty.
struct Cancelled {};

bool sameFile(const std::string& a, const std::string& b) {
  if (a.empty() || b.empty()) return false;
  std::error_code ec;
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec)) return std::filesystem::equivalent(a, b, ec);
  return std::filesystem::absolute(a).lexically_normal() == std::filesystem::absolute(b).lexically_normal();
}

void bounds(const TriMesh& m, glm::vec3& lo, glm::vec3& hi) {
  if (!m.bounds(lo, hi)) lo = hi = glm::vec3(0);
}

}  // namespace

Document::Document() : snapshot_(std::make_shared<Snapshot>()) {}

Document::~Document() {
  cancel_ = true;
  if (worker_.joinable()) worker_.join();
}

void Document::open(const std::string& path) {
  Scene s = pipeline::loadScene(path);
  const bool bare = s.fromBareMesh;
  makeBareMeshExplicit(s);
  // A bare mesh has no scene file: Save asks for one.
  reset(std::move(s), bare ? "" : std::filesystem::absolute(path).lexically_normal().string());
}

void Document::reset(Scene scene, const std::string& path) {
  cancel_ = true;
  if (worker_.joinable()) worker_.join();
  running_ = false;
  done_ = false;
  cancel_ = false;
  scene_ = std::move(scene);
  path_ = path;
  modified_ = false;
  ++changes_;
  undo_.clear();
  redo_.clear();
  gestureOpen_ = false;
  time_ = scene_.time;
  lod_ = scene_.render.lod;  // the preview's cap; levels by screen size follow render.lod_by_screen_size
  meshedView_.reset();
  pipeline_ = std::make_unique<Pipeline>(scene_);
  pending_.reset();
  timeDirty_ = lodDirty_ = false;
  failed_ = halted_ = false;
  needEval_ = true;
  metrics_.reset();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    snapshot_ = std::make_shared<Snapshot>();
    workerSnapshot_.reset();
    jobError_.reset();
    progress_ = {};
  }
  ++resultVersion_;
}

void Document::markChanged(const Scene& before) {
  modified_ = true;
  ++changes_;
  failed_ = false;
  halted_ = false;
  metrics_.reset();
  if (const auto st = pipeline::earliestChangedStage(before, scene_)) {
    pending_ = pending_ ? std::min(*pending_, *st) : *st;
    needEval_ = true;
    if (running_) cancel_ = true;
  }
}

void Document::edit(const std::string& label, const std::function<void(Scene&)>& fn) {
  if (!hasScene()) throw Error("no scene is open");
  Scene next = scene_;
  fn(next);  // may throw: nothing changed yet
  Scene before = std::move(scene_);
  scene_ = std::move(next);
  if (!(gestureOpen_ && label == lastLabel_ && !undo_.empty())) undo_.push_back({label, before});
  gestureOpen_ = true;
  lastLabel_ = label;
  redo_.clear();
  markChanged(before);
}

bool Document::undo() {
  if (undo_.empty()) return false;
  Entry e = std::move(undo_.back());
  undo_.pop_back();
  Scene before = scene_;
  redo_.push_back({e.label, scene_});
  scene_ = std::move(e.scene);
  gestureOpen_ = false;
  markChanged(before);
  return true;
}

bool Document::redo() {
  if (redo_.empty()) return false;
  Entry e = std::move(redo_.back());
  redo_.pop_back();
  Scene before = scene_;
  undo_.push_back({e.label, scene_});
  scene_ = std::move(e.scene);
  gestureOpen_ = false;
  markChanged(before);
  return true;
}

bool Document::saveAs(const std::string& path, bool overwrite) {
  if (!hasScene()) throw Error("no scene is open");
  if (path.empty()) throw Error("no file name given");
  if (extensionOf(path) != ".json") throw Error("a scene file must end in .json", path);
  if (fileExists(path) && !overwrite && !sameFile(path, path_)) return false;
  const std::string abs = std::filesystem::absolute(path).lexically_normal().string();
  const auto dir = std::filesystem::path(abs).parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir)) throw Error("directory does not exist", abs);
  // The preview level of detail (lod()) is the viewer's, not the scene's: render.lod is saved as edited.
  Scene s = scene_;
  s.time = time_;
  pipeline::saveScene(abs, s);
  // Saved paths are relative to the file: remember where it is so later saves resolve the same way.
  scene_.file = abs;
  scene_.time = time_;
  path_ = abs;
  modified_ = false;
  return true;
}

void Document::save() {
  if (path_.empty()) throw Error("the scene has no file yet: use Save As");
  saveAs(path_, true);
}

void Document::setTime(double t) {
  if (!std::isfinite(t)) throw Error("time must be a finite number", "", "time");
  if (t == time_) return;
  time_ = t;
  timeDirty_ = true;
  needEval_ = true;
  failed_ = false;
  halted_ = false;
  metrics_.reset();
  if (running_) cancel_ = true;
}

void Document::setLod(double f) {
  if (!(f > 0 && f <= 1)) throw Error("level of detail must be in (0, 1]", "", "lod");
  if (f == lod_) return;
  lod_ = f;
  lodDirty_ = true;
  needEval_ = true;
  failed_ = false;
  halted_ = false;
  if (running_) cancel_ = true;
}

bool Document::PreviewView::operator==(const PreviewView& o) const {
  return camera.eye == o.camera.eye && camera.target == o.camera.target && camera.up == o.camera.up &&
         camera.fovYDegrees == o.camera.fovYDegrees && width == o.width && height == o.height;
}

void Document::setPreviewView(const render::Camera& camera, int width, int height) {
  if (width < 1 || height < 1) return;
  view_ = PreviewView{camera, width, height};
}

void Document::cancel() {
  if (running_) cancel_ = true;
  halted_ = true;
}

void Document::resume() { halted_ = false; }

bool Document::upToDate() const {
  return hasScene() && !running_ && !failed_ && !needEval_ && !pending_ && !timeDirty_ && !lodDirty_ && !checkWanted_ &&
         !exportWanted_ && (scene_.render.lodByScreenSize ? view_ : std::nullopt) == meshedView_;
}

JobProgress Document::progress() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return progress_;
}

std::optional<std::string> Document::takeError() {
  std::optional<std::string> e;
  e.swap(error_);
  return e;
}

const Snapshot& Document::snapshot() const { return *snapshot_; }

void Document::requestExport(ExportRequest request) {
  if (request.path.empty()) throw Error("no file name given", "", "export");
  exchange::formatOf(request.path);  // refuses an unknown extension now, naming the file
  exportWanted_ = std::move(request);
}

void Document::requestCheck() {
  checkWanted_ = true;
  metrics_.reset();
}

void Document::update() {
  if (!hasScene()) return;
  if (running_) {
    {
      // Adopt phases the worker has published (skin first, then follicles, then the coat).
      std::lock_guard<std::mutex> lock(mutex_);
      if (workerSnapshot_) snapshot_ = std::move(workerSnapshot_);
    }
    if (!done_) return;
    finishJob();
  }
  if (failed_ || halted_) return;
  // Anything that left a stage dirty behind the Document's back is evaluated too (the GL view must
  // never pull a dirty pipeline on the UI thread).
  if (!needEval_ && !pending_ && pipeline_->dirty(Stage::Mesh)) needEval_ = true;
  // Levels of detail by screen size follow the preview's view (and the scene's key, which no stage reads).
  const std::optional<PreviewView> view = scene_.render.lodByScreenSize ? view_ : std::nullopt;
  if (!(view == meshedView_)) needEval_ = true;
  if (!(needEval_ || pending_ || timeDirty_ || lodDirty_ || checkWanted_ || exportWanted_)) return;
  // Hand edits to the pipeline (the worker is idle).
  try {
    if (pending_) pipeline_->editScene(*pending_, [&](Scene& s) { s = scene_; });
    pending_.reset();
    // Always (no-ops when equal): a job cancelled inside Pipeline::check() leaves the checker's full
    // level of detail set.
    pipeline_->setTime(time_);
    pipeline_->setLod(lod_);
    timeDirty_ = lodDirty_ = false;
    jobView_ = meshedView_ = view;
  } catch (const std::exception& e) {
    error_ = e.what();
    failed_ = true;
    return;
  }
  const bool check = checkWanted_;
  checkWanted_ = false;
  needEval_ = false;
  jobExport_ = std::move(exportWanted_);
  exportWanted_.reset();
  startJob(check);
}

void Document::startJob(bool check) {
  cancel_ = false;
  done_ = false;
  running_ = true;
  jobOk_ = false;
  jobError_.reset();
  jobMetrics_.reset();
  jobExportOutcome_.reset();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    progress_ = {"start", 0.0};
  }
  pipeline_->setProgress([this](const std::string& stage, double f) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      progress_ = {stage, f};
    }
    if (cancel_) throw Cancelled{};
    return true;
  });
  auto base = std::make_shared<Snapshot>(*snapshot_);
  worker_ = std::thread([this, check, base] {
    Snapshot work = *base;
    try {
      Pipeline& p = *pipeline_;
      const uint64_t poseBefore = p.evaluations(Stage::Pose), tractsBefore = p.evaluations(Stage::Tracts);
      const uint64_t distBefore = p.evaluations(Stage::Distribute);
      const bool poseDirty = p.dirty(Stage::Pose);
      // Phase 1: the rest skin, shown while the rest evaluates.
      const uint64_t skinBefore = p.evaluations(Stage::Skin);
      const coat::SkinMesh& rest = p.restSkin();
      if (!work.restSkin || p.evaluations(Stage::Skin) != skinBefore)
        work.restSkin = std::make_shared<const coat::SkinMesh>(rest);
      if (poseDirty && p.evaluations(Stage::Skin) > 0 && (work.skinVersion == 0 || work.skin.empty())) {
        work.skin = coat::toTriMesh(rest);
        bounds(work.skin, work.skinLo, work.skinHi);
        work.groupNames = rest.groupNames;
        ++work.skinVersion;
        publishSnapshot(work);
      }
      const auto& tracts = p.tracts();
      if (p.evaluations(Stage::Tracts) != tractsBefore || work.tractNames.size() != tracts.size()) {
        work.tractNames.clear();
        work.tractFaces.clear();
        for (const auto& t : tracts) {
          work.tractNames.push_back(t.name);
          work.tractFaces.push_back(t.faces);
        }
        work.groupNames = rest.groupNames;
      }
      // Phase 2: follicles.
      const coat::Follicles& f = p.follicles();
      if (p.evaluations(Stage::Distribute) != distBefore || work.follicleVersion == 0) {
        work.follicle.assign(f.size(), glm::vec3(0));
        work.follicleNormal.assign(f.size(), glm::vec3(0));
        for (size_t i = 0; i < f.size(); ++i) {
          work.follicle[i] = glm::vec3(f.position[i]);
          work.follicleNormal[i] = glm::vec3(f.normal[i]);
        }
        work.follicleId = f.id;
        work.follicleTract = f.tract;
        ++work.follicleVersion;
        publishSnapshot(work);
      }
      // Phase 3: posed skin and the coat.
      const coat::SkinMesh& posed = p.posedSkin();
      if (p.evaluations(Stage::Pose) != poseBefore || work.skinVersion == 0) {
        work.skin = coat::toTriMesh(posed);
        bounds(work.skin, work.skinLo, work.skinHi);
        work.posedVertex.assign(posed.positions.begin(), posed.positions.end());
        work.groupNames = rest.groupNames;
        ++work.skinVersion;
      }
      // Levels by screen size from the packed feathers (pulls the pack, not the mesh).
      p.setFeatherLods(jobView_ ? render::screenSizeLods(p, jobView_->camera, jobView_->width, jobView_->height)
                                : std::vector<double>{});
      const pipeline::CoatMesh& cm = p.coatMesh();
      const coat::CoatFeathers& cf = p.feathers();
      const std::vector<double>& elev = p.elevations();
      const size_t n = cf.size();
      work.featherOrigin.resize(n);
      work.featherTangent.resize(n);
      work.featherNormal.resize(n);
      work.featherElevation.resize(n);
      for (size_t i = 0; i < n; ++i) {
        work.featherOrigin[i] = glm::vec3(cf.frames[i].origin);
        work.featherTangent[i] = glm::vec3(cf.frames[i].tangent);
        work.featherNormal[i] = glm::vec3(cf.frames[i].normal);
        work.featherElevation[i] = i < elev.size() ? float(elev[i]) : 0.0f;
      }
      work.featherFollicle = cf.follicle;
      work.featherPresent = cf.present;
      work.featherTract = cf.tract;
      work.featherAge.assign(cf.age.begin(), cf.age.end());
      work.featherLayerOrder = cf.layerOrder;
      work.featherMaterial.assign(n, UINT32_MAX);
      for (const auto& r : cm.ranges)
        if (r.feather < n) work.featherMaterial[r.feather] = r.material;
      work.featherLength.resize(n);
      for (size_t i = 0; i < n; ++i) work.featherLength[i] = float(cf.params[i].rachisLength);
      work.materials = cm.materials;
      work.coatTriangles = cm.mesh.triangleCount();
      work.coatFeathers = cm.ranges.size();
      glm::vec3 lo, hi;
      if (cm.mesh.bounds(lo, hi)) {
        work.coatLo = lo;
        work.coatHi = hi;
      } else {
        work.coatLo = work.skinLo;
        work.coatHi = work.skinHi;
      }
      work.haveCoat = true;
      for (size_t s = 0; s < pipeline::kStageCount; ++s) work.stageSeconds[s] = p.lastSeconds(Stage(s));
      ++work.coatVersion;
      publishSnapshot(work);
      if (check) {
        pipeline::QualityMetrics m = p.check();
        p.coatMesh();  // the checker meshes at full detail; mesh again at the viewer's level of detail
        std::lock_guard<std::mutex> lock(mutex_);
        jobMetrics_ = m;
      }
      if (jobExport_) {
        ExportOutcome out;
        out.path = jobExport_->path;
        // Exports carry every feather at the level of detail, not the preview's levels by screen size.
        const std::vector<double> levels = p.featherLods();
        p.setFeatherLods({});
        try {
          out.result = exchange::exportCoat(p, jobExport_->path, jobExport_->options);
        } catch (const Cancelled&) {
          out.error = "cancelled (nothing was written)";
        } catch (const std::exception& e) {
          out.error = e.what();
        }
        p.setFeatherLods(levels);
        p.coatMesh();  // a frame range moved the time; evaluate the viewer's frame again
        std::lock_guard<std::mutex> lock(mutex_);
        jobExportOutcome_ = std::move(out);
      }
      jobOk_ = true;
    } catch (const Cancelled&) {
      // The edit that cancelled the job starts a new one.
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      jobError_ = e.what();
    }
    done_ = true;
  });
}

void Document::publishSnapshot(const Snapshot& s) {
  auto copy = std::make_shared<Snapshot>(s);
  std::lock_guard<std::mutex> lock(mutex_);
  workerSnapshot_ = std::move(copy);
}

void Document::finishJob() {
  worker_.join();
  running_ = false;
  pipeline_->setProgress({});
  std::lock_guard<std::mutex> lock(mutex_);
  if (workerSnapshot_) snapshot_ = std::move(workerSnapshot_);
  progress_ = {};
  if (jobExportOutcome_) lastExport_ = std::move(jobExportOutcome_);
  jobExportOutcome_.reset();
  jobExport_.reset();
  if (jobError_) {
    error_ = *jobError_;
    failed_ = true;
  } else if (jobOk_) {
    if (jobMetrics_) metrics_ = jobMetrics_;
    ++resultVersion_;
  } else {
    needEval_ = true;  // cancelled: evaluate again with what changed meanwhile
  }
}

bool Document::waitIdle() {
  for (;;) {
    update();
    if (failed_ || halted_) return false;
    if (upToDate()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

}  // namespace pteryla::viewer
