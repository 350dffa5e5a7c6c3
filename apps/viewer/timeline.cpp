// Timeline playback in the viewer (issue #26, item 3): playback at the timeline's frame rate in wall time
// (a frame not ready when the next is due is dropped, so playback never lags behind the clock), and the
// flipbook of drawn frames (playback.hpp): a time drawn before, with the same view and scene, shows at
// once when it is played or scrubbed to again, while its coat is evaluated behind it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "timeline.hpp"

#include "scene_edit.hpp"

namespace pteryla::viewer {

namespace {
double wallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

void fitTimeRange(const Document& doc, ViewState& view) {
  view.timeStart = 0.0f;
  view.timeEnd = 10.0f;
  if (!doc.hasScene()) return;
  if (const auto span = sceneTimeSpan(doc.scene())) {
    view.timeStart = float(std::min(0.0, span->first));
    view.timeEnd = float(std::max(span->second, span->first + 1.0));
  }
  view.timeEnd = std::max(view.timeEnd, float(doc.time()));
  view.timeStart = std::min(view.timeStart, float(doc.time()));
}

void Timeline::playFor(double seconds) {
  view_.playing = true;
  playClock_.stop();
  play_.seconds = seconds;
  play_.until = 1;  // (set to the end when the clock starts)
}

std::vector<float> Timeline::flipbookKey(double lod, bool fast) const {
  std::vector<float> k = viewport_.viewKey();
  if (k.size() > Viewport::kUploadKeyIndex)
    k.erase(k.begin() + Viewport::kUploadKeyIndex);  // the upload counter: the time and the scene stand for it
  k.push_back(float(lod));
  k.push_back(float(doc_.changeCount()));
  k.push_back(float(static_cast<int>(view_.colourBy)));
  if (fast) {  // the fast playback quality: its resolution
    k.push_back(1.0f);
    k.push_back(float(std::clamp(view_.navigationScale, 1, 8)));
  }
  return k;
}

const render::Image* Timeline::findFrame(double t, double lod) {
  if (const render::Image* img = flipbook_.find(t, flipbookKey(lod))) return img;
  return view_.playing && view_.fastPlayback ? flipbook_.find(t, flipbookKey(lod, true)) : nullptr;
}

void Timeline::advance() {
  if (!doc_.hasScene()) return;
  // An edit (or undo) makes every frame drawn before stale.
  if (doc_.changeCount() != flipbookChanges_) {
    flipbook_.clear();
    flipbookChanges_ = doc_.changeCount();
  }
  flipbook_.setBudget(size_t(std::max(0, view_.flipbookMB)) << 20);
  view_.flipbookFrames = flipbook_.size();
  view_.flipbookBytes = flipbook_.bytes();
  const double now = wallSeconds();
  if (view_.cacheRangeRequested) {
    view_.cacheRangeRequested = false;
    if (!fill_.active && !view_.playing) {
      fill_ = CacheFill{};
      fill_.active = true;
      fill_.returnTo = doc_.time();
    }
  }
  if (fill_.active) {
    view_.playing = false;
    advanceCacheFill();
  }
  view_.caching = fill_.active;
  if (!view_.playing) {
    if (playClock_.running()) {
      playClock_.stop();
      endPlay();
    }
    displayTime_ = doc_.time();
    view_.shownTime = displayTime_;
    return;
  }
  const FrameGrid grid{view_.timeStart, view_.timeEnd, view_.timeStep};
  if (!playClock_.running()) {
    const double seconds = play_.seconds;
    play_ = PlayStats{};
    play_.seconds = seconds;
    play_.until = seconds > 0 ? now + seconds : 0;
    play_.startWall = now;
    // Play from where the timeline is; at (or past) the end of a range played once, from its start.
    const bool atEnd = !view_.loop && grid.nearest(doc_.time()) >= grid.last();
    playClock_.start(grid, atEnd ? grid.start : doc_.time(), now);
    ask_ = Ask{};
    displayTime_ = doc_.time();
  }
  // The frame asked for last is on screen once it is evaluated, its coat uploaded and the view drawn
  // (renderView, which also keeps it in the flipbook); only then is the next one asked for.
  if (play_.awaitingResult && doc_.upToDate() && doc_.time() == displayTime_ &&
      doc_.resultVersion() == viewport_.syncedResult() && viewport_.drawnResult() == viewport_.syncedResult()) {
    play_.awaitingResult = false;
    ++play_.shown;
    ++play_.evaluated;
  }
  auto stop = [&] {
    view_.playing = false;
    playClock_.stop();
    endPlay();
  };
  if (play_.until > 0 && now >= play_.until) return stop();
  const std::optional<int64_t> due = playClock_.due(now, view_.playFps, view_.loop);
  if (!due) {
    // Played once to the end: the playhead stops on the range's last frame (evaluated on pause when it
    // was not drawn in time).
    if (view_.flipbookMB > 0) displayTime_ = grid.time(grid.last());
    return stop();
  }
  if (doc_.failed()) return stop();
  if (view_.flipbookMB > 0) return advanceAhead(grid, *due, now);
  if (*due == play_.lastDue) return;
  const double t = grid.time(*due);
  if (findFrame(t, doc_.lod())) {
    play_.lastDue = *due;
    displayTime_ = t;
    play_.awaitingResult = false;  // an evaluation still running is overtaken
    ++play_.shown;
    ++play_.fromCache;
    return;
  }
  // Still evaluating or drawing the frame asked for last: it shows when ready, and the frames due
  // meanwhile are dropped (the next one asked for is the one due then).
  if (play_.awaitingResult || !doc_.upToDate()) return;
  play_.lastDue = *due;
  displayTime_ = t;
  play_.awaitingResult = true;
  doc_.setTime(t);
}

bool Timeline::inFlipbook(double t) const {
  return flipbook_.contains(t, flipbookKey(doc_.lod())) ||
         (view_.fastPlayback && flipbook_.contains(t, flipbookKey(doc_.lod(), true)));
}

// Playing with a flipbook: the clock shows the frame due from the flipbook (or keeps the last one: a frame
// not drawn in time is dropped), while the coat is evaluated ahead of it: each frame asked for is the first
// not in the flipbook from where the clock will be when its evaluation ends (the smoothed time an
// evaluation has taken), and is drawn into the flipbook as soon as it is ready (App::renderView). The
// drawing and the next evaluation overlap, and no evaluation is wasted: one overtaken by the clock plays
// on the next pass of a loop.
void Timeline::advanceAhead(const FrameGrid& grid, int64_t due, double now) {
  const int64_t n = grid.last() + 1;
  int64_t arrived = -1;  // the frame asked for, just drawn into the flipbook
  if (ask_.pending) {
    if (doc_.time() != ask_.time) {
      ask_.pending = false;  // the time was set elsewhere (a scrub): ask again
    } else if (ask_.drawn && doc_.upToDate()) {
      ask_.pending = false;
      arrived = ask_.index;
      ++play_.evaluated;
      const double took = std::max(0.0, now - ask_.wall);
      evalSeconds_ = evalSeconds_ > 0 ? 0.5 * (evalSeconds_ + took) : took;
    }
  }
  // The first pass: as many frames due as the range has (before any was drawn on an earlier pass).
  if (play_.firstPassSeconds == 0 && view_.playFps > 0 && now - play_.startWall >= double(n) / view_.playFps) {
    play_.firstPassSeconds = std::max(1e-9, now - play_.startWall);
    play_.firstPassShown = play_.shown;
  }
  play_.lastDue = due;
  // A frame that came in after the clock passed it, but newer than the one on screen: shown (at most an
  // evaluation late, as playback without a flipbook shows its frames).
  if (arrived >= 0 && due != play_.shownDue) {
    const auto ahead = [n](int64_t a, int64_t b) { return ((b - a) % n + n) % n; };
    if (play_.shownDue < 0 ||
        (ahead(play_.shownDue, arrived) > 0 && ahead(play_.shownDue, arrived) <= ahead(play_.shownDue, due))) {
      displayTime_ = grid.time(arrived);
      play_.shownDue = arrived;
      ++play_.shown;
    }
  }
  if (due != play_.shownDue) {
    const double t = grid.time(due);
    if (findFrame(t, doc_.lod())) {
      displayTime_ = t;
      play_.shownDue = due;
      ++play_.shown;
      ++play_.fromCache;
    }
  }
  view_.shownTime = displayTime_;
  if (ask_.pending || !doc_.upToDate()) return;
  const int64_t lead = static_cast<int64_t>(std::ceil(evalSeconds_ * double(std::max(view_.playFps, 0.0f))));
  for (int64_t k = 0; k < n; ++k) {
    int64_t m = due + lead + k;
    if (m >= n) {
      if (!view_.loop) break;
      m %= n;
    }
    const double t = grid.time(m);
    if (inFlipbook(t)) continue;
    ask_ = Ask{true, false, m, t, now};
    doc_.setTime(t);
    break;
  }
}

bool Timeline::evaluatedFrameToDraw() const {
  return playingAhead() && ask_.pending && !ask_.drawn && doc_.upToDate() && doc_.time() == ask_.time &&
         doc_.resultVersion() == viewport_.syncedResult();
}

void Timeline::showShownFrame() {
  if (flipbookShown_ && flipbookShownTime_ == displayTime_) return;
  const render::Image* img = findFrame(displayTime_, doc_.lod());
  if (!img) return;  // nothing drawn for it yet: the last image stays
  viewport_.showImage(*img);
  flipbookShown_ = true;
  flipbookShownTime_ = displayTime_;
}

void Timeline::endPlay() {
  finishPlayReport();
  // Played ahead of the clock: the document's time may be a frame asked for and never shown; the paused
  // view is the frame on screen.
  if (view_.flipbookMB > 0 && displayTime_ != doc_.time()) doc_.setTime(displayTime_);
  ask_ = Ask{};
}

// One step of filling the flipbook: once the frame asked for is evaluated and drawn (renderView stores
// it), ask for the next frame of the range that is not in the flipbook; at the end, go back.
void Timeline::advanceCacheFill() {
  const FrameGrid grid{view_.timeStart, view_.timeEnd, view_.timeStep};
  const int64_t n = grid.last() + 1;
  if (doc_.failed() || view_.flipbookMB <= 0) {
    fill_.active = false;
    return;
  }
  if (!doc_.upToDate() || doc_.resultVersion() != viewport_.syncedResult()) return;  // evaluating or not drawn yet
  const std::vector<float> key = flipbookKey(doc_.lod());
  if (doc_.time() != grid.time(fill_.next) || !flipbook_.contains(doc_.time(), key)) {
    // The frame asked for is evaluated but not drawn yet (renderView stores it this frame), unless it
    // is not the one asked for: ask.
    if (doc_.time() != grid.time(fill_.next) && fill_.next < n && !flipbook_.contains(grid.time(fill_.next), key)) {
      doc_.setTime(grid.time(fill_.next));
      return;
    }
    if (doc_.time() == grid.time(fill_.next) && !flipbook_.contains(doc_.time(), key)) return;
  }
  if (doc_.time() == grid.time(fill_.next)) ++fill_.drawn;
  while (fill_.next < n && flipbook_.contains(grid.time(fill_.next), key)) ++fill_.next;
  view_.cacheProgress = float(double(fill_.next) / double(n));
  if (fill_.next >= n) {
    fill_.active = false;
    doc_.setTime(fill_.returnTo);
    char buf[160];
    std::snprintf(buf, sizeof buf, "flipbook: drew %zu frames of %lld (%zu kept)", fill_.drawn, (long long)n,
                  flipbook_.size());
    view_.playReadout = buf;
    return;
  }
  doc_.setTime(grid.time(fill_.next));
}

bool Timeline::awaitingPlayedFrame() const {
  if (!view_.playing) return false;
  const bool live = doc_.upToDate() && doc_.resultVersion() == viewport_.syncedResult() && displayTime_ == doc_.time();
  return !live && !viewport_.image().empty();
}

bool Timeline::showFlipbookFrame() {
  const double shown = view_.playing ? displayTime_ : doc_.time();
  const bool live = doc_.upToDate() && doc_.resultVersion() == viewport_.syncedResult() && shown == doc_.time();
  if (live) return false;
  const double lod = view_.scrubSavedLod > 0 ? view_.scrubSavedLod : doc_.lod();
  const render::Image* img = findFrame(shown, lod);
  if (!img && lod != doc_.lod()) img = findFrame(shown, doc_.lod());
  if (!img) return false;
  const render::Image& onScreen = viewport_.image();
  if (!flipbookShown_ || flipbookShownTime_ != shown || onScreen.width != img->width ||
      onScreen.height != img->height) {
    viewport_.showImage(*img);
    flipbookShown_ = true;
    flipbookShownTime_ = shown;
  }
  return true;
}

void Timeline::storeFlipbookFrame(bool fast, bool drawn) {
  if (fast && drawn) ++play_.drawnFast;
  if (ask_.pending && doc_.time() == ask_.time) ask_.drawn = true;
  if (view_.flipbookMB <= 0 || viewport_.image().empty()) return;
  if (!doc_.upToDate() || doc_.resultVersion() != viewport_.syncedResult()) return;
  flipbook_.store(doc_.time(), flipbookKey(doc_.lod(), fast), viewport_.image());
  view_.flipbookFrames = flipbook_.size();
  view_.flipbookBytes = flipbook_.bytes();
}

void Timeline::finishPlayReport() {
  const double seconds = std::max(1e-9, wallSeconds() - play_.startWall);
  // Frames the clock passed: every one of them was due once; those not shown were dropped.
  const size_t due = size_t(std::floor(seconds * double(view_.playFps))) + 1;
  // The first pass through the range: what played before anything was in the flipbook from an earlier pass.
  const double firstSeconds = play_.firstPassSeconds > 0 ? play_.firstPassSeconds : seconds;
  const size_t firstShown = play_.firstPassSeconds > 0 ? play_.firstPassShown : play_.shown;
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "last play: %.1f s, %.1f of %.1f fps shown (%zu frames: %zu evaluated, %zu from the flipbook; "
                "%zu dropped)",
                seconds, double(play_.shown) / seconds, double(view_.playFps), play_.shown, play_.evaluated,
                play_.fromCache, due > play_.shown ? due - play_.shown : 0);
  view_.playReadout = buf;
  if (play_.until > 0) {
    std::snprintf(buf, sizeof buf,
                  "{\"play_seconds\": %.3f, \"fps_target\": %.2f, \"frames_due\": %zu, \"frames_shown\": %zu, "
                  "\"frames_evaluated\": %zu, \"frames_from_flipbook\": %zu, \"fps_shown\": %.2f, "
                  "\"frames_drawn_fast\": %zu, \"flipbook_frames\": %zu, \"flipbook_mb\": %.1f, "
                  "\"first_pass_seconds\": %.3f, \"frames_shown_first_pass\": %zu, \"fps_shown_first_pass\": %.2f, "
                  "\"evaluation_seconds\": %.3f, \"time_shown\": %.9g}",
                  seconds, double(view_.playFps), due, play_.shown, play_.evaluated, play_.fromCache,
                  double(play_.shown) / seconds, play_.drawnFast, flipbook_.size(),
                  double(flipbook_.bytes()) / (1 << 20), firstSeconds, firstShown, double(firstShown) / firstSeconds,
                  evalSeconds_, displayTime_);
    std::cout << buf << std::endl;
    play_.until = 0;
    play_.seconds = 0;
  }
}

}  // namespace pteryla::viewer
