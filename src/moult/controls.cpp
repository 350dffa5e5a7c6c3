// Expressive lift controls: AnimFur (Grier 2019, 3.2 "Design for Hair Rig", 4.3 "The Hair Rig": controls
// bound to their nearest hairs; lift, aim, direction, random twist and dynamic blend behaviours) applied
// through Streit 2003, 8.3 fixed feather angles (lifted feathers keep their angle, the rest is packed
// against them). The dynamic blend bends the shaft as a spring chain (chain.cpp); springLag is its rigid
// one-segment case in closed form.
#include "pteryla/moult/controls.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"
#include "spring_internal.hpp"

namespace pteryla::moult {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHalfPi = 0.5 * kPi;
constexpr uint64_t kTwistSalt = 0x7477697374ull;

using spring::SpringMap;
using spring::springMap;

glm::dvec3 poly(const std::array<glm::dvec3, 4>& c, double s) { return c[0] + s * (c[1] + s * (c[2] + s * c[3])); }
glm::dvec3 polyD(const std::array<glm::dvec3, 4>& c, double s) { return c[1] + s * (2.0 * c[2] + s * 3.0 * c[3]); }

double smoothWeight(double dist, double radius, double falloff) {
  const double r = dist / radius;
  if (r > 1) return 0;
  const double inner = 1 - falloff;
  if (r <= inner || falloff <= 0) return 1;
  const double x = std::clamp((r - inner) / falloff, 0.0, 1.0);
  return 1 - x * x * (3 - 2 * x);
}

// T turned about N toward the tangent-plane direction of g by fraction w of the angle between them.
bool turnToward(glm::dvec3& T, const glm::dvec3& N, const glm::dvec3& g, double w) {
  if (!(w > 0)) return false;
  const glm::dvec3 gp = g - glm::dot(g, N) * N;
  const double len = glm::length(gp);
  if (!(len > 1e-12 * std::max(1.0, glm::length(g)))) return false;
  const glm::dvec3 gu = gp / len;
  const double phi = std::atan2(glm::dot(N, glm::cross(T, gu)), glm::dot(T, gu));
  const double ang = w * phi;
  if (ang == 0) return false;
  T = glm::normalize(std::cos(ang) * T + std::sin(ang) * glm::cross(N, T));
  return true;
}

double elevationOf(const glm::dvec3& g, const glm::dvec3& N) {
  const double len = glm::length(g);
  if (!(len > 0)) return 0;
  return std::asin(std::clamp(glm::dot(g, N) / len, -1.0, 1.0));
}

void readAttribute(JsonReader& r, const std::string& key, double lo, double hi, Track& track) {
  if (!r.has(key)) {
    r.allow(key);
    return;
  }
  track.addKey(0.0, glm::dvec3(r.number(key, lo, hi), 0, 0));
}

}  // namespace

glm::dvec3 springLag(const Track& u, double frequency, double damping, double t) {
  if (u.empty() || t <= u.t.front()) return glm::dvec3(0.0);
  const double w = 2 * kPi * frequency, C = 2 * damping * w, W = w * w;
  const std::vector<TrackSegment> segs = u.segments();
  glm::dvec3 x = u.v.front(), xd(0.0);
  for (size_t k = 1; k < segs.size(); ++k) {  // segs[0] is the constant before the first key
    const TrackSegment& sg = segs[k];
    const auto& c = sg.c;
    // Polynomial particular solution of x'' + C x' + W x = W u(s).
    std::array<glm::dvec3, 4> p;
    p[3] = c[3];
    p[2] = c[2] - 3.0 * C * p[3] / W;
    p[1] = c[1] - (6.0 * p[3] + 2.0 * C * p[2]) / W;
    p[0] = c[0] - (2.0 * p[2] + C * p[1]) / W;
    const double s = std::min(t, sg.end) - sg.start;
    const glm::dvec3 h0 = x - p[0], hd0 = xd - p[1];
    const SpringMap m = springMap(w, damping, s);
    const glm::dvec3 h = m.a * h0 + m.b * hd0, hd = m.c * h0 + m.d * hd0;
    x = poly(p, s) + h;
    xd = polyD(p, s) + hd;
    if (t < sg.end) return x - poly(c, s);
  }
  return glm::dvec3(0.0);  // unreachable: the last segment is unbounded
}

