#include "navigation.hpp"

#include <algorithm>
#include <limits>
#include <utility>

#include <glm/geometric.hpp>

namespace pteryla::viewer {
namespace {

template <class T>
void copySpan(std::vector<T>& dst, const std::vector<T>& src, uint32_t lo, uint32_t hi) {
  if (!src.empty()) dst.insert(dst.end(), src.begin() + lo, src.begin() + hi + 1);
}

// Appends a card for feather range `d`: its vertices binned along the shaft (the range's axisX from its
// origin), and per bin the two vertices farthest to either side (axisY); consecutive bins are joined by
// two triangles. The card's vertices are copies of those extreme vertices (positions, normals, texture
// coordinates, ...), opaque. False when the feather has too few vertices to span a card.
bool addCard(const TriMesh& m, const pipeline::CoatDrawRange& d, int bins, TriMesh& out,
             std::vector<pipeline::CoatDrawRange>& ranges) {
  glm::vec3 ax = d.axisX, ay = d.axisY;
  if (!(glm::length(ax) > 0) || !(glm::length(ay) > 0)) return false;
  ax = glm::normalize(ax);
  ay = glm::normalize(ay);
  float s0 = std::numeric_limits<float>::max(), s1 = -s0;
  for (uint32_t i = d.firstIndex; i < d.firstIndex + d.indexCount; ++i) {
    const float s = glm::dot(m.positions[m.indices[i]] - d.origin, ax);
    s0 = std::min(s0, s);
    s1 = std::max(s1, s);
  }
  if (!(s1 > s0)) return false;
  const int B = std::max(bins, 2);
  std::vector<uint32_t> left(size_t(B), UINT32_MAX), right(size_t(B), UINT32_MAX);
  std::vector<float> wl(size_t(B), std::numeric_limits<float>::max()),
      wr(size_t(B), -std::numeric_limits<float>::max());
  for (uint32_t i = d.firstIndex; i < d.firstIndex + d.indexCount; ++i) {
    const uint32_t v = m.indices[i];
    const glm::vec3 e = m.positions[v] - d.origin;
    const int b = std::min(B - 1, int(float(B) * (glm::dot(e, ax) - s0) / (s1 - s0)));
    const float w = glm::dot(e, ay);
    if (w < wl[size_t(b)]) wl[size_t(b)] = w, left[size_t(b)] = v;
    if (w > wr[size_t(b)]) wr[size_t(b)] = w, right[size_t(b)] = v;
  }
  std::vector<std::pair<uint32_t, uint32_t>> rows;  // (left, right) of the bins that have vertices
  for (int b = 0; b < B; ++b)
    if (left[size_t(b)] != UINT32_MAX) rows.emplace_back(left[size_t(b)], right[size_t(b)]);
  if (rows.size() < 2) return false;
  const uint32_t base = static_cast<uint32_t>(out.positions.size());
  auto copy = [&](uint32_t v) {
    auto one = [&](auto& dst, const auto& src) {
      if (!src.empty()) dst.push_back(src[v]);
    };
    one(out.positions, m.positions);
    one(out.normals, m.normals);
    one(out.tangents, m.tangents);
    one(out.uvGlobal, m.uvGlobal);
    one(out.uvBarb, m.uvBarb);
    one(out.uvGrowth, m.uvGrowth);
    if (!m.alpha.empty()) out.alpha.push_back(1.0f);  // opaque: the card stands for the whole vane
    one(out.sheath, m.sheath);
    one(out.barbCount, m.barbCount);
    one(out.featherId, m.featherId);
  };
  for (const auto& [l, r] : rows) copy(l), copy(r);
  pipeline::CoatDrawRange nd = d;
  nd.firstIndex = static_cast<uint32_t>(out.indices.size());
  for (uint32_t k = 0; k + 1 < rows.size(); ++k) {
    const uint32_t l0 = base + 2 * k, r0 = l0 + 1, l1 = l0 + 2, r1 = l0 + 3;
    out.indices.insert(out.indices.end(), {l0, r0, r1, l0, r1, l1});
  }
  nd.indexCount = static_cast<uint32_t>(out.indices.size()) - nd.firstIndex;
  for (uint32_t& c : nd.partCount) c = 0;  // one part: the card
  ranges.push_back(nd);
  return true;
}

}  // namespace

NavigationCoat makeNavigationCoat(const pipeline::CoatMesh& coat, size_t budget) {
  NavigationCoat out;
  const size_t triangles = coat.mesh.triangleCount();
  if (budget == 0 || triangles <= budget || coat.ranges.empty()) return out;
  const TriMesh& m = coat.mesh;
  const size_t n = coat.ranges.size();
  // Vertex span and length (farthest vertex from the follicle) of every feather.
  std::vector<uint32_t> lo(n, std::numeric_limits<uint32_t>::max()), hi(n, 0);
  std::vector<float> length(n, 0.0f);
  for (size_t r = 0; r < n; ++r) {
    const pipeline::CoatDrawRange& d = coat.ranges[r];
    for (uint32_t i = d.firstIndex; i < d.firstIndex + d.indexCount; ++i) {
      const uint32_t v = m.indices[i];
      lo[r] = std::min(lo[r], v);
      hi[r] = std::max(hi[r], v);
      const glm::vec3 e = m.positions[v] - d.origin;
      length[r] = std::max(length[r], e.x * e.x + e.y * e.y + e.z * e.z);
    }
  }
  // Long feathers first (top tenth by length, within half the budget).
  std::vector<size_t> byLength(n);
  for (size_t r = 0; r < n; ++r) byLength[r] = r;
  std::stable_sort(byLength.begin(), byLength.end(), [&](size_t a, size_t b) { return length[a] > length[b]; });
  std::vector<uint8_t> keep(n, 0);
  size_t used = 0;
  for (size_t k = 0; k < n / 10; ++k) {
    const size_t r = byLength[k];
    const size_t t = coat.ranges[r].indexCount / 3;
    if (used + t > budget / 2) break;
    keep[r] = 1;
    used += t;
    ++out.longKept;
  }
  // Every other feather as a card (so the body stays covered): as many bins along the shaft as the
  // room allows (2 to kMaxCardBins, 2 (bins - 1) triangles each); every k-th card only when even the
  // smallest cards do not fit.
  size_t others = 0;
  for (size_t r = 0; r < n; ++r)
    if (!keep[r] && coat.ranges[r].indexCount > 0) ++others;
  const size_t room = std::max<size_t>(budget - used, 1);
  const size_t perCard = others > 0 ? room / others : 0;  // triangles each card may have
  out.cardBins = int(std::clamp<size_t>(perCard / 2 + 1, 2, kMaxCardBins));
  const size_t cardTriangles = 2 * size_t(out.cardBins - 1);
  out.stride = std::max<size_t>((others * cardTriangles + room - 1) / room, 1);
  std::vector<uint8_t> card(n, 0);
  for (size_t r = 0, j = 0; r < n; ++r) {
    if (keep[r] || coat.ranges[r].indexCount == 0) continue;
    if (j++ % out.stride == 0) card[r] = 1;
  }
  for (size_t r = 0; r < n; ++r) {
    const pipeline::CoatDrawRange& d = coat.ranges[r];
    if (card[r]) {
      if (addCard(m, d, out.cardBins, out.mesh, out.ranges)) ++out.cards;
      continue;
    }
    if (!keep[r] || d.indexCount == 0) continue;
    const uint32_t base = static_cast<uint32_t>(out.mesh.positions.size());
    copySpan(out.mesh.positions, m.positions, lo[r], hi[r]);
    copySpan(out.mesh.normals, m.normals, lo[r], hi[r]);
    copySpan(out.mesh.tangents, m.tangents, lo[r], hi[r]);
    copySpan(out.mesh.uvGlobal, m.uvGlobal, lo[r], hi[r]);
    copySpan(out.mesh.uvBarb, m.uvBarb, lo[r], hi[r]);
    copySpan(out.mesh.uvGrowth, m.uvGrowth, lo[r], hi[r]);
    copySpan(out.mesh.alpha, m.alpha, lo[r], hi[r]);
    copySpan(out.mesh.sheath, m.sheath, lo[r], hi[r]);
    copySpan(out.mesh.barbCount, m.barbCount, lo[r], hi[r]);
    copySpan(out.mesh.featherId, m.featherId, lo[r], hi[r]);
    pipeline::CoatDrawRange nd = d;
    nd.firstIndex = static_cast<uint32_t>(out.mesh.indices.size());
    for (uint32_t i = d.firstIndex; i < d.firstIndex + d.indexCount; ++i)
      out.mesh.indices.push_back(m.indices[i] - lo[r] + base);
    out.ranges.push_back(nd);
  }
  return out;
}

bool useNavigationCoat(bool forced, bool adaptive, double movingFullCoatMs, double budgetMs) {
  if (forced || !adaptive) return true;
  if (movingFullCoatMs < 0.0) return false;  // measure the full coat first
  return movingFullCoatMs > budgetMs;
}

double smoothFrameMs(double previousMs, double sampleMs) {
  return previousMs < 0.0 ? sampleMs : 0.7 * previousMs + 0.3 * sampleMs;
}

}  // namespace pteryla::viewer
