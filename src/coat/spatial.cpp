// Spatial helpers for packing (Streit 2003, 6.3.2: "a subset of the surrounding feathers") and the coat
// checker: uniform point grid, binned-SAH triangle BVH, and Moeller's triangle-triangle interval test
// (T. Moeller, "A Fast Triangle-Triangle Intersection Test", J. Graphics Tools 2(2), 1997).
#include "spatial.hpp"

#include "pteryla/coat/skin.hpp"

#include <algorithm>
#include <array>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "pteryla/core/error.hpp"

namespace pteryla::coat::detail {

// ---------------------------------------------------------------- PointGrid

void PointGrid::build(const glm::dvec3* points, size_t count, double cell) {
  count_ = count;
  offsets_.clear();
  items_.clear();
  if (count == 0) return;
  PTERYLA_CHECK(cell > 0 && std::isfinite(cell), "grid cell must be positive");
  Box b;
  for (size_t i = 0; i < count; ++i) b.add(points[i]);
  // Keep the cell count bounded (a few cells per point at most).
  const glm::dvec3 ext = b.hi - b.lo;
  PTERYLA_CHECK(std::isfinite(ext.x) && std::isfinite(ext.y) && std::isfinite(ext.z), "grid points must be finite");
  double c = cell;
  for (;;) {
    const double n = std::floor(ext.x / c + 1) * std::floor(ext.y / c + 1) * std::floor(ext.z / c + 1);
    if (n <= 4.0 * static_cast<double>(count) + 64) break;
    c *= 1.5;
  }
  cell_ = c;
  origin_ = b.lo;
  for (int k = 0; k < 3; ++k) dims_[k] = static_cast<int>(std::floor(ext[k] / c)) + 1;
  const size_t cells = static_cast<size_t>(dims_.x) * dims_.y * dims_.z;
  offsets_.assign(cells + 1, 0);
  std::vector<uint32_t> cellOfPoint(count);
  for (size_t i = 0; i < count; ++i) {
    const glm::ivec3 q = cellOf(points[i]);
    const size_t ci = (static_cast<size_t>(q.z) * dims_.y + q.y) * dims_.x + q.x;
    cellOfPoint[i] = static_cast<uint32_t>(ci);
    ++offsets_[ci + 1];
  }
  for (size_t i = 0; i < cells; ++i) offsets_[i + 1] += offsets_[i];
  items_.resize(count);
  std::vector<uint32_t> fill(offsets_.begin(), offsets_.end() - 1);
  for (size_t i = 0; i < count; ++i) items_[fill[cellOfPoint[i]]++] = static_cast<uint32_t>(i);
}

// ---------------------------------------------------------------- TriangleBvh

namespace {

// A float box: primitive boxes are rounded outward from the double geometry, so they and every union of
// them (the nodes' bounds) contain it. Half the bytes of a double box to stream at every level of the
// build; which tree comes out does not change any query's answer (docs/architecture.md).
struct FBox {
  glm::vec3 lo{std::numeric_limits<float>::infinity()};
  glm::vec3 hi{-std::numeric_limits<float>::infinity()};
  void add(const glm::vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void add(const FBox& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  double area() const {
    if (lo.x > hi.x) return 0;
    const glm::dvec3 d = glm::dvec3(hi) - glm::dvec3(lo);
    return 2 * (d.x * d.y + d.y * d.z + d.z * d.x);
  }
};

// A primitive's bounds, kept in slot order and partitioned in place (sequential memory at every level).
// Its centroid is the box centre, recomputed where needed (the same arithmetic, a smaller record).
struct PrimInfo {
  FBox box;
  uint32_t id;
  float centroid(int axis) const { return 0.5f * (box.lo[axis] + box.hi[axis]); }
  glm::vec3 centroid() const { return 0.5f * (box.lo + box.hi); }
};

constexpr int kBins = 16;
constexpr uint32_t kLeafSize = 4;
constexpr int kMaxSahDepth = 48;

// Subtrees at least this large are built in parallel (TBB). The node layout does not depend on it: a
// node is followed by its left subtree, then its right subtree, exactly as a serial depth-first build.
constexpr uint32_t kParallelBuild = 8192;

// A node's primitive bounds and centroid bounds. Unions of boxes are exact (min / max), so bounds a
// parent gathered from its bins are the very values a pass over the child's primitives would give.
struct NodeBounds {
  FBox bounds, centroids;
};

struct Builder {
  std::vector<PrimInfo>& info;  // slot order

  // Builds the subtree of slots [begin, end) and appends its nodes to `nodes` (indices in `nodes`).
  // `known`: the subtree's bounds when the parent has them (an SAH split), else computed here.
  uint32_t build(uint32_t begin, uint32_t end, int depth, std::vector<TriangleBvh::Node>& nodes,
                 const NodeBounds* known = nullptr) {
    const uint32_t ni = static_cast<uint32_t>(nodes.size());
    nodes.emplace_back();
    NodeBounds nb;
    if (known) {
      nb = *known;
    } else {
      for (uint32_t i = begin; i < end; ++i) {
        nb.bounds.add(info[i].box);
        nb.centroids.add(info[i].centroid());
      }
    }
    const FBox& bounds = nb.bounds;
    const FBox& cb = nb.centroids;
    for (int k = 0; k < 3; ++k) {
      nodes[ni].lo[k] = bounds.lo[k];  // the primitives' boxes are rounded outward already
      nodes[ni].hi[k] = bounds.hi[k];
    }
    const uint32_t count = end - begin;
    auto makeLeaf = [&] {
      nodes[ni].first = begin;
      nodes[ni].count = count;
      return ni;
    };
    if (count <= kLeafSize) return makeLeaf();
    const glm::dvec3 ext = glm::dvec3(cb.hi) - glm::dvec3(cb.lo);
    int axis = 0;
    if (ext.y > ext[axis]) axis = 1;
    if (ext.z > ext[axis]) axis = 2;
    uint32_t mid = begin;
    bool split = false;
    NodeBounds childBounds[2];
    bool childKnown = false;
    if (ext[axis] > 0 && depth < kMaxSahDepth) {
      FBox binBox[kBins], binCentroids[kBins];
      uint32_t binCount[kBins] = {};
      const double scale = kBins / ext[axis];
      auto binOf = [&](const PrimInfo& p) {
        const int b = static_cast<int>((p.centroid(axis) - cb.lo[axis]) * scale);
        return std::min(std::max(b, 0), kBins - 1);
      };
      for (uint32_t i = begin; i < end; ++i) {
        const int b = binOf(info[i]);
        binBox[b].add(info[i].box);
        binCentroids[b].add(info[i].centroid());
        ++binCount[b];
      }
      double rightArea[kBins];
      uint32_t rightCount[kBins];
      FBox acc;
      uint32_t cnt = 0;
      for (int b = kBins - 1; b > 0; --b) {
        acc.add(binBox[b]);
        cnt += binCount[b];
        rightArea[b] = acc.area();
        rightCount[b] = cnt;
      }
      FBox left;
      uint32_t lc = 0;
      double best = std::numeric_limits<double>::infinity();
      int bestB = -1;
      for (int b = 1; b < kBins; ++b) {
        left.add(binBox[b - 1]);
        lc += binCount[b - 1];
        if (lc == 0 || rightCount[b] == 0) continue;
        const double cost = left.area() * lc + rightArea[b] * rightCount[b];
        if (cost < best) {
          best = cost;
          bestB = b;
        }
      }
      if (bestB > 0) {
        const double leafCost = bounds.area() * count;
        if (best >= leafCost && count <= 2 * kLeafSize) return makeLeaf();
        mid = static_cast<uint32_t>(std::partition(info.begin() + begin, info.begin() + end,
                                                   [&](const PrimInfo& p) { return binOf(p) < bestB; }) -
                                    info.begin());
        split = mid > begin && mid < end;
        if (split) {
          for (int b = 0; b < kBins; ++b) {
            NodeBounds& c = childBounds[b < bestB ? 0 : 1];
            c.bounds.add(binBox[b]);
            c.centroids.add(binCentroids[b]);
          }
          childKnown = true;
        }
      }
    }
    if (!split) {
      // Median by (centroid, index): a total order, so the split is deterministic.
      mid = begin + count / 2;
      std::nth_element(info.begin() + begin, info.begin() + mid, info.begin() + end,
                       [&](const PrimInfo& a, const PrimInfo& b) {
                         const double ca = a.centroid(axis), cb2 = b.centroid(axis);
                         return ca < cb2 || (ca == cb2 && a.id < b.id);
                       });
    }
    const NodeBounds* leftKnown = childKnown ? &childBounds[0] : nullptr;
    const NodeBounds* rightKnown = childKnown ? &childBounds[1] : nullptr;
    if (count < kParallelBuild) {
      build(begin, mid, depth + 1, nodes, leftKnown);
      const uint32_t right = build(mid, end, depth + 1, nodes, rightKnown);
      nodes[ni].first = right;
      nodes[ni].count = 0;
      return ni;
    }
    // The two halves own disjoint slot ranges: the right one is built into its own array and
    // appended after the left one, with its inner nodes' right-child indices moved by the offset.
    std::vector<TriangleBvh::Node> rightNodes;
    tbb::parallel_invoke([&] { build(begin, mid, depth + 1, nodes, leftKnown); },
                         [&] { build(mid, end, depth + 1, rightNodes, rightKnown); });
    const uint32_t offset = static_cast<uint32_t>(nodes.size());
    for (TriangleBvh::Node& n : rightNodes)
      if (n.count == 0) n.first += offset;
    nodes.insert(nodes.end(), rightNodes.begin(), rightNodes.end());
    nodes[ni].first = offset;
    nodes[ni].count = 0;
    return ni;
  }
};

}  // namespace

void TriangleBvh::build(const glm::vec3* positions, const uint32_t* indices, size_t triangleCount) {
  posF_ = positions;
  posD_ = nullptr;
  idx_ = indices;
  buildNodes(triangleCount);
}

void TriangleBvh::build(const glm::dvec3* positions, const uint32_t* indices, size_t triangleCount) {
  posF_ = nullptr;
  posD_ = positions;
  idx_ = indices;
  buildNodes(triangleCount);
}

void TriangleBvh::buildNodes(size_t triangleCount) {
  nodes_.clear();
  prims_.clear();
  primBoxes_.clear();
  slotGroup_.clear();
  nodeGroup_.clear();
  if (triangleCount == 0) return;
  PTERYLA_CHECK(triangleCount < (1u << 31), "too many triangles for the BVH");
  std::vector<PrimInfo> info(triangleCount);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangleCount, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t < r.end(); ++t) {
      PrimInfo& pi = info[t];
      pi.id = static_cast<uint32_t>(t);
      outwardBox(static_cast<uint32_t>(t), &pi.box.lo[0], &pi.box.hi[0]);
    }
  });
  nodes_.reserve(2 * triangleCount / kLeafSize + 1);
  Builder{info}.build(0, static_cast<uint32_t>(triangleCount), 0, nodes_);
  prims_.resize(triangleCount);
  primBoxes_.resize(triangleCount);
  for (size_t k = 0; k < triangleCount; ++k) {
    prims_[k] = info[k].id;
    PrimBox& pb = primBoxes_[k];
    for (int a = 0; a < 3; ++a) {
      pb.lo[a] = info[k].box.lo[a];
      pb.hi[a] = info[k].box.hi[a];
    }
  }
}

