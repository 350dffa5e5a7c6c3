#pragma once
// The one placement of a feather in its follicle frame (thesis 6.3.1; docs/architecture.md, "Frames").
// A follicle frame is (T, B, N): N the skin normal, T the direction the feather lies along, B = N x T.
// A feather raised by elevation e turns T toward N about B. Its local axes (+x shaft, +y left vane,
// +z dorsal) are then
//   x = cos e T + sin e N,   y = B,   z = -sin e T + cos e N.
// Every module that places a feather (packing, meshing, controls, the synthetic coat) takes its axes from
// here, in double or float.
#include <cmath>

namespace pteryla {

template <class V>
struct ElevatedAxes {
  V x, y, z;  // shaft, left vane, dorsal
};

template <class V, class S>
inline ElevatedAxes<V> elevatedAxes(const V& T, const V& B, const V& N, S elevation) {
  const S c = std::cos(elevation), s = std::sin(elevation);
  return {c * T + s * N, B, -s * T + c * N};
}

}  // namespace pteryla
