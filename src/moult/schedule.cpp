// Feather replacement (moult), Streit 2003, 8.2: per-tract replacement sequences ordering the feathers
// by a distance d in [0,1] from the moult start in (u,v), and an overlapping window of width w moving
// along that order; each feather's position inside the window is its growth age (8.1).
#include "pteryla/moult/schedule.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "pteryla/core/error.hpp"
#include "pteryla/core/rng.hpp"

namespace pteryla::moult {

namespace {

struct SequenceName {
  MoultSequence s;
  const char* name;
};
constexpr SequenceName kSequences[] = {
    {MoultSequence::CentreOut, "centre_out"},
    {MoultSequence::BoundaryIn, "boundary_in"},
    {MoultSequence::CentreOutU, "centre_out_u"},
    {MoultSequence::BoundaryInU, "boundary_in_u"},
    {MoultSequence::CentreOutV, "centre_out_v"},
    {MoultSequence::BoundaryInV, "boundary_in_v"},
    {MoultSequence::IncreasingU, "increasing_u"},
    {MoultSequence::DecreasingU, "decreasing_u"},
    {MoultSequence::IncreasingV, "increasing_v"},
    {MoultSequence::DecreasingV, "decreasing_v"},
    {MoultSequence::Radial, "radial"},
    {MoultSequence::Random, "random"},
};

// Salts so the random order and the jitter are independent streams of one seed.
constexpr uint64_t kRandomOrderSalt = 0x6d6f756c745f6f72ull;
constexpr uint64_t kJitterSalt = 0x6d6f756c745f6a69ull;

void normaliseMax(std::vector<double>& d) {
  double hi = 0;
  for (double x : d) hi = std::max(hi, x);
  if (hi > 0)
    for (double& x : d) x /= hi;
}

void validate(const MoultOptions& o, const std::string& file, const std::string& where) {
  auto bad = [&](const std::string& what, const std::string& key) {
    throw Error(what, file, where.empty() ? key : where + "." + key);
  };
  if (!(o.duration > 0) || !std::isfinite(o.duration)) bad("duration must be a positive number", "duration");
  if (!std::isfinite(o.start)) bad("start must be finite", "start");
  if (!(o.window > 0 && o.window <= 1)) bad("window must be in (0, 1]", "window");
  if (!(o.gap >= 0 && o.gap < 1)) bad("gap must be in [0, 1)", "gap");
  if (!(o.random >= 0 && o.random <= 1)) bad("random must be in [0, 1]", "random");
  if (!(o.sizeExponent >= 0 && o.sizeExponent <= 8)) bad("size_exponent must be in [0, 8]", "size_exponent");
  if (!(o.boundarySlowdown >= 0 && o.boundarySlowdown <= 100))
    bad("boundary_slowdown must be in [0, 100]", "boundary_slowdown");
  if (o.center && !(std::isfinite(o.center->x) && std::isfinite(o.center->y))) bad("center must be finite", "center");
}

}  // namespace

const char* moultSequenceName(MoultSequence s) {
  for (const auto& e : kSequences)
    if (e.s == s) return e.name;
  return "?";
}

bool parseMoultSequence(const std::string& name, MoultSequence& out) {
  std::string n = name;
  if (n.rfind("center_", 0) == 0) n = "centre_" + n.substr(7);
  for (const auto& e : kSequences)
    if (n == e.name) {
      out = e.s;
      return true;
    }
  return false;
}

MoultPlan planMoult(const std::vector<glm::dvec2>& uv, const std::vector<double>& size, const std::vector<uint64_t>& id,
                    const MoultOptions& options) {
  validate(options, {}, {});
  PTERYLA_CHECK(uv.size() == size.size() && uv.size() == id.size(), "planMoult: uv, size and id differ in length");
  const size_t n = uv.size();
  MoultPlan plan;
  plan.options = options;
  plan.distance.assign(n, 0.0);
  plan.order.assign(n, 0.0);
  plan.window.assign(n, options.window);
  if (n == 0) {
    plan.sweep = 1 + options.window;
    return plan;
  }

  glm::dvec2 lo = uv[0], hi = uv[0];
  for (const auto& p : uv) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::dvec2 c = options.center ? *options.center : 0.5 * (lo + hi);
  // Half extents of the box around the centre, so the elliptic distance is <= 1 inside the tract.
  glm::dvec2 half = glm::max(c - lo, hi - c);
  half = glm::max(half, glm::dvec2(1e-12));

  // Elliptic distance from the centre: CentreOut/BoundaryIn order and the boundary slowdown.
  std::vector<double> elliptic(n);
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2 q = (uv[i] - c) / half;
    elliptic[i] = std::sqrt(q.x * q.x + q.y * q.y);
  }
  normaliseMax(elliptic);

