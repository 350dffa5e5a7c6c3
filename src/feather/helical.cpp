// Zhang & Kanai, "Biological Modeling of Feather Based on Morphogenesis", 4.1 Helical Growth stage:
// follicle collar C(s), emitters and spawn loci (eqs. 1-3), barb elongation (Algorithm 1), longitudinal
// movement (eq. 4) and termination. Motion is integrated exactly through travel-time tables instead of
// Algorithm 1's explicit Euler steps, so the result does not depend on the animation time step.
// Also: Curve1D (monotone cubic Hermite, Fritsch & Carlson 1980) for the speed distributions.
#include "pteryla/feather/helical.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "pteryla/core/error.hpp"

namespace pteryla::feather {

namespace {

constexpr double kTwoPi = 2.0 * kPi;
constexpr int kTableIntervals = 2048;
constexpr size_t kMaxSamples = 20'000'000;  // total trail points of one growth
constexpr int kMaxBarbCount = 100'000;

// 4-point Gauss-Legendre on [0,1].
constexpr double kGaussX[4] = {0.0694318442029737, 0.3300094782075719, 0.6699905217924281, 0.9305681557970263};
constexpr double kGaussW[4] = {0.1739274225687269, 0.3260725774312731, 0.3260725774312731, 0.1739274225687269};

double wrap01(double s) {
  s -= std::floor(s);
  return s >= 1.0 ? 0.0 : s;
}

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

double hermite(double p0, double p1, double m0, double m1, double t) {
  const double t2 = t * t, t3 = t2 * t;
  return (2 * t3 - 3 * t2 + 1) * p0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * p1 + (t3 - t2) * m1;
}

template <class G>
detail::TravelTable buildTable(double span, G&& g) {
  detail::TravelTable t;
  t.span = span;
  t.h = span / kTableIntervals;
  t.value.resize(kTableIntervals + 1);
  t.slope.resize(kTableIntervals + 1);
  double acc = 0;
  for (int k = 0; k <= kTableIntervals; ++k) {
    const double s0 = k * t.h;
    t.value[k] = acc;
    t.slope[k] = g(s0);
    if (k < kTableIntervals) {
      double sum = 0;
      for (int q = 0; q < 4; ++q) sum += kGaussW[q] * g(s0 + kGaussX[q] * t.h);
      acc += sum * t.h;
    }
  }
  return t;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Curve1D

Curve1D::Curve1D(std::vector<glm::dvec2> keys) { setKeys(std::move(keys)); }

void Curve1D::setKeys(std::vector<glm::dvec2> keys) {
  for (size_t i = 0; i < keys.size(); ++i) {
    if (!std::isfinite(keys[i].x) || !std::isfinite(keys[i].y))
      throw Error("curve key is not finite", {}, "keys[" + std::to_string(i) + "]");
    if (i > 0 && !(keys[i].x > keys[i - 1].x))
      throw Error("curve keys must have strictly increasing x", {}, "keys[" + std::to_string(i) + "]");
  }
  keys_ = std::move(keys);
  const size_t n = keys_.size();
  slopes_.assign(n, 0.0);
  if (n < 2) return;
  std::vector<double> d(n - 1), h(n - 1);
  for (size_t i = 0; i + 1 < n; ++i) {
    h[i] = keys_[i + 1].x - keys_[i].x;
    d[i] = (keys_[i + 1].y - keys_[i].y) / h[i];
  }
  slopes_[0] = d[0];
  slopes_[n - 1] = d[n - 2];
  for (size_t i = 1; i + 1 < n; ++i) {
    if (d[i - 1] * d[i] <= 0) continue;  // local extremum or flat: zero slope keeps the curve in range
    // Fritsch-Butland weighted harmonic mean: slope/secant ratios stay in [0, 3], hence monotone.
    const double w1 = 2 * h[i] + h[i - 1], w2 = h[i] + 2 * h[i - 1];
    slopes_[i] = (w1 + w2) / (w1 / d[i - 1] + w2 / d[i]);
  }
}

double Curve1D::operator()(double x) const {
  const size_t n = keys_.size();
  if (n == 0) return 0.0;
  if (n == 1 || x <= keys_.front().x) return keys_.front().y;
  if (x >= keys_.back().x) return keys_.back().y;
  const auto it =
      std::upper_bound(keys_.begin(), keys_.end(), x, [](double v, const glm::dvec2& k) { return v < k.x; });
  const size_t i = static_cast<size_t>(it - keys_.begin()) - 1;
  const double h = keys_[i + 1].x - keys_[i].x;
  const double t = (x - keys_[i].x) / h;
  return hermite(keys_[i].y, keys_[i + 1].y, slopes_[i] * h, slopes_[i + 1] * h, t);
}

double Curve1D::minValue() const {
  double m = keys_.empty() ? 0.0 : keys_.front().y;
  for (const auto& k : keys_) m = std::min(m, k.y);
  return m;
}

double Curve1D::maxValue() const {
  double m = keys_.empty() ? 0.0 : keys_.front().y;
  for (const auto& k : keys_) m = std::max(m, k.y);
  return m;
}

Json curveToJson(const Curve1D& c) {
  Json a = Json::array();
  for (const auto& k : c.keys()) a.push_back({k.x, k.y});
  return a;
}

Curve1D curveFromJson(const Json& j, const std::string& file, const std::string& path) {
  if (!j.is_array() || j.empty()) throw Error("expected a non-empty array of [x, y] keys", file, path);
  std::vector<glm::dvec2> keys;
  keys.reserve(j.size());
  for (size_t i = 0; i < j.size(); ++i) {
    const std::string p = path + "[" + std::to_string(i) + "]";
    if (!j[i].is_array() || j[i].size() != 2) throw Error("expected a key [x, y]", file, p);
    keys.emplace_back(jsonNumber(j[i][0], file, p + "[0]"), jsonNumber(j[i][1], file, p + "[1]"));
    if (i > 0 && !(keys[i].x > keys[i - 1].x)) throw Error("curve keys must have strictly increasing x", file, p);
  }
  return Curve1D(std::move(keys));
}

// ---------------------------------------------------------------------------------------------------
// Collar

Collar::Collar(const CollarShape& shape, const std::string& file) : shape_(shape) {
  if (shape_.kind == CollarShape::Kind::Circle) {
    if (!std::isfinite(shape_.radius) || shape_.radius <= 0)
      throw Error("collar radius must be > 0", file, "helical.collar.radius");
    length_ = kTwoPi * shape_.radius;
    return;
  }
  const size_t n = shape_.points.size();
  if (n < 3 || n % 3 != 0)
    throw Error("a closed composite cubic Bezier collar needs 3K control points (K >= 1), got " + std::to_string(n),
                file, "helical.collar.points");
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(shape_.points[i].x) || !std::isfinite(shape_.points[i].y))
      throw Error("collar control point is not finite", file, "helical.collar.points[" + std::to_string(i) + "]");
  const size_t segs = n / 3;
  constexpr int kPerSeg = 128;
  const size_t m = segs * kPerSeg;
  tableU_.resize(m + 1);
  tableS_.resize(m + 1);
  tableD_.resize(m + 1);
  double acc = 0, area2 = 0;
  glm::dvec2 prev = evalU(0.0, nullptr);
  for (size_t k = 0; k <= m; ++k) {
    const double u0 = static_cast<double>(k) / kPerSeg;
    tableU_[k] = u0;
    tableS_[k] = acc;
    glm::dvec2 d0;
    evalU(u0, &d0);
    tableD_[k] = std::sqrt(d0.x * d0.x + d0.y * d0.y);  // ds/du, normalized below
    if (k == m) break;
    const double du = 1.0 / kPerSeg;
    double seg = 0;
    for (int q = 0; q < 4; ++q) {
      glm::dvec2 d;
      evalU(u0 + kGaussX[q] * du, &d);
      seg += kGaussW[q] * std::sqrt(d.x * d.x + d.y * d.y);
    }
    acc += seg * du;
    const glm::dvec2 next = evalU(u0 + du, nullptr);
    area2 += prev.x * next.y - next.x * prev.y;
    prev = next;
  }
  length_ = acc;
  if (!(length_ > 1e-12)) throw Error("collar has zero length", file, "helical.collar.points");
  if (!(area2 > 1e-9 * length_ * length_))
    throw Error("collar must be a counter-clockwise closed curve (signed area " + num(0.5 * area2) + ")", file,
                "helical.collar.points");
  for (auto& s : tableS_) s /= length_;
  for (auto& d : tableD_) d /= length_;
}

glm::dvec2 Collar::evalU(double u, glm::dvec2* d) const {
  const auto& P = shape_.points;
  const size_t segs = P.size() / 3;
  size_t k = static_cast<size_t>(std::max(0.0, std::floor(u)));
  if (k >= segs) k = segs - 1;
  const double t = std::clamp(u - static_cast<double>(k), 0.0, 1.0), a = 1 - t;
  const glm::dvec2 p0 = P[3 * k], p1 = P[3 * k + 1], p2 = P[3 * k + 2], p3 = P[(3 * k + 3) % P.size()];
  if (d) *d = 3 * a * a * (p1 - p0) + 6 * a * t * (p2 - p1) + 3 * t * t * (p3 - p2);
  return a * a * a * p0 + 3 * a * a * t * p1 + 3 * a * t * t * p2 + t * t * t * p3;
}

double Collar::uOfS(double s) const {
  const auto it = std::upper_bound(tableS_.begin(), tableS_.end(), s);
  size_t i = it == tableS_.begin() ? 0 : static_cast<size_t>(it - tableS_.begin()) - 1;
  if (i + 1 >= tableS_.size()) i = tableS_.size() - 2;
  const double ds = tableS_[i + 1] - tableS_[i];
  const double f = ds > 0 ? (s - tableS_[i]) / ds : 0.0;
  if (!(tableD_[i] > 1e-12 && tableD_[i + 1] > 1e-12))  // cusp: linear
    return tableU_[i] + f * (tableU_[i + 1] - tableU_[i]);
  // Cubic Hermite of the inverse map with the exact slopes du/ds = 1 / (ds/du).
  const double u = hermite(tableU_[i], tableU_[i + 1], ds / tableD_[i], ds / tableD_[i + 1], f);
  return std::clamp(u, tableU_[i], tableU_[i + 1]);
}

glm::dvec2 Collar::point(double s) const {
  s = wrap01(s);
  if (shape_.kind == CollarShape::Kind::Circle)
    return shape_.radius * glm::dvec2(std::cos(kTwoPi * s), std::sin(kTwoPi * s));
  return evalU(uOfS(s), nullptr);
}

glm::dvec2 Collar::tangent(double s) const {
  s = wrap01(s);
  if (shape_.kind == CollarShape::Kind::Circle) return {-std::sin(kTwoPi * s), std::cos(kTwoPi * s)};
  glm::dvec2 d;
  evalU(uOfS(s), &d);
  double len = std::sqrt(d.x * d.x + d.y * d.y);
  if (len < 1e-12) {  // cusp: central difference in s
    d = point(s + 1e-6) - point(s - 1e-6);
    len = std::sqrt(d.x * d.x + d.y * d.y);
  }
  return d / len;
}

glm::dvec2 Collar::outwardNormal(double s) const {
  const glm::dvec2 t = tangent(s);
  return {t.y, -t.x};  // counter-clockwise curve: the outside is on the right of the tangent
}

// ---------------------------------------------------------------------------------------------------
// Parameters

bool HelicalParams::operator==(const HelicalParams& o) const {
  return collar == o.collar && anteriorLeft == o.anteriorLeft && anteriorRight == o.anteriorRight &&
         posteriorLeft == o.posteriorLeft && posteriorRight == o.posteriorRight && frequency == o.frequency &&
         growthSpeed == o.growthSpeed && emitterSpeed == o.emitterSpeed && barbSpeed == o.barbSpeed &&
         syncSpeedToPolar == o.syncSpeedToPolar && barbCount == o.barbCount && spawnMode == o.spawnMode &&
         sampleDt == o.sampleDt && unfurlLeft == o.unfurlLeft && unfurlRight == o.unfurlRight && length == o.length &&
         fitCvs == o.fitCvs && keyBarbTolerance == o.keyBarbTolerance && maxKeyBarbs == o.maxKeyBarbs;
}

void validateHelical(const HelicalParams& p, const std::string& file) {
  auto bad = [&](const std::string& key, const std::string& what) { throw Error(what, file, "helical." + key); };
  auto finite = [&](double v, const std::string& key) {
    if (!std::isfinite(v)) bad(key, "expected a finite number");
  };
  finite(p.anteriorLeft, "anterior.left");
  finite(p.anteriorRight, "anterior.right");
  finite(p.posteriorLeft, "posterior.left");
  finite(p.posteriorRight, "posterior.right");
  if (!(0 < p.anteriorRight && p.anteriorRight < p.posteriorRight && p.posteriorRight < p.posteriorLeft &&
        p.posteriorLeft < p.anteriorLeft && p.anteriorLeft < 1))
    bad("posterior",
        "loci must satisfy 0 < anterior.right < posterior.right < posterior.left < anterior.left < 1 (got " +
            num(p.anteriorRight) + ", " + num(p.posteriorRight) + ", " + num(p.posteriorLeft) + ", " +
            num(p.anteriorLeft) + ")");
  if (!std::isfinite(p.frequency) || p.frequency <= 0) bad("frequency", "must be > 0");
  if (!std::isfinite(p.growthSpeed) || p.growthSpeed <= 0) bad("growthSpeed", "must be > 0");
  if (p.emitterSpeed.empty() || !(p.emitterSpeed.minValue() > 0))
    bad("emitterSpeed", "speed curve needs keys with values > 0");
  if (p.barbSpeed.empty() || !(p.barbSpeed.minValue() > 0)) bad("barbSpeed", "speed curve needs keys with values > 0");
  if (!std::isfinite(p.emitterSpeed.maxValue()) || !std::isfinite(p.barbSpeed.maxValue()))
    bad("barbSpeed", "speed curve is not finite");
  if (p.barbCount < 1 || p.barbCount > kMaxBarbCount)
    bad("barbCount", "must be in [1, " + std::to_string(kMaxBarbCount) + "]");
  if (!std::isfinite(p.sampleDt) || p.sampleDt <= 0) bad("sampleDt", "must be > 0");
  if (!(p.unfurlLeft >= 0 && p.unfurlLeft <= 1)) bad("unfurl.left", "must be in [0, 1]");
  if (!(p.unfurlRight >= 0 && p.unfurlRight <= 1)) bad("unfurl.right", "must be in [0, 1]");
  if (!std::isfinite(p.length) || p.length < 0) bad("length", "must be >= 0 (0 keeps the grown length)");
  if (p.fitCvs < 2 || p.fitCvs > 8) bad("fitCvs", "must be in [2, 8]");
  if (!std::isfinite(p.keyBarbTolerance) || p.keyBarbTolerance <= 0) bad("keyBarbTolerance", "must be > 0");
  if (p.maxKeyBarbs < 2 || p.maxKeyBarbs > 10000) bad("maxKeyBarbs", "must be in [2, 10000]");
  Collar collar(p.collar, file);  // shape checks
}

namespace {

CollarShape readCollar(JsonReader r) {
  CollarShape c;
  const std::string type = r.oneOf("type", "circle", {"circle", "bezier"});
  if (type == "circle") {
    c.kind = CollarShape::Kind::Circle;
    c.radius = r.number("radius", 1.5, 1e-9, 1e9);
  } else {
    c.kind = CollarShape::Kind::Bezier;
    const Json& pts = r.raw("points");
    if (!pts.is_array()) r.fail("points", "expected an array of [x, y] control points");
    for (size_t i = 0; i < pts.size(); ++i) {
      const std::string path = r.pathOf("points") + "[" + std::to_string(i) + "]";
      if (!pts[i].is_array() || pts[i].size() != 2) throw Error("expected a point [x, y]", r.file(), path);
      c.points.emplace_back(jsonNumber(pts[i][0], r.file(), path + "[0]"),
                            jsonNumber(pts[i][1], r.file(), path + "[1]"));
    }
  }
  r.finish();
  return c;
}

}  // namespace

HelicalParams readHelical(JsonReader& r) {
  HelicalParams p;
  if (r.has("collar")) p.collar = readCollar(r.object("collar"));
  if (r.has("anterior")) {
    JsonReader a = r.object("anterior");
    p.anteriorLeft = a.number("left", p.anteriorLeft, 0, 1);
    p.anteriorRight = a.number("right", p.anteriorRight, 0, 1);
    a.finish();
  }
  if (r.has("posterior")) {
    JsonReader a = r.object("posterior");
    if (a.has("polar")) {
      const double polar = a.number("polar", 0, 1);
      const double hw = a.number("halfWidth", 0.01, 0, 0.5);
      p.setPosteriorPolar(polar, hw);
    } else {
      p.posteriorLeft = a.number("left", p.posteriorLeft, 0, 1);
      p.posteriorRight = a.number("right", p.posteriorRight, 0, 1);
    }
    a.finish();
  }
  p.frequency = r.number("frequency", p.frequency, 1e-9, 1e9);
  p.growthSpeed = r.number("growthSpeed", p.growthSpeed, 1e-12, 1e12);
  if (r.has("emitterSpeed")) p.emitterSpeed = curveFromJson(r.raw("emitterSpeed"), r.file(), r.pathOf("emitterSpeed"));
  if (r.has("barbSpeed")) p.barbSpeed = curveFromJson(r.raw("barbSpeed"), r.file(), r.pathOf("barbSpeed"));
  p.syncSpeedToPolar = r.boolean("syncSpeedToPolar", p.syncSpeedToPolar);
  p.barbCount = static_cast<int>(r.integer("barbCount", p.barbCount, 1, kMaxBarbCount));
  p.spawnMode = r.oneOf("spawnMode", "time", {"time", "arcLength"}) == "time" ? SpawnMode::Time : SpawnMode::ArcLength;
  p.sampleDt = r.number("sampleDt", p.sampleDt, 1e-9, 1e9);
  if (r.has("unfurl")) {
    JsonReader u = r.object("unfurl");
    p.unfurlLeft = u.number("left", p.unfurlLeft, 0, 1);
    p.unfurlRight = u.number("right", p.unfurlRight, 0, 1);
    u.finish();
  }
  p.length = r.number("length", p.length, 0, 1e12);
  p.fitCvs = static_cast<int>(r.integer("fitCvs", p.fitCvs, 2, 8));
  p.keyBarbTolerance = r.number("keyBarbTolerance", p.keyBarbTolerance, 1e-9, 10);
  p.maxKeyBarbs = static_cast<int>(r.integer("maxKeyBarbs", p.maxKeyBarbs, 2, 10000));
  r.finish();
  validateHelical(p, r.file());
  return p;
}

Json helicalToJson(const HelicalParams& p) {
  Json j = Json::object();
  Json c = Json::object();
  if (p.collar.kind == CollarShape::Kind::Circle) {
    c["type"] = "circle";
    c["radius"] = p.collar.radius;
  } else {
    c["type"] = "bezier";
    Json pts = Json::array();
    for (const auto& q : p.collar.points) pts.push_back({q.x, q.y});
    c["points"] = pts;
  }
  j["collar"] = c;
  j["anterior"] = {{"left", p.anteriorLeft}, {"right", p.anteriorRight}};
  j["posterior"] = {{"left", p.posteriorLeft}, {"right", p.posteriorRight}};
  j["frequency"] = p.frequency;
  j["growthSpeed"] = p.growthSpeed;
  j["emitterSpeed"] = curveToJson(p.emitterSpeed);
  j["barbSpeed"] = curveToJson(p.barbSpeed);
  j["syncSpeedToPolar"] = p.syncSpeedToPolar;
  j["barbCount"] = p.barbCount;
  j["spawnMode"] = p.spawnMode == SpawnMode::Time ? "time" : "arcLength";
  j["sampleDt"] = p.sampleDt;
  j["unfurl"] = {{"left", p.unfurlLeft}, {"right", p.unfurlRight}};
  j["length"] = p.length;
  j["fitCvs"] = p.fitCvs;
  j["keyBarbTolerance"] = p.keyBarbTolerance;
  j["maxKeyBarbs"] = p.maxKeyBarbs;
  return j;
}

// ---------------------------------------------------------------------------------------------------
// Travel-time tables

namespace detail {

double TravelTable::operator()(double sigma) const {
  if (sigma <= 0) return 0.0;
  if (sigma >= span) return total();
  int k = static_cast<int>(sigma / h);
  k = std::clamp(k, 0, static_cast<int>(value.size()) - 2);
  const double t = (sigma - k * h) / h;
  return hermite(value[k], value[k + 1], slope[k] * h, slope[k + 1] * h, t);
}

double TravelTable::inverse(double f) const {
  if (f <= 0) return 0.0;
  if (f >= total()) return span;
  const auto it = std::upper_bound(value.begin(), value.end(), f);
  size_t k = static_cast<size_t>(it - value.begin()) - 1;
  if (k + 1 >= value.size()) k = value.size() - 2;
  const double df = value[k + 1] - value[k];
  const double t = (f - value[k]) / df;
  const double s = hermite(k * h, (k + 1) * h, df / slope[k], df / slope[k + 1], t);
  return std::clamp(s, k * h, (k + 1) * h);
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------------
// Growth schedule

double HelicalGrowth::speedArg(double s) const {
  if (!p_.syncSpeedToPolar) return s;
  const double polar = p_.posteriorPolar();
  return s < polar ? 0.5 * s / polar : 0.5 + 0.5 * (s - polar) / (1.0 - polar);
}

double HelicalGrowth::span(int vane) const {
  return vane == 0 ? p_.anteriorLeft - p_.posteriorLeft : p_.posteriorRight - p_.anteriorRight;
}
double HelicalGrowth::locusOf(int vane, double sigma) const {
  return vane == 0 ? p_.anteriorLeft - sigma : p_.anteriorRight + sigma;
}
double HelicalGrowth::sigmaOf(int vane, double s) const {
  return vane == 0 ? p_.anteriorLeft - s : s - p_.anteriorRight;
}

HelicalGrowth::HelicalGrowth(const HelicalParams& p, const std::string& file) : p_(p), collar_(p.collar, file) {
  validateHelical(p_, file);
  const double L = collar_.length(), v = p_.growthSpeed;
  for (int vane = 0; vane < 2; ++vane) {
    const double D = span(vane);
    emit_[vane] = buildTable(D, [&](double sg) { return 1.0 / p_.emitterSpeed(speedArg(locusOf(vane, sg))); });
    barb_[vane] = buildTable(D, [&](double sg) { return 1.0 / p_.barbSpeed(speedArg(locusOf(vane, sg))); });
    if (p_.spawnMode == SpawnMode::ArcLength)
      trail_[vane] = buildTable(D, [&](double sg) {
        const double ve = p_.emitterSpeed(speedArg(locusOf(vane, sg)));
        return std::sqrt(L * L + v * v / (ve * ve));
      });
  }

  // Termination: the N-th completion over both vanes. Completion times increase along each vane (later
  // spawns start further from I_A until the emitter clamps, then all travel the same distance).
  HelicalBarb next[2] = {spawn(0, 1), spawn(1, 1)};
  uint32_t idx[2] = {1, 1};
  for (int n = 0; n < p_.barbCount; ++n) {
    const int v = next[0].completionTime <= next[1].completionTime ? 0 : 1;
    endTime_ = next[v].completionTime;
    next[v] = spawn(v, ++idx[v]);
  }
  size_t samples = 0;
  for (int vane = 0; vane < 2; ++vane) {
    vaneBegin_[vane] = barbs_.size();
    for (uint32_t i = 1;; ++i) {
      HelicalBarb b = spawn(vane, i);
      if (b.spawnTime > endTime_) break;
      if (b.completionTime <= endTime_) ++completed_;
      barbs_.push_back(b);
      samples += maxStampCount(b);
      if (samples > kMaxSamples)
        throw Error("helical growth would record more than " + std::to_string(kMaxSamples) +
                        " barb points; raise sampleDt or the speeds, or lower barbCount",
                    file, "helical.sampleDt");
    }
  }
  vaneBegin_[2] = barbs_.size();
}

HelicalBarb HelicalGrowth::spawn(int vane, uint32_t i) const {
  HelicalBarb b;
  b.vane = static_cast<uint8_t>(vane);
  b.index = i;
  const double D = span(vane);
  const double clamp = emit_[vane].total();
  double sigma;
  if (p_.spawnMode == SpawnMode::Time) {
    b.spawnTime = i / p_.frequency;
    sigma = emit_[vane].inverse(b.spawnTime);
    b.tipRegion = b.spawnTime < clamp;
  } else {
    const double d = p_.growthSpeed / p_.frequency;  // trail length between spawns
    const double ell = i * d, trail = trail_[vane].total();
    if (ell < trail) {
      sigma = trail_[vane].inverse(ell);
      b.spawnTime = emit_[vane](sigma);
      b.tipRegion = true;
    } else {
      sigma = D;
      b.spawnTime = clamp + (ell - trail) / p_.growthSpeed;
    }
  }
  if (!b.tipRegion) sigma = D;
  b.spawnLocus = locusOf(vane, sigma);
  b.completionTime = b.spawnTime + barb_[vane](sigma);
  return b;
}

double HelicalGrowth::clampTime(int vane) const { return emit_[vane].total(); }

double HelicalGrowth::emitterLocus(int vane, double t) const {
  return locusOf(vane, t >= emit_[vane].total() ? span(vane) : emit_[vane].inverse(t));
}

double HelicalGrowth::barbLocus(const HelicalBarb& b, double tau) const {
  if (tau <= 0) return b.spawnLocus;
  const auto& tb = barb_[b.vane];
  const double sigma0 = sigmaOf(b.vane, b.spawnLocus);
  return locusOf(b.vane, tb.inverse(tb(sigma0) - tau));
}

void HelicalGrowth::barbStamps(const HelicalBarb& b, double t, std::vector<double>& stamps) const {
  stamps.clear();
  const double end = std::min(t, b.completionTime);
  if (end < b.spawnTime) return;
  const double h = p_.sampleDt, eps = 1e-9 * h;
  for (uint64_t k = 0;; ++k) {
    const double s = b.spawnTime + static_cast<double>(k) * h;
    if (!(s < end - eps)) break;
    stamps.push_back(s);
  }
  stamps.push_back(end);
}

size_t HelicalGrowth::maxStampCount(const HelicalBarb& b) const {
  const double T = b.completionTime - b.spawnTime, h = p_.sampleDt;
  size_t k = static_cast<size_t>(std::max(0.0, std::ceil(T / h))) + 2;  // upper bound, then exact
  const double eps = 1e-9 * h;
  while (k > 0 && !(b.spawnTime + static_cast<double>(k - 1) * h < b.completionTime - eps)) --k;
  return k + 1;
}

glm::dvec3 HelicalGrowth::folliclePoint(double s, double stamp, double t) const {
  const glm::dvec2 c = collar_.point(s);
  return {c.x, p_.growthSpeed * (t - stamp), c.y};
}

// ---------------------------------------------------------------------------------------------------
// Snapshots and stepping

HelicalSnapshot helicalSnapshot(const HelicalGrowth& g, double t) {
  t = std::clamp(t, 0.0, g.endTime());
  HelicalSnapshot snap;
  snap.time = t;
  for (int v = 0; v < 2; ++v) {
    snap.emitterLocus[v] = g.emitterLocus(v, t);
    snap.emitterPoint[v] = g.folliclePoint(snap.emitterLocus[v], t, t);
  }
  std::vector<double> stamps;
  const auto& barbs = g.barbs();
  for (uint32_t i = 0; i < barbs.size(); ++i) {
    const HelicalBarb& b = barbs[i];
    if (b.spawnTime > t) continue;
    g.barbStamps(b, t, stamps);
    snap.barb.push_back(i);
    snap.offset.push_back(static_cast<uint32_t>(snap.points.size()));
    snap.complete.push_back(b.completionTime <= t ? 1 : 0);
    for (double s : stamps) snap.points.push_back(g.folliclePoint(g.barbLocus(b, s - b.spawnTime), s, t));
  }
  snap.offset.push_back(static_cast<uint32_t>(snap.points.size()));
  return snap;
}

HelicalState::HelicalState(const HelicalGrowth& g) : g_(&g) { reset(); }

void HelicalState::reset() {
  t_ = 0;
  nextSpawn_[0] = static_cast<uint32_t>(g_->vaneBegin(0));
  nextSpawn_[1] = static_cast<uint32_t>(g_->vaneBegin(1));
  barbs_.clear();
  loci_.clear();
  stamps_.clear();
}

void HelicalState::step(double dt) {
  PTERYLA_CHECK(dt >= 0 && std::isfinite(dt), "HelicalState::step needs a finite dt >= 0");
  const double tEnd = g_->endTime();
  const double t = std::min(t_ + dt, tEnd);
  const auto& all = g_->barbs();
  for (int v = 0; v < 2; ++v) {
    while (nextSpawn_[v] < g_->vaneBegin(v + 1) && all[nextSpawn_[v]].spawnTime <= t) {
      const HelicalBarb& b = all[nextSpawn_[v]];
      const auto cap = static_cast<uint32_t>(g_->maxStampCount(b));
      barbs_.push_back({nextSpawn_[v], static_cast<uint32_t>(loci_.size()), cap, 0});
      loci_.resize(loci_.size() + cap);
      stamps_.resize(stamps_.size() + cap);
      ++nextSpawn_[v];
    }
  }
  const double h = g_->params().sampleDt, eps = 1e-9 * h;
  for (Active& a : barbs_) {
    if (a.filled == a.capacity) continue;
    const HelicalBarb& b = all[a.barb];
    const double end = std::min(t, b.completionTime);
    // Grid samples strictly before the current end, then the completion point itself.
    while (a.filled + 1 < a.capacity) {
      const double s = b.spawnTime + static_cast<double>(a.filled) * h;
      if (!(s < end - eps)) break;
      stamps_[a.first + a.filled] = s;
      loci_[a.first + a.filled] = g_->barbLocus(b, s - b.spawnTime);
      ++a.filled;
    }
    if (b.completionTime <= t && a.filled + 1 == a.capacity) {
      stamps_[a.first + a.filled] = b.completionTime;
      loci_[a.first + a.filled] = g_->barbLocus(b, b.completionTime - b.spawnTime);
      ++a.filled;
    }
  }
  t_ = t;
}

HelicalSnapshot HelicalState::snapshot() const {
  HelicalSnapshot snap;
  snap.time = t_;
  for (int v = 0; v < 2; ++v) {
    snap.emitterLocus[v] = g_->emitterLocus(v, t_);
    snap.emitterPoint[v] = g_->folliclePoint(snap.emitterLocus[v], t_, t_);
  }
  const auto& all = g_->barbs();
  // Same order as helicalSnapshot: by index into g.barbs() (left vane, then right).
  std::vector<const Active*> order(barbs_.size());
  for (size_t i = 0; i < barbs_.size(); ++i) order[i] = &barbs_[i];
  std::sort(order.begin(), order.end(), [](const Active* a, const Active* b) { return a->barb < b->barb; });
  for (const Active* a : order) {
    const HelicalBarb& b = all[a->barb];
    snap.barb.push_back(a->barb);
    snap.offset.push_back(static_cast<uint32_t>(snap.points.size()));
    const bool done = a->filled == a->capacity;
    snap.complete.push_back(done ? 1 : 0);
    for (uint32_t k = 0; k < a->filled; ++k)
      snap.points.push_back(g_->folliclePoint(loci_[a->first + k], stamps_[a->first + k], t_));
    if (!done) snap.points.push_back(g_->folliclePoint(g_->barbLocus(b, t_ - b.spawnTime), t_, t_));
  }
  snap.offset.push_back(static_cast<uint32_t>(snap.points.size()));
  return snap;
}

}  // namespace pteryla::feather
