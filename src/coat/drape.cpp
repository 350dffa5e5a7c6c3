// Draped packing (drape.hpp): feathers laid on the skin along surface charts and stacked by height over
// the skin, in layer order.
#include "pteryla/coat/drape.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
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

// What laying a chart reads of the coat laid so far: per active node the highest top among its
// requirement samples (and past the skin's edge, the highest laid point over it), then the top at every
// sample under its material. Laying depends on nothing else but the chart: equal reads, equal heights.
void readChart(const Chart& C, const CoatTop& top, const AirTop& air, std::vector<double>& reads) {
  reads.clear();
  for (size_t j = 0; j < C.active.size(); ++j) {
    const Node& n = C.nodes[C.active[j]];
    double highest = 0;
    for (uint32_t q = C.reqOffset[j]; q < C.reqOffset[j + 1]; ++q) highest = std::max(highest, top.at(C.reqSamples[q]));
    reads.push_back(highest);
    if (n.free) reads.push_back(air.highest(n.c, n.n, 0.25 * (C.nx - 1) * C.hx));
  }
  for (const Chart::Cover& cv : C.under) reads.push_back(top.at(cv.sample));
}

// Heights of one chart's active nodes over the skin from what it read (readChart): above the coat's top
// near each node by the gap, as the smallest function with slope <= maxSlope over those requirements.
void layFromReads(Chart& C, const std::vector<double>& reads, double gap, double maxSlope, std::vector<double>& req) {
  const std::vector<int>& idx = C.active;
  req.resize(idx.size());
  size_t r = 0;
  for (size_t j = 0; j < idx.size(); ++j) {
    const Node& n = C.nodes[idx[j]];
    req[j] = reads[r++] + gap + n.sag;
    if (n.free) req[j] = std::max(req[j], reads[r++] + gap);
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
  for (size_t k = 0; k < C.under.size(); ++k) {
    const Chart::Cover& cv = C.under[k];
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
    const double need = reads[r + k] + gap + sag;
    if (h < need)
      for (int m = 0; m < 4; ++m) c4[m]->h = std::max(c4[m]->h, need);
  }
  envelope();
}

// The laid feather becomes the coat's top over the samples its material covers (writeChart), and its
// nodes join the coat in the air (addToAir; only a chart with free nodes reads the air, readsAir).
void writeChart(const Chart& C, CoatTop& top) {
  for (const Chart::Cover& cv : C.under) {
    const double u = cv.u, v = cv.v;
    top.raise(cv.sample, (1 - u) * (1 - v) * C.at(cv.a, cv.b).h + u * (1 - v) * C.at(cv.a + 1, cv.b).h +
                             (1 - u) * v * C.at(cv.a, cv.b + 1).h + u * v * C.at(cv.a + 1, cv.b + 1).h);
  }
}
void addToAir(const Chart& C, AirTop& air) {
  for (int k : C.active) air.add(C.nodes[k].c + C.nodes[k].h * C.nodes[k].n, C.nodes[k].n);
}
bool readsAir(const Chart& C) {
  return std::any_of(C.active.begin(), C.active.end(), [&](int k) { return C.nodes[k].free != 0; });
}

// Moves a feather's vertices (vs[0..count), flat, at elevation 0 in frame F) onto its laid chart: each to
// its chart point plus its height along the chart normal, normals and tangents turned with the chart
// frame. Vertices over a cell that folds or that the chart did not reach are marked bad (trimmed).
// Returns the feather's elevation: the steepest rise of the spine's nodes past the calamus.
double placeOnChart(const Chart& C, const FeatherFrame& F, TriMesh& mesh, const uint32_t* vs, size_t count, bool hasN,
                    bool hasT, std::vector<glm::vec3>& surfacePoint, std::vector<uint8_t>& bad) {
  for (size_t q = 0; q < count; ++q) {
    const uint32_t v = vs[q];
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
      return glm::vec3(glm::dot(ed, F.tangent) * tt + glm::dot(ed, F.binormal) * bb + glm::dot(ed, F.normal) * nn);
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
  return e;
}

// The follicles of a layer order with their root zones (the calamus ramp and half the rachis), in a
// grid of cell reachMax.
struct RootZones {
  const std::vector<uint32_t>& order;
  const CoatFeathers& coat;
  const std::vector<double>& rootZone;  // per feather
  double reachMax;
  const detail::PointGrid& grid;  // origins in layer order
};
struct LaterZone {
  dvec3 g;
  double rj, reach;  // the root zone's radius; how far from a triangle's box it can matter
};

// Trims material of the feather k-th in layer order over a later feather's follicle, where that feather
// rises out of the skin: marks every triangle (tris[0..count), not already bad) whose surface projection
// comes within the later feather's root zone. Exact per triangle, so a feather with long triangles (a
// flight feather's barbs) loses only the triangles over the follicle, not a band its edge wide. Returns the
// box of the triangles' surface points.
detail::Box trimOverFollicles(const RootZones& Z, size_t k, const TriMesh& mesh, const uint32_t* tris, size_t count,
                              const std::vector<glm::vec3>& surfacePoint, const std::vector<uint8_t>& bad,
                              std::vector<uint8_t>& overFollicle, std::vector<LaterZone>& later) {
  // The later follicles within reach of its surface points (from the grid, once), then per triangle those
  // whose root zone its box comes near: the follicles the test below can find.
  detail::Box fb;
  for (size_t q = 0; q < count; ++q)
    for (int c = 0; c < 3; ++c) fb.add(dvec3(surfacePoint[mesh.indices[3 * static_cast<size_t>(tris[q]) + c]]));
  if (fb.empty()) return fb;
  later.clear();
  Z.grid.query(fb.lo - dvec3(Z.reachMax), fb.hi + dvec3(Z.reachMax), [&](uint32_t j) {
    if (j <= k) return;
    const uint32_t f = Z.order[j];
    const dvec3& g = Z.coat.frames[f].origin;
    const double rj = Z.rootZone[f];
    // A little past rj: the closest point's rounding never matters.
    const double reach = rj + 1e-6 * (rj + std::max({std::abs(g.x), std::abs(g.y), std::abs(g.z)}));
    later.push_back({g, rj, reach});
  });
  if (later.empty()) return fb;
  for (size_t q = 0; q < count; ++q) {
    const uint32_t t = tris[q];
    const uint32_t* tri = &mesh.indices[3 * static_cast<size_t>(t)];
    if (bad[tri[0]] || bad[tri[1]] || bad[tri[2]]) continue;
    const dvec3 a(surfacePoint[tri[0]]), b(surfacePoint[tri[1]]), c(surfacePoint[tri[2]]);
    const dvec3 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
    for (const LaterZone& L : later) {
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
  return fb;
}

bool isCut(const TriMesh& mesh, size_t t) {
  const uint32_t* tri = &mesh.indices[3 * t];
  return tri[1] == tri[0] && tri[2] == tri[0];
}

// The crossing pairs of live triangles (t < u, as t << 32 | u) with at least one changed triangle: the
// pair search over the live triangles of every feather whose live bounds meet those of a feather with a
// changed live triangle. A pair's test depends on its two triangles alone (and which comes first in the
// mesh, kept here), so these are exactly the changed triangles' pairs of a search over the whole coat.
std::vector<uint64_t> pairsWithChanged(const TriMesh& mesh, const std::vector<uint32_t>& order,
                                       const std::vector<uint32_t>& trisOf, const std::vector<uint32_t>& tris,
                                       const std::vector<uint8_t>& changedTri, const ProgressFn& progress) {
  const size_t n = trisOf.size() - 1, nt = mesh.triangleCount(), nv = mesh.positions.size();
  std::vector<uint8_t> touched(n, 0);   // feathers with a changed live triangle
  std::vector<detail::Box> liveBox(n);  // per feather, its live triangles' bounds
  for (uint32_t i : order)
    for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) {
      const size_t t = tris[q];
      if (isCut(mesh, t)) continue;
      if (changedTri[t]) touched[i] = 1;
      for (int c = 0; c < 3; ++c) liveBox[i].add(dvec3(mesh.positions[mesh.indices[3 * t + c]]));
    }
  std::vector<uint32_t> touchedList;
  for (uint32_t i : order)
    if (touched[i]) touchedList.push_back(i);
  std::vector<uint64_t> pairs;
  if (touchedList.empty()) return pairs;
  std::vector<uint8_t> take(n, 0);
  for (uint32_t i : order) {
    if (liveBox[i].empty()) continue;
    for (uint32_t j : touchedList)
      if (liveBox[i].overlaps(liveBox[j])) {
        take[i] = 1;
        break;
      }
  }
  // The taken feathers' live triangles in mesh order, on their own vertices.
  TriMesh part;
  std::vector<uint32_t> triBack, vertOf(nv, UINT32_MAX);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    if (!take[mesh.featherId[tri[0]]] || isCut(mesh, t)) continue;
    for (int c = 0; c < 3; ++c) {
      uint32_t& w = vertOf[tri[c]];
      if (w == UINT32_MAX) {
        w = static_cast<uint32_t>(part.positions.size());
        part.positions.push_back(mesh.positions[tri[c]]);
        part.featherId.push_back(mesh.featherId[tri[c]]);
      }
      part.indices.push_back(w);
    }
    triBack.push_back(static_cast<uint32_t>(t));
  }
  for (uint64_t pr : intersectingTrianglePairsWith(part, touched, progress)) {
    const uint32_t t = triBack[pr >> 32], u = triBack[pr & 0xffffffffu];
    if (changedTri[t] || changedTri[u]) pairs.push_back((uint64_t(std::min(t, u)) << 32) | std::max(t, u));
  }
  return pairs;
}

// Where laying a chart reads the coat in the air: around its free nodes, within the air radius of the
// line along the normal, to a depth of a quarter of its length (AirTop::highest's reach, and a little).
detail::Box airReadBox(const Chart& C, double airRadius) {
  detail::Box b;
  const double depth = 0.25 * (C.nx - 1) * C.hx;
  for (int k : C.active) {
    const Node& nd = C.nodes[k];
    if (!nd.free) continue;
    const dvec3 r = depth * glm::abs(nd.n) + dvec3(airRadius * (1 + 1e-6) + 1e-9 * (1 + depth));
    b.add(nd.c - r);
    b.add(nd.c + r);
  }
  return b;
}

// Where laying a chart reads: its requirement and covered samples, and the air (airReadBox).
detail::Box readBoxOf(const Chart& C, const CoatTop& top, double airRadius) {
  detail::Box b = airReadBox(C, airRadius);
  for (uint32_t s : C.reqSamples) b.add(top.position(s));
  for (const Chart::Cover& cv : C.under) b.add(top.position(cv.sample));
  return b;
}

// Where a laid chart writes: the samples under its material, and its nodes' lifted points (the air).
detail::Box writeBoxOf(const Chart& C, const CoatTop& top) {
  detail::Box b;
  for (const Chart::Cover& cv : C.under) b.add(top.position(cv.sample));
  for (int k : C.active) b.add(C.nodes[k].c + C.nodes[k].h * C.nodes[k].n);
  return b;
}

// What the last drape kept of one feather (DrapeCache).
struct FeatherMemo {
  bool laid = false;  // it was draped
  // Inputs: the follicle frame, what the drape reads of the parameters, the flat mesh.
  FeatherFrame frame;
  double rachisWidth = 0, calamusLength = 0, totalLength = 0, baseRadius = 0;
  std::vector<glm::vec3> flatPos, flatNrm, flatTan;
  std::vector<uint32_t> flatTris;  // local vertex indices
  // Outputs.
  double shrink = 1, scale = 1, flatEdge = 0, reach = 0, rootZone = 0, elevation = 0;
  Chart chart;                   // laid, after the fold test, with what it gathered
  std::vector<uint32_t> folded;  // nodes the fold test cleared
  std::vector<double> reads;     // what laying it read (readChart)
  std::vector<glm::vec3> pos, nrm, tan, surface;
  std::vector<uint8_t> bad, inside;                // per vertex: trimmed by the chart; under the skin
  std::vector<uint8_t> overFollicle, preCut, cut;  // per triangle: over a later follicle; cut before the pairs; cut
  detail::Box box;                                 // surface points of its triangles
  detail::Box readBox, writeBox;                   // where laying it read (the top's samples, the air) and wrote
};

// A coat mesh's vertices and triangles per feather (CSR, each feather's ascending), each one's place
// among its feather's, and the draped feathers (those with vertices) in layer order.
struct CoatLayout {
  std::vector<uint32_t> first, verts, localVert;  // vertices: verts[first[i] .. first[i + 1])
  std::vector<uint32_t> trisOf, tris, localTri;   // triangles: tris[trisOf[i] .. trisOf[i + 1])
  std::vector<int64_t> rank;                      // place in `order`, -1 = not draped
  std::vector<uint32_t> order;
  // Throws Error for a featherId out of range.
  CoatLayout(const CoatFeathers& coat, const TriMesh& mesh) {
    const size_t n = coat.size(), nv = mesh.positions.size(), nt = mesh.triangleCount();
    first.assign(n + 1, 0);
    verts.resize(nv);
    localVert.resize(nv);
    for (uint32_t f : mesh.featherId) {
      if (f >= n) throw Error("featherId " + std::to_string(f) + " out of range", {}, "featherId");
      ++first[f + 1];
    }
    for (size_t i = 0; i < n; ++i) first[i + 1] += first[i];
    {
      std::vector<uint32_t> fill(first.begin(), first.end() - 1);
      for (uint32_t v = 0; v < nv; ++v) {
        const uint32_t f = mesh.featherId[v];
        localVert[v] = fill[f] - first[f];
        verts[fill[f]++] = v;
      }
    }
    rank.assign(n, -1);
    for (uint32_t i : coat.layerOrder)
      if (i < n && rank[i] < 0 && first[i + 1] > first[i]) {
        rank[i] = static_cast<int64_t>(order.size());
        order.push_back(i);
      }
    trisOf.assign(n + 1, 0);
    tris.resize(nt);
    localTri.resize(nt);
    for (size_t t = 0; t < nt; ++t) ++trisOf[mesh.featherId[mesh.indices[3 * t]] + 1];
    for (size_t i = 0; i < n; ++i) trisOf[i + 1] += trisOf[i];
    std::vector<uint32_t> fill(trisOf.begin(), trisOf.end() - 1);
    for (size_t t = 0; t < nt; ++t) {
      const uint32_t f = mesh.featherId[mesh.indices[3 * t]];
      localTri[t] = fill[f] - trisOf[f];
      tris[fill[f]++] = static_cast<uint32_t>(t);
    }
  }
};

// Sets inside[v] for the vertices of `feathers` only: 1 where the checker counts the vertex as under the
// skin (verticesInsideSkin on those vertices alone; a vertex's test depends on it, its feather's base
// and the skin). Throws Error if the progress callback stopped the test.
void insideSkinFor(const SkinMesh& skin, const TriMesh& mesh, const CoatLayout& L,
                   const std::vector<uint32_t>& feathers, const CheckOptions& co, std::vector<uint8_t>& inside) {
  if (feathers.empty()) return;
  TriMesh part;
  std::vector<uint32_t> back;
  for (uint32_t i : feathers)
    for (uint32_t q = L.first[i]; q < L.first[i + 1]; ++q) {
      back.push_back(L.verts[q]);
      part.positions.push_back(mesh.positions[L.verts[q]]);
      part.featherId.push_back(i);
    }
  const std::vector<uint8_t> in = verticesInsideSkin(skin, part, co);
  if (in.size() != back.size()) throw Error("the drape was cancelled", {}, "drape");
  for (size_t k = 0; k < back.size(); ++k) inside[back[k]] = in[k];
}

// Is feather i of `mesh` (flat, as given to a drape) the one a memo was made from: the same vertices
// (positions, normals, tangents where the mesh has them) and triangles, in the same order?
bool sameFlat(const FeatherMemo& m, const TriMesh& mesh, const CoatLayout& L, uint32_t i) {
  const uint32_t* vs = L.verts.data() + L.first[i];
  const size_t cnt = L.first[i + 1] - L.first[i], tc = L.trisOf[i + 1] - L.trisOf[i];
  const bool hasN = mesh.normals.size() == mesh.positions.size(), hasT = mesh.tangents.size() == mesh.positions.size();
  if (m.flatPos.size() != cnt || m.flatTris.size() != 3 * tc) return false;
  if ((hasN && m.flatNrm.size() != cnt) || (hasT && m.flatTan.size() != cnt)) return false;
  for (size_t q = 0; q < cnt; ++q)
    if (m.flatPos[q] != mesh.positions[vs[q]] || (hasN && m.flatNrm[q] != mesh.normals[vs[q]]) ||
        (hasT && m.flatTan[q] != mesh.tangents[vs[q]]))
      return false;
  for (size_t q = 0; q < tc; ++q)
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = mesh.indices[3 * static_cast<size_t>(L.tris[L.trisOf[i] + q]) + c];
      if (mesh.featherId[v] != i || m.flatTris[3 * q + c] != L.localVert[v]) return false;
    }
  return true;
}

// The drape's counts: draped feathers, overhanging nodes of their charts, and those that lost triangles
// (`cut` per feather) or every triangle (`kept` none).
void tally(DrapeResult& res, const std::vector<uint32_t>& order, const std::vector<size_t>& cut,
           const std::vector<size_t>& kept, const std::function<const Chart&(uint32_t)>& chartOf) {
  for (uint32_t i : order) {
    ++res.stats.draped;
    for (const Node& nd : chartOf(i).nodes) res.stats.overhangingNodes += nd.free && nd.active;
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
}

// A crossing pair of triangles, as feather and triangle within the feather.
struct PairMemo {
  uint32_t fa, ta, fb, tb;
};

}  // namespace

struct DrapeCache::State {
  bool valid = false;
  SkinMesh skin;  // the skin it was laid on (the Surface refers to it)
  std::unique_ptr<Surface> surface;
  double gapOption = 0, spacingOption = 0, maxSlope = 0, baseAllowance = 0;
  int gridAlong = 0, gridAcross = 0;
  double gap = 0, spacing = 0, airRadius = 0;
  std::unique_ptr<CoatTop> top;
  std::vector<FeatherMemo> feathers;
  std::vector<uint32_t> order;
  std::vector<PairMemo> pairs;
  // The skin of the last drape and how many drapes in a row found it moved (drapeCoatMesh).
  std::vector<glm::dvec3> lastSkin;
  int skinMoves = 0;
  bool keepAlways = false;  // keep every drape (drapeOverMature reads the mature coat's)
};

DrapeCache::DrapeCache() : state_(std::make_unique<State>()) {}
DrapeCache::~DrapeCache() = default;
DrapeCache::DrapeCache(DrapeCache&&) noexcept = default;
DrapeCache& DrapeCache::operator=(DrapeCache&&) noexcept = default;
void DrapeCache::clear() {
  const bool keepAlways = state_->keepAlways;
  state_ = std::make_unique<State>();
  state_->keepAlways = keepAlways;
}
void DrapeCache::keepEveryDrape() { state_->keepAlways = true; }
size_t DrapeCache::bytes() const {
  const State& s = *state_;
  size_t b = s.skin.positions.capacity() * sizeof(dvec3) * 3 + s.skin.faces.capacity() * 16 +
             s.pairs.capacity() * sizeof(PairMemo) + (s.top ? s.top->bytes() : 0);
  for (const FeatherMemo& f : s.feathers) {
    b += sizeof(FeatherMemo) + (f.flatPos.capacity() + f.flatNrm.capacity() + f.flatTan.capacity() + f.pos.capacity() +
                                f.nrm.capacity() + f.tan.capacity() + f.surface.capacity()) *
                                   sizeof(glm::vec3);
    b += f.flatTris.capacity() * 4 + f.reads.capacity() * 8 + f.chart.nodes.capacity() * sizeof(Node) +
         f.chart.reqSamples.capacity() * 4 + f.chart.under.capacity() * sizeof(Chart::Cover) + f.chart.fine.capacity() +
         f.bad.capacity() * 2 + f.overFollicle.capacity() * 2;
  }
  return b;
}

struct DrapeAccess {
  static DrapeCache::State& state(DrapeCache& c) { return *c.state_; }
  static const DrapeCache::State& state(const DrapeCache& c) { return *c.state_; }
};

namespace {

bool sameSkin(const SkinMesh& a, const SkinMesh& b) {
  return a.positions.size() == b.positions.size() && a.faces.size() == b.faces.size() &&
         std::equal(a.positions.begin(), a.positions.end(), b.positions.begin()) &&
         std::equal(a.faces.begin(), a.faces.end(), b.faces.begin()) &&
         std::equal(a.vertexNormals.begin(), a.vertexNormals.end(), b.vertexNormals.begin(), b.vertexNormals.end()) &&
         std::equal(a.faceNormals.begin(), a.faceNormals.end(), b.faceNormals.begin(), b.faceNormals.end());
}

bool sameFrame(const FeatherFrame& a, const FeatherFrame& b) {
  return a.origin == b.origin && a.normal == b.normal && a.tangent == b.tangent && a.binormal == b.binormal;
}

template <class T>
bool sameRange(const std::vector<T>& a, const T* b, size_t count) {
  return a.size() == count && std::equal(a.begin(), a.end(), b);
}

// Drapes the coat (M: the cache, or null). With `only`, stops once the gap and spacing are known and
// returns them there (the mesh is left untouched).
DrapeResult drape(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh, const DrapeOptions& o,
                  DrapeCache::State* M, DrapeSpacing* only = nullptr) {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t n = coat.size(), nv = mesh.positions.size();
  if (mesh.featherId.size() != nv) throw Error("the coat mesh needs one featherId per vertex", {}, "featherId");
  if (coat.frames.size() != n || coat.params.size() != n)
    throw Error("the coat needs one frame and one parameter set per feather", {}, "frames");
  DrapeResult res;
  res.elevation.assign(n, 0.0);
  res.trimmed.assign(n, 0);
  res.hidden.assign(n, 0);
  if (nv == 0 || skin.faces.empty()) {
    if (M) *M = DrapeCache::State{};
    return res;
  }
  const CoatLayout L(coat, mesh);
  const std::vector<uint32_t>&first = L.first, &verts = L.verts, &localVert = L.localVert;
  const std::vector<uint32_t>&trisOf = L.trisOf, &tris = L.tris, &localTri = L.localTri;
  const std::vector<int64_t>& rank = L.rank;
  const std::vector<uint32_t>& order = L.order;
  if (order.empty()) {
    if (M) *M = DrapeCache::State{};
    return res;
  }
  const size_t nt = mesh.triangleCount();
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
  const bool hasN = mesh.normals.size() == nv, hasT = mesh.tangents.size() == nv;
  auto baseRadius = [&](uint32_t i) {
    const feather::FeatherParams& p = coat.params[i];
    return std::max(o.baseAllowance * p.totalLength(), 0.5 * p.calamusWidthRatio * p.rachisWidth);
  };
  // The last drape can be reused where the skin, the options and the layers' relative order are the same.
  bool usable = M && M->valid && M->feathers.size() == n && M->gapOption == o.gap && M->spacingOption == o.spacing &&
                M->maxSlope == o.maxSlope && M->baseAllowance == o.baseAllowance && M->gridAlong == o.gridAlong &&
                M->gridAcross == o.gridAcross && sameSkin(M->skin, skin);
  if (usable) {
    // Feathers in both layer orders keep their relative order.
    size_t k = 0;
    for (uint32_t i : M->order) {
      if (rank[i] < 0) continue;
      while (k < order.size() && !M->feathers[order[k]].laid) ++k;
      if (k == order.size() || order[k] != i) {
        usable = false;
        break;
      }
      ++k;
    }
  }
  if (M) {
    M->valid = false;  // until this drape completes
    if (!usable) {
      M->feathers.assign(n, FeatherMemo{});
      M->pairs.clear();
      M->top.reset();
      M->skin = skin;
      M->surface = std::make_unique<Surface>(M->skin);
      M->gapOption = o.gap;
      M->spacingOption = o.spacing;
      M->maxSlope = o.maxSlope;
      M->baseAllowance = o.baseAllowance;
      M->gridAlong = o.gridAlong;
      M->gridAcross = o.gridAcross;
    }
  }
  std::unique_ptr<Surface> ownSurface;
  if (!M) ownSurface = std::make_unique<Surface>(skin);
  const Surface& S = M ? *M->surface : *ownSurface;
  auto memo = [&](uint32_t i) -> FeatherMemo& { return M->feathers[i]; };
  // Per feather: the same inputs as last time (frame, parameters read, flat vertices and triangles).
  std::vector<uint8_t> sameInput(n, 0);
  // Per feather: its follicle, as the later-follicle tests of other feathers see it, changed (or it came
  // or went).
  std::vector<uint8_t> footChanged(n, 0);
  if (usable) {
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const FeatherMemo& m = M->feathers[i];
          const bool laid = rank[i] >= 0;
          const feather::FeatherParams& p = coat.params[i];
          const bool sameFoot =
              laid == m.laid && (!laid || (sameFrame(m.frame, coat.frames[i]) && m.rachisWidth == p.rachisWidth &&
                                           m.calamusLength == p.calamusLength && m.totalLength == p.totalLength()));
          footChanged[i] = !sameFoot;
          if (!laid || !m.laid || !sameFoot || m.baseRadius != baseRadius(static_cast<uint32_t>(i))) continue;
          sameInput[i] = sameFlat(m, mesh, L, static_cast<uint32_t>(i));
        }
      });
    });
  }
  // The flat inputs of the others, before the drape moves them.
  if (M)
    for (uint32_t i : order) {
      if (sameInput[i]) continue;
      FeatherMemo& m = M->feathers[i];
      const size_t cnt = first[i + 1] - first[i], tc = trisOf[i + 1] - trisOf[i];
      m.flatPos.resize(cnt);
      m.flatNrm.resize(hasN ? cnt : 0);
      m.flatTan.resize(hasT ? cnt : 0);
      for (size_t l = 0; l < cnt; ++l) {
        const uint32_t v = verts[first[i] + l];
        m.flatPos[l] = mesh.positions[v];
        if (hasN) m.flatNrm[l] = mesh.normals[v];
        if (hasT) m.flatTan[l] = mesh.tangents[v];
      }
      m.flatTris.resize(3 * tc);
      for (size_t q = 0; q < tc; ++q)
        for (int c = 0; c < 3; ++c)
          m.flatTris[3 * q + c] = localVert[mesh.indices[3 * static_cast<size_t>(tris[trisOf[i] + q]) + c]];
    }
  // Nothing changed: the last drape, copied.
  if (usable && std::none_of(footChanged.begin(), footChanged.end(), [](uint8_t c) { return c != 0; }) &&
      std::all_of(order.begin(), order.end(), [&](uint32_t i) { return sameInput[i] != 0; })) {
    std::vector<size_t> cut(n, 0), kept(n, 0);
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k < r.end(); ++k) {
          const uint32_t i = order[k];
          const FeatherMemo& m = M->feathers[i];
          const glm::vec3 parked(coat.frames[i].origin);
          for (uint32_t q = first[i]; q < first[i + 1]; ++q) {
            const uint32_t v = verts[q], l = q - first[i];
            mesh.positions[v] = m.bad[l] || m.inside[l] ? parked : m.pos[l];
            if (hasN) mesh.normals[v] = m.nrm[l];
            if (hasT) mesh.tangents[v] = m.tan[l];
          }
          for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) {
            uint32_t* tri = &mesh.indices[3 * static_cast<size_t>(tris[q])];
            if (m.cut[q - trisOf[i]]) {
              if (tri[1] == tri[0] && tri[2] == tri[0]) continue;  // collapsed as given
              tri[1] = tri[2] = tri[0];
              ++cut[i];
            } else {
              ++kept[i];
            }
          }
          res.elevation[i] = m.elevation;
        }
      });
    });
    res.stats.gap = M->gap;
    tally(res, order, cut, kept, [&](uint32_t i) -> const Chart& { return M->feathers[i].chart; });
    res.stats.reused = order.size();
    M->order = order;
    M->valid = true;
    step(1);
    res.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return res;
  }
  // Follicles whose change can reach feather i's tests: origins (last and now) of changed follicles.
  std::vector<dvec3> movedFeet;
  if (usable)
    for (size_t j = 0; j < n; ++j)
      if (footChanged[j]) {
        if (M->feathers[j].laid) movedFeet.push_back(M->feathers[j].frame.origin);
        if (rank[j] >= 0) movedFeet.push_back(coat.frames[j].origin);
      }
  // Longest triangle edge per feather as meshed (flat): its chords dip below the skin-following surface by
  // about edge^2 x curvature / 8, which the gap over what lies under it must exceed.
  std::vector<double> flatEdge(n, 0.0);
  for (uint32_t i : order) {
    if (sameInput[i]) {
      flatEdge[i] = memo(i).flatEdge;
      continue;
    }
    for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) {
      const uint32_t* tri = &mesh.indices[3 * static_cast<size_t>(tris[q])];
      for (int k = 0; k < 3; ++k)
        flatEdge[i] =
            std::max(flatEdge[i], double(glm::length(mesh.positions[tri[k]] - mesh.positions[tri[(k + 1) % 3]])));
    }
  }
  // Scale factors: no feather covers a later follicle's root zone.
  std::vector<double> scale(n, 1.0), shrink(n, 1.0), reachOf(n, 0.0);
  {
    std::vector<dvec3> origins;
    double reach = 0;
    for (uint32_t i : order) {
      origins.push_back(coat.frames[i].origin);
      if (sameInput[i]) {
        reachOf[i] = memo(i).reach;
      } else {
        for (uint32_t q = first[i]; q < first[i + 1]; ++q)
          reachOf[i] =
              std::max(reachOf[i], double(glm::length(dvec3(mesh.positions[verts[q]]) - coat.frames[i].origin)));
      }
      reach = std::max(reach, reachOf[i]);
    }
    // A feather's factor depends on its own flat mesh and the later follicles within its reach.
    std::vector<uint32_t> todo;
    for (size_t k = 0; k < order.size(); ++k) {
      const uint32_t i = order[k];
      bool need = !sameInput[i];
      const double r2 = reachOf[i] * (1 + 1e-9) + 1e-12;
      for (size_t m = 0; m < movedFeet.size() && !need; ++m) {
        const dvec3 d = movedFeet[m] - coat.frames[i].origin;
        need = glm::dot(d, d) <= r2 * r2;
      }
      if (need)
        todo.push_back(static_cast<uint32_t>(k));
      else
        shrink[i] = memo(i).shrink;
    }
    detail::PointGrid og;
    og.build(origins, std::max(reach, 1e-12));
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, todo.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<std::pair<glm::dvec2, double>> later;
        for (size_t z = r.begin(); z < r.end(); ++z) {
          const size_t k = todo[z];
          const uint32_t i = order[k];
          const FeatherFrame& F = coat.frames[i];
          const double ri = reachOf[i];
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
          shrink[i] = shrinkScale(F, mesh, verts.data() + first[i], first[i + 1] - first[i], later,
                                  4 * (std::max(2, o.gridAlong) - 1), 4 * (std::max(2, o.gridAcross) - 1), 0.3);
        }
      });
    });
  }
  step(0.03);
  std::vector<Chart> charts(n);
  // Per feather: its chart was built now (else it is the last drape's, laid and fold-tested).
  std::vector<uint8_t> newChart(n, 0);
  {
    std::vector<uint32_t> todo;
    for (uint32_t i : order) {
      if (sameInput[i] && shrink[i] == memo(i).shrink) {
        charts[i] = std::move(memo(i).chart);
        scale[i] = memo(i).scale;
      } else {
        newChart[i] = 1;
        scale[i] = shrink[i];
        todo.push_back(i);
      }
    }
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, todo.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t z = r.begin(); z < r.end(); ++z) {
          const uint32_t i = todo[z];
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
  }
  std::vector<double> lengths;
  for (uint32_t i : order) lengths.push_back(charts[i].hx * (charts[i].nx - 1));
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  const double medianLength = lengths[lengths.size() / 2];
  const double gap = o.gap > 0 ? o.gap : 0.004 * medianLength;
  res.stats.gap = gap;
  std::vector<double> steps;
  for (uint32_t i : order) steps.push_back(std::min(charts[i].hx, charts[i].hy));
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  double spacing = o.spacing > 0 ? o.spacing : std::max(0.75 * steps[steps.size() / 2], 1e-12);
  const double area = skin.totalArea();
  if (area / (spacing * spacing) > 8e6) spacing = std::sqrt(area / 8e6);  // at most about 8M samples
  if (only) {
    *only = {gap, spacing};
    return res;
  }
  step(0.14);
  // The coat's top is reused with the same samples (the same skin and spacing); what was gathered
  // against it, and read from it, stays valid.
  const bool sameTop = usable && M->top && M->spacing == spacing && M->gap == gap;
  std::unique_ptr<CoatTop> ownTop;
  if (M) {
    if (sameTop)
      M->top->reset();
    else
      M->top = std::make_unique<CoatTop>(skin, spacing);
    M->gap = gap;
    M->spacing = spacing;
  } else {
    ownTop = std::make_unique<CoatTop>(skin, spacing);
  }
  CoatTop& top = M ? *M->top : *ownTop;
  step(0.16);
  // Per feather: laid now (its heights, fold test and vertices computed again).
  std::vector<uint8_t> laidNow(n, 0);
  {
    std::vector<uint32_t> todo;
    for (uint32_t i : order)
      if (newChart[i] || !sameTop) {
        todo.push_back(i);
        if (!newChart[i]) {
          // A kept chart gathers again: restore what its last fold test cleared.
          for (uint32_t k : memo(i).folded) charts[i].nodes[k].ok = 1;
          memo(i).folded.clear();
        }
      }
    double airRadius = 1.5 * spacing;
    for (uint32_t i : order) airRadius = std::max(airRadius, 0.75 * charts[i].diag);
    AirTop air(airRadius);
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, todo.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t z = r.begin(); z < r.end(); ++z) gatherSamples(charts[todo[z]], top, 1.5 * spacing);
      });
    });
    step(0.37);
    std::vector<double> req, reads;
    // Where the coat's top or the coat in the air may differ from last time when a feather reads it: the
    // places feathers laid again so far wrote (before and now), and those of feathers gone since. A kept
    // chart whose reads meet none of them reads what it read last time, so it is not read again.
    std::vector<detail::Box> dirty;
    const double airReach = air.radius();
    // The air's radius is the largest chart's: when it changes, every read of the air may.
    const bool sameAir = M && M->airRadius == airReach;
    if (M) M->airRadius = airReach;
    if (M && sameTop)
      for (size_t j = 0; j < n; ++j)
        if (M->feathers[j].laid && rank[j] < 0) dirty.push_back(M->feathers[j].writeBox);
    // The air holds the nodes of the feathers laid so far whose lifted nodes' box meets that of a chart
    // that read it: added when a chart reads it, from the feathers before it whose nodes can be found.
    std::vector<detail::Box> airBox(n);
    std::vector<uint8_t> inAir(n, 0);
    for (size_t k = 0; k < order.size(); ++k) {
      const uint32_t i = order[k];
      Chart& C = charts[i];
      bool mustRead = newChart[i] || !sameTop || !sameAir;
      if (!mustRead) {
        const detail::Box& rb = memo(i).readBox;
        mustRead = std::any_of(dirty.begin(), dirty.end(), [&](const detail::Box& b) { return rb.overlaps(b); });
      }
      bool relay = false;
      if (mustRead) {
        if (readsAir(C)) {
          const detail::Box rb = airReadBox(C, airReach);
          for (size_t j = 0; j < k; ++j) {
            const uint32_t f = order[j];
            if (!inAir[f] && airBox[f].overlaps(rb)) {
              addToAir(charts[f], air);
              inAir[f] = 1;
            }
          }
        }
        readChart(C, top, air, reads);
        relay = newChart[i] || !sameTop || reads != memo(i).reads;
      }
      if (relay) {
        if (!newChart[i] && sameTop) {
          for (uint32_t k : memo(i).folded) C.nodes[k].ok = 1;
          memo(i).folded.clear();
        }
        if (M) dirty.push_back(memo(i).writeBox);
        layFromReads(C, reads, gap, o.maxSlope, req);
        laidNow[i] = 1;
        if (M) {
          memo(i).reads = reads;
          memo(i).readBox = readBoxOf(C, top, airReach);
          memo(i).writeBox = writeBoxOf(C, top);
          dirty.push_back(memo(i).writeBox);
        }
      }
      writeChart(C, top);
      for (int a : C.active) airBox[i].add(C.nodes[a].c + C.nodes[a].h * C.nodes[a].n);
      if (!M) {
        // What was gathered for laying is not needed again.
        C.reqSamples = {};
        C.reqOffset = {};
        C.under = {};
      }
    }
    step(0.46);
  }
  std::vector<uint32_t> relaid;
  for (uint32_t i : order)
    if (laidNow[i]) {
      relaid.push_back(i);
      if (M) memo(i).folded.clear();
    }
  // A node whose lifted point has other skin closer than half its height sits in a fold: not draped.
  // (Thin parts keep their coat: a node's height goes out along its own normal, away from the other
  // side, and past a thin part's rim the feather overhangs instead of wrapping onto the other side.)
  detail::inArena(o.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, relaid.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t z = r.begin(); z < r.end(); ++z) {
        const uint32_t i = relaid[z];
        std::vector<Node>& nodes = charts[i].nodes;
        for (size_t k = 0; k < nodes.size(); ++k) {
          Node& nd = nodes[k];
          if (nd.ok && nd.active && S.skinWithin(nd.c + nd.h * nd.n, 0.5 * nd.h * (1 - 1e-9))) {
            nd.ok = 0;
            if (M) memo(i).folded.push_back(static_cast<uint32_t>(k));
          }
        }
      }
    });
  });
  // Move every vertex; remember its surface point for trimming.
  std::vector<glm::vec3> surfacePoint(nv);
  std::vector<uint8_t> bad(nv, 0);
  detail::inArena(o.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        const uint32_t i = order[k];
        if (!laidNow[i]) {
          // The last drape's vertices.
          const FeatherMemo& m = memo(i);
          for (uint32_t q = first[i]; q < first[i + 1]; ++q) {
            const uint32_t v = verts[q], l = q - first[i];
            mesh.positions[v] = m.pos[l];
            if (hasN) mesh.normals[v] = m.nrm[l];
            if (hasT) mesh.tangents[v] = m.tan[l];
            surfacePoint[v] = m.surface[l];
            bad[v] = m.bad[l];
          }
          res.elevation[i] = m.elevation;
          continue;
        }
        res.elevation[i] = placeOnChart(charts[i], coat.frames[i], mesh, verts.data() + first[i],
                                        first[i + 1] - first[i], hasN, hasT, surfacePoint, bad);
      }
    });
  });
  step(0.5);
  // Trim lower feathers' material over a later feather's follicle, where that feather rises out of the
  // skin: every triangle whose surface projection comes within the later feather's root zone (its calamus
  // ramp and half its rachis) of that follicle. Exact per triangle, so a feather with long triangles
  // (a flight feather's barbs) loses only the triangles over the follicle, not a band its edge wide.
  std::vector<dvec3> origins;
  std::vector<double> rootZone(n, 0.0);
  double reachMax = 0;
  for (uint32_t i : order) {
    origins.push_back(coat.frames[i].origin);
    rootZone[i] = charts[i].ramp + 0.5 * coat.params[i].rachisWidth;
    reachMax = std::max(reachMax, rootZone[i]);
  }
  std::vector<detail::Box> surfaceBox(n);
  std::vector<uint8_t> overFollicle(nt, 0);
  {
    // A feather's triangles are tested again when it was laid again, or a follicle whose root zone
    // changed (or that came or went) is near its triangles.
    std::vector<dvec3> zoneFeet;
    std::vector<double> zoneRadius;
    if (usable)
      for (size_t j = 0; j < n; ++j) {
        const FeatherMemo& m = M->feathers[j];
        const bool laid = rank[j] >= 0;
        if (laid == m.laid && (!laid || (m.frame.origin == coat.frames[j].origin && m.rootZone == rootZone[j])))
          continue;
        const double rz = std::max(laid ? rootZone[j] : 0.0, m.laid ? m.rootZone : 0.0);
        if (m.laid) {
          zoneFeet.push_back(m.frame.origin);
          zoneRadius.push_back(rz);
        }
        if (laid) {
          zoneFeet.push_back(coat.frames[j].origin);
          zoneRadius.push_back(rz);
        }
      }
    std::vector<uint8_t> retest(n, 0);
    for (uint32_t i : order) {
      if (laidNow[i] || !usable) {
        retest[i] = 1;
        continue;
      }
      const detail::Box& b = memo(i).box;
      surfaceBox[i] = b;
      if (b.empty()) continue;
      for (size_t m = 0; m < zoneFeet.size() && !retest[i]; ++m) {
        const double r = 2 * zoneRadius[m] + 1e-6 * (1 + glm::length(zoneFeet[m]));
        const dvec3 g = zoneFeet[m];
        retest[i] = g.x >= b.lo.x - r && g.y >= b.lo.y - r && g.z >= b.lo.z - r && g.x <= b.hi.x + r &&
                    g.y <= b.hi.y + r && g.z <= b.hi.z + r;
      }
      if (!retest[i]) {
        const FeatherMemo& m = memo(i);
        for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) overFollicle[tris[q]] = m.overFollicle[q - trisOf[i]];
      }
    }
    // Per feather the later follicles within reach of its surface points (from the grid, once), then
    // per triangle those whose root zone its box comes near: the follicles the test below can find.
    detail::PointGrid grid;
    grid.build(origins, std::max(reachMax, 1e-12));
    const RootZones zones{order, coat, rootZone, reachMax, grid};
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<LaterZone> later;
        for (size_t k = r.begin(); k < r.end(); ++k) {
          const uint32_t i = order[k];
          if (!retest[i]) continue;
          surfaceBox[i] = trimOverFollicles(zones, k, mesh, tris.data() + trisOf[i], trisOf[i + 1] - trisOf[i],
                                            surfacePoint, bad, overFollicle, later);
        }
      });
    });
  }
  // Vertices under the skin, tested again only for feathers laid again (a test of one vertex depends on
  // its position, its feather's base and the skin).
  std::vector<uint8_t> inside(nv, 0);
  {
    step(0.53);
    CheckOptions co;
    setFeatherBases(co, coat, o.baseAllowance);
    co.progress = within(0.53, 0.65);
    if (!usable || relaid.size() == order.size()) {
      inside = verticesInsideSkin(skin, mesh, co);
    } else {
      for (uint32_t i : order)
        if (!laidNow[i])
          for (uint32_t q = first[i]; q < first[i + 1]; ++q) inside[verts[q]] = memo(i).inside[q - first[i]];
      insideSkinFor(skin, mesh, L, relaid, co, inside);
    }
    if (inside.size() != nv) throw Error("the drape was cancelled", {}, "drape");
  }
  // Keep what the trims and tests below need of this drape's own outputs before trimming moves vertices.
  if (M) {
    for (uint32_t i : relaid) {
      FeatherMemo& m = memo(i);
      const size_t cnt = first[i + 1] - first[i];
      m.pos.resize(cnt);
      m.nrm.resize(hasN ? cnt : 0);
      m.tan.resize(hasT ? cnt : 0);
      m.surface.resize(cnt);
      m.bad.resize(cnt);
      for (size_t l = 0; l < cnt; ++l) {
        const uint32_t v = verts[first[i] + l];
        m.pos[l] = mesh.positions[v];
        if (hasN) m.nrm[l] = mesh.normals[v];
        if (hasT) m.tan[l] = mesh.tangents[v];
        m.surface[l] = surfacePoint[v];
        m.bad[l] = bad[v];
      }
      m.elevation = res.elevation[i];
    }
  }
  for (uint32_t v = 0; v < nv; ++v)
    if (inside[v] && rank[mesh.featherId[v]] >= 0) bad[v] = 1;
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
  // Crossing pairs. With the last drape's pairs: a pair of triangles both unchanged (same feather input,
  // not laid again, cut before the pairs as before) crosses as it did; pairs with a changed triangle are
  // searched among the triangles near the changed ones.
  std::vector<uint64_t> pairs;
  if (!usable) {
    pairs = intersectingTrianglePairs(mesh, within(0.65, 1));
  } else {
    std::vector<uint8_t> changedTri(nt, 0);
    for (uint32_t i : order)
      for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q)
        changedTri[tris[q]] = laidNow[i] || memo(i).preCut[q - trisOf[i]] != (isCut(mesh, tris[q]) ? 1 : 0);
    for (const PairMemo& pm : M->pairs) {
      if (rank[pm.fa] < 0 || rank[pm.fb] < 0 || laidNow[pm.fa] || laidNow[pm.fb]) continue;
      if (pm.ta >= trisOf[pm.fa + 1] - trisOf[pm.fa] || pm.tb >= trisOf[pm.fb + 1] - trisOf[pm.fb]) continue;
      const uint32_t t = tris[trisOf[pm.fa] + pm.ta], u = tris[trisOf[pm.fb] + pm.tb];
      if (changedTri[t] || changedTri[u] || isCut(mesh, t) || isCut(mesh, u)) continue;
      pairs.push_back((uint64_t(std::min(t, u)) << 32) | std::max(t, u));
    }
    const std::vector<uint64_t> found = pairsWithChanged(mesh, order, trisOf, tris, changedTri, within(0.65, 1));
    pairs.insert(pairs.end(), found.begin(), found.end());
    std::sort(pairs.begin(), pairs.end());
  }
  // Of every crossing pair, the lower feather's triangle goes.
  std::vector<uint8_t> preCut;
  if (M) {
    preCut.resize(nt);
    for (size_t t = 0; t < nt; ++t) preCut[t] = isCut(mesh, t) ? 1 : 0;
  }
  for (uint64_t pr : pairs) {
    const size_t t = pr >> 32, u = pr & 0xffffffffu;
    const uint32_t ft = mesh.featherId[mesh.indices[3 * t]], fu = mesh.featherId[mesh.indices[3 * u]];
    if (rank[ft] < 0 || rank[fu] < 0) continue;
    collapse(rank[ft] < rank[fu] ? t : u);
  }
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    if (tri[1] != tri[0] || tri[2] != tri[0]) ++kept[mesh.featherId[tri[0]]];
  }
  tally(res, order, cut, kept, [&](uint32_t i) -> const Chart& { return charts[i]; });
  res.stats.relaid = relaid.size();
  res.stats.reused = order.size() - relaid.size();
  if (M) {
    // Keep this drape for the next.
    for (size_t i = 0; i < n; ++i) {
      FeatherMemo& m = memo(static_cast<uint32_t>(i));
      if (rank[i] < 0) {
        m = FeatherMemo{};
        continue;
      }
      m.laid = true;
      m.chart = std::move(charts[i]);
      m.shrink = shrink[i];
      m.scale = scale[i];
      m.flatEdge = flatEdge[i];
      m.reach = reachOf[i];
      m.rootZone = rootZone[i];
      m.box = surfaceBox[i];
      const size_t tc = trisOf[i + 1] - trisOf[i];
      m.overFollicle.resize(tc);
      m.preCut.resize(tc);
      m.cut.resize(tc);
      for (size_t q = 0; q < tc; ++q) {
        m.overFollicle[q] = overFollicle[tris[trisOf[i] + q]];
        m.preCut[q] = preCut[tris[trisOf[i] + q]];
        m.cut[q] = isCut(mesh, tris[trisOf[i] + q]) ? 1 : 0;
      }
      if (laidNow[i]) {
        const size_t cnt = first[i + 1] - first[i];
        m.inside.resize(cnt);
        for (size_t l = 0; l < cnt; ++l) m.inside[l] = inside[verts[first[i] + l]];
      }
      if (!sameInput[i]) {
        const feather::FeatherParams& p = coat.params[i];
        m.frame = coat.frames[i];
        m.rachisWidth = p.rachisWidth;
        m.calamusLength = p.calamusLength;
        m.totalLength = p.totalLength();
        m.baseRadius = baseRadius(static_cast<uint32_t>(i));
      }
    }
    M->order = order;
    M->pairs.clear();
    for (uint64_t pr : pairs) {
      const uint32_t t = static_cast<uint32_t>(pr >> 32), u = static_cast<uint32_t>(pr & 0xffffffffu);
      const uint32_t ft = mesh.featherId[mesh.indices[3 * static_cast<size_t>(t)]],
                     fu = mesh.featherId[mesh.indices[3 * static_cast<size_t>(u)]];
      M->pairs.push_back({ft, localTri[t], fu, localTri[u]});
    }
    M->valid = true;
  }
  res.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

