#include "navigation.hpp"

#include <algorithm>
#include <limits>

namespace pteryla::viewer {
namespace {

template <class T>
void copySpan(std::vector<T>& dst, const std::vector<T>& src, uint32_t lo, uint32_t hi) {
  if (!src.empty()) dst.insert(dst.end(), src.begin() + lo, src.begin() + hi + 1);
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
  // Then every k-th of the others, in layer order.
  size_t rest = 0;
  for (size_t r = 0; r < n; ++r)
    if (!keep[r]) rest += coat.ranges[r].indexCount / 3;
  const size_t room = std::max<size_t>(budget - used, 1);
  out.stride = std::max<size_t>((rest + room - 1) / room, 1);
  for (size_t r = 0, j = 0; r < n; ++r) {
    if (keep[r]) continue;
    if (j++ % out.stride == 0) keep[r] = 1;
  }
  for (size_t r = 0; r < n; ++r) {
    const pipeline::CoatDrawRange& d = coat.ranges[r];
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
