// Packing on a deformed skin from a reference pack (pack.hpp, packDeformed): Streit 2003, 8.3 repacks the
// coat in its rest layer order on every posed skin. Most of a posed bird moves rigidly with some bone, and
// a feather whose surroundings (the skin under it, the feathers it packs against) moved rigidly with its
// follicle packs exactly as it did in the reference, carried by that motion. Only the feathers whose
// surroundings moved relative to them by more than the tolerance are packed again, with every feather that
// packs against a changed one.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pteryla/core/error.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat {

using namespace packing;

namespace {

// The rigid motion carrying a feather's reference frame g onto its frame f: x -> f.o + R (x - g.o) with
// R = [f.t f.b f.n] [g.t g.b g.n]^T.
struct Motion {
  bool identity = false;  // the frames are the same bits: points are copied, not moved
  dvec3 go{0}, fo{0};
  dvec3 c0{1, 0, 0}, c1{0, 1, 0}, c2{0, 0, 1};  // columns of R
  static Motion between(const FeatherFrame& g, const FeatherFrame& f) {
    Motion m;
    m.identity = std::memcmp(&g, &f, sizeof(FeatherFrame)) == 0;
    m.go = g.origin;
    m.fo = f.origin;
    // Column k of R is R e_k = sum over the reference axes a of f.a * (g.a . e_k).
    auto col = [&](int k) { return f.tangent * g.tangent[k] + f.binormal * g.binormal[k] + f.normal * g.normal[k]; };
    m.c0 = col(0);
    m.c1 = col(1);
    m.c2 = col(2);
    return m;
  }
  dvec3 rotate(const dvec3& d) const { return c0 * d.x + c1 * d.y + c2 * d.z; }
  dvec3 operator()(const dvec3& x) const { return identity ? x : fo + rotate(x - go); }
  // Frobenius norm of R_a - R_b (a bound on how far the two rotations part a unit vector).
  static double rotationGap(const Motion& a, const Motion& b) {
    if (a.identity && b.identity) return 0;
    const dvec3 d0 = a.c0 - b.c0, d1 = a.c1 - b.c1, d2 = a.c2 - b.c2;
    return std::sqrt(glm::dot(d0, d0) + glm::dot(d1, d1) + glm::dot(d2, d2));
  }
};

// Can a sphere (world centre c, radius r) touch the footprint of feather L in frame F (the region the
// packer gathers candidates from: ahead of the follicle, within its lateral extent and reach)?
bool inFootprint(const LocalFeather& L, const FeatherFrame& F, const dvec3& c, double r) {
  const dvec3 l = toFrame(F, c);
  return l.x + r >= 0 && l.x - r <= L.reach && l.y + r >= L.yMin && l.y - r <= L.yMax &&
         glm::dot(l, l) <= (L.reach + r) * (L.reach + r);
}

// Feather i kept from the reference, carried by its motion: elevation and key barbs are follicle-frame
// values and stay; the world points and spheres move.
void keepMoved(const PackResult& ref, PackResult& res, Output& out, uint32_t i, const Motion& m,
               const FeatherFrame& f) {
  res.elevation[i] = ref.elevation[i];
  copyKeys(ref.packedKeys, res.packedKeys, i);
  res.barbsChanged[i] = ref.barbsChanged[i];
  const glm::dvec4& b = ref.bounds[i];
  res.bounds[i] = glm::dvec4(f.origin, b.w * (1 + 1e-6) + 1e-9);
  const uint32_t p0 = ref.pointOffset[i], p1 = ref.pointOffset[i + 1], q0 = res.pointOffset[i];
  for (uint32_t p = p0; p < p1; ++p) {
    const glm::vec4& a = ref.points[p];
    res.points[q0 + (p - p0)] = glm::vec4(glm::vec3(m(dvec3(a.x, a.y, a.z))), a.w);
  }
  const uint32_t g0 = ref.groupOffset[i], g1 = ref.groupOffset[i + 1], h0 = res.groupOffset[i];
  for (uint32_t g = g0; g < g1; ++g) {
    const glm::vec4& s = ref.groupBounds[g];
    const dvec3 c = m(dvec3(s.x, s.y, s.z));
    // Padded for the float rounding of the moved points and centre.
    const double r = double(s.w) * (1 + 1e-6) + 1e-6 * glm::length(c) + 1e-12;
    res.groupBounds[h0 + (g - g0)] = glm::vec4(glm::vec3(c), static_cast<float>(r));
  }
  closeChunks(out, i);
}

}  // namespace

