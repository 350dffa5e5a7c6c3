#pragma once
// Render frames (docs/viewer.md, "Render frames"; frame_render.cpp): the timeline range written to PNGs
// from the Scene panel (ViewState::frameRequest, script `render-frames`), on a pipeline of its own
// evaluated on a worker thread and drawn on the window's GL context between UI frames, with progress
// and Cancel (ViewState::framesRunning, framesDone, frameCancel, framesStatus).
#include <memory>

#include "document.hpp"
#include "panels.hpp"

namespace pteryla::viewer {

class GlfwContext;

class FrameRenderer {
 public:
  FrameRenderer(Document& doc, ViewState& view);
  ~FrameRenderer();
  // Once per frame: starts a requested render, writes the frame whose evaluation finished and asks for
  // the next. True when a frame was written (keep drawing while frames are made). Throws an Error when
  // the request is bad or a frame fails (the render stops).
  bool step(GlfwContext& context);

 private:
  struct Job;
  Document& doc_;
  ViewState& view_;
  std::unique_ptr<Job> job_;
};

}  // namespace pteryla::viewer
