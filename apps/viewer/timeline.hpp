#pragma once
// Timeline playback in the viewer (issue #26, item 3; timeline.cpp): playback at the timeline's frame rate
// in wall time (a frame not ready when the next is due is dropped, so playback never lags behind the
// clock), the flipbook of drawn frames (playback.hpp: a time drawn before, with the same view and scene,
// shows at once when it is played or scrubbed to again, while its coat is evaluated behind it), and
// filling the flipbook over the range ("Cache range"). It reads the 3D view (Viewport) and sets the
// document's time; the Timeline panel (panels_time.cpp) talks to it through ViewState.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "document.hpp"
#include "panels.hpp"
#include "playback.hpp"
#include "viewport.hpp"

namespace pteryla::viewer {

// The timeline range from the scene's keys and moult windows (and the document's time).
void fitTimeRange(const Document& doc, ViewState& view);

class Timeline {
 public:
  Timeline(Document& doc, ViewState& view, Viewport& viewport) : doc_(doc), view_(view), viewport_(viewport) {}

  // Once per frame, before the view is drawn: the playback clock, the frame it asks for, the cache fill.
  void advance();
  // Shows a flipbook frame instead of rendering (a time whose coat is not evaluated yet); false: none.
  bool showFlipbookFrame();
  void liveViewShown() { flipbookShown_ = false; }
  // Playing, and the time on screen is not the evaluated, uploaded coat's yet (its evaluation runs).
  bool awaitingPlayedFrame() const;
  // The view just rendered, complete and at rest (or `fast`: at the fast playback quality), for its time
  // (`drawn`: rendered now, not the view kept from before).
  void storeFlipbookFrame(bool fast = false, bool drawn = true);
  // Playing ahead of the clock (a flipbook to play from): frames are evaluated ahead of the time on
  // screen, each drawn into the flipbook when ready, and the frame due is shown from the flipbook.
  bool playingAhead() const { return view_.playing && view_.flipbookMB > 0 && playClock_.running(); }
  // Playing ahead: the frame asked for is evaluated and synced to the view, not drawn yet.
  bool evaluatedFrameToDraw() const;
  // Playing ahead: shows the flipbook frame of the time on screen (again, after the view drew another).
  void showShownFrame();

  // A scripted `play S`: plays for S seconds, then prints what the playback showed (JSON on stdout).
  void playFor(double seconds);
  bool scriptedPlayRunning() const { return view_.playing && play_.until > 0; }
  bool filling() const { return fill_.active; }
  // The time whose frame is on screen (or about to be): while playing it may run ahead of the document's.
  double shownTime() const { return view_.playing ? displayTime_ : doc_.time(); }

 private:
  // The flipbook's key of the 3D view at a level of detail: what the image depends on besides the time
  // (`fast`: drawn at the fast playback quality, ViewState::fastPlayback).
  std::vector<float> flipbookKey(double lod, bool fast = false) const;
  // A frame of time t at this level of detail: at full quality, or while playing also a fast one.
  const render::Image* findFrame(double t, double lod);
  void advanceCacheFill();
  // Playing ahead of the clock (playingAhead()): show the frame due, ask for the next one to evaluate.
  void advanceAhead(const FrameGrid& grid, int64_t due, double now);
  bool inFlipbook(double t) const;
  void finishPlayReport();  // `play S`: prints what the playback showed
  void endPlay();           // the play report, and the paused time is the time on screen

  Document& doc_;
  ViewState& view_;
  Viewport& viewport_;
  // Playback: the clock, what it showed, and the flipbook.
  PlaybackClock playClock_;
  Flipbook flipbook_;
  double displayTime_ = 0;      // the time on screen while playing (a flipbook frame may run ahead)
  bool flipbookShown_ = false;  // the view texture holds a flipbook frame (of flipbookShownTime_)
  double flipbookShownTime_ = 0;
  uint64_t flipbookChanges_ = 0;  // the document's change count the flipbook's frames belong to
  // Filling the flipbook over the timeline range (Timeline panel "Cache range", script `cache-range`):
  // the next frame to draw, and the time to return to.
  struct CacheFill {
    bool active = false;
    int64_t next = 0;
    double returnTo = 0;
    size_t drawn = 0;
  } fill_;
  struct PlayStats {
    double startWall = 0, until = 0;  // until > 0: a scripted `play S` ends then
    double seconds = 0;               // `play S`: S (until is set when the clock starts)
    int64_t lastDue = -1, firstDue = -1;
    size_t due = 0, shown = 0, fromCache = 0, evaluated = 0;
    size_t drawnFast = 0;  // views drawn at the fast playback quality
    bool awaitingResult = false;
    int64_t shownDue = -1;  // playing ahead: the frame index last shown
    size_t firstPassShown = 0;
    double firstPassSeconds = 0;  // the wall time of the first pass through the range (0: not over)
  } play_;
  // Playing ahead: the frame asked for (its evaluation runs or its view is not drawn yet), and the
  // smoothed seconds from asking to drawn, which set how far ahead of the clock the next ask is.
  struct Ask {
    bool pending = false, drawn = false;
    int64_t index = -1;
    double time = 0, wall = 0;
  } ask_;
  double evalSeconds_ = 0;
};

}  // namespace pteryla::viewer
