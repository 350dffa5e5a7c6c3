#pragma once
// Timeline playback in the viewer (issue #26, item 3), without GL or ImGui (unit-tested in tests/viewer):
//  - PlaybackClock: playback at a frame rate in wall time. The frame due is the one the clock has reached,
//    so a frame that takes longer than 1/fps to evaluate drops the frames it missed instead of making
//    playback lag behind.
//  - Flipbook: recently drawn views of the 3D view, by timeline time and what else the image depends on
//    (camera, look, level of detail, scene edits), within a memory budget (least recently used first
//    out). Scrubbing or playing back over a cached time shows its image at once.
#include <cstddef>
#include <cstdint>
#include <list>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "pteryla/render/image.hpp"

namespace pteryla::viewer {

// Frames of a timeline range: start + m * step for m = 0 .. last(), the last one at or before end.
struct FrameGrid {
  double start = 0, end = 10, step = 1.0 / 24.0;
  int64_t last() const;             // index of the last frame (>= 0)
  int64_t nearest(double t) const;  // the frame nearest to t, clamped to the range
  double time(int64_t m) const { return start + double(m) * step; }
};

class PlaybackClock {
 public:
  // Playback starts on the frame nearest to t at wall time `wall` (seconds).
  void start(const FrameGrid& grid, double t, double wall);
  bool running() const { return running_; }
  void stop() { running_ = false; }
  // The frame due at `wall`: the start frame plus the frames fps has counted since, wrapped to the
  // range's start when looping; nullopt once past the last frame without looping.
  std::optional<int64_t> due(double wall, double fps, bool loop) const;
  const FrameGrid& grid() const { return grid_; }

 private:
  FrameGrid grid_;
  int64_t first_ = 0;
  double wall0_ = 0;
  bool running_ = false;
};

class Flipbook {
 public:
  explicit Flipbook(size_t budgetBytes = size_t(512) << 20) : budget_(budgetBytes) {}
  // The image drawn at time t with the view `key`, or null. A hit becomes the most recently used.
  const render::Image* find(double t, const std::vector<float>& key);
  bool contains(double t, const std::vector<float>& key) const;
  // Keeps a copy (replacing one with the same time and key), then drops the least recently used
  // images until the total is within the budget. An image larger than the budget is not kept.
  void store(double t, const std::vector<float>& key, const render::Image& image);
  void setBudget(size_t bytes);
  size_t budget() const { return budget_; }
  size_t bytes() const { return bytes_; }
  size_t size() const { return entries_.size(); }
  void clear();

 private:
  using Key = std::pair<int64_t, std::vector<float>>;  // time in microseconds, view key
  struct Entry {
    Key key;
    render::Image image;
  };
  static Key keyOf(double t, const std::vector<float>& view);
  void evict();
  size_t budget_ = 0, bytes_ = 0;
  std::list<Entry> entries_;  // most recently used first
  std::map<Key, std::list<Entry>::iterator> index_;
};

}  // namespace pteryla::viewer