// drapeOverMature (drape.hpp).
DrapeResult drapeOver(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh, const DrapeCache::State& M,
                      const DrapeOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t n = coat.size(), nv = mesh.positions.size();
  if (mesh.featherId.size() != nv) throw Error("the coat mesh needs one featherId per vertex", {}, "featherId");
  if (coat.frames.size() != n || coat.params.size() != n)
    throw Error("the coat needs one frame and one parameter set per feather", {}, "frames");
  if (!M.valid) throw Error("the mature coat has not been draped", {}, "mature");
  if (M.feathers.size() != n)
    throw Error(
        "the mature coat has " + std::to_string(M.feathers.size()) + " feathers, this frame " + std::to_string(n), {},
        "mature");
  if (!sameSkin(M.skin, skin)) throw Error("the mature coat was draped over another skin", {}, "mature");
  DrapeResult res;
  res.elevation.assign(n, 0.0);
  res.trimmed.assign(n, 0);
  res.hidden.assign(n, 0);
  res.stats.gap = M.gap;
  if (nv == 0) return res;
  const CoatLayout L(coat, mesh);
  const std::vector<uint32_t>&first = L.first, &verts = L.verts, &trisOf = L.trisOf, &tris = L.tris;
  const std::vector<int64_t>& rank = L.rank;
  const std::vector<uint32_t>& order = L.order;
  for (uint32_t i : order)
    if (!M.feathers[i].laid) throw Error("feather " + std::to_string(i) + " has no mature drape", {}, "mature");
  {
    // This frame's layers keep the mature coat's order.
    size_t k = 0;
    for (uint32_t i : M.order)
      if (k < order.size() && order[k] == i) ++k;
    if (k != order.size()) throw Error("the frame's layer order differs from the mature coat's", {}, "layerOrder");
  }
  const size_t nt = mesh.triangleCount();
  const bool hasN = mesh.normals.size() == nv, hasT = mesh.tangents.size() == nv;
  report(o.progress, "drape", 0);
  // Per feather: its flat mesh is the mature drape's (copied), else placed on its mature chart.
  std::vector<uint8_t> placed(n, 0);
  std::vector<glm::vec3> surfacePoint(nv);
  std::vector<uint8_t> bad(nv, 0), inside(nv, 0), overFollicle(nt, 0);
  detail::inArena(o.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        const uint32_t i = order[k];
        const FeatherMemo& m = M.feathers[i];
        const uint32_t* vs = verts.data() + first[i];
        const size_t cnt = first[i + 1] - first[i], tc = trisOf[i + 1] - trisOf[i];
        const bool same = sameFrame(m.frame, coat.frames[i]) && sameFlat(m, mesh, L, i);
        if (same) {
          for (size_t l = 0; l < cnt; ++l) {
            const uint32_t v = vs[l];
            mesh.positions[v] = m.pos[l];
            if (hasN) mesh.normals[v] = m.nrm[l];
            if (hasT) mesh.tangents[v] = m.tan[l];
            surfacePoint[v] = m.surface[l];
            bad[v] = m.bad[l];
            inside[v] = m.inside[l];
          }
          for (size_t q = 0; q < tc; ++q) overFollicle[tris[trisOf[i] + q]] = m.overFollicle[q];
          res.elevation[i] = m.elevation;
        } else {
          placed[i] = 1;
          res.elevation[i] = placeOnChart(m.chart, coat.frames[i], mesh, vs, cnt, hasN, hasT, surfacePoint, bad);
        }
      }
    });
  });
  std::vector<uint32_t> placedList;
  for (uint32_t i : order)
    if (placed[i]) placedList.push_back(i);
  report(o.progress, "drape", 0.3);
  // Placed feathers' material over a later follicle of this frame.
  {
    std::vector<dvec3> origins;
    std::vector<double> rootZone(n, 0.0);
    double reachMax = 0;
    for (uint32_t i : order) {
      origins.push_back(coat.frames[i].origin);
      rootZone[i] = M.feathers[i].rootZone;
      reachMax = std::max(reachMax, rootZone[i]);
    }
    detail::PointGrid grid;
    grid.build(origins, std::max(reachMax, 1e-12));
    const RootZones zones{order, coat, rootZone, reachMax, grid};
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, placedList.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<LaterZone> later;
        for (size_t z = r.begin(); z < r.end(); ++z) {
          const uint32_t i = placedList[z];
          trimOverFollicles(zones, static_cast<size_t>(rank[i]), mesh, tris.data() + trisOf[i],
                            trisOf[i + 1] - trisOf[i], surfacePoint, bad, overFollicle, later);
        }
      });
    });
  }
  // Placed feathers' vertices under the skin.
  if (!placedList.empty()) {
    CheckOptions co;
    setFeatherBases(co, coat, o.baseAllowance);
    insideSkinFor(skin, mesh, L, placedList, co, inside);
  }
  report(o.progress, "drape", 0.6);
  for (uint32_t v = 0; v < nv; ++v)
    if (inside[v]) bad[v] = 1;
  std::vector<size_t> kept(n, 0), cut(n, 0);
  auto collapse = [&](size_t t) {
    uint32_t* tri = &mesh.indices[3 * t];
    if (tri[1] == tri[0] && tri[2] == tri[0]) return;
    tri[1] = tri[2] = tri[0];
    ++cut[mesh.featherId[tri[0]]];
  };
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    if (overFollicle[t] || bad[tri[0]] || bad[tri[1]] || bad[tri[2]]) collapse(t);
  }
  for (uint32_t v = 0; v < nv; ++v)
    if (bad[v]) mesh.positions[v] = glm::vec3(coat.frames[mesh.featherId[v]].origin);
  // Crossing pairs: the mature drape's pairs of two copied feathers' live triangles, and those of the
  // placed feathers' triangles searched here. A pair with a lost feather is gone, and its lower triangle
  // stays.
  std::vector<uint64_t> pairs;
  for (const PairMemo& pm : M.pairs) {
    if (rank[pm.fa] < 0 || rank[pm.fb] < 0 || placed[pm.fa] || placed[pm.fb]) continue;
    const uint32_t t = tris[trisOf[pm.fa] + pm.ta], u = tris[trisOf[pm.fb] + pm.tb];
    if (isCut(mesh, t) || isCut(mesh, u)) continue;
    pairs.push_back((uint64_t(std::min(t, u)) << 32) | std::max(t, u));
  }
  {
    std::vector<uint8_t> changedTri(nt, 0);
    for (uint32_t i : placedList)
      for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) changedTri[tris[q]] = 1;
    const std::vector<uint64_t> found = pairsWithChanged(mesh, order, trisOf, tris, changedTri, {});
    pairs.insert(pairs.end(), found.begin(), found.end());
  }
  for (uint64_t pr : pairs) {
    const size_t t = pr >> 32, u = pr & 0xffffffffu;
    const uint32_t ft = mesh.featherId[mesh.indices[3 * t]], fu = mesh.featherId[mesh.indices[3 * u]];
    collapse(rank[ft] < rank[fu] ? t : u);
  }
  for (size_t t = 0; t < nt; ++t)
    if (!isCut(mesh, t)) ++kept[mesh.featherId[mesh.indices[3 * t]]];
  tally(res, order, cut, kept, [&](uint32_t i) -> const Chart& { return M.feathers[i].chart; });
  res.stats.relaid = placedList.size();
  res.stats.reused = order.size() - placedList.size();
  report(o.progress, "drape", 1);
  res.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace

