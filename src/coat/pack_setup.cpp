// Packing set-up: input checks, the layer order, feather-local data, clearances, reach classes, the
// dependency graph and the skin samples.
#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "pteryla/core/error.hpp"
#include "pack_internal.hpp"

namespace pteryla::coat::packing {

// ------------------------------------------------------------------ setup

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + m, v.end());
  return v[m];
}

void checkInput(const CoatFeathers& c, const PackOptions& o, const PackConstraints& k) {
  const size_t n = c.size();
  auto need = [&](size_t got, const char* what) {
    if (got != n)
      throw Error(std::string("CoatFeathers.") + what + " has " + std::to_string(got) + " entries, expected " +
                      std::to_string(n),
                  {}, what);
  };
  need(c.params.size(), "params");
  need(c.frames.size(), "frames");
  if (!c.tract.empty()) need(c.tract.size(), "tract");
  if (!c.age.empty()) need(c.age.size(), "age");
  if (!c.present.empty()) need(c.present.size(), "present");
  for (const auto& [v, what] :
       {std::pair{&k.fixedElevation, "fixedElevation"}, {&k.minElevation, "minElevation"}, {&k.shaftBand, "shaftBand"}})
    if (!v->empty() && v->size() != n)
      throw Error(std::string(what) + " has " + std::to_string(v->size()) + " entries, expected " + std::to_string(n),
                  {}, what);
  std::vector<uint8_t> seen(n, 0);
  for (size_t k = 0; k < c.layerOrder.size(); ++k) {
    const uint32_t i = c.layerOrder[k];
    if (i >= n)
      throw Error("layer order names feather " + std::to_string(i) + " of " + std::to_string(n), {},
                  "layerOrder[" + std::to_string(k) + "]");
    if (seen[i])
      throw Error("layer order lists feather " + std::to_string(i) + " twice", {},
                  "layerOrder[" + std::to_string(k) + "]");
    seen[i] = 1;
  }
  for (size_t i = 0; i < n; ++i) {
    const FeatherFrame& f = c.frames[i];
    for (const dvec3* v : {&f.origin, &f.normal, &f.tangent, &f.binormal})
      if (!std::isfinite(v->x) || !std::isfinite(v->y) || !std::isfinite(v->z))
        throw Error("feather frame is not finite", {}, "frames[" + std::to_string(i) + "]");
  }
  if (!(o.maxElevation >= o.minElevation)) throw Error("maxElevation below minElevation", {}, "maxElevation");
  if (!(o.maxFlatten >= 0 && o.maxFlatten <= 2)) throw Error("maxFlatten must be in [0, 2]", {}, "maxFlatten");
}

// Reach classes over the packed feathers' origins (Context::reachClasses): class c holds the feathers
// whose radius is up to 2^(c+1) x `med`; radius[i] bounds feather i's points around its origin.
void buildReachClasses(Context& ctx, const std::vector<double>& radius, double med) {
  std::vector<std::vector<uint32_t>> members;
  for (size_t k = 0; k < ctx.order.size(); ++k) {
    const double ratio = radius[ctx.order[k]] / (2 * med);
    const size_t c = ratio <= 1 ? 0 : std::min<size_t>(16, static_cast<size_t>(std::ceil(std::log2(ratio))));
    if (members.size() <= c) members.resize(c + 1);
    members[c].push_back(static_cast<uint32_t>(k));
  }
  ctx.reachClasses.clear();
  for (auto& m : members) {
    if (m.empty()) continue;
    Context::ReachClass rc;
    std::vector<glm::dvec3> origins(m.size());
    for (size_t q = 0; q < m.size(); ++q) {
      origins[q] = ctx.coat.frames[ctx.order[m[q]]].origin;
      rc.maxReach = std::max(rc.maxReach, radius[ctx.order[m[q]]]);
    }
    rc.grid.build(origins, std::max(rc.maxReach, 1e-9));
    rc.members = std::move(m);
    ctx.reachClasses.push_back(std::move(rc));
  }
}

