// Internals of the draped packing (drape.cpp): the surfaces a feather's chart is laid against. The skin
// (Surface), the top of the coat laid so far over the skin (CoatTop) and the coat in the air past the
// skin's edge (AirTop), with the chart of nodes a feather is laid as (Node, Chart). Not installed.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pteryla/coat/drape.hpp"
#include "pteryla/core/error.hpp"
#include "spatial.hpp"

namespace pteryla::coat::draping {

using glm::dvec3;

constexpr double kFoldCos = 0.766;  // cos 40 degrees
constexpr double kFacing = 0.35;    // cos 70 degrees: samples facing away belong to another part
// A feather follows skin curved no tighter than this x its length (a rachis is stiff; measured on the
// bird and the corpus: 0.5 stood coats off fingers and ears, armadillo coverage 0.926 vs 0.956 at 0.15).
constexpr double kStiffness = 0.15;
constexpr double kWrapCos = 0.0;  // a feather follows the skin at most a quarter turn from its follicle

struct Node {
  dvec3 c{0};          // surface point
  dvec3 n{0, 0, 1};    // skin normal there
  dvec3 t{1, 0, 0};    // the feather's direction transported into the tangent plane
  double h = 0;        // height over the skin
  double sag = 0;      // how far the feather's triangles (chords) may dip below their vertices' surface here
  uint8_t ok = 0;      // the chart reached the skin here
  uint8_t active = 0;  // next to feather material
  uint8_t free = 0;    // past the skin's edge: the feather goes straight on (c is not on the skin)
  // The skin point the node was marched to (a free node: the last one before the edge), as face and
  // barycentric weights of its second and third corners; -1 = none (the follicle itself). A posed frame
  // carries the node with that point (drapeCarried).
  int32_t face = -1;
  double bu = 0, bv = 0;
};

struct Chart {
  double x0 = 0, y0 = 0, hx = 1, hy = 1, diag = 0;
  int nx = 0, ny = 0;
  double ramp = 0;                // the height ramps up from the skin over x in [0, ramp] (the calamus)
  double scale = 1;               // the feather's flat layout is scaled by this (shortened over later follicles)
  std::vector<uint8_t> material;  // per cell ((nx - 1) x (ny - 1)): holds feather vertices
  // Finer material mask: kSub x kSub sub-cells per cell, set where a vertex lies, dilated by one sub-cell.
  static constexpr int kSub = 4;
  std::vector<uint8_t> fine;
  int fineX() const { return (nx - 1) * kSub; }
  int fineY() const { return (ny - 1) * kSub; }
  bool covers(double x, double y) const {
    const int a = static_cast<int>(std::floor((x - x0) / hx * kSub)),
              b = static_cast<int>(std::floor((y - y0) / hy * kSub));
    if (a < 0 || b < 0 || a >= fineX() || b >= fineY()) return false;
    return fine[static_cast<size_t>(a) * fineY() + b] != 0;
  }
  std::vector<Node> nodes;     // a * ny + b
  size_t overhanging = 0;      // active nodes past the skin's edge (free), counted when the chart is built
  std::vector<int32_t> faces;  // the distinct skin faces its nodes were marched to, ascending
  // The skin samples a chart reads and writes while it is laid (static geometry, gathered in parallel
  // before the sequential pass): per active node (in node order) the samples facing like it within the
  // requirement radius, and once per sample the cell and weights of the material over it.
  struct Cover {
    uint32_t sample;
    uint16_t a, b;
    float u, v;
  };
  std::vector<int> active;          // active node indices
  std::vector<uint32_t> reqOffset;  // active.size() + 1 offsets into reqSamples
  std::vector<uint32_t> reqSamples;
  std::vector<Cover> under;
  const Node& at(int a, int b) const { return nodes[static_cast<size_t>(a) * ny + b]; }
  Node& at(int a, int b) { return nodes[static_cast<size_t>(a) * ny + b]; }
  // Cell and bilinear weights of local (x, y), clamped to the grid.
  void locate(double x, double y, int& a, int& b, double& u, double& v) const {
    const double fx = (x - x0) / hx, fy = (y - y0) / hy;
    a = std::clamp(static_cast<int>(std::floor(fx)), 0, nx - 2);
    b = std::clamp(static_cast<int>(std::floor(fy)), 0, ny - 2);
    u = std::clamp(fx - a, 0.0, 1.0);
    v = std::clamp(fy - b, 0.0, 1.0);
  }
};

class Surface {
 public:
  explicit Surface(const SkinMesh& s) : skin_(s) {
    flat_.resize(3 * s.faces.size());
    for (size_t f = 0; f < s.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) flat_[3 * f + k] = s.faces[f][k];
    bvh_.build(s.positions.data(), flat_.data(), s.faces.size());
  }
  // One step of length dist along the unit tangent dir from `from`, back onto the skin (the closest skin
  // point within dist of the moved point); the direction t is transported into the new tangent plane.
  // Where the skin ends under the feather (the step barely advances: a rim or the edge of a thin part),
  // curves away more tightly than the feather bends (radius under minRadius) or has turned past the
  // follicle's tangent plane (normal against rootN), the feather overhangs: from there on it goes
  // straight on in its last direction (`free` nodes), like a flight feather past the wing's edge.
  bool step(const Node& from, const dvec3& dir, double dist, const dvec3& rootN, double minRadius, Node& to) const {
    const dvec3 q = from.c + dist * dir;
    auto overhang = [&] {
      to = from;
      to.c = q;
      to.free = 1;
      to.ok = 1;
      return true;
    };
    if (from.free) return overhang();
    const double md = std::max(dist, 1e-300);
    dvec3 bary;
    double d2 = 0;
    const int64_t f = bvh_.nearest(q, md * md, bary, d2);
    if (f < 0) return overhang();
    to.c = pointAt(skin_, static_cast<uint32_t>(f), bary);
    to.n = normalAt(skin_, static_cast<uint32_t>(f), bary);
    to.face = static_cast<int32_t>(f);
    to.bu = bary.y;
    to.bv = bary.z;
    // The skin curves away under the feather more tightly than the feather bends: a radius of curvature
    // along the step under kStiffness x its length (angle turned > step / radius).
    const double turn = std::acos(std::clamp(glm::dot(to.n, from.n), -1.0, 1.0));
    if (glm::length(to.c - from.c) < 0.5 * dist || turn > dist / minRadius || glm::dot(to.n, rootN) < kWrapCos)
      return overhang();
    const dvec3 t = from.t - glm::dot(from.t, to.n) * to.n;
    const double l = glm::length(t);
    if (!(l > 1e-12) || !std::isfinite(l)) return overhang();
    to.t = t / l;
    to.ok = 1;
    to.free = 0;
    return true;
  }
  // Marches a signed distance along the feather direction (along) or across it (+ = n x t), in steps of
  // at most maxStep.
  bool march(Node p, bool along, double dist, double maxStep, const dvec3& rootN, double minRadius, Node& out) const {
    if (dist == 0) {
      out = p;
      return p.ok;
    }
    const int steps = std::max(1, static_cast<int>(std::ceil(std::abs(dist) / maxStep)));
    const double d = std::abs(dist) / steps, sign = dist < 0 ? -1.0 : 1.0;
    for (int k = 0; k < steps; ++k) {
      const dvec3 dir = sign * (along ? p.t : glm::normalize(glm::cross(p.n, p.t)));
      Node next;
      if (!step(p, dir, d, rootN, minRadius, next)) return false;
      p = next;
    }
    out = p;
    return true;
  }
  // Is any skin closer to p than `dist`?
  bool skinWithin(const dvec3& p, double dist) const {
    dvec3 bary;
    double d2 = 0;
    return bvh_.nearest(p, dist * dist, bary, d2) >= 0;
  }