DrapeResult drapeCoatMesh(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh, const DrapeOptions& o) {
  return drape(skin, coat, mesh, o, nullptr);
}

DrapeResult drapeOverMature(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh, const DrapeCache& mature,
                            const DrapeOptions& o) {
  return drapeOver(skin, coat, mesh, DrapeAccess::state(mature), o);
}

DrapeSpacing drapeSpacing(const SkinMesh& skin, const CoatFeathers& coat, const TriMesh& mesh, const DrapeOptions& o) {
  DrapeSpacing out;
  TriMesh& unchanged = const_cast<TriMesh&>(mesh);  // read only: drape() returns before it moves anything
  DrapeOptions quiet = o;
  quiet.progress = {};
  drape(skin, coat, unchanged, quiet, nullptr, &out);
  if (out.spacing == 0) out.gap = o.gap;  // nothing to drape
  return out;
}

DrapeResult drapeCoatMesh(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh, const DrapeOptions& o,
                          DrapeCache& cache) {
  DrapeCache::State& M = DrapeAccess::state(cache);
  // A skin that moved at each of the last two drapes (an animated pose) leaves nothing a drape could
  // reuse at the next, so none is kept until it holds still (the result is the same either way).
  const bool moved = !M.lastSkin.empty() && M.lastSkin != skin.positions;
  M.skinMoves = moved ? M.skinMoves + 1 : 0;
  M.lastSkin = skin.positions;
  const bool keep = M.keepAlways || M.skinMoves < 2;
  if (!keep && (M.valid || !M.feathers.empty())) {
    DrapeCache::State fresh;
    fresh.lastSkin = std::move(M.lastSkin);
    fresh.skinMoves = M.skinMoves;
    M = std::move(fresh);
  }
  try {
    return drape(skin, coat, mesh, o, keep ? &M : nullptr);
  } catch (...) {
    cache.clear();
    throw;
  }
}

}  // namespace pteryla::coat
