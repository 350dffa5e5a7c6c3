// Uniform hash grid and capped segment distance (internal helpers for relax.cpp and metrics.cpp).
#include "spatial_hash.hpp"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "pteryla/core/rng.hpp"

namespace pteryla::coat::detail {

void CellGrid::build(const glm::dvec3* pts, size_t n) {
  std::vector<std::pair<uint64_t, uint32_t>> kv(n);
  for (size_t i = 0; i < n; ++i) kv[i] = {key(pts[i]), static_cast<uint32_t>(i)};
  if (n > 50000)
    tbb::parallel_sort(kv.begin(), kv.end());
  else
    std::sort(kv.begin(), kv.end());
  order_.resize(n);
  size_t runs = 0;
  for (size_t i = 0; i < n; ++i) {
    order_[i] = kv[i].second;
    if (i == 0 || kv[i].first != kv[i - 1].first) ++runs;
  }
  size_t cap = 16;
  while (cap < 2 * runs) cap <<= 1;
  mask_ = cap - 1;
  tableKey_.assign(cap, kEmpty);
  tableBegin_.assign(cap, 0);
  tableEnd_.assign(cap, 0);
  runKey_.clear();
  runBegin_.clear();
  minC_ = {kMaxCell, kMaxCell, kMaxCell};
  maxC_ = {0, 0, 0};
  for (size_t i = 0; i < n;) {
    size_t j = i;
    while (j < n && kv[j].first == kv[i].first) ++j;
    const uint64_t k = kv[i].first;
    runKey_.push_back(k);
    runBegin_.push_back(static_cast<uint32_t>(i));
    uint64_t slot = mix64(k) & mask_;
    while (tableKey_[slot] != kEmpty) slot = (slot + 1) & mask_;
    tableKey_[slot] = k;
    tableBegin_[slot] = static_cast<uint32_t>(i);
    tableEnd_[slot] = static_cast<uint32_t>(j);
    const auto c = unpack(k);
    for (int a = 0; a < 3; ++a) {
      minC_[a] = std::min(minC_[a], c[a]);
      maxC_[a] = std::max(maxC_[a], c[a]);
    }
    i = j;
  }
  runBegin_.push_back(static_cast<uint32_t>(n));
}

std::pair<uint32_t, uint32_t> CellGrid::find(uint64_t key) const {
  if (tableKey_.empty()) return {0, 0};
  uint64_t slot = mix64(key) & mask_;
  while (true) {
    const uint64_t k = tableKey_[slot];
    if (k == key) return {tableBegin_[slot], tableEnd_[slot]};
    if (k == kEmpty) return {0, 0};
    slot = (slot + 1) & mask_;
  }
}

void CellGrid::gatherShell(const std::array<int64_t, 3>& c, int r, std::vector<uint32_t>& out) const {
  auto take = [&](int64_t i, int64_t j, int64_t k) {
    const auto [b, e] = cell(i, j, k);
    for (uint32_t q = b; q < e; ++q) out.push_back(order_[q]);
  };
  if (r == 0) {
    take(c[0], c[1], c[2]);
    return;
  }
  for (int64_t di = -r; di <= r; ++di)
    for (int64_t dj = -r; dj <= r; ++dj) {
      const bool faceIJ = std::abs(di) == r || std::abs(dj) == r;
      if (faceIJ) {
        for (int64_t dk = -r; dk <= r; ++dk) take(c[0] + di, c[1] + dj, c[2] + dk);
      } else {
        take(c[0] + di, c[1] + dj, c[2] - r);
        take(c[0] + di, c[1] + dj, c[2] + r);
      }
    }
}

int CellGrid::maxShell(const std::array<int64_t, 3>& c) const {
  int64_t r = 0;
  for (int a = 0; a < 3; ++a) r = std::max({r, c[a] - minC_[a], maxC_[a] - c[a]});
  return static_cast<int>(r);
}

void CellGrid::kNearest(const glm::dvec3* pts, const glm::dvec3& p, uint32_t self, size_t k,
                        std::vector<std::pair<double, uint32_t>>& out, double* nextD2,
                        std::vector<uint32_t>& shell) const {
  out.clear();
  const auto c = coords(p);
  const int rmax = maxShell(c);
  // Shell r costs about 24 r^2 + 2 table look-ups. Points far apart (an outlier, or mesh components 1e6
  // cells away) would need millions of shells; once the look-ups would exceed a few per point, a scan of
  // every point is cheaper and gives the same answer (exact distances, ties by index).
  const double scanCost = 4.0 * static_cast<double>(order_.size()) + 64.0;
  double spent = 0;
  for (int r = 0;; ++r) {
    spent += 24.0 * double(r) * double(r) + 2.0;
    if (r > 1 && spent > scanCost) {
      out.clear();
      for (uint32_t q : order_) {
        if (q == self) continue;
        const glm::dvec3 d = pts[q] - p;
        out.emplace_back(glm::dot(d, d), q);
      }
      break;
    }
    shell.clear();
    gatherShell(c, r, shell);
    for (uint32_t q : shell) {
      if (q == self) continue;
      const glm::dvec3 d = pts[q] - p;
      out.emplace_back(glm::dot(d, d), q);
    }
    const size_t want = k + 1;
    const double guard = static_cast<double>(r) * h_;
    if (out.size() >= want) {
      std::nth_element(out.begin(), out.begin() + static_cast<long>(want - 1), out.end());
      if (out[want - 1].first <= guard * guard || r >= rmax) break;
    } else if (r >= rmax) {
      break;
    }
  }
  const size_t keep = std::min(out.size(), k + 1);
  std::partial_sort(out.begin(), out.begin() + static_cast<long>(keep), out.end());
  if (nextD2) *nextD2 = out.size() > k ? out[k].first : std::numeric_limits<double>::infinity();
  if (out.size() > k) out.resize(k);
}

SegmentDistance::SegmentDistance(const std::vector<std::array<glm::dvec3, 2>>& segments, double radius)
    : radius_(radius) {
  if (segments.empty() || !(radius > 0)) return;
  glm::dvec3 lo(std::numeric_limits<double>::max());
  glm::dvec3 hi(-std::numeric_limits<double>::max());
  for (const auto& s : segments)
    for (const auto& p : s) {
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  const double h = std::max(radius, extent / 1.0e6);
  // Pieces no longer than h/2: a point within `radius` of a piece has its midpoint within 1.25 h.
  for (const auto& s : segments) {
    const double len = glm::length(s[1] - s[0]);
    const int parts = std::max(1, static_cast<int>(std::ceil(len / (0.5 * h))));
    for (int i = 0; i < parts; ++i) {
      const glm::dvec3 a = s[0] + (s[1] - s[0]) * (double(i) / parts);
      const glm::dvec3 b = s[0] + (s[1] - s[0]) * (double(i + 1) / parts);
      pieces_.push_back({a, b});
      mids_.push_back(0.5 * (a + b));
    }
  }
  grid_ = CellGrid(lo - glm::dvec3(3 * h), h);
  grid_.build(mids_.data(), mids_.size());
}

double SegmentDistance::operator()(const glm::dvec3& p) const {
  if (pieces_.empty()) return radius_;
  const auto c = grid_.coords(p);
  double best = radius_ * radius_;
  for (int64_t di = -2; di <= 2; ++di)
    for (int64_t dj = -2; dj <= 2; ++dj)
      for (int64_t dk = -2; dk <= 2; ++dk) {
        const auto [b, e] = grid_.cell(c[0] + di, c[1] + dj, c[2] + dk);
        for (uint32_t q = b; q < e; ++q) {
          const auto& s = pieces_[grid_.order()[q]];
          const glm::dvec3 ab = s[1] - s[0];
          const double l2 = glm::dot(ab, ab);
          const double t = l2 > 0 ? std::clamp(glm::dot(p - s[0], ab) / l2, 0.0, 1.0) : 0.0;
          const glm::dvec3 d = s[0] + t * ab - p;
          best = std::min(best, glm::dot(d, d));
        }
      }
  return std::sqrt(best);
}

}  // namespace pteryla::coat::detail
