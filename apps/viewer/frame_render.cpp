// Render frames (docs/viewer.md, "Render frames"): the range from..to at fps, frame k at from + k / fps
// written to DIR/frame_NNNN.png (the names `pteryla frames` uses), at the scene's render size, level of
// detail and camera. The frames are evaluated by a Pipeline of their own on a worker thread (the
// document's pipeline and the timeline are untouched), one at a time, and drawn on the window's GL
// context between UI frames, so the viewer stays responsive; Cancel stops after the frame under way.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "frame_render.hpp"
#include "glfw_context.hpp"
#include "pteryla/core/error.hpp"
#include "pteryla/render/scene_view.hpp"

namespace pteryla::viewer {

struct FrameRenderer::Job {
  ViewState::FrameRequest request;
  size_t count = 0, next = 0;
  std::unique_ptr<pipeline::Pipeline> pipe;
  std::unique_ptr<render::SceneView> view;
  std::thread worker;
  std::atomic<bool> done{false}, cancel{false};
  std::string error;
  int width = 0, height = 0;
  ~Job() {
    cancel = true;
    if (worker.joinable()) worker.join();
  }
  void evaluate(size_t k) {
    done = false;
    const double t = request.from + double(k) / request.fps;
    worker = std::thread([this, t] {
      try {
        pipe->setTime(t);
        pipe->coatMesh();
      } catch (const std::exception& e) {
        error = e.what();
      }
      done = true;
    });
  }
};

FrameRenderer::FrameRenderer(Document& doc, ViewState& view) : doc_(doc), view_(view) {}

FrameRenderer::~FrameRenderer() = default;

bool FrameRenderer::step(GlfwContext& context) {
  if (view_.frameCancel) {
    view_.frameCancel = false;
    if (job_) job_->cancel = true;
  }
  if (view_.frameRequest && !job_ && doc_.hasScene()) {
    const ViewState::FrameRequest rq = *view_.frameRequest;
    view_.frameRequest.reset();
    if (rq.dir.empty() || !(rq.fps > 0) || !(rq.to >= rq.from) || !std::isfinite(rq.from) || !std::isfinite(rq.to))
      throw Error("render frames needs a directory, fps > 0 and to >= from", "", "render frames");
    std::error_code ec;
    std::filesystem::create_directories(rq.dir, ec);
    if (ec) throw Error("cannot create the directory: " + ec.message(), rq.dir);
    auto job = std::make_unique<Job>();
    job->request = rq;
    job->count = size_t(std::floor((rq.to - rq.from) * rq.fps + 1e-9)) + 1;
    const pipeline::Scene& s = doc_.scene();
    job->width = s.render.width;
    job->height = s.render.height;
    auto* jp = job.get();
    job->pipe = std::make_unique<pipeline::Pipeline>(s, [jp](const std::string&, double) { return !jp->cancel; });
    job->pipe->setLod(s.render.lod);
    job->view = std::make_unique<render::SceneView>(context);
    job_ = std::move(job);
    view_.framesRunning = true;
    view_.framesDone = 0;
    view_.framesTotal = job_->count;
    view_.framesStatus.clear();
    job_->evaluate(0);
  }
  if (!job_ || !job_->done) return false;
  Job& f = *job_;
  f.worker.join();
  auto finish = [&](const std::string& status) {
    view_.framesStatus = status;
    view_.framesRunning = false;
    context.makeCurrent();
    job_.reset();
  };
  if (f.cancel) {
    finish("cancelled after " + std::to_string(f.next) + " of " + std::to_string(f.count) + " frames");
    return false;
  }
  if (!f.error.empty()) {
    const std::string e = f.error;
    finish("failed at frame " + std::to_string(f.next) + ": " + e);
    throw Error(e, "", "render frames");
  }
  char name[32];
  std::snprintf(name, sizeof name, "frame_%04zu.png", f.next);
  const std::string path = (std::filesystem::path(f.request.dir) / name).string();
  try {
    context.makeCurrent();
    f.view->markDirty();  // a new time: upload the coat and its materials afresh
    render::saveImage(path, f.view->render(*f.pipe, f.width, f.height));
  } catch (const std::exception& e) {
    finish(std::string("failed: ") + e.what());
    throw;
  }
  ++f.next;
  view_.framesDone = f.next;
  if (f.next < f.count) {
    f.evaluate(f.next);
    return true;
  }
  finish(std::to_string(f.count) + " frames written to " + f.request.dir);
  return true;
}

}  // namespace pteryla::viewer