void TriangleBvh::setGroups(const uint32_t* groupOfTriangle) {
  makePrimBoxes();
  slotGroup_.resize(prims_.size());
  for (size_t k = 0; k < prims_.size(); ++k) slotGroup_[k] = groupOfTriangle[prims_[k]];
  // Children follow their parent in nodes_, so one backward sweep sees both before the parent.
  nodeGroup_.assign(nodes_.size(), kMixed);
  for (size_t i = nodes_.size(); i-- > 0;) {
    const Node& n = nodes_[i];
    uint32_t g;
    if (n.count > 0) {
      g = slotGroup_[n.first];
      for (uint32_t k = 1; k < n.count && g != kMixed; ++k)
        if (slotGroup_[n.first + k] != g) g = kMixed;
    } else {
      g = nodeGroup_[i + 1] == nodeGroup_[n.first] ? nodeGroup_[i + 1] : kMixed;
    }
    nodeGroup_[i] = g;
  }
}

void TriangleBvh::outwardBox(uint32_t t, float* lo, float* hi) const {
  Box box;
  for (int c = 0; c < 3; ++c) box.add(vertex(t, c));
  for (int a = 0; a < 3; ++a) {
    // Rounded outward, so the float box contains the double triangle.
    lo[a] = nextDown(static_cast<float>(box.lo[a]));
    hi[a] = nextUp(static_cast<float>(box.hi[a]));
  }
}

