#pragma once
// Document: the scene being edited in the viewer, its undo history, where it is saved, and the Pipeline
// that evaluates it on a background thread so the window keeps drawing during relaxation, packing or a
// full evaluation.
//
// Threading: the UI thread owns the Document. Edits change the Document's own copy of the Scene
// (scene()) at once and are handed to the Pipeline with Pipeline::editScene(stage, ...) when no job is
// running; `stage` is the earliest stage the edit affects (pipeline::earliestChangedStage, the
// pipeline's section-to-stage table), so only what is downstream re-runs. While a job runs the Pipeline
// belongs to the worker thread: the UI reads only the Snapshot, which the worker publishes in phases
// (posed skin, follicles, coat) as stages finish.
// A new edit while a job runs cancels it at the next progress report (stage boundary or relaxation
// iteration); the cancelled stage stays dirty and is re-run with the edit applied.
//
// Undo/redo: every edit stores the whole Scene before it (scenes are small: sections are JSON), so undo
// is exact. Edits with the same label inside one gesture (a slider drag) share one undo step.
// Save never overwrites an existing file unless asked to (saveAs(path, overwrite)).
// No GL, no ImGui: unit-tested in tests/viewer.
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <glm/vec3.hpp>

#include "pteryla/coat/skin.hpp"
#include "pteryla/core/trimesh.hpp"
#include "pteryla/exchange/coat_export.hpp"
#include "pteryla/pipeline/pipeline.hpp"
#include "pteryla/pipeline/scene.hpp"
#include "pteryla/render/camera.hpp"

namespace pteryla::viewer {

// What the panels and overlays read from the last evaluation (copied off the worker thread).
struct Snapshot {
  uint64_t skinVersion = 0, follicleVersion = 0, coatVersion = 0;  // bump when the part changes
  TriMesh skin;  // posed skin (triangles, for picking and the wire overlay)
  // The rest skin as the library has it (vertex and triangle numbering, source polygons: what tract
  // faces and the density map index) and its vertices posed (one per rest vertex): painting (paint.hpp).
  std::shared_ptr<const coat::SkinMesh> restSkin;
  std::vector<glm::vec3> posedVertex;
  glm::vec3 skinLo{0}, skinHi{0};
  std::vector<std::string> groupNames;  // skin mesh groups (tract building blocks)
  std::vector<std::string> tractNames;
  std::vector<std::vector<uint32_t>> tractFaces;  // triangles of each tract
  // Follicles at rest (before any pose).
  std::vector<glm::vec3> follicle, follicleNormal;
  std::vector<uint64_t> follicleId;
  std::vector<uint32_t> follicleTract;
  // Feathers at the current time: follicle frame origin / tangent / normal, elevation, key flag.
  std::vector<glm::vec3> featherOrigin, featherTangent, featherNormal;
  std::vector<float> featherElevation;    // radians
  std::vector<uint32_t> featherFollicle;  // index into follicle arrays
  std::vector<uint8_t> featherPresent;
  std::vector<uint32_t> featherTract;       // tract index per feather
  std::vector<float> featherAge;            // growth and wear age (growth.md)
  std::vector<uint32_t> featherLayerOrder;  // feather indices, bottom layer first
  std::vector<uint32_t> featherMaterial;    // index into `materials` (UINT32_MAX: not drawn)
  std::vector<float> featherLength;         // rachis length, scene units (to frame a selection)
  std::vector<pipeline::CoatMaterial> materials;
  size_t coatTriangles = 0, coatFeathers = 0;
  glm::vec3 coatLo{0}, coatHi{0};
  bool haveCoat = false;
  double stageSeconds[pipeline::kStageCount] = {};  // last evaluation time of each stage
};

struct JobProgress {
  std::string stage;  // "distribute", "pack", ...
  double fraction = 0;
};

class Document {
 public:
  Document();
  ~Document();
  Document(const Document&) = delete;
  Document& operator=(const Document&) = delete;

  // Loads a scene file or a bare mesh (made explicit, see makeBareMeshExplicit). Throws pteryla::Error;
  // the current document is kept then. Clears the undo history.
  void open(const std::string& path);
  // Starts from an in-memory scene (`path` = where Save writes, "" = ask).
  void reset(pipeline::Scene scene, const std::string& path);
  bool hasScene() const { return pipeline_ != nullptr; }
  const pipeline::Scene& scene() const { return scene_; }
  const std::string& path() const { return path_; }  // "" for bare meshes: Save needs a path
  bool modified() const { return modified_; }
  // Counts changes of the scene (edits, undo, redo, open): autosave writes when it moved on.
  uint64_t changeCount() const { return changes_; }
  // Marks the document as having unsaved changes (a scene restored from a recovery file).
  void markModified() {
    modified_ = true;
    ++changes_;
  }

  // Applies `fn` to the scene; one undo step (merged with the previous one when `label` is the same
  // and the gesture has not ended). A throwing `fn` leaves the scene unchanged.
  void edit(const std::string& label, const std::function<void(pipeline::Scene&)>& fn);
  void endGesture() { gestureOpen_ = false; }
  bool canUndo() const { return !undo_.empty(); }
  bool canRedo() const { return !redo_.empty(); }
  std::string undoLabel() const { return undo_.empty() ? "" : undo_.back().label; }
  std::string redoLabel() const { return redo_.empty() ? "" : redo_.back().label; }
  bool undo();
  bool redo();