  std::vector<double>& d = plan.distance;
  bool reverse = false;
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec2& p = uv[i];
    switch (options.sequence) {
      case MoultSequence::CentreOut:
        d[i] = elliptic[i];
        break;
      case MoultSequence::BoundaryIn:
        d[i] = elliptic[i];
        reverse = true;
        break;
      case MoultSequence::CentreOutU:
        d[i] = std::abs(p.x - c.x);
        break;
      case MoultSequence::BoundaryInU:
        d[i] = std::abs(p.x - c.x);
        reverse = true;
        break;
      case MoultSequence::CentreOutV:
        d[i] = std::abs(p.y - c.y);
        break;
      case MoultSequence::BoundaryInV:
        d[i] = std::abs(p.y - c.y);
        reverse = true;
        break;
      case MoultSequence::IncreasingU:
        d[i] = p.x - lo.x;
        break;
      case MoultSequence::DecreasingU:
        d[i] = hi.x - p.x;
        break;
      case MoultSequence::IncreasingV:
        d[i] = p.y - lo.y;
        break;
      case MoultSequence::DecreasingV:
        d[i] = hi.y - p.y;
        break;
      case MoultSequence::Radial:
        d[i] = glm::length(p - c);
        break;
      case MoultSequence::Random:
        d[i] = hashUniform(options.seed ^ kRandomOrderSalt, id[i]);
        break;
    }
  }
  normaliseMax(d);
  if (reverse)
    for (double& x : d) x = 1.0 - x;

  // Jittered sort key (8.2, Fig. 8.5 right: "randomness added to feather choice").
  std::vector<double> key(d);
  if (options.random > 0)
    for (size_t i = 0; i < n; ++i) key[i] += options.random * (hashUniform(options.seed ^ kJitterSalt, id[i]) - 0.5);

  if (options.pace == MoultPace::Order) {
    std::vector<uint32_t> idx(n);
    std::iota(idx.begin(), idx.end(), 0u);
    std::sort(idx.begin(), idx.end(), [&](uint32_t a, uint32_t b) {
      if (key[a] != key[b]) return key[a] < key[b];
      if (id[a] != id[b]) return id[a] < id[b];
      return a < b;
    });
    for (size_t r = 0; r < n; ++r) plan.order[idx[r]] = n > 1 ? double(r) / double(n - 1) : 0.0;
  } else {
    double kLo = key[0], kHi = key[0];
    for (double k : key) {
      kLo = std::min(kLo, k);
      kHi = std::max(kHi, k);
    }
    for (size_t i = 0; i < n; ++i) plan.order[i] = kHi > kLo ? (key[i] - kLo) / (kHi - kLo) : 0.0;
  }

  // Window per feather: larger feathers and feathers near the boundary grow slower (8.2).
  double median = 0;
  if (options.sizeExponent > 0) {
    std::vector<double> s(size);
    std::nth_element(s.begin(), s.begin() + s.size() / 2, s.end());
    median = s[s.size() / 2];
  }
  double wMax = 0;
  for (size_t i = 0; i < n; ++i) {
    double w = options.window;
    if (options.sizeExponent > 0 && median > 0 && size[i] > 0) w *= std::pow(size[i] / median, options.sizeExponent);
    w *= 1.0 + options.boundarySlowdown * elliptic[i];
    w = std::max(w, 1e-9);
    plan.window[i] = w;
    wMax = std::max(wMax, w);
  }
  plan.sweep = 1.0 + wMax;
  return plan;
}

double moultFront(const MoultPlan& plan, double t) {
  const MoultOptions& o = plan.options;
  const double tau = (t - o.start) / o.duration;
  return std::min(tau, 1.0) * plan.sweep;
}

MoultState moultStateAt(const MoultPlan& plan, size_t i, double t) {
  MoultState s;
  const double phi = (moultFront(plan, t) - plan.order[i]) / plan.window[i];
  const double gap = plan.options.gap;
  if (!(phi > 0)) {
    s.age = plan.options.oldAge;
    return s;  // Old
  }
  // The last feather of the order ends its window exactly when the front stops (phi = 1 up to rounding).
  if (phi >= 1 - 1e-9) {
    s.phase = MoultPhase::Renewed;
    const MoultOptions& o = plan.options;
    if (o.wearTime > 0) {
      // Mature since the front passed the end of its window: order + window = front = tau * sweep.
      const double renewedAt = o.start + o.duration * (plan.order[i] + plan.window[i]) / plan.sweep;
      s.age = 1.0 + std::clamp((t - renewedAt) / o.wearTime, 0.0, 1.0);
    }
    return s;
  }
  if (phi < gap) {
    s.phase = MoultPhase::Lost;
    s.present = false;
    s.age = 0;
    return s;
  }
  s.phase = MoultPhase::Growing;
  s.age = std::clamp((phi - gap) / (1.0 - gap), 0.0, 1.0);
  return s;
}

