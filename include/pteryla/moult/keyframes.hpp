#pragma once
// Keyframed values over time (Streit 2003, Ch.8: everything in the alteration component is a function of
// time; AnimFur: control attributes are animated with keys). A Track holds sorted keys of up to three
// components (scalars use x); evaluation is a pure function of t, so a timeline can be scrubbed in any
// order. Before the first key a track holds the first value, after the last key the last value.
//
// Interpolation between keys k and k+1 (x = (t - t_k) / (t_{k+1} - t_k)):
//   linear  v_k + (v_{k+1} - v_k) x
//   smooth  v_k + (v_{k+1} - v_k) (3x^2 - 2x^3)   (ease in and out, zero slope at every key)
//   step    v_k (jumps at t_{k+1})
#include <glm/vec3.hpp>

#include <array>
#include <string>
#include <vector>

namespace pteryla::moult {

enum class Interpolation { Linear, Smooth, Step };
const char* interpolationName(Interpolation i);  // "linear", "smooth", "step"
// Parses an interpolation name; returns false for an unknown name.
bool parseInterpolation(const std::string& name, Interpolation& out);

// One segment of a track as a cubic in s = t - start: value = c[0] + c[1] s + c[2] s^2 + c[3] s^3,
// valid for t in [start, end) (end = +inf after the last key, start = -inf before the first key).
struct TrackSegment {
  double start = 0, end = 0;
  std::array<glm::dvec3, 4> c{};
};

struct Track {
  std::vector<double> t;      // strictly increasing key times
  std::vector<glm::dvec3> v;  // key values
  Interpolation interpolation = Interpolation::Linear;

  bool empty() const { return t.empty(); }
  // Adds a key; keys may come in any order, addKey keeps them sorted. Returns false when a key already
  // exists at exactly this time (the caller reports the duplicate).
  bool addKey(double time, const glm::dvec3& value);
  glm::dvec3 at(double time) const;  // zero for an empty track
  double scalarAt(double time) const { return at(time).x; }
  // Segments covering (-inf, +inf) in time order: a constant before the first key, one per key
  // interval, a constant after the last key. Empty track: one zero constant.
  std::vector<TrackSegment> segments() const;
};

}  // namespace pteryla::moult