// Dependencies (ctx.depOff / ctx.deps, CSR over every feather; empty but for `items`): for each feather
// in `items`, the feathers before it in layer order whose radius ball can touch its footprint, in index
// order. Needs the reach classes and the items' feather-local data.
void buildDependencies(Context& ctx, const std::vector<uint32_t>& items, const std::vector<double>& radius,
                       size_t grain) {
  const size_t n = ctx.coat.size();
  std::vector<std::vector<uint32_t>> depLists(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, items.size(), grain), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t w = r.begin(); w < r.end(); ++w) {
      const uint32_t i = items[w];
      const LocalFeather& L = ctx.local[i];
      const FeatherFrame& F = ctx.coat.frames[i];
      std::vector<uint32_t>& d = depLists[i];
      ctx.forNearOrigins(F.origin, L.reach, [&](uint32_t kj) {
        if (kj >= ctx.pos[i]) return;
        const uint32_t j = ctx.order[kj];
        const double Rj = radius[j];
        const dvec3 c = toFrame(F, ctx.coat.frames[j].origin);
        if (glm::length(c) > L.reach + Rj) return;
        if (c.x < -Rj || c.y < L.yMin - Rj || c.y > L.yMax + Rj) return;
        d.push_back(j);
      });
      std::sort(d.begin(), d.end());
    }
  });
  ctx.depOff.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) ctx.depOff[i + 1] = ctx.depOff[i] + static_cast<uint32_t>(depLists[i].size());
  ctx.deps.resize(ctx.depOff[n]);
  for (size_t i = 0; i < n; ++i) std::copy(depLists[i].begin(), depLists[i].end(), ctx.deps.begin() + ctx.depOff[i]);
}

std::vector<uint32_t> presentInLayerOrder(const CoatFeathers& coat) {
  const size_t n = coat.size();
  std::vector<uint32_t> order;
  if (coat.layerOrder.empty()) {
    for (uint32_t i = 0; i < n; ++i) order.push_back(i);
  } else {
    order = coat.layerOrder;
  }
  order.erase(std::remove_if(order.begin(), order.end(),
                             [&](uint32_t i) { return !coat.present.empty() && coat.present[i] == 0; }),
              order.end());
  return order;
}

std::vector<uint8_t> changedMask(const std::vector<uint32_t>& changed, size_t n) {
  std::vector<uint8_t> mask(n, 0);
  for (uint32_t c : changed) {
    if (c >= n) throw Error("changed feather " + std::to_string(c) + " out of range", {}, "changed");
    mask[c] = 1;
  }
  return mask;
}

void beginContext(Context& ctx, std::vector<uint32_t> order) {
  ctx.fixed = ctx.constraints.fixedElevation;
  ctx.minElevation = ctx.constraints.minElevation;
  ctx.shaftBand = ctx.constraints.shaftBand;
  ctx.order = std::move(order);
  ctx.pos.assign(ctx.coat.size(), UINT32_MAX);
  for (size_t k = 0; k < ctx.order.size(); ++k) ctx.pos[ctx.order[k]] = static_cast<uint32_t>(k);
}

void setup(Context& ctx) {
  const CoatFeathers& coat = ctx.coat;
  const PackOptions& o = ctx.opt;
  const size_t n = coat.size();
  beginContext(ctx, presentInLayerOrder(coat));

  ctx.local.resize(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16), [&](const tbb::blocked_range<size_t>& r) {
    detail::HugeArena& arena = ctx.arenas.local();
    for (size_t i = r.begin(); i < r.end(); ++i) {
      ctx.local[i].packable = ctx.pos[i] != UINT32_MAX;
      if (ctx.local[i].packable)
        buildLocal(coat, static_cast<uint32_t>(i), o, arena, ctx.local[i]);
      else
        ctx.local[i].pointCount = 0;
    }
  });

  // Clearances.
  std::vector<double> widths, reaches;
  for (uint32_t i : ctx.order) {
    widths.push_back(coat.params[i].rachisWidth);
    reaches.push_back(ctx.local[i].reach);
  }
  ctx.clearance = o.clearance > 0 ? o.clearance : 0.25 * median(widths);
  ctx.skinClearance = o.skinClearance > 0 ? o.skinClearance : ctx.clearance;
  const double medReach = std::max(1e-12, median(reaches));
  ctx.medianReach = medReach;
  double maxReach = 0;
  for (double r : reaches) maxReach = std::max(maxReach, r);
  ctx.maxReach = maxReach;

  // Dependency graph: j before i whose reach ball can touch i's footprint.
  std::vector<double> radius(n, 0.0);
  for (uint32_t i : ctx.order) radius[i] = ctx.local[i].reach;
  buildReachClasses(ctx, radius, medReach);
  buildDependencies(ctx, ctx.order, radius, 16);

  buildSkinSamples(ctx, medReach);
}

