#include "pteryla/core/finite.hpp"

#include <cmath>

#include "pteryla/core/error.hpp"

namespace pteryla {
namespace {

float component(const glm::vec3& v, int c) { return v[c]; }
float component(const glm::vec2& v, int c) { return v[c]; }
float component(const PackedDir& v, int c) { return PackedDir::unpack(v.q[c]); }
float component(Half v, int) { return v; }

template <class V>
void check(const std::vector<V>& values, int comps, const char* what, const std::string& file) {
  for (size_t i = 0; i < values.size(); ++i)
    for (int c = 0; c < comps; ++c)
      if (!std::isfinite(component(values[i], c)))
        throw Error("the computed mesh has a non-finite " + std::string(what) +
                        " (an input value is too large or degenerate); nothing written",
                    file, "vertex " + std::to_string(i));
}

}  // namespace

void requireFinite(const TriMesh& m, const std::string& file) {
  check(m.positions, 3, "position", file);
  check(m.normals, 3, "normal", file);
  check(m.tangents, 3, "tangent", file);
  check(m.uvGlobal, 2, "texture coordinate", file);
  check(m.uvBarb, 2, "barb texture coordinate", file);
  check(m.uvGrowth, 2, "growth texture coordinate", file);
  check(m.alpha, 1, "alpha", file);
  check(m.sheath, 1, "sheath weight", file);
  check(m.barbCount, 1, "barb count", file);
}

}  // namespace pteryla