void TriangleBvh::refit(const glm::vec3* positions, const uint32_t* indices) {
  posF_ = positions;
  posD_ = nullptr;
  idx_ = indices;
  constexpr float inf = std::numeric_limits<float>::infinity();
  for (size_t k = 0; k < prims_.size(); ++k) {
    PrimBox& pb = primBoxes_[k];
    const uint32_t t = prims_[k];
    const uint32_t* i = idx_ + 3 * static_cast<size_t>(t);
    if (i[0] == i[1] && i[0] == i[2]) {
      for (int a = 0; a < 3; ++a) {
        pb.lo[a] = inf;
        pb.hi[a] = -inf;
      }
      continue;
    }
    outwardBox(t, pb.lo, pb.hi);
  }
  // Children follow their parent: one backward sweep sees both before the parent.
  for (size_t n = nodes_.size(); n-- > 0;) {
    Node& nd = nodes_[n];
    float lo[3] = {inf, inf, inf}, hi[3] = {-inf, -inf, -inf};
    auto add = [&](const float* l, const float* h) {
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], l[a]);
        hi[a] = std::max(hi[a], h[a]);
      }
    };
    if (nd.count > 0) {
      for (uint32_t k = 0; k < nd.count; ++k) add(primBoxes_[nd.first + k].lo, primBoxes_[nd.first + k].hi);
    } else {
      add(nodes_[n + 1].lo, nodes_[n + 1].hi);
      add(nodes_[nd.first].lo, nodes_[nd.first].hi);
    }
    for (int a = 0; a < 3; ++a) {
      nd.lo[a] = lo[a];
      nd.hi[a] = hi[a];
    }
  }
}