 private:
  const SkinMesh& skin_;
  std::vector<uint32_t> flat_;
  detail::TriangleBvh bvh_;
};

// The top of the coat laid so far, on samples of the skin: every face sampled on a barycentric grid no
// coarser than `spacing`; top[s] is the height over the skin of the highest feather material over sample s
// (0: bare skin). Samples are looked up by position and only count for a node whose normal is within
// about 70 degrees of theirs, so the far side of a thin part never raises a feather. Samples are numbered
// in the grid's slot order (cell by cell, row by row), so those near one point have nearby numbers.
class CoatTop {
 public:
  // Face by face in parallel (in the arena the caller runs in); the samples are those of one pass.
  CoatTop(const SkinMesh& skin, double spacing) {
    const size_t nf = skin.faces.size();
    std::vector<int> steps(nf);
    std::vector<size_t> first(nf + 1, 0);
    for (size_t f = 0; f < nf; ++f) {
      const auto& t = skin.faces[f];
      const dvec3 a = skin.positions[t[0]], b = skin.positions[t[1]], c = skin.positions[t[2]];
      const double e = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
      const int m = std::clamp(static_cast<int>(std::ceil(e / spacing)), 1, 4096);
      steps[f] = m;
      first[f + 1] = first[f] + static_cast<size_t>(m + 1) * static_cast<size_t>(m + 2) / 2;
    }
    pos_.resize(first[nf]);
    nrm_.resize(first[nf]);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nf, 64), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t f = r.begin(); f < r.end(); ++f) {
        const int m = steps[f];
        size_t s = first[f];
        for (int i = 0; i <= m; ++i)
          for (int j = 0; i + j <= m; ++j, ++s) {
            const dvec3 bary(double(m - i - j) / m, double(i) / m, double(j) / m);
            pos_[s] = pointAt(skin, static_cast<uint32_t>(f), bary);
            nrm_[s] = normalAt(skin, static_cast<uint32_t>(f), bary);
          }
      }
    });
    top_.assign(pos_.size(), 0.0f);
    grid_.build(pos_, spacing * 2);
    // The samples again in the grid's slot order, so that a query reads them one after the other.
    slotPos_.resize(pos_.size());
    slotNrm_.resize(pos_.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, pos_.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        const uint32_t s = grid_.item(static_cast<uint32_t>(k));
        slotPos_[k] = pos_[s];
        slotNrm_[k] = nrm_[s];
      }
    });
    // Read only through the slots from here on.
    std::vector<dvec3>().swap(pos_);
    std::vector<dvec3>().swap(nrm_);
  }
  size_t size() const { return slotPos_.size(); }
  // Calls f(sample) for the samples within radius of c facing like n.
  template <class F>
  void near(const dvec3& c, const dvec3& n, double radius, F&& f) const {
    nearAll(c, n, radius, [&](uint32_t s, const dvec3&, double) { f(s); });
  }
  // f(sample, sample - c, its squared length) for the samples within radius of c facing like n, in
  // near()'s order: one pass serves several radii up to `radius`.
  template <class F>
  void nearAll(const dvec3& c, const dvec3& n, double radius, F&& f) const {
    const double r2 = radius * radius;
    grid_.querySlots(c - dvec3(radius), c + dvec3(radius), [&](uint32_t first, uint32_t last) {
      for (uint32_t k = first; k < last; ++k) {
        const dvec3 d = slotPos_[k] - c;
        const double dd = glm::dot(d, d);
        if (dd <= r2 && glm::dot(slotNrm_[k], n) > kFacing) f(k, d, dd);
      }
    });
  }
  const dvec3& position(uint32_t s) const { return slotPos_[s]; }
  double at(uint32_t s) const { return top_[s]; }
  void raise(uint32_t s, double h) { top_[s] = std::max(top_[s], static_cast<float>(h)); }
  void reset() { std::fill(top_.begin(), top_.end(), 0.0f); }  // bare skin again
  size_t bytes() const {
    return (slotPos_.capacity() + slotNrm_.capacity()) * sizeof(dvec3) + top_.capacity() * sizeof(float);
  }

 private:
  std::vector<dvec3> pos_, nrm_;          // per sample, only while the slots are made
  std::vector<dvec3> slotPos_, slotNrm_;  // per sample (numbered by slot), its position and normal
  std::vector<float> top_;
  detail::PointGrid grid_;
};