// Skin samples (9.1.2: the surface under the feather, including neighbouring polygons).
bool samplesFitSkin(const detail::PackSkinSamples& sd, const SkinMesh& skin) {
  auto same = [](const auto& a, const auto& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
  };
  return same(sd.skinPositions, skin.positions) && same(sd.skinFaces, skin.faces) &&
         same(sd.skinFaceNormals, skin.faceNormals);
}

bool packedOnSkin(const PackResult& r, const SkinMesh& skin, const PackOptions& o) {
  if (!(o.skin && !skin.faces.empty())) return r.skinSamples == nullptr;
  return r.skinSamples && samplesFitSkin(*r.skinSamples, skin);
}

void buildSkinSamples(Context& ctx, double medReach) {
  const PackOptions& o = ctx.opt;
  ctx.skinData.reset();
  if (o.skin && !ctx.skin.faces.empty()) {
    const double h = o.skinSampleSpacing > 0 ? o.skinSampleSpacing : 0.1 * medReach;
    const double cell = std::max(0.2 * medReach, 2 * h);
    // Samples of this skin at this spacing are the same bits however often they are built.
    for (const auto& r : ctx.reusable)
      if (r && r->spacing == h && r->cell == cell && samplesFitSkin(*r, ctx.skin)) {
        ctx.skinData = r;
        return;
      }
    auto data = std::make_shared<detail::PackSkinSamples>();
    detail::PackSkinSamples& sd = *data;
    sd.skinPositions = ctx.skin.positions;
    sd.skinFaces = ctx.skin.faces;
    sd.skinFaceNormals = ctx.skin.faceNormals;
    sd.spacing = h;
    sd.cell = cell;
    // Every used vertex once, points along each edge once (the face with the lower index, or the only
    // face, owns it), and interior points of each face; counts from the edge/face size and spacing h.
    const SkinMesh& sk = ctx.skin;
    const size_t nf = sk.faces.size();
    auto segs = [&](double len) { return std::clamp(static_cast<int>(std::ceil(len / h)), 1, 32); };
    std::vector<uint8_t> used(sk.positions.size(), 0);
    for (const auto& t : sk.faces) used[t[0]] = used[t[1]] = used[t[2]] = 1;
    size_t base = 0;
    for (size_t v = 0; v < sk.positions.size(); ++v) base += used[v];
    std::vector<uint32_t> faceOff(nf + 1, 0);
    std::vector<int> faceN(nf);
    for (size_t f = 0; f < nf; ++f) {
      const auto& t = sk.faces[f];
      uint32_t cnt = 0;
      double le = 0;
      for (int c = 0; c < 3; ++c) {
        const double l = glm::length(sk.positions[t[(c + 1) % 3]] - sk.positions[t[c]]);
        le = std::max(le, l);
        const int32_t nb = sk.faceNeighbors.empty() ? -1 : sk.faceNeighbors[f][c];
        if (nb < 0 || static_cast<size_t>(nb) > f) cnt += static_cast<uint32_t>(segs(l) - 1);
      }
      const int m = segs(le);
      faceN[f] = m;
      cnt += static_cast<uint32_t>(m >= 3 ? (m - 1) * (m - 2) / 2 : 0);
      faceOff[f + 1] = faceOff[f] + cnt;
    }
    sd.pts.resize(base + faceOff.back());
    {
      size_t q = 0;
      for (size_t v = 0; v < sk.positions.size(); ++v)
        if (used[v]) sd.pts[q++] = sk.positions[v];
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nf, 64), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t f = r.begin(); f < r.end(); ++f) {
        const auto& t = sk.faces[f];
        const dvec3 P[3] = {sk.positions[t[0]], sk.positions[t[1]], sk.positions[t[2]]};
        size_t q = base + faceOff[f];
        for (int c = 0; c < 3; ++c) {
          const int32_t nb = sk.faceNeighbors.empty() ? -1 : sk.faceNeighbors[f][c];
          if (!(nb < 0 || static_cast<size_t>(nb) > f)) continue;
          const dvec3 a = P[c], b = P[(c + 1) % 3];
          const int m = segs(glm::length(b - a));
          for (int k = 1; k < m; ++k) sd.pts[q++] = a + (static_cast<double>(k) / m) * (b - a);
        }
        const int m = faceN[f];
        for (int x = 1; x < m; ++x)
          for (int y = 1; x + y < m; ++y) {
            const double u = static_cast<double>(x) / m, v = static_cast<double>(y) / m;
            sd.pts[q++] = P[0] + u * (P[1] - P[0]) + v * (P[2] - P[0]);
          }
        PTERYLA_DCHECK_EQ(q, base + faceOff[f + 1], "skin sample count mismatch");
      }
    });
    // The sample grid (serial, ~2.5 MB of fresh memory on the bird) is built beside the patches.
    auto patches = [&] {
      // Patches. A point of face f lies in the sub-triangle of f's m-subdivision (longest edge le / m,
      // covering radius <= le / (m sqrt 3)); a corner of that sub-triangle on an edge of f may be replaced by
      // the nearest sample of that edge, at most half an edge step away.
      std::vector<double> faceRho(nf);
      for (size_t f = 0; f < nf; ++f) {
        const auto& t = sk.faces[f];
        double le = 0, edgeHalf = 0;
        for (int c = 0; c < 3; ++c) {
          const double l = glm::length(sk.positions[t[(c + 1) % 3]] - sk.positions[t[c]]);
          le = std::max(le, l);
          edgeHalf = std::max(edgeHalf, 0.5 * l / segs(l));
        }
        faceRho[f] = (le / faceN[f] / std::sqrt(3.0) + edgeHalf) * (1 + 1e-9);
      }
      sd.normal.resize(sd.pts.size());
      sd.rho.resize(sd.pts.size());
      sd.cone.resize(sd.pts.size());
      auto setPatch = [&](size_t q, const uint32_t* faces, size_t count) {
        dvec3 nsum(0);
        double rho = 0;
        for (size_t k = 0; k < count; ++k) {
          nsum += sk.faceNormals[faces[k]];
          rho = std::max(rho, faceRho[faces[k]]);
        }
        const double l = glm::length(nsum);
        const dvec3 nrm = l > 1e-12 ? nsum / l : sk.faceNormals[faces[0]];
        double cone = 0;
        for (size_t k = 0; k < count; ++k) {
          const dvec3 x = glm::cross(nrm, sk.faceNormals[faces[k]]);
          // sine of the angle (or 1 past 90 degrees)
          cone = std::max(cone, glm::dot(nrm, sk.faceNormals[faces[k]]) < 0 ? 1.0 : glm::length(x));
        }
        sd.normal[q] = nrm;
        sd.rho[q] = static_cast<float>(rho * (1 + 1e-6));
        sd.cone[q] = static_cast<float>(std::min(1.0, cone * (1 + 1e-6) + 1e-9));
      };
      {
        size_t q = 0;
        std::vector<uint32_t> inc;
        for (size_t v = 0; v < sk.positions.size(); ++v) {
          if (!used[v]) continue;
          inc.clear();
          if (!sk.vertexFaceOffsets.empty()) {
            for (uint32_t k = sk.vertexFaceOffsets[v]; k < sk.vertexFaceOffsets[v + 1]; ++k)
              inc.push_back(sk.vertexFaces[k]);
          } else {
            for (uint32_t f = 0; f < nf; ++f)
              if (sk.faces[f][0] == v || sk.faces[f][1] == v || sk.faces[f][2] == v) inc.push_back(f);
          }
          setPatch(q++, inc.data(), inc.size());
        }
      }
      tbb::parallel_for(tbb::blocked_range<size_t>(0, nf, 64), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t f = r.begin(); f < r.end(); ++f) {
          size_t q = base + faceOff[f];
          const uint32_t self = static_cast<uint32_t>(f);
          for (int c = 0; c < 3; ++c) {
            const int32_t nb = sk.faceNeighbors.empty() ? -1 : sk.faceNeighbors[f][c];
            if (!(nb < 0 || static_cast<size_t>(nb) > f)) continue;
            const int m = segs(glm::length(sk.positions[sk.faces[f][(c + 1) % 3]] - sk.positions[sk.faces[f][c]]));
            const uint32_t two[2] = {self, static_cast<uint32_t>(nb < 0 ? self : static_cast<uint32_t>(nb))};
            for (int k = 1; k < m; ++k) setPatch(q++, two, 2);
          }
          for (; q < base + faceOff[f + 1]; ++q) setPatch(q, &self, 1);
        }
      });
    };
    tbb::parallel_invoke([&] { sd.grid.build(sd.pts.data(), sd.pts.size(), cell); }, patches);
    for (float r : sd.rho) sd.maxRho = std::max(sd.maxRho, static_cast<double>(r));
    ctx.skinData = std::move(data);
  }
}

}  // namespace pteryla::coat::packing