void TriangleBvh::makePrimBoxes() {
  // The build keeps each slot's own box (float, rounded outward): the pair traversal's filter and the
  // nearest search's per-triangle bound.
  PTERYLA_CHECK(primBoxes_.size() == prims_.size(), "primitive boxes are made by the build");
}

std::vector<std::pair<uint32_t, uint32_t>> TriangleBvh::pairTasks(size_t minTasks) const {
  std::vector<std::pair<uint32_t, uint32_t>> tasks;
  if (nodes_.empty()) return tasks;
  if (!mixedPair(0, 0)) return tasks;
  tasks.emplace_back(0, 0);
  // Breadth-first splitting of node pairs, the same way the traversal splits them, until there are
  // enough; pairs of leaves stay whole. Deterministic: it depends on the tree only.
  for (bool grew = true; grew && tasks.size() < minTasks;) {
    grew = false;
    std::vector<std::pair<uint32_t, uint32_t>> next;
    next.reserve(4 * tasks.size());
    for (const auto& [a, b] : tasks) {
      if (nodes_[a].count > 0 && nodes_[b].count > 0) {
        next.emplace_back(a, b);
      } else {
        splitPair(a, b, [&](uint32_t x, uint32_t y) { next.emplace_back(x, y); });
        grew = true;
      }
    }
    tasks.swap(next);
  }
  return tasks;
}

double rayTriangle(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& a, const glm::dvec3& b,
                   const glm::dvec3& c) {
  const glm::dvec3 e1 = b - a, e2 = c - a;
  const glm::dvec3 p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (std::abs(det) < 1e-300) return -1;
  const double inv = 1.0 / det;
  const glm::dvec3 s = o - a;
  const double u = glm::dot(s, p) * inv;
  if (u < 0 || u > 1) return -1;
  const glm::dvec3 q = glm::cross(s, e1);
  const double v = glm::dot(d, q) * inv;
  if (v < 0 || u + v > 1) return -1;
  return glm::dot(e2, q) * inv;
}

namespace {

// Squared distance from p to a float box (a node's or a triangle's: lo[3], hi[3]); 0 inside.
template <class B>
inline __attribute__((always_inline)) double boxDist2(const B& n, const glm::dvec3& p) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double v = p[k] < n.lo[k] ? n.lo[k] - p[k] : (p[k] > n.hi[k] ? p[k] - n.hi[k] : 0.0);
    d2 += v * v;
  }
  return d2;
}

}  // namespace

