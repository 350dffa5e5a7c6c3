// Keyframe tracks for the time-dependent stages (Streit 2003, Ch.8; AnimFur, Grier 2019, 4.3: animated
// control attributes).
#include "pteryla/moult/keyframes.hpp"

#include <algorithm>
#include <limits>

namespace pteryla::moult {

const char* interpolationName(Interpolation i) {
  switch (i) {
    case Interpolation::Linear:
      return "linear";
    case Interpolation::Smooth:
      return "smooth";
    case Interpolation::Step:
      return "step";
  }
  return "?";
}

bool parseInterpolation(const std::string& name, Interpolation& out) {
  if (name == "linear")
    out = Interpolation::Linear;
  else if (name == "smooth")
    out = Interpolation::Smooth;
  else if (name == "step")
    out = Interpolation::Step;
  else
    return false;
  return true;
}

bool Track::addKey(double time, const glm::dvec3& value) {
  const auto it = std::lower_bound(t.begin(), t.end(), time);
  if (it != t.end() && *it == time) return false;
  const auto k = it - t.begin();
  t.insert(it, time);
  v.insert(v.begin() + k, value);
  return true;
}

glm::dvec3 Track::at(double time) const {
  if (t.empty()) return glm::dvec3(0);
  if (time <= t.front()) return v.front();
  if (time >= t.back()) return v.back();
  const size_t k = static_cast<size_t>(std::upper_bound(t.begin(), t.end(), time) - t.begin()) - 1;
  const double x = (time - t[k]) / (t[k + 1] - t[k]);
  switch (interpolation) {
    case Interpolation::Linear:
      return v[k] + (v[k + 1] - v[k]) * x;
    case Interpolation::Smooth:
      return v[k] + (v[k + 1] - v[k]) * (x * x * (3.0 - 2.0 * x));
    case Interpolation::Step:
      return v[k];
  }
  return v[k];
}

std::vector<TrackSegment> Track::segments() const {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<TrackSegment> out;
  if (t.empty()) {
    out.push_back({-kInf, kInf, {}});
    return out;
  }
  TrackSegment first{-kInf, t.front(), {}};
  first.c[0] = v.front();
  out.push_back(first);
  for (size_t k = 0; k + 1 < t.size(); ++k) {
    TrackSegment s{t[k], t[k + 1], {}};
    const double d = t[k + 1] - t[k];
    const glm::dvec3 dv = v[k + 1] - v[k];
    s.c[0] = v[k];
    switch (interpolation) {
      case Interpolation::Linear:
        s.c[1] = dv / d;
        break;
      case Interpolation::Smooth:
        s.c[2] = 3.0 * dv / (d * d);
        s.c[3] = -2.0 * dv / (d * d * d);
        break;
      case Interpolation::Step:
        break;
    }
    out.push_back(s);
  }
  TrackSegment last{t.back(), kInf, {}};
  last.c[0] = v.back();
  out.push_back(last);
  return out;
}

}  // namespace pteryla::moult