PackResult packing::packDeformedFrom(Context& ctx, const SkinMesh& refSkin, const std::vector<FeatherFrame>& refFrames,
                                     const PackResult& ref, double tolerance, DeformedPackStats* report) {
  const auto t0 = std::chrono::steady_clock::now();
  const SkinMesh& skin = ctx.skin;
  const CoatFeathers& coat = ctx.coat;
  const PackOptions& options = ctx.opt;
  checkInput(coat, options, ctx.constraints);
  const size_t n = coat.size();
  if (!(tolerance >= 0) || !std::isfinite(tolerance))
    throw Error("the pose tolerance must be a finite number >= 0, got " + std::to_string(tolerance), {},
                "pose_tolerance");
  if (refFrames.size() != n)
    throw Error("packDeformed: " + std::to_string(refFrames.size()) + " reference frames for " + std::to_string(n) +
                    " feathers",
                {}, "refFrames");
  if (refSkin.positions.size() != skin.positions.size())
    throw Error("packDeformed: the reference skin has " + std::to_string(refSkin.positions.size()) +
                    " vertices, the skin " + std::to_string(skin.positions.size()),
                {}, "refSkin");
  const bool refUsable = ref.elevation.size() == n && ref.pointOffset.size() == n + 1 &&
                         ref.groupOffset.size() == n + 1 && ref.packedKeys.keyOffset.size() == n + 1 &&
                         ref.bounds.size() == n && ref.order == presentInLayerOrder(coat);
  DeformedPackStats local;
  DeformedPackStats& st = report ? *report : local;
  st = DeformedPackStats{};
  if (tolerance == 0 || !refUsable || options.captureFields) {
    PackResult r = packAll(ctx);
    st.repacked = r.stats.recomputed;
    return r;
  }

  PackResult res;
  detail::inArena(options.threads, [&] {
    setup(ctx);
    const double tol = tolerance * ctx.clearance;
    st.toleranceUnits = tol;
    layoutResult(ctx, localSources(ctx), nullptr, res);
    const std::vector<uint32_t>& order = ctx.order;

    std::vector<Motion> motion(n);
    for (uint32_t i : order) motion[i] = Motion::between(refFrames[i], coat.frames[i]);

    // Feathers whose reference points could touch i's reference footprint: the reference's dependencies
    // (the posed ones are ctx.deps). A grid over the centres of the reference spheres up to twice the
    // median radius; the few larger ones (flight feathers) are tested one by one.
    std::vector<double> radii;
    for (uint32_t j : order) radii.push_back(ref.bounds[j].w);
    const double smallR = 2 * median(radii);
    std::vector<glm::dvec3> centres;
    std::vector<uint32_t> smallAt, large;  // positions in order
    for (size_t k = 0; k < order.size(); ++k) {
      const glm::dvec4& b = ref.bounds[order[k]];
      if (b.w <= smallR) {
        centres.push_back(dvec3(b));
        smallAt.push_back(static_cast<uint32_t>(k));
      } else {
        large.push_back(static_cast<uint32_t>(k));
      }
    }
    const double cell = std::max(1e-9, ctx.medianReach);
    detail::PointGrid refGrid;
    refGrid.build(centres, cell);
    // Skin vertices at rest, for how the skin under a feather moved; a face reaching into the footprint
    // has its vertices within its longest edge of it.
    double maxEdge = 0;
    for (size_t f = 0; f < refSkin.faces.size(); ++f) {
      const auto& t = refSkin.faces[f];
      for (int e = 0; e < 3; ++e)
        maxEdge = std::max(maxEdge, glm::length(refSkin.positions[t[e]] - refSkin.positions[t[(e + 1) % 3]]));
    }
    // Skin vertices at rest, all of them and those the pose moved: a feather that did not move itself
    // only needs to look at the moved ones.
    detail::PointGrid skinGrid, movedGrid;
    std::vector<glm::dvec3> movedAt;
    std::vector<uint32_t> movedVertex;
    const bool skinMatters = options.skin && !skin.faces.empty();
    if (skinMatters) {
      skinGrid.build(refSkin.positions, cell);
      for (uint32_t v = 0; v < refSkin.positions.size(); ++v)
        if (std::memcmp(&refSkin.positions[v], &skin.positions[v], sizeof(dvec3)) != 0) {
          movedAt.push_back(refSkin.positions[v]);
          movedVertex.push_back(v);
        }
      movedGrid.build(movedAt, cell);
    }

    // moved[i]: i's surroundings moved relative to it by more than tol.
    std::vector<std::vector<uint32_t>> extra(n);
    std::vector<uint8_t> moved(n, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 8), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t ki = r.begin(); ki < r.end(); ++ki) {
        const uint32_t i = order[ki];
        const LocalFeather& L = ctx.local[i];
        const Motion& mi = motion[i];
        const dvec3 gi = refFrames[i].origin;
        bool m = false;
        // Feathers under it, in the reference or now.
        // Only the parts of j that reach i's footprint matter: each of j's point groups (a sphere around
        // the shaft's or a key barb's points) that lies within i's reach of its follicle, in the reference
        // or carried by j's motion to now, must be where i's own motion puts it, to within tol (the gap of
        // the two motions at the sphere's centre plus the rotation gap times its radius).
        auto differs = [&](uint32_t j) {
          const Motion& mj = motion[j];
          if (mi.identity && mj.identity) return false;  // neither moved
          const double gap = Motion::rotationGap(mi, mj);
          for (uint32_t g = ref.groupOffset[j]; g < ref.groupOffset[j + 1]; ++g) {
            const glm::vec4& sg = ref.groupBounds[g];
            const dvec3 c(sg.x, sg.y, sg.z);
            const double r = sg.w;
            const dvec3 cj = mj(c);
            const bool near = inFootprint(L, refFrames[i], c, r) || inFootprint(L, coat.frames[i], cj, r);
            if (near && glm::length(mi(c) - cj) + r * gap > tol) return true;
          }
          return false;
        };
        for (uint32_t k = ctx.depOff[i]; k < ctx.depOff[i + 1] && !m; ++k) m = differs(ctx.deps[k]);
        std::vector<uint32_t>& ex = extra[i];
        auto consider = [&](uint32_t kj) {
          if (kj >= ki) return;
          const uint32_t j = order[kj];
          const glm::dvec4& b = ref.bounds[j];
          if (glm::length(dvec3(b) - gi) > L.reach + b.w) return;
          ex.push_back(j);
        };
        const double q = L.reach + smallR;
        refGrid.query(gi - dvec3(q), gi + dvec3(q), [&](uint32_t item) { consider(smallAt[item]); });
        for (uint32_t kj : large) consider(kj);
        std::sort(ex.begin(), ex.end());
        for (size_t k = 0; k < ex.size() && !m; ++k) m = differs(ex[k]);
        // The skin under it.
        if (!m && skinMatters) {
          const double s = L.reach + maxEdge;
          const bool still = mi.identity;
          (still ? movedGrid : skinGrid).query(gi - dvec3(s), gi + dvec3(s), [&](uint32_t item) {
            const uint32_t v = still ? movedVertex[item] : item;
            if (m) return;
            const dvec3& p0 = refSkin.positions[v];
            if (!inFootprint(L, refFrames[i], p0, maxEdge) &&
                !inFootprint(L, coat.frames[i], skin.positions[v], maxEdge))
              return;
            if (glm::length(mi(p0) - skin.positions[v]) > tol) m = true;
          });
        }
        moved[i] = m ? 1 : 0;
      }
    });
    // Dependencies: the posed ones and the reference ones (so a feather that moved away from under i
    // still makes i pack again).
    {
      std::vector<uint32_t> off(n + 1, 0), deps;
      for (size_t i = 0; i < n; ++i) {
        std::vector<uint32_t>& ex = extra[i];
        ex.insert(ex.end(), ctx.deps.begin() + ctx.depOff[i], ctx.deps.begin() + ctx.depOff[i + 1]);
        std::sort(ex.begin(), ex.end());
        ex.erase(std::unique(ex.begin(), ex.end()), ex.end());
        off[i + 1] = off[i] + static_cast<uint32_t>(ex.size());
      }
      deps.reserve(off[n]);
      for (size_t i = 0; i < n; ++i) deps.insert(deps.end(), extra[i].begin(), extra[i].end());
      ctx.depOff = std::move(off);
      ctx.deps = std::move(deps);
    }
    for (uint32_t i : order) st.moved += moved[i];

    std::vector<uint8_t> outChanged(n, 0);
    Run run(res);
    schedule(ctx, order, nullptr, options.threads, [&](uint32_t i) {
      bool dirty = moved[i] != 0;
      for (uint32_t k = ctx.depOff[i]; k < ctx.depOff[i + 1] && !dirty; ++k) dirty = outChanged[ctx.deps[k]] != 0;
      const uint32_t cnt = res.pointOffset[i + 1] - res.pointOffset[i];
      const bool sameShape =
          ref.pointOffset[i + 1] - ref.pointOffset[i] == cnt &&
          ref.groupOffset[i + 1] - ref.groupOffset[i] == res.groupOffset[i + 1] - res.groupOffset[i] &&
          sameKeyLayout(ref.packedKeys, res.packedKeys, i);
      if (!dirty && sameShape) {
        if (motion[i].identity)
          keepFeather(ref, res, run.out, i);
        else
          keepMoved(ref, res, run.out, i, motion[i], coat.frames[i]);
        return;
      }
      run.packOne(ctx, res, i);
      // Changed for what packs over it: its points left the reference's, carried, by more than tol.
      bool diff = !sameShape;
      const Motion& m = motion[i];
      for (uint32_t q = 0; q < cnt && !diff; ++q) {
        const glm::vec4& a = ref.points[ref.pointOffset[i] + q];
        const glm::vec4& b = res.points[res.pointOffset[i] + q];
        diff = glm::length(m(dvec3(a.x, a.y, a.z)) - dvec3(b.x, b.y, b.z)) > tol;
      }
      outChanged[i] = diff ? 1 : 0;
    });
    finish(ctx, run.scratch, res, t0);
  });
  st.repacked = res.stats.recomputed;
  return res;
}

}  // namespace pteryla::coat