ControlValues controlValuesAt(const ControlSpec& c, double t) {
  ControlValues v;
  v.lift = std::clamp(c.lift.scalarAt(t), 0.0, 1.0);
  v.aim = std::clamp(c.aim.scalarAt(t), 0.0, 1.0);
  v.direction = std::clamp(c.direction.scalarAt(t), 0.0, 1.0);
  v.random = std::clamp(c.random.scalarAt(t), 0.0, 1.0);
  v.dynamic = std::clamp(c.dynamic.scalarAt(t), 0.0, 1.0);
  v.offset = c.offset.at(t);
  if (v.dynamic > 0) v.lag = springLag(c.offset, c.springFrequency, c.springDamping, t);
  return v;
}

ControlBinding bindControls(const coat::SkinMesh& rest, const coat::Follicles& follicles,
                            const std::vector<ControlSpec>& controls,
                            const std::vector<std::vector<uint32_t>>& controlTracts) {
  ControlBinding b;
  const size_t nc = controls.size(), nf = follicles.size();
  b.anchor.resize(nc);
  b.bound.assign(nc, 0);
  b.control.assign(nf, -1);
  b.weight.assign(nf, 0.0);
  std::vector<glm::dvec3> at(nc);
  for (size_t c = 0; c < nc; ++c) {
    b.anchor[c] = coat::closestSurfacePoint(rest, controls[c].at);
    at[c] = coat::pointAt(rest, b.anchor[c]);
  }
  for (size_t f = 0; f < nf; ++f) {
    const glm::dvec3 p = coat::pointAt(rest, follicles.face[f], follicles.bary[f]);
    double best = std::numeric_limits<double>::infinity();
    int32_t bestC = -1;
    for (size_t c = 0; c < nc; ++c) {
      if (c < controlTracts.size() && !controlTracts[c].empty() &&
          std::find(controlTracts[c].begin(), controlTracts[c].end(), follicles.tract[f]) == controlTracts[c].end())
        continue;
      const double d = glm::length(p - at[c]);
      if (d <= controls[c].radius && d < best) {
        best = d;
        bestC = static_cast<int32_t>(c);
      }
    }
    if (bestC < 0) continue;
    const ControlSpec& cs = controls[static_cast<size_t>(bestC)];
    const double w = smoothWeight(best, cs.radius, cs.falloff);
    if (!(w > 0)) continue;
    b.control[f] = bestC;
    b.weight[f] = w;
    ++b.bound[static_cast<size_t>(bestC)];
  }
  return b;
}

ControlResult evaluateControls(const std::vector<ControlSpec>& controls, const ControlBinding& binding,
                               const coat::SkinMesh& posed, const coat::Follicles& follicles, double t,
                               const coat::PackOptions& pack, const coat::PackConstraints& constraints,
                               coat::CoatFeathers& coat, std::vector<double>& fixedElevation) {
  coat::PackResult natural;
  const NaturalPackFn own = [&natural](const coat::SkinMesh& s, const coat::CoatFeathers& c, const coat::PackOptions& o,
                                       const coat::PackConstraints& k) -> const coat::PackResult& {
    natural = coat::pack(s, c, o, k);
    return natural;
  };
  ControlResult res =
      evaluateControls(controls, binding, posed, follicles, t, pack, constraints, coat, fixedElevation, own);
  if (res.naturalPacked) res.natural = std::move(natural);
  return res;
}