int64_t TriangleBvh::nearest(const glm::dvec3& p, double maxDist2, glm::dvec3& bary, double& dist2) const {
  int64_t best = -1;
  double bestD = maxDist2;
  if (nodes_.empty()) return best;
  // Nodes with their box distance, computed once (when the parent ranks its children). Left
  // uninitialised: only the entries pushed are read.
  struct Entry {
    uint32_t node;
    double d2;
  };
  Entry stack[128];
  int sp = 0;
  stack[sp++] = {0u, boxDist2(nodes_[0], p)};
  while (sp > 0) {
    const uint32_t ni = stack[sp - 1].node;
    const double nd = stack[sp - 1].d2;
    --sp;
    const Node& n = nodes_[ni];
    if (nd > bestD) continue;
    if (n.count > 0) {
      for (uint32_t k = 0; k < n.count; ++k) {
        // The triangle's box is farther than the best so far: so is the triangle (the box contains it).
        if (boxDist2(primBoxes_[n.first + k], p) > bestD) continue;
        const uint32_t t = prims_[n.first + k];
        glm::dvec3 b;
        const glm::dvec3 q = closestPointOnTriangle(p, vertex(t, 0), vertex(t, 1), vertex(t, 2), &b);
        const glm::dvec3 d = q - p;
        const double dd = glm::dot(d, d);
        // Ties go to the lower triangle index, so the answer does not depend on traversal order.
        if (dd < bestD || (dd == bestD && best >= 0 && t < best) || (dd == bestD && best < 0)) {
          bestD = dd;
          best = t;
          bary = b;
        }
      }
    } else {
      const uint32_t l = ni + 1, r = n.first;
      const double dl = boxDist2(nodes_[l], p), dr = boxDist2(nodes_[r], p);
      // Push the farther child first so the nearer one is visited next.
      if (dl <= dr) {
        stack[sp++] = {r, dr};
        stack[sp++] = {l, dl};
      } else {
        stack[sp++] = {l, dl};
        stack[sp++] = {r, dr};
      }
    }
  }
  dist2 = bestD;
  return best;
}

// ---------------------------------------------------------------- triangle / triangle

namespace {

using V3 = glm::dvec3;

// 2D segment intersection (closed).
bool segments2d(const double* p0, const double* p1, const double* q0, const double* q1) {
  auto orient = [](const double* a, const double* b, const double* c) {
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  };
  auto onSeg = [](const double* a, const double* b, const double* c) {
    return std::min(a[0], b[0]) <= c[0] && c[0] <= std::max(a[0], b[0]) && std::min(a[1], b[1]) <= c[1] &&
           c[1] <= std::max(a[1], b[1]);
  };
  const double d1 = orient(q0, q1, p0), d2 = orient(q0, q1, p1), d3 = orient(p0, p1, q0), d4 = orient(p0, p1, q1);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
  if (d1 == 0 && onSeg(q0, q1, p0)) return true;
  if (d2 == 0 && onSeg(q0, q1, p1)) return true;
  if (d3 == 0 && onSeg(p0, p1, q0)) return true;
  if (d4 == 0 && onSeg(p0, p1, q1)) return true;
  return false;
}

bool pointInTri2d(const double* p, const double (*t)[2]) {
  auto orient = [](const double* a, const double* b, const double* c) {
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  };
  const double a = orient(t[0], t[1], p), b = orient(t[1], t[2], p), c = orient(t[2], t[0], p);
  return (a >= 0 && b >= 0 && c >= 0) || (a <= 0 && b <= 0 && c <= 0);
}

bool coplanar(const V3& n, const V3* a, const V3* b) {
  int i0 = 0, i1 = 1;
  const V3 an = glm::abs(n);
  if (an.x >= an.y && an.x >= an.z) {
    i0 = 1;
    i1 = 2;
  } else if (an.y >= an.z) {
    i0 = 0;
    i1 = 2;
  }
  double pa[3][2], pb[3][2];
  for (int k = 0; k < 3; ++k) {
    pa[k][0] = a[k][i0];
    pa[k][1] = a[k][i1];
    pb[k][0] = b[k][i0];
    pb[k][1] = b[k][i1];
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segments2d(pa[i], pa[(i + 1) % 3], pb[j], pb[(j + 1) % 3])) return true;
  return pointInTri2d(pa[0], pb) || pointInTri2d(pb[0], pa);
}

// Interval of the line of intersection covered by a triangle, given projections p and plane distances d.
// Returns false when the triangle's vertices all lie in the other plane (coplanar).
bool interval(const double p[3], const double d[3], double& t0, double& t1) {
  auto from = [&](int k, int i, int j) {
    t0 = p[k] + (p[i] - p[k]) * d[k] / (d[k] - d[i]);
    t1 = p[k] + (p[j] - p[k]) * d[k] / (d[k] - d[j]);
    if (t0 > t1) std::swap(t0, t1);
    return true;
  };
  if (d[0] * d[1] > 0) return from(2, 0, 1);
  if (d[0] * d[2] > 0) return from(1, 0, 2);
  if (d[1] * d[2] > 0 || d[0] != 0) return from(0, 1, 2);
  if (d[1] != 0) return from(1, 0, 2);
  if (d[2] != 0) return from(2, 0, 1);
  return false;
}

}  // namespace