CoatMoultPlan planCoatMoult(const std::vector<coat::TractParameterization>& params, const coat::Follicles& follicles,
                            const coat::CoatFeathers& coat, const std::vector<std::optional<MoultOptions>>& perTract) {
  CoatMoultPlan out;
  out.tractPlan.assign(perTract.size(), -1);
  std::vector<std::vector<uint32_t>> byTract(perTract.size());
  for (size_t i = 0; i < coat.size(); ++i) {
    const uint32_t t = coat.tract[i];
    if (t < perTract.size() && perTract[t] && perTract[t]->enabled) byTract[t].push_back(static_cast<uint32_t>(i));
  }
  for (size_t t = 0; t < perTract.size(); ++t) {
    if (!perTract[t] || !perTract[t]->enabled) continue;
    if (t >= params.size()) throw Error("tract " + std::to_string(t) + " has no parameterization", {}, "moult");
    const coat::TractParameterization& p = params[t];
    const std::vector<uint32_t>& fs = byTract[t];
    std::vector<glm::dvec2> uv(fs.size());
    std::vector<double> size(fs.size());
    std::vector<uint64_t> id(fs.size());
    for (size_t k = 0; k < fs.size(); ++k) {
      const uint32_t f = coat.follicle[fs[k]];
      const auto it = std::lower_bound(p.follicles.begin(), p.follicles.end(), f);
      if (it == p.follicles.end() || *it != f)
        throw Error("feather " + std::to_string(fs[k]) + ": follicle " + std::to_string(f) +
                        " is not in its tract's parameterization",
                    {}, "moult");
      uv[k] = p.follicleUv[static_cast<size_t>(it - p.follicles.begin())];
      size[k] = coat.params[fs[k]].totalLength();
      id[k] = f < follicles.id.size() ? follicles.id[f] : f;
    }
    out.tractPlan[t] = static_cast<int32_t>(out.plans.size());
    out.plans.push_back(planMoult(uv, size, id, *perTract[t]));
    out.feathers.push_back(fs);
  }
  return out;
}

MoultStats applyMoult(const CoatMoultPlan& plan, double t, coat::CoatFeathers& coat) {
  MoultStats st;
  coat.age.assign(coat.size(), 1.0);
  coat.present.assign(coat.size(), 1);
  size_t moulting = 0;
  for (size_t p = 0; p < plan.plans.size(); ++p) {
    const MoultPlan& mp = plan.plans[p];
    const std::vector<uint32_t>& fs = plan.feathers[p];
    moulting += fs.size();
    for (size_t k = 0; k < fs.size(); ++k) {
      const MoultState s = moultStateAt(mp, k, t);
      coat.age[fs[k]] = s.age;
      coat.present[fs[k]] = s.present ? 1 : 0;
      switch (s.phase) {
        case MoultPhase::Old:
          ++st.old;
          break;
        case MoultPhase::Lost:
          ++st.lost;
          break;
        case MoultPhase::Growing:
          ++st.growing;
          break;
        case MoultPhase::Renewed:
          ++st.renewed;
          break;
      }
    }
  }
  st.old += coat.size() - moulting;
  return st;
}

MoultOptions readMoultOptions(JsonReader& r, const MoultOptions& defaults) {
  MoultOptions o = defaults;
  o.enabled = r.boolean("enabled", o.enabled);
  o.start = r.number("start", o.start, -1e12, 1e12);
  o.duration = r.number("duration", o.duration, 1e-12, 1e12);
  o.window = r.number("window", o.window, 1e-6, 1.0);
  if (r.has("sequence")) {
    const std::string name = r.string("sequence");
    if (!parseMoultSequence(name, o.sequence)) {
      std::string list;
      for (const auto& e : kSequences) list += (list.empty() ? "" : ", ") + std::string(e.name);
      r.fail("sequence", "unknown moult sequence '" + name + "' (one of " + list + ")");
    }
  } else {
    r.allow("sequence");
  }
  const std::string pace = r.oneOf("pace", o.pace == MoultPace::Order ? "order" : "distance", {"order", "distance"});
  o.pace = pace == "order" ? MoultPace::Order : MoultPace::Distance;
  o.gap = r.number("gap", o.gap, 0.0, 0.999);
  o.random = r.number("random", o.random, 0.0, 1.0);
  o.seed = r.seed("seed", o.seed);
  if (r.has("center"))
    o.center = r.vec2("center");
  else
    r.allow("center");
  o.sizeExponent = r.number("size_exponent", o.sizeExponent, 0.0, 8.0);
  o.boundarySlowdown = r.number("boundary_slowdown", o.boundarySlowdown, 0.0, 100.0);
  o.oldAge = r.number("old_age", o.oldAge, 1.0, 2.0);
  o.wearTime = r.number("wear_time", o.wearTime, 0.0, 1e12);
  r.finish();
  validate(o, r.file(), r.path());
  return o;
}

Json moultOptionsToJson(const MoultOptions& o) {
  Json j;
  j["enabled"] = o.enabled;
  j["start"] = o.start;
  j["duration"] = o.duration;
  j["window"] = o.window;
  j["sequence"] = moultSequenceName(o.sequence);
  j["pace"] = o.pace == MoultPace::Order ? "order" : "distance";
  j["gap"] = o.gap;
  j["random"] = o.random;
  j["seed"] = o.seed;
  if (o.center) j["center"] = Json::array({o.center->x, o.center->y});
  j["size_exponent"] = o.sizeExponent;
  j["boundary_slowdown"] = o.boundarySlowdown;
  j["old_age"] = o.oldAge;
  j["wear_time"] = o.wearTime;
  return j;
}

}  // namespace pteryla::moult
