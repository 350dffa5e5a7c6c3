#pragma once
// Internal: uniform hash grid over 3-D points (cells keyed by packed integer coordinates, open-addressing
// table from key to a run of a key-sorted index array) and a capped point-to-segments distance query.
// Used by relaxation (nearest site per sample) and metrics (k nearest neighbours).
#include <glm/vec3.hpp>

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace pteryla::coat::detail {

class CellGrid {
 public:
  static constexpr int64_t kMaxCell = (1 << 21) - 1;
  static constexpr uint64_t kEmpty = ~uint64_t(0);

  CellGrid() = default;
  // lo: lower corner of the region of interest; cellSize > 0. Coordinates are clamped into 21 bits.
  CellGrid(const glm::dvec3& lo, double cellSize) : lo_(lo), h_(cellSize), inv_(1.0 / cellSize) {}

  double cellSize() const { return h_; }
  std::array<int64_t, 3> coords(const glm::dvec3& p) const {
    const glm::dvec3 q = (p - lo_) * inv_;
    return {clampc(q.x), clampc(q.y), clampc(q.z)};
  }
  static uint64_t pack(int64_t i, int64_t j, int64_t k) {
    return (static_cast<uint64_t>(i) << 42) | (static_cast<uint64_t>(j) << 21) | static_cast<uint64_t>(k);
  }
  static std::array<int64_t, 3> unpack(uint64_t key) {
    return {static_cast<int64_t>(key >> 42), static_cast<int64_t>((key >> 21) & kMaxCell),
            static_cast<int64_t>(key & kMaxCell)};
  }
  uint64_t key(const glm::dvec3& p) const {
    const auto c = coords(p);
    return pack(c[0], c[1], c[2]);
  }

  // Builds the table for points pts[0..n): order() lists point indices sorted by (cell key, index).
  void build(const glm::dvec3* pts, size_t n);
  // [begin, end) into order() for a cell, or {0,0} when empty / out of range.
  std::pair<uint32_t, uint32_t> cell(int64_t i, int64_t j, int64_t k) const {
    if (i < 0 || j < 0 || k < 0 || i > kMaxCell || j > kMaxCell || k > kMaxCell) return {0, 0};
    return find(pack(i, j, k));
  }
  std::pair<uint32_t, uint32_t> find(uint64_t key) const;
  const std::vector<uint32_t>& order() const { return order_; }
  // Non-empty cells in key order: cell r holds order()[runBegin()[r] .. runBegin()[r+1]).
  const std::vector<uint64_t>& runKeys() const { return runKey_; }
  const std::vector<uint32_t>& runBegin() const { return runBegin_; }

  // Appends to `out` the indices of points in cells at Chebyshev cell distance exactly r (r = 0: the cell).
  void gatherShell(const std::array<int64_t, 3>& c, int r, std::vector<uint32_t>& out) const;
  // Largest shell radius that can still contain points (beyond it everything has been seen).
  int maxShell(const std::array<int64_t, 3>& c) const;
  // k nearest points to p (excluding index `self`), sorted by distance; writes squared distances.
  // Also returns, in *nextD2, the squared distance of the (k+1)-th nearest (infinity when none).
  void kNearest(const glm::dvec3* pts, const glm::dvec3& p, uint32_t self, size_t k,
                std::vector<std::pair<double, uint32_t>>& out, double* nextD2 = nullptr) const {
    std::vector<uint32_t> shell;
    kNearest(pts, p, self, k, out, nextD2, shell);
  }
  // Same with a caller-owned scratch buffer (no allocation once it has grown).
  void kNearest(const glm::dvec3* pts, const glm::dvec3& p, uint32_t self, size_t k,
                std::vector<std::pair<double, uint32_t>>& out, double* nextD2, std::vector<uint32_t>& shell) const;

 private:
  static int64_t clampc(double x) {
    if (!(x > 0)) return 0;
    if (x >= static_cast<double>(kMaxCell)) return kMaxCell;
    return static_cast<int64_t>(x);
  }
  glm::dvec3 lo_{0};
  double h_ = 1, inv_ = 1;
  std::vector<uint32_t> order_;
  std::vector<uint64_t> runKey_;
  std::vector<uint32_t> runBegin_;
  std::vector<uint64_t> tableKey_;
  std::vector<uint32_t> tableBegin_, tableEnd_;
  uint64_t mask_ = 0;
  std::array<int64_t, 3> minC_{0, 0, 0}, maxC_{0, 0, 0};
};

// Distance from points to a set of segments, capped at `radius` (exact below it).
class SegmentDistance {
 public:
  SegmentDistance(const std::vector<std::array<glm::dvec3, 2>>& segments, double radius);
  double operator()(const glm::dvec3& p) const;
  bool empty() const { return pieces_.empty(); }

 private:
  double radius_;
  std::vector<std::array<glm::dvec3, 2>> pieces_;
  std::vector<glm::dvec3> mids_;
  CellGrid grid_;
};

}  // namespace pteryla::coat::detail