  // Writes the scene to `path`. Returns false (and writes nothing) when `path` exists, is not the
  // document's own file and `overwrite` is false. Throws pteryla::Error when writing fails.
  bool saveAs(const std::string& path, bool overwrite = false);
  // saveAs(path()) — the document's own file may be overwritten. Throws when path() is empty.
  void save();

  void setTime(double t);
  double time() const { return time_; }
  void setLod(double fraction);  // (0, 1]
  double lod() const { return lod_; }
  // The view the preview is drawn with (the viewer calls this when the camera is at rest). With the
  // scene's render.lod_by_screen_size (default on) the preview meshes each feather at lod() times the
  // fraction render::screenSizeLods gives it in this view, as `pteryla render` does, so lod() is the cap;
  // a different view re-meshes (the mesh stage only). Without a view, or with the key false, every
  // feather is meshed at lod().
  void setPreviewView(const render::Camera& camera, int width, int height);

  // Call once per frame on the UI thread: collects a finished job, hands pending edits to the pipeline
  // and starts an evaluation when something is out of date. Never blocks on a running job.
  void update();
  bool busy() const { return running_; }
  bool upToDate() const;                   // idle, no pending edit, last evaluation complete and ok
  bool failed() const { return failed_; }  // the last evaluation threw (until the next edit)
  JobProgress progress() const;
  // Stops the running job at its next progress report and holds evaluation until the next edit or
  // resume() (the user's Cancel).
  void cancel();
  void resume();
  bool halted() const { return halted_; }
  // Blocks until idle and up to date (or failed); returns false when the evaluation failed.
  bool waitIdle();
  // The last error message (from a job or a failed re-evaluation), handed out once.
  std::optional<std::string> takeError();
  const Snapshot& snapshot() const;
  // Bumps each time a job finished successfully (the GL view re-syncs with the pipeline then).
  uint64_t resultVersion() const { return resultVersion_; }
  // The pipeline, only when no job runs (nullptr otherwise). Do not edit its scene directly.
  pipeline::Pipeline* idlePipeline() { return running_ || !pipeline_ ? nullptr : pipeline_.get(); }

  // Runs the independent checker in the background; metrics() has the result when it finishes.
  void requestCheck();
  const std::optional<pipeline::QualityMetrics>& metrics() const { return metrics_; }

  // Exports the coat (exchange::exportCoat: glTF, USD, OBJ, PLY; docs/export.md) in the background once
  // the evaluation is complete; progress() reports its frames, cancel() stops it (nothing is left
  // behind). lastExport() says how the last one ended.
  struct ExportRequest {
    std::string path;
    exchange::ExportOptions options;
  };
  struct ExportOutcome {
    std::string path;
    std::optional<exchange::ExportResult> result;  // empty: it failed or was cancelled
    std::string error;
  };
  void requestExport(ExportRequest request);
  const std::optional<ExportOutcome>& lastExport() const { return lastExport_; }

 private:
  struct Entry {
    std::string label;
    pipeline::Scene scene;
  };
  void markChanged(const pipeline::Scene& before);
  void startJob(bool check);
  void finishJob();
  void publishSnapshot(const Snapshot& s);  // worker thread

  pipeline::Scene scene_;
  std::string path_;
  bool modified_ = false;
  uint64_t changes_ = 0;
  std::vector<Entry> undo_, redo_;
  bool gestureOpen_ = false;
  std::string lastLabel_;
  double time_ = 0, lod_ = 1;
  struct PreviewView {
    render::Camera camera;
    int width = 0, height = 0;
    bool operator==(const PreviewView& o) const;
  };
  std::optional<PreviewView> view_;        // the last view given (setPreviewView)
  std::optional<PreviewView> meshedView_;  // the view of the last job's levels (none: every feather at lod_)
  std::optional<PreviewView> jobView_;     // the running job's (the worker's copy)

  std::unique_ptr<pipeline::Pipeline> pipeline_;
  std::optional<pipeline::Stage> pending_;  // earliest stage to invalidate before the next job
  bool timeDirty_ = false, lodDirty_ = false;
  bool failed_ = false, halted_ = false, needEval_ = false, checkWanted_ = false;
  std::optional<pipeline::QualityMetrics> metrics_;

  std::thread worker_;
  bool running_ = false;
  std::atomic<bool> done_{false}, cancel_{false};
  mutable std::mutex mutex_;  // guards the fields below, shared with the worker
  JobProgress progress_;
  std::shared_ptr<Snapshot> snapshot_, workerSnapshot_;
  std::optional<std::string> jobError_, error_;
  std::optional<pipeline::QualityMetrics> jobMetrics_;
  std::optional<ExportRequest> exportWanted_, jobExport_;
  std::optional<ExportOutcome> lastExport_, jobExportOutcome_;
  bool jobOk_ = false;
  uint64_t resultVersion_ = 0;
};

}  // namespace pteryla::viewer
