#pragma once
// Spatial helpers shared by packing and the coat checker (internal to pteryla_coat):
//  - PointGrid: uniform grid over points (counting-sort CSR, deterministic), box queries;
//  - TriangleBvh: binned-SAH bounding volume hierarchy over triangles, self-pair / tree-pair / ray /
//    nearest queries;
//  - trianglesIntersect: Moeller's interval test (J. Graphics Tools 2(2), 1997) in double precision
//    with a separate 2D test for coplanar triangles.
#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include <tbb/task_arena.h>

namespace pteryla::coat::detail {

// Runs f in a task arena of `threads` threads (0 = TBB's default arena, all cores).
template <class F>
void inArena(int threads, F&& f) {
  if (threads >= 1) {
    tbb::task_arena arena(threads);
    arena.execute(f);
  } else {
    f();
  }
}

// std::nextafter(x, +-infinity) for a float, inline (the build and refit call it six times a triangle):
// the neighbouring float (its bits one step away from or toward zero); an infinity stepped outward and
// NaN stay as they are, and zero steps to the smallest subnormal.
inline float stepFloat(float x, bool up) {
  if (x != x) return x;
  constexpr float inf = std::numeric_limits<float>::infinity();
  if (x == (up ? inf : -inf)) return x;
  if (x == 0) return up ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min();
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  bits = (x > 0) == up ? bits + 1 : bits - 1;
  std::memcpy(&x, &bits, sizeof bits);
  return x;
}
inline float nextUp(float x) { return stepFloat(x, true); }
inline float nextDown(float x) { return stepFloat(x, false); }

struct Box {
  glm::dvec3 lo{std::numeric_limits<double>::infinity()};
  glm::dvec3 hi{-std::numeric_limits<double>::infinity()};
  void add(const glm::dvec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void add(const Box& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  bool empty() const { return lo.x > hi.x; }
  bool overlaps(const Box& b) const {
    return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y && lo.z <= b.hi.z && b.lo.z <= hi.z;
  }
  double area() const {
    if (empty()) return 0;
    const glm::dvec3 d = hi - lo;
    return 2 * (d.x * d.y + d.y * d.z + d.z * d.x);
  }
};

// Uniform grid: cells of edge `cell`, points bucketed in input order, so queries visit points in a
// deterministic order.
class PointGrid {
 public:
  void build(const std::vector<glm::dvec3>& points, double cell) { build(points.data(), points.size(), cell); }
  void build(const glm::dvec3* points, size_t count, double cell);
  // Calls f(index) for every point in a cell overlapping [lo, hi] (a superset of the points in the box).
  template <class F>
  void query(const glm::dvec3& lo, const glm::dvec3& hi, F&& f) const {
    if (count_ == 0) return;
    const glm::ivec3 a = cellOf(lo), b = cellOf(hi);
    for (int z = a.z; z <= b.z; ++z)
      for (int y = a.y; y <= b.y; ++y)
        for (int x = a.x; x <= b.x; ++x) {
          const size_t c = (static_cast<size_t>(z) * dims_.y + y) * dims_.x + x;
          for (uint32_t k = offsets_[c]; k < offsets_[c + 1]; ++k) f(items_[k]);
        }
  }
  // Same, but a cell is visited only when cellTest(centre, halfDiagonal) holds.
  template <class C, class F>
  void query(const glm::dvec3& lo, const glm::dvec3& hi, C&& cellTest, F&& f) const {
    if (count_ == 0) return;
    const glm::ivec3 a = cellOf(lo), b = cellOf(hi);
    const double half = 0.5 * cell_ * std::sqrt(3.0);
    for (int z = a.z; z <= b.z; ++z)
      for (int y = a.y; y <= b.y; ++y)
        for (int x = a.x; x <= b.x; ++x) {
          const size_t c = (static_cast<size_t>(z) * dims_.y + y) * dims_.x + x;
          if (offsets_[c] == offsets_[c + 1]) continue;
          const glm::dvec3 centre = origin_ + cell_ * (glm::dvec3(x, y, z) + 0.5);
          if (!cellTest(centre, half)) continue;
          for (uint32_t k = offsets_[c]; k < offsets_[c + 1]; ++k) f(items_[k]);
        }
  }
  // Same as query(lo, hi, f), a row of cells at a time: f(first, last) for the slots [first, last) of the
  // row's cells in the box (slot k holds point item(k)); slots are numbered in the order query() visits
  // points, so the visits are query()'s.
  template <class F>
  void querySlots(const glm::dvec3& lo, const glm::dvec3& hi, F&& f) const {
    if (count_ == 0) return;
    const glm::ivec3 a = cellOf(lo), b = cellOf(hi);
    for (int z = a.z; z <= b.z; ++z)
      for (int y = a.y; y <= b.y; ++y) {
        const size_t row = (static_cast<size_t>(z) * dims_.y + y) * dims_.x;
        // A row's cells are consecutive: their slots are one range.
        const uint32_t first = offsets_[row + a.x], last = offsets_[row + b.x + 1];
        if (first < last) f(first, last);
      }
  }
  uint32_t item(uint32_t slot) const { return items_[slot]; }
  double cell() const { return cell_; }

 private:
  glm::ivec3 cellOf(const glm::dvec3& p) const {
    glm::ivec3 c;
    for (int k = 0; k < 3; ++k) {
      const double v = std::floor((p[k] - origin_[k]) / cell_);
      c[k] = v < 0 ? 0 : (v >= dims_[k] - 1 ? dims_[k] - 1 : static_cast<int>(v));
    }
    return c;
  }
  glm::dvec3 origin_{0};
  glm::ivec3 dims_{1};
  double cell_ = 1;
  size_t count_ = 0;
  std::vector<uint32_t> offsets_, items_;
};

// Ray / triangle (Moeller-Trumbore); returns t or a negative value.
double rayTriangle(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& a, const glm::dvec3& b,
                   const glm::dvec3& c);

// BVH over triangles given as positions + index triples (float, like TriMesh).
class TriangleBvh {
 public:
  struct PrimBox {  // a triangle's box, float, rounded outward (it contains the triangle)
    float lo[3], hi[3];
  };
  struct Node {
    float lo[3], hi[3];
    uint32_t first;  // leaf: first primitive slot; inner: right child (left child = this + 1)
    uint32_t count;  // leaf: primitive count (> 0); inner: 0
  };
  // Positions (float or double) and indices must outlive the BVH.
  void build(const glm::vec3* positions, const uint32_t* indices, size_t triangleCount);
  void build(const glm::dvec3* positions, const uint32_t* indices, size_t triangleCount);
  glm::dvec3 vertex(uint32_t triangle, int corner) const {
    const uint32_t v = idx_[3 * static_cast<size_t>(triangle) + corner];
    return posD_ ? posD_[v] : glm::dvec3(posF_[v]);
  }
  bool empty() const { return nodes_.empty(); }
  size_t triangleCount() const { return prims_.size(); }

  // Self-overlap (a dual-tree traversal, each unordered pair visited once): calls f(t, u), t < u, for
  // every pair of distinct triangles whose bounding boxes overlap (and, after setGroups(), whose groups
  // differ: subtrees of one group are never paired with themselves or each other). pairTasks() cuts the work into at
  // least minTasks independent node pairs (fewer only when the tree is small); overlappingPairs(task, f)
  // does one of them. Together they visit each such pair exactly once, in a deterministic order per task.
  std::vector<std::pair<uint32_t, uint32_t>> pairTasks(size_t minTasks) const;
  // A group per triangle (e.g. its feather), indexed like the build's triangles. Call after build() and
  // before pairTasks() / overlappingPairs(), which need it.
  void setGroups(const uint32_t* groupOfTriangle);
  template <class F>
  void overlappingPairs(std::pair<uint32_t, uint32_t> task, F&& f) const {
    std::vector<std::pair<uint32_t, uint32_t>> stack{task};
    while (!stack.empty()) {
      const auto [a, b] = stack.back();
      stack.pop_back();
      const Node &na = nodes_[a], &nb = nodes_[b];
      if (na.count == 0 || nb.count == 0) {
        splitPair(a, b, [&](uint32_t x, uint32_t y) { stack.emplace_back(x, y); });
        continue;
      }
      // Two leaves, or one leaf with itself: the primitive pairs whose own boxes overlap.
      for (uint32_t i = 0; i < na.count; ++i) {
        const uint32_t si = na.first + i;
        for (uint32_t j = a == b ? i + 1 : 0; j < nb.count; ++j) {
          const uint32_t sj = nb.first + j;
          if (!slotGroup_.empty() && slotGroup_[si] == slotGroup_[sj]) continue;
          if (!boxesOverlap(primBoxes_[si].lo, primBoxes_[si].hi, primBoxes_[sj].lo, primBoxes_[sj].hi)) continue;
          const uint32_t t = prims_[si], u = prims_[sj];
          if (t < u)
            f(t, u);
          else
            f(u, t);
        }
      }
    }
  }
  // Pairs between two BVHs (e.g. two feathers'): calls f(t, u), t of this BVH and u of `other` (indices
  // as each was built), once for every pair whose boxes overlap. Both need makePrimBoxes() first.
  template <class F>
  void overlappingPairs(const TriangleBvh& other, F&& f) const {
    if (nodes_.empty() || other.nodes_.empty()) return;
    // Called once per pair of meeting feathers: the stack lives on the call's own stack (a pop pushes at
    // most two, so it stays near the two trees' depths), in a vector only past that.
    constexpr size_t kLocal = 128;
    std::pair<uint32_t, uint32_t> local[kLocal];
    size_t top = 0;
    std::vector<std::pair<uint32_t, uint32_t>> spill;
    auto push = [&](uint32_t x, uint32_t y) {
      if (top < kLocal)
        local[top++] = {x, y};
      else
        spill.emplace_back(x, y);
    };
    if (boxesOverlap(nodes_[0].lo, nodes_[0].hi, other.nodes_[0].lo, other.nodes_[0].hi)) push(0, 0);
    while (top > 0 || !spill.empty()) {
      std::pair<uint32_t, uint32_t> ab;
      if (!spill.empty()) {
        ab = spill.back();
        spill.pop_back();
      } else {
        ab = local[--top];
      }
      const auto [a, b] = ab;
      const Node &na = nodes_[a], &nb = other.nodes_[b];
      if (na.count > 0 && nb.count > 0) {
        for (uint32_t i = 0; i < na.count; ++i) {
          const PrimBox& pa = primBoxes_[na.first + i];
          for (uint32_t j = 0; j < nb.count; ++j) {
            const PrimBox& pb = other.primBoxes_[nb.first + j];
            if (boxesOverlap(pa.lo, pa.hi, pb.lo, pb.hi)) f(prims_[na.first + i], other.prims_[nb.first + j]);
          }
        }
        continue;
      }
      // Split the larger inner node (a leaf is never split).
      const bool splitA = nb.count > 0 || (na.count == 0 && area(na) >= area(nb));
      if (splitA) {
        for (uint32_t c : {a + 1, na.first})
          if (boxesOverlap(nodes_[c].lo, nodes_[c].hi, nb.lo, nb.hi)) push(c, b);
      } else {
        for (uint32_t c : {b + 1, nb.first})
          if (boxesOverlap(na.lo, na.hi, other.nodes_[c].lo, other.nodes_[c].hi)) push(a, c);
      }
    }
  }
  // Each slot's own box for the pair queries (setGroups() makes them too).
  void makePrimBoxes();
  // The same tree over moved corners (as many triangles as it was built over, numbered the same): every
  // slot's box and node's bounds made again from `positions` and `indices`, which must outlive the use.
  // A collapsed triangle (three equal indices) gets an empty box, so the pair queries never return it
  // and it widens no bounds. For the pair queries only: which tree holds the triangles does not change
  // what they return, and refitting skips the build's partitioning.
  void refit(const glm::vec3* positions, const uint32_t* indices);
  // The bounds of everything in the BVH (float, rounded outward); false when empty.
  bool bounds(glm::vec3& lo, glm::vec3& hi) const {
    if (nodes_.empty()) return false;
    lo = glm::vec3(nodes_[0].lo[0], nodes_[0].lo[1], nodes_[0].lo[2]);
    hi = glm::vec3(nodes_[0].hi[0], nodes_[0].hi[1], nodes_[0].hi[2]);
    return true;
  }
  // Any triangle hit by the ray origin + t dir, t in (tMin, tMax]?
  bool anyHit(const glm::dvec3& origin, const glm::dvec3& dir, double tMin, double tMax) const {
    return anyLeafHit(origin, dir, tMin, tMax, [&](uint32_t t) {
      const double h = rayTriangle(origin, dir, vertex(t, 0), vertex(t, 1), vertex(t, 2));
      return h > tMin && h <= tMax;
    });
  }
  // The traversal of anyHit() with another test for what a leaf holds: true as soon as hit(t) is true
  // for a primitive t in a leaf the ray meets.
  template <class H>
  bool anyLeafHit(const glm::dvec3& origin, const glm::dvec3& dir, double tMin, double tMax, H&& hit) const;
  // Nearest triangle to p (squared distance <= maxDist2); returns -1 when none, else the triangle and
  // writes the closest point's barycentric coordinates.
  int64_t nearest(const glm::dvec3& p, double maxDist2, glm::dvec3& bary, double& dist2) const;

 private:
  static float area(const Node& n) {
    const float dx = n.hi[0] - n.lo[0], dy = n.hi[1] - n.lo[1], dz = n.hi[2] - n.lo[2];
    return dx * dy + dy * dz + dz * dx;
  }
  static bool boxesOverlap(const float* alo, const float* ahi, const float* blo, const float* bhi) {
    return alo[0] <= bhi[0] && blo[0] <= ahi[0] && alo[1] <= bhi[1] && blo[1] <= ahi[1] && alo[2] <= bhi[2] &&
           blo[2] <= ahi[2];
  }
  // One step of the dual traversal on an overlapping pair that is not two leaves: emits the child pairs
  // whose boxes overlap. A node with itself: (left, left), (right, right), (left, right). Two nodes:
  // the larger inner node (by box area; a leaf is never split) against the other.
  static constexpr uint32_t kMixed = 0xffffffffu;
  // Can the pair (a, b) hold two triangles of different groups?
  bool mixedPair(uint32_t a, uint32_t b) const {
    if (nodeGroup_.empty()) return true;
    const uint32_t ga = nodeGroup_[a];
    return ga == kMixed || (a != b && ga != nodeGroup_[b]);
  }
  template <class Emit>
  void splitPair(uint32_t a, uint32_t b, Emit&& emit) const {
    const Node& na = nodes_[a];
    if (a == b) {
      const uint32_t l = a + 1, r = na.first;
      if (mixedPair(l, l)) emit(l, l);
      if (mixedPair(r, r)) emit(r, r);
      if (mixedPair(l, r) && boxesOverlap(nodes_[l].lo, nodes_[l].hi, nodes_[r].lo, nodes_[r].hi)) emit(l, r);
      return;
    }
    const Node& nb = nodes_[b];
    const bool splitA = nb.count > 0 || (na.count == 0 && area(na) >= area(nb));
    const uint32_t keep = splitA ? b : a, inner = splitA ? a : b;
    const Node& k = nodes_[keep];
    for (uint32_t c : {inner + 1, nodes_[inner].first})
      if (mixedPair(c, keep) && boxesOverlap(nodes_[c].lo, nodes_[c].hi, k.lo, k.hi))
        emit(splitA ? c : keep, splitA ? keep : c);
  }
  void buildNodes(size_t triangleCount);
  // Triangle t's box in float, rounded outward (it contains the triangle).
  void outwardBox(uint32_t t, float* lo, float* hi) const;
  const glm::vec3* posF_ = nullptr;
  const glm::dvec3* posD_ = nullptr;
  const uint32_t* idx_ = nullptr;
  std::vector<Node> nodes_;
  std::vector<PrimBox> primBoxes_;               // per prims_ slot
  std::vector<uint32_t> slotGroup_, nodeGroup_;  // setGroups(): per slot; per node (kMixed: several)
  std::vector<uint32_t> prims_;
};

template <class H>
bool TriangleBvh::anyLeafHit(const glm::dvec3& origin, const glm::dvec3& dir, double tMin, double tMax, H&& hit) const {
  if (nodes_.empty()) return false;
  glm::dvec3 inv;
  for (int k = 0; k < 3; ++k) inv[k] = dir[k] != 0 ? 1.0 / dir[k] : std::copysign(1e300, dir[k] == 0 ? 1.0 : dir[k]);
  uint32_t stack[128];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const Node& n = nodes_[stack[--sp]];
    double t0 = tMin, t1 = tMax;
    bool miss = false;
    for (int k = 0; k < 3 && !miss; ++k) {
      double ta = (n.lo[k] - origin[k]) * inv[k], tb = (n.hi[k] - origin[k]) * inv[k];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      miss = t0 > t1;
    }
    if (miss) continue;
    if (n.count > 0) {
      for (uint32_t k = 0; k < n.count; ++k)
        if (hit(prims_[n.first + k])) return true;
    } else {
      const uint32_t ni = static_cast<uint32_t>(&n - nodes_.data());
      stack[sp++] = n.first;
      stack[sp++] = ni + 1;
    }
  }
  return false;
}

// Do the closed triangles (a0,a1,a2) and (b0,b1,b2) share a point? Degenerate triangles never intersect.
bool trianglesIntersect(const glm::dvec3& a0, const glm::dvec3& a1, const glm::dvec3& a2, const glm::dvec3& b0,
                        const glm::dvec3& b1, const glm::dvec3& b2);

// A tree over boxes: box k becomes the "triangle" (lo, hi, lo) of corners[2k], corners[2k + 1], whose box
// is the box itself (held in float, rounded outward), so its pair queries give every pair of boxes that
// meet, and at most a few more that the caller's exact test drops. corners and indices hold the tree's
// input and must outlive it.
inline void buildBoxTree(const std::vector<Box>& boxes, std::vector<glm::dvec3>& corners,
                         std::vector<uint32_t>& indices, TriangleBvh& tree) {
  corners.resize(2 * boxes.size());
  indices.resize(3 * boxes.size());
  for (size_t k = 0; k < boxes.size(); ++k) {
    corners[2 * k] = boxes[k].lo;
    corners[2 * k + 1] = boxes[k].hi;
    const uint32_t c = static_cast<uint32_t>(2 * k);
    indices[3 * k] = c;
    indices[3 * k + 1] = c + 1;
    indices[3 * k + 2] = c;
  }
  tree.build(corners.data(), indices.data(), boxes.size());
  tree.makePrimBoxes();
}

// What trianglesIntersect computes of each triangle alone (the square roots), made once per triangle
// when it meets many others. The overload below gives the very answer of the one above.
struct TriangleShape {
  glm::dvec3 normal{0};     // (a1 - a0) x (a2 - a0), unnormalised
  double normalLength = 0;  // |normal|; not > 0: degenerate, never intersects
  double longestEdge = 0;
  bool degenerate() const { return !(normalLength > 0); }
};
TriangleShape triangleShape(const glm::dvec3& a0, const glm::dvec3& a1, const glm::dvec3& a2);
bool trianglesIntersect(const glm::dvec3& a0, const glm::dvec3& a1, const glm::dvec3& a2, const TriangleShape& sa,
                        const glm::dvec3& b0, const glm::dvec3& b1, const glm::dvec3& b2, const TriangleShape& sb);

}  // namespace pteryla::coat::detail
