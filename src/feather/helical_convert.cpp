// Zhang & Kanai, "Biological Modeling of Feather Based on Morphogenesis", 4.1-4.2 output handed to the
// Streit 2003 feather model (5.2.2 key barbs, 5.2.3 silhouette): unfurled barbs are fitted with Bezier
// curves, a subset becomes key barbs, and the feather file's "helical" generator derives the Streit
// parameters at load time so every consumer of FeatherParams works unchanged.
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/bezier.hpp"
#include "pteryla/feather/helical.hpp"

namespace pteryla::feather {

namespace {

// All Bernstein basis values B_{i,n}(u), i = 0..n, into b (size n + 1).
void bernsteinAll(int n, double u, double* b) {
  // Pascal-like recurrence: B_{i,k} = (1-u) B_{i,k-1} + u B_{i-1,k-1}.
  b[0] = 1.0;
  const double a = 1.0 - u;
  for (int k = 1; k <= n; ++k) {
    double saved = 0.0;
    for (int i = 0; i < k; ++i) {
      const double t = b[i];
      b[i] = saved + a * t;
      saved = u * t;
    }
    b[k] = saved;
  }
}

// Solves the small dense system A x = b (row-major m x m) in place; false when singular.
bool solveSmall(std::vector<double>& A, std::vector<glm::dvec3>& b, int m) {
  for (int c = 0; c < m; ++c) {
    int piv = c;
    for (int r = c + 1; r < m; ++r)
      if (std::abs(A[r * m + c]) > std::abs(A[piv * m + c])) piv = r;
    if (std::abs(A[piv * m + c]) < 1e-14) return false;
    if (piv != c) {
      for (int k = 0; k < m; ++k) std::swap(A[c * m + k], A[piv * m + k]);
      std::swap(b[c], b[piv]);
    }
    for (int r = c + 1; r < m; ++r) {
      const double f = A[r * m + c] / A[c * m + c];
      for (int k = c; k < m; ++k) A[r * m + k] -= f * A[c * m + k];
      b[r] -= f * b[c];
    }
  }
  for (int c = m - 1; c >= 0; --c) {
    glm::dvec3 x = b[c];
    for (int k = c + 1; k < m; ++k) x -= A[c * m + k] * b[k];
    b[c] = x / A[c * m + c];
  }
  return true;
}

glm::dvec3 polylineAt(const glm::dvec3* pts, size_t n, const std::vector<double>& u, double t) {
  const auto it = std::upper_bound(u.begin(), u.end(), t);
  size_t i = it == u.begin() ? 0 : static_cast<size_t>(it - u.begin()) - 1;
  if (i + 1 >= n) return pts[n - 1];
  const double du = u[i + 1] - u[i];
  const double f = du > 0 ? (t - u[i]) / du : 0.0;
  return pts[i] + f * (pts[i + 1] - pts[i]);
}

// Key barb selection (Douglas-Peucker over the barb sequence): keep the first and last barb, then
// repeatedly add the barb worst reproduced by linear interpolation (eq. 5.1) of its neighbouring keys.
std::vector<size_t> selectKeys(const std::vector<double>& rp, const std::vector<std::vector<glm::dvec3>>& cvs,
                               double tol, int maxKeys) {
  const size_t n = rp.size();
  std::vector<size_t> keys;
  if (n == 0) return keys;
  keys = {0};
  if (n > 1) keys.push_back(n - 1);
  while (static_cast<int>(keys.size()) < maxKeys) {
    double worst = tol;
    size_t worstIdx = n;
    for (size_t k = 0; k + 1 < keys.size(); ++k) {
      const size_t a = keys[k], b = keys[k + 1];
      for (size_t i = a + 1; i < b; ++i) {
        const double t = rp[b] > rp[a] ? (rp[i] - rp[a]) / (rp[b] - rp[a]) : 0.0;
        double err = 0;
        for (size_t c = 0; c < cvs[i].size(); ++c)
          err = std::max(err, glm::length((1 - t) * cvs[a][c] + t * cvs[b][c] - cvs[i][c]));
        if (err > worst) {
          worst = err;
          worstIdx = i;
        }
      }
    }
    if (worstIdx == n) break;
    keys.insert(std::upper_bound(keys.begin(), keys.end(), worstIdx), worstIdx);
  }
  return keys;
}

}  // namespace

std::vector<glm::dvec3> fitBezier(const glm::dvec3* ptsIn, size_t nIn, int cvCount, double* maxError) {
  PTERYLA_CHECK(cvCount >= 2 && cvCount <= 16 && nIn >= 1, "fitBezier needs 2..16 control vertices and a point");
  // Dense trails are thinned to kMaxFitPoints evenly spaced samples (end points kept): a cubic barb is
  // fully determined long before that, and the fit stays cheap for thousands of barbs.
  constexpr size_t kMaxFitPoints = 64;
  constexpr int kFitIterations = 64;  // max solve + reparameterize rounds (Hoschek's parameter correction)
  std::vector<glm::dvec3> thin;
  const glm::dvec3* pts = ptsIn;
  size_t n = nIn;
  if (nIn > kMaxFitPoints) {
    thin.resize(kMaxFitPoints);
    for (size_t i = 0; i < kMaxFitPoints; ++i)
      thin[i] = ptsIn[(i * (nIn - 1) + (kMaxFitPoints - 1) / 2) / (kMaxFitPoints - 1)];
    thin.front() = ptsIn[0];
    thin.back() = ptsIn[nIn - 1];
    pts = thin.data();
    n = kMaxFitPoints;
  }
  const int m = cvCount, deg = m - 1;
  std::vector<glm::dvec3> cvs(static_cast<size_t>(m));
  // Chord-length parameters.
  std::vector<double> u(n, 0.0);
  for (size_t i = 1; i < n; ++i) u[i] = u[i - 1] + glm::length(pts[i] - pts[i - 1]);
  const double total = n > 1 ? u[n - 1] : 0.0;
  if (total > 0)
    for (double& x : u) x /= total;
  cvs.front() = pts[0];
  cvs.back() = pts[n - 1];
  // Start from points on the polyline (also the answer when there are too few points to fit).
  for (int i = 1; i < deg; ++i) cvs[i] = polylineAt(pts, n, u, static_cast<double>(i) / deg);

  const int inner = m - 2;
  double B[16];
  glm::dvec3 d1[16], d2[16];
  if (inner > 0 && n > static_cast<size_t>(m) && total > 0) {
    std::vector<double> A(static_cast<size_t>(inner * inner));
    std::vector<glm::dvec3> rhs(static_cast<size_t>(inner));
    for (int iter = 0; iter < kFitIterations; ++iter) {
      std::fill(A.begin(), A.end(), 0.0);
      std::fill(rhs.begin(), rhs.end(), glm::dvec3(0.0));
      for (size_t k = 0; k < n; ++k) {
        bernsteinAll(deg, u[k], B);
        const glm::dvec3 r = pts[k] - B[0] * cvs.front() - B[deg] * cvs.back();
        for (int i = 0; i < inner; ++i) {
          rhs[i] += B[i + 1] * r;
          for (int j = 0; j < inner; ++j) A[i * inner + j] += B[i + 1] * B[j + 1];
        }
      }
      if (!solveSmall(A, rhs, inner)) break;
      for (int i = 0; i < inner; ++i) cvs[i + 1] = rhs[i];
      if (iter + 1 == kFitIterations) break;
      // Reparameterize: project every interior point onto the curve (Newton on (C(u) - p) . C'(u)).
      double moved = 0;
      for (int i = 0; i + 1 < m; ++i) d1[i] = static_cast<double>(deg) * (cvs[i + 1] - cvs[i]);
      for (int i = 0; i + 2 < m; ++i) d2[i] = static_cast<double>(deg - 1) * (d1[i + 1] - d1[i]);
      for (size_t k = 1; k + 1 < n; ++k) {
        double t = u[k];
        for (int it = 0; it < 2; ++it) {
          const glm::dvec3 d = bezierPoint(cvs.data(), cvs.size(), t) - pts[k];
          const glm::dvec3 c1 = bezierPoint(d1, static_cast<size_t>(deg), t);
          const glm::dvec3 c2 = deg > 1 ? bezierPoint(d2, static_cast<size_t>(deg - 1), t) : glm::dvec3(0.0);
          const double f = glm::dot(d, c1);
          double fp = glm::dot(c1, c1) + glm::dot(d, c2);
          if (!(fp > 0)) fp = glm::dot(c1, c1);  // Gauss-Newton when Newton would go uphill
          if (!(fp > 0)) break;
          t = std::clamp(t - f / fp, 0.0, 1.0);
        }
        moved = std::max(moved, std::abs(t - u[k]));
        u[k] = t;
      }
      if (moved < 1e-10) break;
    }
  }
  if (maxError) {
    double e = 0;
    for (size_t k = 0; k < n; ++k) {
      // Distance to the curve: a few projection steps from the fitted parameter.
      double t = u[k];
      for (int it = 0; it < 3; ++it) {
        const glm::dvec3 d = bezierPoint(cvs.data(), cvs.size(), t) - pts[k];
        const glm::dvec3 dt = bezierDerivative(cvs.data(), cvs.size(), t);
        const double tt = glm::dot(dt, dt);
        if (!(tt > 0)) break;
        t = std::clamp(t - glm::dot(d, dt) / tt, 0.0, 1.0);
      }
      e = std::max(e, glm::length(bezierPoint(cvs.data(), cvs.size(), t) - pts[k]));
    }
    *maxError = e;
  }
  return cvs;
}

HelicalConversion convertHelical(const HelicalGrowth& g, const HelicalFeather& f, double rachisLength) {
  if (!(f.length > 0)) throw Error("helical feather has zero length", {}, "helical");
  const double target = g.params().length > 0 ? g.params().length : rachisLength;
  return convertHelicalScaled(g, f, target > 0 ? target / f.length : 1.0);
}

HelicalConversion convertHelicalScaled(const HelicalGrowth& g, const HelicalFeather& f, double scale) {
  const HelicalParams& hp = g.params();
  HelicalConversion out;
  FeatherParams& p = out.feather;
  if (!(f.length >= 0) || !(scale > 0) || !std::isfinite(scale))
    throw Error("helical feather needs a length >= 0 and a positive scale", {}, "helical");
  out.scale = scale;
  p.generator = "streit";
  p.rachisLength = f.length * scale;
  p.calamusLength = 0.1 * p.rachisLength;
  p.rachisWidth = f.rachisWidth * scale;
  p.rachisLateralCurvature = 0;
  p.rachisVentralDorsalCurvature = 0;
  p.silhouette = Silhouette();

  // Barbs in the barb-local unit frame (away from the rachis, toward the tip, dorsal; chord 1). Key
  // barbs are chosen on arc-length resamplings of the trails; only the chosen ones are fitted.
  constexpr int kShapeSamples = 16;
  std::vector<double> rp, chord, gapRp, gap;
  std::vector<const HelicalFeatherBarb*> src;
  std::vector<std::vector<glm::dvec3>> shape;
  std::vector<glm::dvec3> unitTrail;
  for (int vane = 0; vane < 2; ++vane) {
    const double side = vane == 0 ? 1.0 : -1.0;
    auto toUnit = [&](const HelicalFeatherBarb& b, double c, std::vector<glm::dvec3>& outPts) {
      outPts.resize(b.count);
      const glm::dvec3 p0 = f.points[b.first];
      for (uint32_t k = 0; k < b.count; ++k) {
        const glm::dvec3 d = (f.points[b.first + k] - p0) / c;
        outPts[k] = {side * d.y, d.x, d.z};
      }
    };
    rp.clear();
    chord.clear();
    src.clear();
    shape.clear();
    double prevAttach = -1;
    for (const HelicalFeatherBarb& b : f.barbs) {
      if (b.vane != vane || b.count < 2) continue;
      const double c = glm::length(f.points[b.first + b.count - 1] - f.points[b.first]);
      if (!(c > 1e-9 * f.length)) continue;
      toUnit(b, c, unitTrail);
      std::vector<double> acc(unitTrail.size(), 0.0);
      for (size_t k = 1; k < unitTrail.size(); ++k) acc[k] = acc[k - 1] + glm::length(unitTrail[k] - unitTrail[k - 1]);
      if (acc.back() > 0)
        for (double& a : acc) a /= acc.back();
      std::vector<glm::dvec3> q(kShapeSamples);
      for (int j = 0; j < kShapeSamples; ++j)
        q[j] = polylineAt(unitTrail.data(), unitTrail.size(), acc, static_cast<double>(j) / (kShapeSamples - 1));
      rp.push_back(std::clamp(b.attach / f.length, 0.0, 1.0));
      chord.push_back(c * scale);
      src.push_back(&b);
      shape.push_back(std::move(q));
      if (prevAttach >= 0) {
        gapRp.push_back(0.5 * (b.attach + prevAttach) / f.length);
        gap.push_back((b.attach - prevAttach) * scale);
      }
      prevAttach = b.attach;
    }
    out.barbs[vane] = static_cast<int>(rp.size());
    VaneParams& vp = p.vane(vane);
    vp.baseAngle = vp.tipAngle = 0.5 * kPi;
    vp.keyBarbs.clear();
    LengthProfile& prof = vane == 0 ? p.silhouette.left : p.silhouette.right;
    if (rp.empty()) {
      // No completed barb on this vane: a bare rachis side.
      prof.points = {{0.0, 0.0}, {1.0, 0.0}};
      vp.keyBarbs = {{0.0, defaultPennaceousBarb()}, {1.0, defaultPennaceousBarb()}};
      continue;
    }
    for (size_t i = 0; i < rp.size(); ++i) prof.points.emplace_back(rp[i], chord[i]);
    if (rp.back() < 1.0) prof.points.emplace_back(1.0, 0.0);  // the vane closes at the rachis tip
    const std::vector<size_t> keys = selectKeys(rp, shape, hp.keyBarbTolerance, std::max(2, hp.maxKeyBarbs - 2));
    std::vector<std::vector<glm::dvec3>> fitted;
    for (size_t k : keys) {
      const HelicalFeatherBarb& b = *src[k];
      toUnit(b, chord[k] / scale, unitTrail);
      double err = 0;
      fitted.push_back(fitBezier(unitTrail.data(), unitTrail.size(), hp.fitCvs, &err));
      out.maxFitError = std::max(out.maxFitError, err * chord[k] / scale / f.length);
    }
    // Explicit key barbs at rp 0 and 1 so the Streit defaults (5.2.2) never enter a helical vane.
    if (rp[keys.front()] > 0.0) vp.keyBarbs.push_back({0.0, fitted.front()});
    for (size_t i = 0; i < keys.size(); ++i) vp.keyBarbs.push_back({rp[keys[i]], fitted[i]});
    if (rp[keys.back()] < 1.0) vp.keyBarbs.push_back({1.0, fitted.back()});
    out.keyBarbs[vane] = static_cast<int>(vp.keyBarbs.size());
  }

  // Spacing: least-squares line through the attachment gaps of both vanes.
  if (gap.size() >= 2) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0, lo = gap[0];
    const double n = static_cast<double>(gap.size());
    for (size_t i = 0; i < gap.size(); ++i) {
      sx += gapRp[i];
      sy += gap[i];
      sxx += gapRp[i] * gapRp[i];
      sxy += gapRp[i] * gap[i];
      lo = std::min(lo, gap[i]);
    }
    const double den = n * sxx - sx * sx;
    const double slope = std::abs(den) > 1e-300 ? (n * sxy - sx * sy) / den : 0.0;
    const double icpt = (sy - slope * sx) / n;
    const double floor = std::max(0.5 * lo, p.rachisLength * 1e-4);
    p.spacingBase = std::max(icpt, floor);
    p.spacingTip = std::max(icpt + slope, floor);
  } else {
    p.spacingBase = p.spacingTip = p.rachisLength / 8;
  }
  return out;
}