ControlResult evaluateControls(const std::vector<ControlSpec>& controls, const ControlBinding& binding,
                               const coat::SkinMesh& posed, const coat::Follicles& follicles, double t,
                               const coat::PackOptions& pack, const coat::PackConstraints& constraints,
                               coat::CoatFeathers& coat, std::vector<double>& fixedElevation,
                               const NaturalPackFn& naturalPack) {
  ControlResult res;
  const size_t n = coat.size();
  PTERYLA_CHECK_EQ(binding.control.size(), follicles.size(), "control binding was made for other follicles");
  PTERYLA_CHECK_EQ(binding.anchor.size(), controls.size(), "control binding was made for other controls");
  if (fixedElevation.empty()) fixedElevation.assign(n, std::numeric_limits<double>::quiet_NaN());
  PTERYLA_CHECK_EQ(fixedElevation.size(), n, "fixedElevation must have one entry per feather");
  if (controls.empty()) return res;

  std::vector<ControlValues> values(controls.size());
  std::vector<glm::dvec3> position(controls.size());
  for (size_t c = 0; c < controls.size(); ++c) {
    values[c] = controlValuesAt(controls[c], t);
    position[c] = coat::pointAt(posed, binding.anchor[c]) + values[c].offset;
  }
  auto present = [&](size_t i) { return coat.present.empty() || coat.present[i] != 0; };

  // Pass 1: turns about the normal (direction, aim, random twist), and whether any feather
  // wants to rise (which needs its natural elevation). A feather absent at t (moulted) is turned as
  // when present: a moult frame's mature coat takes every frame from this one, and its frames must not
  // change as feathers come and go (the mature coat would be packed or draped again).
  std::vector<uint8_t> wantsRaise(n, 0);
  bool needNatural = false;
  for (size_t i = 0; i < n; ++i) {
    const uint32_t f = coat.follicle[i];
    const int32_t c = binding.control[f];
    if (c < 0) continue;
    const double w = binding.weight[f];
    const ControlSpec& cs = controls[static_cast<size_t>(c)];
    const ControlValues& v = values[static_cast<size_t>(c)];
    const bool here = present(i);
    res.bound += here ? 1 : 0;
    coat::FeatherFrame& F = coat.frames[i];
    const glm::dvec3 N = F.normal;
    glm::dvec3 T = F.tangent;
    const glm::dvec3 toControl = position[static_cast<size_t>(c)] - F.origin;
    bool turned = false;
    turned |= turnToward(T, N, v.offset, v.direction * w);
    turned |= turnToward(T, N, toControl, v.aim * w);
    if (v.random > 0) {
      const uint64_t id = f < follicles.id.size() ? follicles.id[f] : f;
      const double ang = v.random * w * cs.twistAngle * (2.0 * hashUniform(cs.seed ^ kTwistSalt, id) - 1.0);
      if (ang != 0) {
        T = glm::normalize(std::cos(ang) * T + std::sin(ang) * glm::cross(N, T));
        turned = true;
      }
    }
    if (turned) {
      F.tangent = T;
      F.binormal = glm::normalize(glm::cross(N, T));
      res.turned += here ? 1 : 0;
    }
    if (!here) continue;
    // `dynamic` neither turns nor raises: it bends the shaft at meshing time (chain.hpp), the root
    // following the packed frame.
    const bool rise =
        (v.lift > 0) || (v.direction > 0 && glm::dot(v.offset, N) > 0) || (v.aim > 0 && glm::dot(toControl, N) > 0);
    if (rise) {
      wantsRaise[i] = 1;
      if (std::isnan(fixedElevation[i])) needNatural = true;
    }
  }
  if (!needNatural && std::none_of(wantsRaise.begin(), wantsRaise.end(), [](uint8_t x) { return x != 0; })) return res;

  const std::vector<double>* natural = nullptr;
  if (needNatural) {
    coat::PackConstraints k = constraints;
    k.fixedElevation = fixedElevation;
    natural = &naturalPack(posed, coat, pack, k).elevation;
    PTERYLA_CHECK_EQ(natural->size(), n, "the natural pack must have one elevation per feather");
    res.naturalPacked = true;
  }

  // Pass 2: raises. Each behaviour moves the elevation toward its target angle by its weight, never down;
  // the start is the natural (or styled) elevation.
  for (size_t i = 0; i < n; ++i) {
    if (!wantsRaise[i]) continue;
    const uint32_t f = coat.follicle[i];
    const size_t c = static_cast<size_t>(binding.control[f]);
    const double w = binding.weight[f];
    const ControlSpec& cs = controls[c];
    const ControlValues& v = values[c];
    const coat::FeatherFrame& F = coat.frames[i];
    const glm::dvec3& N = F.normal;
    const double base = std::isnan(fixedElevation[i]) ? (*natural)[i] : fixedElevation[i];
    double e = base;
    auto raise = [&](double target, double weight) {
      target = std::min(target, cs.maxLift);
      if (weight > 0 && target > e) e += weight * (target - e);
    };
    raise(elevationOf(v.offset, N), v.direction * w);
    raise(elevationOf(position[c] - F.origin, N), v.aim * w);
    raise(cs.maxLift, v.lift * w);
    e = std::min(e, kHalfPi);
    if (e > base) {
      fixedElevation[i] = e;
      res.changed.push_back(static_cast<uint32_t>(i));
      ++res.raised;
      res.maxElevation = std::max(res.maxElevation, e);
    }
  }
  return res;
}

