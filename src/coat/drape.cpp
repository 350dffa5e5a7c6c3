// Draped packing (drape.hpp): feathers laid on the skin along surface charts and stacked by height over
// the skin, in layer order.
#include "pteryla/coat/drape.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pteryla/core/error.hpp"
#include "pteryla/coat/check.hpp"
#include "drape_surfaces.hpp"
#include "spatial.hpp"

namespace pteryla::coat {

using glm::dvec3;

using namespace draping;

namespace {

void buildChart(const Surface& S, const FeatherFrame& F, const feather::FeatherParams& p, const TriMesh& mesh,
                const uint32_t* verts, size_t count, double scale, const DrapeOptions& o, Chart& C) {
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  for (size_t k = 0; k < count; ++k) {
    const dvec3 d = dvec3(mesh.positions[verts[k]]) - F.origin;
    const double x = scale * glm::dot(d, F.tangent), y = scale * glm::dot(d, F.binormal);
    x0 = std::min(x0, x);
    x1 = std::max(x1, x);
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
  }
  const double len = std::max(x1 - x0, 1e-9);
  C.nx = std::max(2, o.gridAlong);
  C.ny = std::max(2, o.gridAcross);
  const double pad = 1e-6 * len;
  C.x0 = x0 - pad;
  C.y0 = y0 - pad;
  C.hx = (x1 - x0 + 2 * pad) / (C.nx - 1);
  C.hy = std::max(y1 - y0 + 2 * pad, 2 * pad) / (C.ny - 1);
  C.diag = std::sqrt(C.hx * C.hx + C.hy * C.hy);
  C.ramp = std::clamp(scale * p.calamusLength, 0.02 * len, 0.25 * len);
  C.nodes.assign(static_cast<size_t>(C.nx) * C.ny, Node{});
  C.scale = scale;
  const double maxStep = std::min(C.hx, std::max(C.hy, 0.25 * C.hx));
  const double minRadius = kStiffness * len;
  Node root;
  root.c = F.origin;
  root.n = F.normal;
  root.t = F.tangent;
  root.ok = 1;
  // The spine (y = 0) at every column's x: forward from the follicle, then backward.
  std::vector<Node> spine(C.nx);
  Node cur = root;
  double xCur = 0;
  bool alive = true;
  for (int a = 0; a < C.nx; ++a) {
    const double x = C.x0 + a * C.hx;
    if (x < 0) continue;
    alive = alive && S.march(cur, true, x - xCur, maxStep, F.normal, minRadius, cur);
    xCur = x;
    spine[a] = alive ? cur : Node{};
  }
  cur = root;
  xCur = 0;
  alive = true;
  for (int a = C.nx - 1; a >= 0; --a) {
    const double x = C.x0 + a * C.hx;
    if (x >= 0) continue;
    alive = alive && S.march(cur, true, x - xCur, maxStep, F.normal, minRadius, cur);
    xCur = x;
    spine[a] = alive ? cur : Node{};
  }
  // Across from the spine: toward +y, then toward -y.
  for (int a = 0; a < C.nx; ++a) {
    for (int side = 0; side < 2; ++side) {
      Node p = spine[a];
      double yCur = 0;
      bool ok = p.ok;
      for (int k = 0; k < C.ny; ++k) {
        const int b = side == 0 ? k : C.ny - 1 - k;
        const double y = C.y0 + b * C.hy;
        if (side == 0 ? y < 0 : y >= 0) continue;
        ok = ok && S.march(p, false, y - yCur, maxStep, F.normal, minRadius, p);
        yCur = y;
        C.at(a, b) = ok ? p : Node{};
      }
    }
  }
  // Nodes next to material: the corners of every cell holding a vertex; the longest edge for trimming.
  std::vector<uint8_t>& cell = C.material;
  cell.assign(static_cast<size_t>(C.nx - 1) * (C.ny - 1), 0);
  for (size_t k = 0; k < count; ++k) {
    const dvec3 d = dvec3(mesh.positions[verts[k]]) - F.origin;
    int a, b;
    double u, v;
    C.locate(scale * glm::dot(d, F.tangent), scale * glm::dot(d, F.binormal), a, b, u, v);
    cell[static_cast<size_t>(a) * (C.ny - 1) + b] = 1;
  }
  std::vector<uint8_t> raw(static_cast<size_t>(C.fineX()) * C.fineY(), 0);
  for (size_t k = 0; k < count; ++k) {
    const dvec3 d = dvec3(mesh.positions[verts[k]]) - F.origin;
    const int a = std::clamp(static_cast<int>(std::floor((scale * glm::dot(d, F.tangent) - C.x0) / C.hx * Chart::kSub)),
                             0, C.fineX() - 1);
    const int b = std::clamp(
        static_cast<int>(std::floor((scale * glm::dot(d, F.binormal) - C.y0) / C.hy * Chart::kSub)), 0, C.fineY() - 1);
    raw[static_cast<size_t>(a) * C.fineY() + b] = 1;
  }
  C.fine.assign(raw.size(), 0);
  for (int a = 0; a < C.fineX(); ++a)
    for (int b = 0; b < C.fineY(); ++b) {
      bool any = false;
      for (int da = -1; da <= 1 && !any; ++da)
        for (int db = -1; db <= 1 && !any; ++db) {
          const int aa = a + da, bb = b + db;
          any = aa >= 0 && bb >= 0 && aa < C.fineX() && bb < C.fineY() && raw[static_cast<size_t>(aa) * C.fineY() + bb];
        }
      C.fine[static_cast<size_t>(a) * C.fineY() + b] = any ? 1 : 0;
    }
  for (int a = 0; a + 1 < C.nx; ++a)
    for (int b = 0; b + 1 < C.ny; ++b)
      if (cell[static_cast<size_t>(a) * (C.ny - 1) + b])
        C.at(a, b).active = C.at(a + 1, b).active = C.at(a, b + 1).active = C.at(a + 1, b + 1).active = 1;
}

// Does a cell holding material fold (corner normals on the skin more than 40 degrees apart) or have a
// corner the chart did not reach?
bool foldsOrLeaves(const Chart& C) {
  for (int a = 0; a + 1 < C.nx; ++a)
    for (int b = 0; b + 1 < C.ny; ++b) {
      if (!C.material[static_cast<size_t>(a) * (C.ny - 1) + b]) continue;
      const Node* c4[4] = {&C.at(a, b), &C.at(a + 1, b), &C.at(a, b + 1), &C.at(a + 1, b + 1)};
      for (int m = 0; m < 4; ++m) {
        if (!c4[m]->ok) return true;
        for (int m2 = m + 1; m2 < 4; ++m2)
          if (!c4[m]->free && !c4[m2]->free && glm::dot(c4[m]->n, c4[m2]->n) <= kFoldCos) return true;
      }
    }
  return false;
}

// Per node: the curvature of the skin toward its chart neighbours (normal turn over distance) and the
// dip of a chord of length `edge` there.
void setSag(Chart& C, double edge) {
  for (int a = 0; a < C.nx; ++a)
    for (int b = 0; b < C.ny; ++b) {
      Node& nd = C.at(a, b);
      if (!nd.ok || nd.free) continue;  // past the edge the feather is straight: no sag
      double kappa = 0;
      const int da[4] = {1, -1, 0, 0}, db[4] = {0, 0, 1, -1};
      for (int k = 0; k < 4; ++k) {
        const int aa = a + da[k], bb = b + db[k];
        if (aa < 0 || bb < 0 || aa >= C.nx || bb >= C.ny || !C.at(aa, bb).ok || C.at(aa, bb).free) continue;
        const Node& o = C.at(aa, bb);
        // At least half the nominal node spacing: where the skin turns at an edge, nodes bunch up.
        const double d = std::max(glm::length(o.c - nd.c), 0.5 * (da[k] ? C.hx : C.hy));
        if (d > 1e-12) kappa = std::max(kappa, std::acos(std::clamp(glm::dot(o.n, nd.n), -1.0, 1.0)) / d);
      }
      nd.sag = 0.5 * edge * edge * kappa / 8;
    }
}

// Layer order agrees with the feathers: a feather never covers the follicle of a feather laid after it
// (that feather would rise out of the skin through it). The flat footprint (a raster of where the
// feather has vertices, local x, y) is tested against the root zones of the later follicles in reach,
// taken into the feather's tangent plane; the feather is scaled about its follicle by the largest factor
// in [minScale, 1] that covers none (bisection).
double shrinkScale(const FeatherFrame& F, const TriMesh& mesh, const uint32_t* verts, size_t count,
                   const std::vector<std::pair<glm::dvec2, double>>& later, int rx, int ry, double minScale) {
  if (later.empty() || count == 0) return 1.0;
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  std::vector<glm::dvec2> loc(count);
  for (size_t k = 0; k < count; ++k) {
    const dvec3 d = dvec3(mesh.positions[verts[k]]) - F.origin;
    loc[k] = {glm::dot(d, F.tangent), glm::dot(d, F.binormal)};
    x0 = std::min(x0, loc[k].x);
    x1 = std::max(x1, loc[k].x);
    y0 = std::min(y0, loc[k].y);
    y1 = std::max(y1, loc[k].y);
  }
  const double cx = std::max(x1 - x0, 1e-12) / rx, cy = std::max(y1 - y0, 1e-12) / ry;
  std::vector<uint8_t> raw(static_cast<size_t>(rx) * ry, 0), m(raw.size(), 0);
  for (const auto& q : loc)
    raw[static_cast<size_t>(std::clamp(int((q.x - x0) / cx), 0, rx - 1)) * ry +
        std::clamp(int((q.y - y0) / cy), 0, ry - 1)] = 1;
  for (int a = 0; a < rx; ++a)
    for (int b = 0; b < ry; ++b)
      for (int da = -1; da <= 1; ++da)
        for (int db = -1; db <= 1; ++db) {
          const int aa = a + da, bb = b + db;
          if (aa >= 0 && bb >= 0 && aa < rx && bb < ry && raw[static_cast<size_t>(aa) * ry + bb])
            m[static_cast<size_t>(a) * ry + b] = 1;
        }
  auto covered = [&](double x, double y) {
    const double fa = std::floor((x - x0) / cx), fb = std::floor((y - y0) / cy);
    return fa >= 0 && fb >= 0 && fa < rx && fb < ry && m[static_cast<size_t>(fa) * ry + static_cast<size_t>(fb)];
  };
  auto anyCovered = [&](double s) {
    for (const auto& [c, r] : later) {
      if (c.x <= 0.5 * r) continue;  // behind or beside the follicle: the calamus, not the vane
      for (int k = 0; k <= 8; ++k) {
        const double ang = k * (2 * 3.14159265358979323846 / 8);
        const double rr = k == 8 ? 0.0 : r;
        if (covered((c.x + rr * std::cos(ang)) / s, (c.y + rr * std::sin(ang)) / s)) return true;
      }
    }
    return false;
  };
  if (!anyCovered(1.0)) return 1.0;
  if (anyCovered(minScale)) return minScale;
  double lo = minScale, hi = 1.0;
  for (int it = 0; it < 10; ++it) {
    const double mid = 0.5 * (lo + hi);
    (anyCovered(mid) ? hi : lo) = mid;
  }
  return lo;
}

// Gathers what laying a chart reads: its active nodes, the samples facing each within reqRadius, and the
// samples under its material (their chart coordinates from the nearest-in-order node's frame that reaches
// them; each sample once, cells whose corners are all on the chart).
void gatherSamples(Chart& C, const CoatTop& top, double reqRadius) {
  C.active.clear();
  C.reqOffset.assign(1, 0);
  C.reqSamples.clear();
  C.under.clear();
  for (int k = 0; k < C.nx * C.ny; ++k) {
    const Node& nd = C.nodes[k];
    if (!nd.ok || !nd.active) continue;
    C.active.push_back(k);
    top.near(nd.c, nd.n, reqRadius, [&](uint32_t s) { C.reqSamples.push_back(s); });
    C.reqOffset.push_back(static_cast<uint32_t>(C.reqSamples.size()));
  }
  for (int k : C.active) {
    const Node& nd = C.nodes[k];
    const double xa = C.x0 + (k / C.ny) * C.hx, yb = C.y0 + (k % C.ny) * C.hy;
    const dvec3 bn = glm::cross(nd.n, nd.t);
    top.near(nd.c, nd.n, 0.75 * C.diag, [&](uint32_t s) {
      const dvec3 d = top.position(s) - nd.c;
      const double x = xa + glm::dot(d, nd.t), y = yb + glm::dot(d, bn);
      if (!C.covers(x, y)) return;
      int a, b;
      double u, v;
      C.locate(x, y, a, b, u, v);
      for (const Node* c : {&C.at(a, b), &C.at(a + 1, b), &C.at(a, b + 1), &C.at(a + 1, b + 1)})
        if (!c->ok || !c->active) return;
      C.under.push_back(
          {s, static_cast<uint16_t>(a), static_cast<uint16_t>(b), static_cast<float>(u), static_cast<float>(v)});
    });
  }
  // Each sample once (the first node that reached it).
  std::vector<size_t> perm(C.under.size());
  for (size_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::stable_sort(perm.begin(), perm.end(), [&](size_t x, size_t y) { return C.under[x].sample < C.under[y].sample; });
  std::vector<uint8_t> keep(C.under.size(), 0);
  for (size_t i = 0; i < perm.size(); ++i)
    if (i == 0 || C.under[perm[i]].sample != C.under[perm[i - 1]].sample) keep[perm[i]] = 1;
  size_t w = 0;
  for (size_t i = 0; i < C.under.size(); ++i)
    if (keep[i]) C.under[w++] = C.under[i];
  C.under.resize(w);
  C.under.shrink_to_fit();
  C.reqSamples.shrink_to_fit();
}

// Heights of one chart's active nodes over the skin: above the coat's top near each node by the gap, as
// the smallest function with slope <= maxSlope over those requirements. Then the feather becomes the
// coat's top over the samples its material covers.
void layChart(Chart& C, CoatTop& top, AirTop& air, double gap, double maxSlope, std::vector<double>& req) {
  const std::vector<int>& idx = C.active;
  req.resize(idx.size());
  for (size_t j = 0; j < idx.size(); ++j) {
    const Node& n = C.nodes[idx[j]];
    double highest = 0;
    for (uint32_t q = C.reqOffset[j]; q < C.reqOffset[j + 1]; ++q) highest = std::max(highest, top.at(C.reqSamples[q]));
    req[j] = highest + gap + n.sag;
    if (n.free) req[j] = std::max(req[j], air.highest(n.c, n.n, 0.25 * (C.nx - 1) * C.hx) + gap);
  }
  // Every node's height becomes the largest of the (pre-envelope) heights less maxSlope x distance. The
  // nodes are visited by height, highest first, so each node stops at the first one no higher than
  // itself: the same maximum, without the pairs that cannot raise it.
  std::vector<uint32_t> byHeight(idx.size());
  auto envelope = [&] {
    for (size_t j = 0; j < idx.size(); ++j) req[j] = C.nodes[idx[j]].h;
    for (size_t j = 0; j < idx.size(); ++j) byHeight[j] = static_cast<uint32_t>(j);
    std::sort(byHeight.begin(), byHeight.end(), [&](uint32_t x, uint32_t y) { return req[x] > req[y]; });
    for (size_t j = 0; j < idx.size(); ++j) {
      const int aj = idx[j] / C.ny, bj = idx[j] % C.ny;
      double h = req[j];
      for (const uint32_t m : byHeight) {
        if (req[m] <= h) break;
        const double dx = (idx[m] / C.ny - aj) * C.hx, dy = (idx[m] % C.ny - bj) * C.hy;
        h = std::max(h, req[m] - maxSlope * std::sqrt(dx * dx + dy * dy));
      }
      C.nodes[idx[j]].h = h;
    }
  };
  for (size_t j = 0; j < idx.size(); ++j) C.nodes[idx[j]].h = req[j];
  // Every sample under the feather's material: where the interpolated height is below the coat's top
  // there plus the gap, the cell's corners rise to it (heights only rise, so one pass leaves every
  // sample satisfied, and no node rises above the highest need near it).
  for (const Chart::Cover& cv : C.under) {
    Node* c4[4] = {&C.at(cv.a, cv.b), &C.at(cv.a + 1, cv.b), &C.at(cv.a, cv.b + 1), &C.at(cv.a + 1, cv.b + 1)};
    const double u = cv.u, v = cv.v;
    const double w4[4] = {(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v};
    double h = 0, sag = 0;
    for (int m = 0; m < 4; ++m) {
      h += w4[m] * c4[m]->h;
      sag = std::max(sag, c4[m]->sag);
    }
    // Each corner rises to the need, no higher: raising all four by the shortfall instead stacked up
    // where neighbouring cells share corners (up to 4x the need, compounding layer over layer).
    const double need = top.at(cv.sample) + gap + sag;
    if (h < need)
      for (int m = 0; m < 4; ++m) c4[m]->h = std::max(c4[m]->h, need);
  }
  envelope();
  for (const Chart::Cover& cv : C.under) {
    const double u = cv.u, v = cv.v;
    top.raise(cv.sample, (1 - u) * (1 - v) * C.at(cv.a, cv.b).h + u * (1 - v) * C.at(cv.a + 1, cv.b).h +
                             (1 - u) * v * C.at(cv.a, cv.b + 1).h + u * v * C.at(cv.a + 1, cv.b + 1).h);
  }
  for (int k : idx) air.add(C.nodes[k].c + C.nodes[k].h * C.nodes[k].n, C.nodes[k].n);
  // What was gathered for laying is not needed again.
  C.reqSamples = {};
  C.reqOffset = {};
  C.under = {};
}

}  // namespace

DrapeResult drapeCoatMesh(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh, const DrapeOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t n = coat.size(), nv = mesh.positions.size();
  if (mesh.featherId.size() != nv) throw Error("the coat mesh needs one featherId per vertex", {}, "featherId");
  if (coat.frames.size() != n || coat.params.size() != n)
    throw Error("the coat needs one frame and one parameter set per feather", {}, "frames");
  DrapeResult res;
  res.elevation.assign(n, 0.0);
  res.trimmed.assign(n, 0);
  res.hidden.assign(n, 0);
  if (nv == 0 || skin.faces.empty()) return res;
  // Vertices per feather (CSR).
  std::vector<uint32_t> first(n + 1, 0), verts(nv);
  for (uint32_t f : mesh.featherId) {
    if (f >= n) throw Error("featherId " + std::to_string(f) + " out of range", {}, "featherId");
    ++first[f + 1];
  }
  for (size_t i = 0; i < n; ++i) first[i + 1] += first[i];
  {
    std::vector<uint32_t> fill(first.begin(), first.end() - 1);
    for (uint32_t v = 0; v < nv; ++v) verts[fill[mesh.featherId[v]]++] = v;
  }
  std::vector<int64_t> rank(n, -1);
  std::vector<uint32_t> order;
  for (uint32_t i : coat.layerOrder)
    if (i < n && rank[i] < 0 && first[i + 1] > first[i]) {
      rank[i] = static_cast<int64_t>(order.size());
      order.push_back(i);
    }
  if (order.empty()) return res;
  // Progress after each step, at the share of the bird's drape done by then.
  auto step = [&](double f) { report(o.progress, "drape", f); };
  auto within = [&](double lo, double hi) -> ProgressFn {
    if (!o.progress) return {};
    return [&o, lo, hi](const std::string&, double f) {
      report(o.progress, "drape", lo + (hi - lo) * f);
      return true;
    };
  };
  step(0);
  const Surface S(skin);
  std::vector<Chart> charts(n);
  // Longest triangle edge per feather as meshed (flat): its chords dip below the skin-following surface by
  // about edge^2 x curvature / 8, which the gap over what lies under it must exceed.
  std::vector<double> flatEdge(n, 0.0);
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    const uint32_t f = mesh.featherId[tri[0]];
    for (int k = 0; k < 3; ++k)
      flatEdge[f] =
          std::max(flatEdge[f], double(glm::length(mesh.positions[tri[k]] - mesh.positions[tri[(k + 1) % 3]])));
  }
  // Scale factors: no feather covers a later follicle's root zone.
  std::vector<double> scale(n, 1.0);
  {
    std::vector<dvec3> origins;
    double reach = 0;
    for (uint32_t i : order) {
      origins.push_back(coat.frames[i].origin);
      for (uint32_t q = first[i]; q < first[i + 1]; ++q)
        reach = std::max(reach, double(glm::length(dvec3(mesh.positions[verts[q]]) - coat.frames[i].origin)));
    }
    detail::PointGrid og;
    og.build(origins, std::max(reach, 1e-12));
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<std::pair<glm::dvec2, double>> later;
        for (size_t k = r.begin(); k < r.end(); ++k) {
          const uint32_t i = order[k];
          const FeatherFrame& F = coat.frames[i];
          double ri = 0;
          for (uint32_t q = first[i]; q < first[i + 1]; ++q)
            ri = std::max(ri, double(glm::length(dvec3(mesh.positions[verts[q]]) - F.origin)));
          later.clear();
          og.query(F.origin - dvec3(ri), F.origin + dvec3(ri), [&](uint32_t j) {
            if (j <= k) return;
            const FeatherFrame& G = coat.frames[order[j]];
            if (glm::dot(G.normal, F.normal) < 0.3) return;  // the far side of a thin part
            const dvec3 d = G.origin - F.origin;
            if (glm::length(d) > ri) return;
            const feather::FeatherParams& pj = coat.params[order[j]];
            later.push_back({{glm::dot(d, F.tangent), glm::dot(d, F.binormal)},
                             0.5 * pj.rachisWidth + std::max(pj.calamusLength, 0.02 * pj.totalLength())});
          });
          scale[i] = shrinkScale(F, mesh, verts.data() + first[i], first[i + 1] - first[i], later,
                                 4 * (std::max(2, o.gridAlong) - 1), 4 * (std::max(2, o.gridAcross) - 1), 0.3);
        }
      });
    });
  }
  step(0.03);
  std::vector<double> lengths;
  detail::inArena(o.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        const uint32_t i = order[k];
        // A feather whose chart folds over a rim or into a crease, or leaves the skin, is shortened
        // (shorter where the surface curves tightly) before anything of it is trimmed.
        for (int attempt = 0;; ++attempt) {
          buildChart(S, coat.frames[i], coat.params[i], mesh, verts.data() + first[i], first[i + 1] - first[i],
                     scale[i], o, charts[i]);
          if (attempt == 3 || scale[i] < 0.4 || !foldsOrLeaves(charts[i])) break;
          scale[i] *= 0.8;
        }
        setSag(charts[i], scale[i] * flatEdge[i]);
      }
    });
  });
  for (uint32_t i : order) lengths.push_back(charts[i].hx * (charts[i].nx - 1));
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  const double medianLength = lengths[lengths.size() / 2];
  const double gap = o.gap > 0 ? o.gap : 0.004 * medianLength;
  res.stats.gap = gap;
  std::vector<double> steps;
  for (uint32_t i : order) steps.push_back(std::min(charts[i].hx, charts[i].hy));
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  double spacing = std::max(0.75 * steps[steps.size() / 2], 1e-12);
  const double area = skin.totalArea();
  if (area / (spacing * spacing) > 8e6) spacing = std::sqrt(area / 8e6);  // at most about 8M samples
  step(0.14);
  CoatTop top(skin, spacing);
  step(0.16);
  {
    std::vector<double> req;
    double airRadius = 1.5 * spacing;
    for (uint32_t i : order) airRadius = std::max(airRadius, 0.75 * charts[i].diag);
    AirTop air(airRadius);
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) gatherSamples(charts[order[k]], top, 1.5 * spacing);
      });
    });
    step(0.37);
    for (uint32_t i : order) layChart(charts[i], top, air, gap, o.maxSlope, req);
    step(0.46);
  }
  // A node whose lifted point has other skin closer than half its height sits in a fold: not draped.
  // (Thin parts keep their coat: a node's height goes out along its own normal, away from the other
  // side, and past a thin part's rim the feather overhangs instead of wrapping onto the other side.)
  detail::inArena(o.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k)
        for (Node& nd : charts[order[k]].nodes)
          if (nd.ok && nd.active && S.skinWithin(nd.c + nd.h * nd.n, 0.5 * nd.h * (1 - 1e-9))) nd.ok = 0;
    });
  });
  // Move every vertex; remember its surface point for trimming.
  std::vector<glm::vec3> surfacePoint(nv);
  std::vector<uint8_t> bad(nv, 0);
  const bool hasN = mesh.normals.size() == nv, hasT = mesh.tangents.size() == nv;
  detail::inArena(o.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        const uint32_t i = order[k];
        Chart& C = charts[i];
        const FeatherFrame& F = coat.frames[i];
        for (uint32_t q = first[i]; q < first[i + 1]; ++q) {
          const uint32_t v = verts[q];
          const dvec3 d = dvec3(mesh.positions[v]) - F.origin;
          const double x = C.scale * glm::dot(d, F.tangent), y = C.scale * glm::dot(d, F.binormal);
          int a, b;
          double u, w;
          C.locate(x, y, a, b, u, w);
          const Node* c4[4] = {&C.at(a, b), &C.at(a + 1, b), &C.at(a, b + 1), &C.at(a + 1, b + 1)};
          const double w4[4] = {(1 - u) * (1 - w), u * (1 - w), (1 - u) * w, u * w};
          dvec3 c(0), nn(0), tt(0);
          double h = 0;
          bool ok = true;
          // A cell whose corners' normals differ by more than ~40 degrees folds over a rim or into a
          // crease: its chords leave the skin's side. Trimmed.
          for (int m = 0; m < 4 && ok; ++m)
            for (int m2 = m + 1; m2 < 4 && ok; ++m2)
              ok = c4[m]->free || c4[m2]->free || glm::dot(c4[m]->n, c4[m2]->n) > kFoldCos;
          for (int m = 0; m < 4; ++m) {
            ok = ok && c4[m]->ok;
            c += w4[m] * c4[m]->c;
            nn += w4[m] * c4[m]->n;
            tt += w4[m] * c4[m]->t;
            h += w4[m] * c4[m]->h;
          }
          const double nl = glm::length(nn);
          if (!ok || !(nl > 1e-9)) {
            bad[v] = 1;
            surfacePoint[v] = glm::vec3(F.origin + d);
            continue;
          }
          nn /= nl;
          tt -= glm::dot(tt, nn) * nn;
          const double tl = glm::length(tt);
          tt = tl > 1e-12 ? tt / tl : F.tangent;
          const dvec3 bb = glm::cross(nn, tt);
          if (x < C.ramp) h *= std::max(0.0, x) / C.ramp;
          const dvec3 pos = c + h * nn;
          mesh.positions[v] = glm::vec3(pos);
          surfacePoint[v] = glm::vec3(c);
          auto turn = [&](const glm::vec3& e) {
            const dvec3 ed(e);
            return glm::vec3(glm::dot(ed, F.tangent) * tt + glm::dot(ed, F.binormal) * bb +
                             glm::dot(ed, F.normal) * nn);
          };
          if (hasN) mesh.normals[v] = turn(mesh.normals[v]);
          if (hasT) mesh.tangents[v] = turn(mesh.tangents[v]);
        }
        // Elevation: the steepest rise of the spine's nodes past the calamus.
        const int b0 = std::clamp(static_cast<int>(std::lround(-C.y0 / C.hy)), 0, C.ny - 1);
        double e = 0;
        for (int a = 0; a < C.nx; ++a) {
          const double x = C.x0 + a * C.hx;
          const Node& nd = C.at(a, b0);
          if (x > C.ramp && nd.ok && nd.active) e = std::max(e, std::atan2(nd.h, x));
        }
        res.elevation[i] = e;
      }
    });
  });
  step(0.5);
  const size_t nt = mesh.triangleCount();
  // Trim lower feathers' material over a later feather's follicle, where that feather rises out of the
  // skin: every triangle whose surface projection comes within the later feather's root zone (its calamus
  // ramp and half its rachis) of that follicle. Exact per triangle, so a feather with long triangles
  // (a flight feather's barbs) loses only the triangles over the follicle, not a band its edge wide.
  std::vector<dvec3> origins;
  double reachMax = 0;
  for (uint32_t i : order) {
    origins.push_back(coat.frames[i].origin);
    reachMax = std::max(reachMax, charts[i].ramp + 0.5 * coat.params[i].rachisWidth);
  }
  std::vector<uint8_t> overFollicle(nt, 0);
  {
    // Per feather the later follicles within reach of its surface points (from the grid, once), then
    // per triangle those whose root zone its box comes near: the follicles the test below can find.
    detail::PointGrid grid;
    grid.build(origins, std::max(reachMax, 1e-12));
    std::vector<uint32_t> trisOf(n + 1, 0), tris(nt);  // triangles per feather (CSR)
    for (size_t t = 0; t < nt; ++t) ++trisOf[mesh.featherId[mesh.indices[3 * t]] + 1];
    for (size_t i = 0; i < n; ++i) trisOf[i + 1] += trisOf[i];
    {
      std::vector<uint32_t> fill(trisOf.begin(), trisOf.end() - 1);
      for (size_t t = 0; t < nt; ++t) tris[fill[mesh.featherId[mesh.indices[3 * t]]]++] = static_cast<uint32_t>(t);
    }
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        struct Later {
          dvec3 g;
          double rj, reach;  // the root zone's radius; how far from a triangle's box it can matter
        };
        std::vector<Later> later;
        for (size_t k = r.begin(); k < r.end(); ++k) {
          const uint32_t i = order[k];
          detail::Box fb;
          for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q)
            for (int c = 0; c < 3; ++c) fb.add(dvec3(surfacePoint[mesh.indices[3 * static_cast<size_t>(tris[q]) + c]]));
          if (fb.empty()) continue;
          later.clear();
          grid.query(fb.lo - dvec3(reachMax), fb.hi + dvec3(reachMax), [&](uint32_t j) {
            if (j <= k) return;
            const uint32_t f = order[j];
            const dvec3& g = coat.frames[f].origin;
            const double rj = charts[f].ramp + 0.5 * coat.params[f].rachisWidth;
            // A little past rj: the closest point's rounding never matters.
            const double reach = rj + 1e-6 * (rj + std::max({std::abs(g.x), std::abs(g.y), std::abs(g.z)}));
            later.push_back({g, rj, reach});
          });
          if (later.empty()) continue;
          for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) {
            const uint32_t t = tris[q];
            const uint32_t* tri = &mesh.indices[3 * static_cast<size_t>(t)];
            if (bad[tri[0]] || bad[tri[1]] || bad[tri[2]]) continue;
            const dvec3 a(surfacePoint[tri[0]]), b(surfacePoint[tri[1]]), c(surfacePoint[tri[2]]);
            const dvec3 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
            for (const Later& L : later) {
              const dvec3& g = L.g;
              if (g.x < lo.x - L.reach || g.y < lo.y - L.reach || g.z < lo.z - L.reach || g.x > hi.x + L.reach ||
                  g.y > hi.y + L.reach || g.z > hi.z + L.reach)
                continue;
              const dvec3 cq = closestPointOnTriangle(g, a, b, c);
              if (glm::dot(cq - g, cq - g) < L.rj * L.rj) {
                overFollicle[t] = 1;
                break;
              }
            }
          }
        }
      });
    });
  }
  {
    step(0.53);
    CheckOptions co;
    setFeatherBases(co, coat, o.baseAllowance);
    co.progress = within(0.53, 0.65);
    const std::vector<uint8_t> inside = verticesInsideSkin(skin, mesh, co);
    for (uint32_t v = 0; v < nv; ++v)
      if (inside[v] && rank[mesh.featherId[v]] >= 0) bad[v] = 1;
  }
  std::vector<size_t> kept(n, 0), cut(n, 0);
  auto collapse = [&](size_t t) {
    uint32_t* tri = &mesh.indices[3 * t];
    if (tri[1] == tri[0] && tri[2] == tri[0]) return;
    tri[1] = tri[2] = tri[0];
    ++cut[mesh.featherId[tri[0]]];
  };
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    if (rank[mesh.featherId[tri[0]]] >= 0 && (overFollicle[t] || bad[tri[0]] || bad[tri[1]] || bad[tri[2]]))
      collapse(t);
  }
  // Trimmed vertices serve only collapsed triangles: park them at their follicle.
  for (uint32_t v = 0; v < nv; ++v)
    if (bad[v] && rank[mesh.featherId[v]] >= 0) mesh.positions[v] = glm::vec3(coat.frames[mesh.featherId[v]].origin);
  for (uint64_t pr : intersectingTrianglePairs(mesh, within(0.65, 1))) {
    const size_t t = pr >> 32, u = pr & 0xffffffffu;
    const uint32_t ft = mesh.featherId[mesh.indices[3 * t]], fu = mesh.featherId[mesh.indices[3 * u]];
    if (rank[ft] < 0 || rank[fu] < 0) continue;
    collapse(rank[ft] < rank[fu] ? t : u);
  }
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    if (tri[1] != tri[0] || tri[2] != tri[0]) ++kept[mesh.featherId[tri[0]]];
  }
  for (uint32_t i : order) {
    ++res.stats.draped;
    for (const Node& nd : charts[i].nodes) res.stats.overhangingNodes += nd.free && nd.active;
    if (cut[i]) {
      res.trimmed[i] = 1;
      ++res.stats.trimmedFeathers;
      res.stats.trimmedTriangles += cut[i];
      if (!kept[i]) {
        res.hidden[i] = 1;
        ++res.stats.hiddenFeathers;
      }
    }
  }
  res.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace pteryla::coat
