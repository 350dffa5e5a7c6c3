// Timeline playback: frame clock and flipbook (playback.hpp).
#include "playback.hpp"

#include <algorithm>
#include <cmath>

namespace pteryla::viewer {

int64_t FrameGrid::last() const {
  if (!(step > 0) || !(end > start)) return 0;
  return std::max<int64_t>(0, static_cast<int64_t>(std::floor((end - start) / step + 1e-6)));
}

int64_t FrameGrid::nearest(double t) const {
  if (!(step > 0) || !std::isfinite(t)) return 0;
  return std::clamp<int64_t>(static_cast<int64_t>(std::llround((t - start) / step)), 0, last());
}

void PlaybackClock::start(const FrameGrid& grid, double t, double wall) {
  grid_ = grid;
  first_ = grid.nearest(t);
  wall0_ = wall;
  running_ = true;
}

std::optional<int64_t> PlaybackClock::due(double wall, double fps, bool loop) const {
  if (!running_) return std::nullopt;
  const double elapsed = std::max(0.0, wall - wall0_);
  const int64_t k = fps > 0 ? static_cast<int64_t>(std::floor(elapsed * fps + 1e-9)) : 0;
  int64_t m = first_ + k;
  const int64_t n = grid_.last() + 1;
  if (m < n) return m;
  if (!loop) return std::nullopt;
  return m % n;
}

Flipbook::Key Flipbook::keyOf(double t, const std::vector<float>& view) {
  return {static_cast<int64_t>(std::llround(t * 1e6)), view};
}

const render::Image* Flipbook::find(double t, const std::vector<float>& key) {
  auto it = index_.find(keyOf(t, key));
  if (it == index_.end()) return nullptr;
  entries_.splice(entries_.begin(), entries_, it->second);
  return &it->second->image;
}

bool Flipbook::contains(double t, const std::vector<float>& key) const { return index_.count(keyOf(t, key)) != 0; }

void Flipbook::store(double t, const std::vector<float>& key, const render::Image& image) {
  const size_t size = image.rgba.size();
  if (size > budget_) return;
  Key k = keyOf(t, key);
  if (auto it = index_.find(k); it != index_.end()) {
    bytes_ -= it->second->image.rgba.size();
    entries_.erase(it->second);
    index_.erase(it);
  }
  entries_.push_front(Entry{k, image});
  index_[std::move(k)] = entries_.begin();
  bytes_ += size;
  evict();
}

void Flipbook::setBudget(size_t bytes) {
  budget_ = bytes;
  evict();
}

void Flipbook::evict() {
  while (bytes_ > budget_ && !entries_.empty()) {
    bytes_ -= entries_.back().image.rgba.size();
    index_.erase(entries_.back().key);
    entries_.pop_back();
  }
}

void Flipbook::clear() {
  entries_.clear();
  index_.clear();
  bytes_ = 0;
}

}  // namespace pteryla::viewer