FeatherParams helicalToFeatherParams(const HelicalParams& p, const std::string& file) {
  const HelicalGrowth g(p, file);
  const HelicalFeather f = helicalFeather(g);
  FeatherParams fp = convertHelical(g, f).feather;
  fp.sourceFile = file;
  return fp;
}

void adoptConvertedBarbs(FeatherParams& p, HelicalConversion&& c) {
  p.rachisLength = c.feather.rachisLength;
  p.barbLength = 0;
  p.silhouette = std::move(c.feather.silhouette);
  p.left = std::move(c.feather.left);
  p.right = std::move(c.feather.right);
  p.spacingBase = c.feather.spacingBase;
  p.spacingTip = c.feather.spacingTip;
}

void applyHelical(FeatherParams& p, const HelicalParams& hp) {
  const HelicalGrowth g(hp, p.sourceFile);
  const HelicalFeather f = helicalFeather(g);
  adoptConvertedBarbs(p, convertHelical(g, f, p.rachisLength));
}

void applyHelical(FeatherParams& p) {
  if (!p.generatorParams.is_object()) throw Error("helical feather has no helical parameters", p.sourceFile, "helical");
  JsonReader r(p.generatorParams, p.sourceFile, "helical");
  applyHelical(p, readHelical(r));
}

FeatherGenerator helicalFeatherGenerator() {
  FeatherGenerator gen;
  gen.read = [](JsonReader& r, FeatherParams& p) {
    JsonReader h = r.object("helical");
    const HelicalParams hp = readHelical(h);
    p.generatorParams = helicalToJson(hp);
    const std::string saved = p.sourceFile;
    p.sourceFile = r.file();
    applyHelical(p, hp);
    p.sourceFile = saved;
  };
  gen.write = [](const FeatherParams& p, Json& j) { j["helical"] = p.generatorParams; };
  gen.grow = growHelical;
  return gen;
}

}  // namespace pteryla::feather
