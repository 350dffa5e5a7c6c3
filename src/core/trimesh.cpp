#include "pteryla/core/trimesh.hpp"
#include "pteryla/core/trimesh_reuse.hpp"

#include <algorithm>
#include <glm/common.hpp>

namespace pteryla {
namespace {
template <class T>
void appendAttr(std::vector<T>& dst, size_t dstVerts, const std::vector<T>& src, size_t srcVerts, const T& def) {
  if (dst.empty() && src.empty()) return;
  if (dst.size() < dstVerts) dst.resize(dstVerts, def);
  if (src.empty()) {
    dst.resize(dstVerts + srcVerts, def);
  } else {
    dst.insert(dst.end(), src.begin(), src.end());
  }
}
}  // namespace

void TriMesh::append(const TriMesh& o) {
  const size_t n = positions.size(), m = o.positions.size();
  appendAttr(normals, n, o.normals, m, PackedDir(glm::vec3(0, 0, 1)));
  appendAttr(tangents, n, o.tangents, m, PackedDir(glm::vec3(1, 0, 0)));
  appendAttr(uvGlobal, n, o.uvGlobal, m, glm::vec2(0));
  appendAttr(uvBarb, n, o.uvBarb, m, glm::vec2(0));
  appendAttr(uvGrowth, n, o.uvGrowth, m, glm::vec2(0));
  appendAttr(alpha, n, o.alpha, m, Half(1.0f));
  appendAttr(sheath, n, o.sheath, m, Half(0.0f));
  appendAttr(barbCount, n, o.barbCount, m, Half(1.0f));
  appendAttr(featherId, n, o.featherId, m, 0u);
  positions.insert(positions.end(), o.positions.begin(), o.positions.end());
  const uint32_t off = static_cast<uint32_t>(n);
  for (uint32_t i : o.indices) indices.push_back(i + off);
}

bool TriMesh::bounds(glm::vec3& lo, glm::vec3& hi) const {
  if (positions.empty()) return false;
  lo = hi = positions[0];
  for (const auto& p : positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  return true;
}

void clearKeepingCapacity(TriMesh& m) {
  m.positions.clear();
  m.normals.clear();
  m.tangents.clear();
  m.uvGlobal.clear();
  m.uvBarb.clear();
  m.uvGrowth.clear();
  m.alpha.clear();
  m.sheath.clear();
  m.barbCount.clear();
  m.featherId.clear();
  m.indices.clear();
}

}  // namespace pteryla