// The coat laid so far, in space: every laid node's lifted point (c + h n) with its normal. Past the
// skin's edge a feather has no skin under it to measure height over; there it rises above the material
// already laid around the line through its node along its normal (a flight feather over the one under
// it, beyond the wing's edge).
class AirTop {
 public:
  explicit AirTop(double radius) : r_(std::max(radius, 1e-12)), cell_(2 * r_) {}
  double radius() const { return r_; }
  void add(const dvec3& p, const dvec3& n) {
    const uint32_t id = static_cast<uint32_t>(pos_.size());
    pos_.push_back(p);
    nrm_.push_back(n);
    cells_[key(cellOf(p))].push_back(id);
  }
  // Highest height over the plane (c, n), up to `depth` above it, of laid points within the radius of
  // the line c + s n; -inf when none. Whichever way they face: past a thin part's rim the coats of its
  // two sides meet, and the later one lies over the earlier instead of through it.
  double highest(const dvec3& c, const dvec3& n, double depth) const {
    double best = -std::numeric_limits<double>::infinity();
    if (pos_.empty()) return best;
    // A point that counts lies within depth along n and r_ beside the line, so along axis k within
    // depth |n_k| + r_ of c (whatever n's length); a hair more covers the tests' rounding. The cells
    // of that box hold every such point (a cube of r_ + depth did too, with many more cells).
    const double slack = 1e-9 * (r_ + depth + std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z)}));
    const dvec3 reach = depth * glm::abs(n) + dvec3(r_ + slack);
    const glm::ivec3 a = cellOf(c - reach), b = cellOf(c + reach);
    for (int z = a.z; z <= b.z; ++z)
      for (int y = a.y; y <= b.y; ++y)
        for (int x = a.x; x <= b.x; ++x) {
          const auto it = cells_.find(key({x, y, z}));
          if (it == cells_.end()) continue;
          for (uint32_t id : it->second) {
            const dvec3 d = pos_[id] - c;
            const double up = glm::dot(d, n);
            if (up <= best || up > depth || up < -depth) continue;
            const dvec3 side = d - up * n;
            if (glm::dot(side, side) <= r_ * r_) best = up;
          }
        }
    return best;
  }

 private:
  glm::ivec3 cellOf(const dvec3& p) const {
    return {static_cast<int>(std::floor(p.x / cell_)), static_cast<int>(std::floor(p.y / cell_)),
            static_cast<int>(std::floor(p.z / cell_))};
  }
  static uint64_t key(const glm::ivec3& c) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(c.x) & 0x1fffff) << 42) |
           (static_cast<uint64_t>(static_cast<uint32_t>(c.y) & 0x1fffff) << 21) |
           static_cast<uint64_t>(static_cast<uint32_t>(c.z) & 0x1fffff);
  }
  double r_, cell_;
  std::vector<dvec3> pos_, nrm_;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
};

}  // namespace pteryla::coat::draping
