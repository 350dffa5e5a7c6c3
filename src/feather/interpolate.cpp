// Feather-type interpolation, Streit 2003 5.2.4: tip inflation of key barb sets, base-to-tip matching by
// rachis position, the bilinear construction of new key barbs, linear blending of every scalar
// parameter; generalized to a barycentric blend of N key feathers for coats (Chapter 6).
#include "pteryla/feather/interpolate.hpp"

#include <algorithm>
#include <cmath>

#include "pteryla/core/error.hpp"
#include "pteryla/feather/bezier.hpp"
#include "pteryla/feather/generator.hpp"

namespace pteryla::feather {

void inflateKeyBarbs(std::vector<KeyBarb>& keys, size_t count) {
  if (keys.size() >= count) return;
  PTERYLA_CHECK(!keys.empty(), "inflateKeyBarbs needs at least one key barb");
  const size_t extra = count - keys.size();
  // Insert before any key barbs sitting exactly at the tip, spread evenly above the last one below it.
  size_t at = keys.size();
  while (at > 0 && keys[at - 1].rp >= 1) --at;
  const double from = at > 0 ? keys[at - 1].rp : 0.0;
  std::vector<KeyBarb> added(extra);
  for (size_t e = 0; e < extra; ++e) {
    added[e].rp = from + (1.0 - from) * static_cast<double>(e + 1) / static_cast<double>(extra + 1);
    barbShapeAt(keys, added[e].rp, added[e].cvs);
  }
  keys.insert(keys.begin() + static_cast<std::ptrdiff_t>(at), added.begin(), added.end());
}

namespace {

// Piecewise-linear profile sum: breakpoints are the union of all inputs plus {0, 1}; jumps are kept.
LengthProfile blendProfiles(const std::vector<LengthProfile>& profs, const std::vector<double>& consts,
                            const std::vector<double>& w) {
  std::vector<double> xs{0.0, 1.0};
  for (const auto& p : profs)
    for (const auto& q : p.points) xs.push_back(q.x);
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
  auto leftLimit = [](const LengthProfile& p, double x) {
    // Value approaching x from below (lower value of a jump at x).
    const auto it =
        std::lower_bound(p.points.begin(), p.points.end(), x, [](const glm::dvec2& q, double r) { return q.x < r; });
    if (it != p.points.end() && it->x == x) return it->y;
    return p.at(x);
  };
  LengthProfile out;
  for (double x : xs) {
    double lo = 0, hi = 0;
    for (size_t i = 0; i < profs.size(); ++i) {
      if (profs[i].empty()) {
        lo += w[i] * consts[i];
        hi += w[i] * consts[i];
      } else {
        lo += w[i] * leftLimit(profs[i], x);
        hi += w[i] * profs[i].at(x);
      }
    }
    if (lo != hi) out.points.emplace_back(x, lo);
    out.points.emplace_back(x, hi);
  }
  return out;
}

size_t heaviest(const std::vector<double>& w) {
  return static_cast<size_t>(std::max_element(w.begin(), w.end()) - w.begin());
}

}  // namespace

FeatherParams blendFeathers(const std::vector<const FeatherParams*>& feathersIn, const std::vector<double>& weightsIn) {
  if (feathersIn.size() != weightsIn.size())
    throw Error("blendFeathers: " + std::to_string(feathersIn.size()) + " feathers but " +
                std::to_string(weightsIn.size()) + " weights");
  std::vector<const FeatherParams*> fs;
  std::vector<double> w;
  double sum = 0;
  for (size_t i = 0; i < feathersIn.size(); ++i) {
    const double wi = weightsIn[i];
    if (!std::isfinite(wi) || wi < 0)
      throw Error("blendFeathers: weights must be finite and >= 0", {}, "weights[" + std::to_string(i) + "]");
    PTERYLA_CHECK_NE(feathersIn[i], nullptr, "null feather in blend");
    if (wi > 0) {
      fs.push_back(feathersIn[i]);
      w.push_back(wi);
      sum += wi;
    }
  }
  if (fs.empty() || !(sum > 0)) throw Error("blendFeathers: weights must have a positive sum");
  // Feathers of different generators (zero weights included, so every blend of the same key feathers
  // agrees) blend in their Streit key-barb form: a helical feather as its converted key barbs.
  bool mixed = false;
  for (const auto* f : feathersIn) mixed = mixed || f->generator != feathersIn.front()->generator;
  if (mixed) {
    std::vector<FeatherParams> converted;
    converted.reserve(fs.size());
    for (const auto* f : fs) converted.push_back(streitForm(*f));
    std::vector<const FeatherParams*> cs;
    for (const auto& f : converted) cs.push_back(&f);
    return blendFeathers(cs, w);
  }
  if (fs.size() == 1) return *fs.front();
  for (double& x : w) x /= sum;
  const size_t nf = fs.size();
  const FeatherParams& top = *fs[heaviest(w)];

  FeatherParams r;
  r.name = top.name;
  r.generator = top.generator;
  r.generatorParams = top.generatorParams;
  if (r.generator != "streit") {
    const FeatherGenerator* g = findFeatherGenerator(r.generator);
    if (!g) throw Error("unknown feather generator '" + r.generator + "'", {}, "generator");
    if (g->blend) r.generatorParams = g->blend(fs, w);
  }
  r.seed = top.seed;
  r.material = top.material;
  r.growth = top.growth;  // the schedule of the heaviest key feather, as its material
  auto mix = [&](auto field) {
    double acc = 0;
    for (size_t i = 0; i < nf; ++i) acc += w[i] * field(*fs[i]);
    return acc;
  };
  r.calamusLength = mix([](const FeatherParams& f) { return f.calamusLength; });
  r.calamusWidthRatio = mix([](const FeatherParams& f) { return f.calamusWidthRatio; });
  r.rachisLength = mix([](const FeatherParams& f) { return f.rachisLength; });
  r.rachisWidth = mix([](const FeatherParams& f) { return f.rachisWidth; });
  r.rachisLateralCurvature = mix([](const FeatherParams& f) { return f.rachisLateralCurvature; });
  r.rachisVentralDorsalCurvature = mix([](const FeatherParams& f) { return f.rachisVentralDorsalCurvature; });
  r.barbLength = mix([](const FeatherParams& f) { return f.barbLength; });
  r.spacingBase = mix([](const FeatherParams& f) { return f.spacingBase; });
  r.spacingTip = mix([](const FeatherParams& f) { return f.spacingTip; });
  r.splits.count = static_cast<int>(std::lround(mix([](const FeatherParams& f) { return double(f.splits.count); })));
  r.splits.reach = static_cast<int>(std::lround(mix([](const FeatherParams& f) { return double(f.splits.reach); })));
  r.splits.rpMin = mix([](const FeatherParams& f) { return f.splits.rpMin; });
  r.splits.rpMax = std::max(r.splits.rpMin, mix([](const FeatherParams& f) { return f.splits.rpMax; }));
  r.splits.openingAngle = mix([](const FeatherParams& f) { return f.splits.openingAngle; });

  bool allColor = true;
  for (const auto* f : fs) allColor = allColor && f->material.baseColor.has_value();
  if (allColor) {
    glm::dvec3 c(0.0);
    for (size_t i = 0; i < nf; ++i) c += w[i] * *fs[i]->material.baseColor;
    r.material.baseColor = c;
  }
  // Barbule parameters likewise, each when every feather sets it (else the heaviest's, or none).
  for (std::optional<double> FeatherMaterial::*field : {&FeatherMaterial::brdfD, &FeatherMaterial::brdfH}) {
    bool all = true;
    for (const auto* f : fs) all = all && (f->material.*field).has_value();
    if (!all) continue;
    double acc = 0;
    for (size_t i = 0; i < nf; ++i) acc += w[i] * *(fs[i]->material.*field);
    r.material.*field = acc;
  }

  // Silhouettes: feathers without one contribute their constant barb length.
  bool anySil = false;
  for (const auto* f : fs) anySil = anySil || !f->silhouette.empty();
  if (anySil) {
    std::vector<double> consts(nf);
    for (size_t i = 0; i < nf; ++i) consts[i] = fs[i]->barbLength;
    for (int v = 0; v < 2; ++v) {
      std::vector<LengthProfile> profs(nf);
      for (size_t i = 0; i < nf; ++i) profs[i] = v == 0 ? fs[i]->silhouette.left : fs[i]->silhouette.right;
      (v == 0 ? r.silhouette.left : r.silhouette.right) = blendProfiles(profs, consts, w);
    }
  }

  // Vanes: angles blend linearly; key barbs by inflation + matching + the bilinear construction.
  for (int v = 0; v < 2; ++v) {
    VaneParams& rv = r.vane(v);
    rv.baseAngle = mix([v](const FeatherParams& f) { return f.vane(v).baseAngle; });
    rv.tipAngle = mix([v](const FeatherParams& f) { return f.vane(v).tipAngle; });
    std::vector<std::vector<KeyBarb>> keys(nf);
    size_t m = 0, n = 0;
    for (size_t i = 0; i < nf; ++i) {
      keys[i] = effectiveKeyBarbs(*fs[i], v);
      m = std::max(m, keys[i].size());
      n = std::max(n, keys[i].front().cvs.size());
    }
    for (auto& ks : keys) {
      inflateKeyBarbs(ks, m);
      for (auto& k : ks)
        if (k.cvs.size() < n) k.cvs = elevateTo(k.cvs, n);
    }
    rv.keyBarbs.resize(m);
    std::vector<glm::dvec3> shape;
    for (size_t j = 0; j < m; ++j) {
      double rp = 0;
      for (size_t i = 0; i < nf; ++i) rp += w[i] * keys[i][j].rp;
      rp = std::clamp(rp, 0.0, 1.0);
      KeyBarb& out = rv.keyBarbs[j];
      out.rp = rp;
      out.cvs.assign(n, glm::dvec3(0.0));
      for (size_t i = 0; i < nf; ++i) {
        barbShapeAt(keys[i], rp, shape, static_cast<int>(j));
        for (size_t c = 0; c < n; ++c) out.cvs[c] += w[i] * shape[c];
      }
    }
    // Rounding can reorder equal positions by an ulp; keep the list sorted.
    std::stable_sort(rv.keyBarbs.begin(), rv.keyBarbs.end(),
                     [](const KeyBarb& a, const KeyBarb& b) { return a.rp < b.rp; });
  }

  // Afterfeather: blend those present, then shrink by the weight of feathers that have one.
  std::vector<const FeatherParams*> afs;
  std::vector<double> aw;
  double wa = 0;
  for (size_t i = 0; i < nf; ++i)
    if (fs[i]->afterfeather) {
      afs.push_back(fs[i]->afterfeather.get());
      aw.push_back(w[i]);
      wa += w[i];
    }
  if (!afs.empty() && wa > 1e-9) {
    FeatherParams a = blendFeathers(afs, aw);
    if (wa < 1) {
      a.calamusLength *= wa;
      a.rachisLength *= wa;
      a.rachisWidth *= wa;
      a.barbLength *= wa;
      for (auto* prof : {&a.silhouette.left, &a.silhouette.right})
        for (auto& q : prof->points) q.y *= wa;
    }
    r.afterfeather = std::make_shared<const FeatherParams>(std::move(a));
  }
  return r;
}

FeatherParams interpolateFeathers(const FeatherParams& a, const FeatherParams& b, double t) {
  if (!std::isfinite(t) || t < 0 || t > 1) throw Error("interpolateFeathers: t must be in [0, 1]", {}, "t");
  return blendFeathers({&a, &b}, {1.0 - t, t});
}

}  // namespace pteryla::feather