ControlSpec readControl(JsonReader& r) {
  ControlSpec c;
  c.name = r.string("name", "");
  c.at = r.vec3("at");
  c.radius = r.number("radius", 1e-12, 1e12);
  c.falloff = r.number("falloff", c.falloff, 0.0, 1.0);
  if (r.has("tracts")) {
    const Json& t = r.raw("tracts");
    if (!t.is_array()) r.fail("tracts", "expected an array of tract names");
    for (size_t k = 0; k < t.size(); ++k) {
      if (!t[k].is_string())
        throw Error("expected a tract name", r.file(), r.pathOf("tracts") + "[" + std::to_string(k) + "]");
      c.tracts.push_back(t[k].get<std::string>());
    }
  } else {
    r.allow("tracts");
  }
  c.seed = r.seed("seed", c.seed);
  c.twistAngle = r.number("twist_angle", c.twistAngle * 180 / kPi, 0.0, 180.0) * kPi / 180;
  c.maxLift = r.number("max_lift", c.maxLift * 180 / kPi, 0.0, 90.0) * kPi / 180;
  if (r.has("spring")) {
    JsonReader s = r.object("spring");
    c.springFrequency = s.number("frequency", c.springFrequency, 1e-6, 1e6);
    c.springDamping = s.number("damping", c.springDamping, 0.0, 100.0);
    c.chainSegments = static_cast<int>(s.integer("segments", c.chainSegments, 1, kMaxChainSegments));
    s.finish();
  } else {
    r.allow("spring");
  }
  Interpolation interp = Interpolation::Linear;
  parseInterpolation(r.oneOf("interpolation", "linear", {"linear", "smooth", "step"}), interp);
  struct Attr {
    const char* key;
    Track* track;
  };
  const Attr scalars[] = {
      {"lift", &c.lift}, {"aim", &c.aim}, {"direction", &c.direction}, {"random", &c.random}, {"dynamic", &c.dynamic}};
  // Constant values at the control level (a single key).
  for (const Attr& a : scalars) readAttribute(r, a.key, 0.0, 1.0, *a.track);
  if (r.has("offset"))
    c.offset.addKey(0.0, r.vec3("offset"));
  else
    r.allow("offset");
  std::vector<JsonReader> keys = r.objects("keys");
  for (auto& k : keys) {
    const double t = k.number("t", -1e12, 1e12);
    bool any = false;
    for (const Attr& a : scalars) {
      if (!k.has(a.key)) {
        k.allow(a.key);
        continue;
      }
      if (r.has(a.key)) k.fail(a.key, std::string("'") + a.key + "' is also given as a constant on the control");
      if (!a.track->addKey(t, glm::dvec3(k.number(a.key, 0.0, 1.0), 0, 0)))
        k.fail("t", std::string("two '") + a.key + "' keys at t = " + std::to_string(t));
      any = true;
    }
    if (k.has("offset")) {
      if (r.has("offset")) k.fail("offset", "'offset' is also given as a constant on the control");
      if (!c.offset.addKey(t, k.vec3("offset"))) k.fail("t", "two 'offset' keys at t = " + std::to_string(t));
      any = true;
    } else {
      k.allow("offset");
    }
    if (!any) k.fail("", "a key needs at least one of lift, aim, direction, random, dynamic, offset");
    k.finish();
  }
  for (const Attr& a : scalars) a.track->interpolation = interp;
  c.offset.interpolation = interp;
  r.finish();
  return c;
}

std::vector<ControlSpec> readControls(const Json& array, const std::string& file, const std::string& path) {
  if (!array.is_array()) throw Error("expected an array of controls", file, path);
  std::vector<ControlSpec> out;
  for (size_t i = 0; i < array.size(); ++i) {
    JsonReader r(array[i], file, path + "[" + std::to_string(i) + "]");
    out.push_back(readControl(r));
  }
  return out;
}

}  // namespace pteryla::moult