TriangleShape triangleShape(const V3& a0, const V3& a1, const V3& a2) {
  TriangleShape s;
  s.normal = glm::cross(a1 - a0, a2 - a0);
  s.normalLength = glm::length(s.normal);
  // The longest edge: the maximum of the three lengths is the same whichever order they come in.
  s.longestEdge = std::max({glm::length(a0 - a1), glm::length(a1 - a2), glm::length(a2 - a0)});
  return s;
}

bool trianglesIntersect(const V3& a0, const V3& a1, const V3& a2, const V3& b0, const V3& b1, const V3& b2) {
  return trianglesIntersect(a0, a1, a2, triangleShape(a0, a1, a2), b0, b1, b2, triangleShape(b0, b1, b2));
}

bool trianglesIntersect(const V3& a0, const V3& a1, const V3& a2, const TriangleShape& sa, const V3& b0, const V3& b1,
                        const V3& b2, const TriangleShape& sb) {
  if (sa.degenerate() || sb.degenerate()) return false;
  const double lna = sa.normalLength, lnb = sb.normalLength;
  const V3 A[3] = {a0, a1, a2}, B[3] = {b0, b1, b2};
  // Both triangles' edges, relative to which "touching" is judged.
  const double eps = 1e-12 * std::max(sa.longestEdge, sb.longestEdge);
  const V3 &na = sa.normal, &nb = sb.normal;
  // Signed distances to the other's plane, first times its normal's length: where all three are beyond
  // twice the tolerance on one side, the distances themselves (rounded, then zeroed below eps) are
  // nonzero on that side too, so the pair is apart as the test below would find, without dividing. (A
  // bound in the subnormal range is not relied on: its rounding is coarser.)
  double da[3], db[3];
  for (int k = 0; k < 3; ++k) da[k] = glm::dot(nb, A[k] - b0);
  const double sureB = 2 * eps * lnb;
  if (sureB >= std::numeric_limits<double>::min() &&
      ((da[0] > sureB && da[1] > sureB && da[2] > sureB) || (da[0] < -sureB && da[1] < -sureB && da[2] < -sureB)))
    return false;
  for (int k = 0; k < 3; ++k) {
    da[k] /= lnb;
    if (std::abs(da[k]) < eps) da[k] = 0;
  }
  if ((da[0] > 0 && da[1] > 0 && da[2] > 0) || (da[0] < 0 && da[1] < 0 && da[2] < 0)) return false;
  for (int k = 0; k < 3; ++k) db[k] = glm::dot(na, B[k] - a0);
  const double sureA = 2 * eps * lna;
  if (sureA >= std::numeric_limits<double>::min() &&
      ((db[0] > sureA && db[1] > sureA && db[2] > sureA) || (db[0] < -sureA && db[1] < -sureA && db[2] < -sureA)))
    return false;
  for (int k = 0; k < 3; ++k) {
    db[k] /= lna;
    if (std::abs(db[k]) < eps) db[k] = 0;
  }
  if ((db[0] > 0 && db[1] > 0 && db[2] > 0) || (db[0] < 0 && db[1] < 0 && db[2] < 0)) return false;
  if (da[0] == 0 && da[1] == 0 && da[2] == 0) return coplanar(na, A, B);
  const V3 dir = glm::cross(na, nb);
  int ax = 0;
  const V3 ad = glm::abs(dir);
  if (ad.y > ad[ax]) ax = 1;
  if (ad.z > ad[ax]) ax = 2;
  const double pa[3] = {A[0][ax], A[1][ax], A[2][ax]}, pb[3] = {B[0][ax], B[1][ax], B[2][ax]};
  double s0, s1, t0, t1;
  if (!interval(pa, da, s0, s1)) return coplanar(na, A, B);
  if (!interval(pb, db, t0, t1)) return coplanar(na, A, B);
  return !(s1 < t0 || t1 < s0);
}

}  // namespace pteryla::coat::detail
