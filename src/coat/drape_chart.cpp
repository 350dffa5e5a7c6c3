// Surface charts of the draped packer (drape_internal.hpp): built along the skin, gathered against the
// coat's top, laid over what they read, and written back.
#include "drape_internal.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace pteryla::coat::draping {

using glm::dvec3;

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
  C.overhanging = 0;
  C.faces.clear();
  for (const Node& nd : C.nodes) {
    C.overhanging += nd.free && nd.active;
    if (nd.face >= 0) C.faces.push_back(nd.face);
  }
  std::sort(C.faces.begin(), C.faces.end());
  C.faces.erase(std::unique(C.faces.begin(), C.faces.end()), C.faces.end());
}

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

void gatherSamples(Chart& C, const CoatTop& top, double reqRadius) {
  C.active.clear();
  C.reqOffset.assign(1, 0);
  C.reqSamples.clear();
  C.under.clear();
  // Each sample once, from the first node (in node order) that reached it: a sample this chart has
  // taken is marked (this thread's marks, a generation per gather), and later nodes skip it.
  thread_local std::vector<uint32_t> taken;
  thread_local uint32_t generation = 0;
  if (taken.size() < top.size()) taken.assign(top.size(), 0);
  if (++generation == 0) {
    std::fill(taken.begin(), taken.end(), 0);
    generation = 1;
  }
  const uint32_t mark = generation;
  uint32_t* const takenBy = taken.data();  // (one look-up of the thread's vector)
  // One look-up per node for both radii: the samples it reads (reqRadius) and those it may cover.
  const double coverRadius = 0.75 * C.diag;
  const double req2 = reqRadius * reqRadius, cover2 = coverRadius * coverRadius;
  for (int k = 0; k < C.nx * C.ny; ++k) {
    const Node& nd = C.nodes[k];
    if (!nd.ok || !nd.active) continue;
    C.active.push_back(k);
    const double xa = C.x0 + (k / C.ny) * C.hx, yb = C.y0 + (k % C.ny) * C.hy;
    const dvec3 bn = glm::cross(nd.n, nd.t);
    top.nearAll(nd.c, nd.n, std::max(reqRadius, coverRadius), [&](uint32_t s, const dvec3& d, double dd) {
      if (dd <= req2) C.reqSamples.push_back(s);
      if (!(dd <= cover2) || takenBy[s] == mark) return;
      const double x = xa + glm::dot(d, nd.t), y = yb + glm::dot(d, bn);
      if (!C.covers(x, y)) return;
      int a, b;
      double u, v;
      C.locate(x, y, a, b, u, v);
      for (const Node* c : {&C.at(a, b), &C.at(a + 1, b), &C.at(a, b + 1), &C.at(a + 1, b + 1)})
        if (!c->ok || !c->active) return;
      takenBy[s] = mark;
      C.under.push_back(
          {s, static_cast<uint16_t>(a), static_cast<uint16_t>(b), static_cast<float>(u), static_cast<float>(v)});
    });
    C.reqOffset.push_back(static_cast<uint32_t>(C.reqSamples.size()));
  }
  C.under.shrink_to_fit();
  C.reqSamples.shrink_to_fit();
}

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
    double highest = -std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < idx.size(); ++j) highest = std::max(highest, req[j]);
    if (maxSlope > 0 && C.hx > 0 && C.hy > 0) {
      // A node farther than (highest - h) / maxSlope cannot raise one at height h: each node looks only
      // at the grid window within that reach, skipping nodes no higher than it has got (as the sorted
      // scan below stops at them). The same candidates' same values: the same maximum.
      thread_local std::vector<double> grid;
      grid.assign(static_cast<size_t>(C.nx) * C.ny, -std::numeric_limits<double>::infinity());
      for (size_t j = 0; j < idx.size(); ++j) grid[static_cast<size_t>(idx[j])] = req[j];
      for (size_t j = 0; j < idx.size(); ++j) {
        const int aj = idx[j] / C.ny, bj = idx[j] % C.ny;
        double h = req[j];
        const double reach = (highest - h) / maxSlope;
        if (reach > 0) {
          const double wa = std::floor(reach / C.hx) + 1, wb = std::floor(reach / C.hy) + 1;
          const int a0 = wa >= aj ? 0 : aj - static_cast<int>(wa);
          const int a1 = wa >= C.nx - 1 - aj ? C.nx - 1 : aj + static_cast<int>(wa);
          const int b0 = wb >= bj ? 0 : bj - static_cast<int>(wb);
          const int b1 = wb >= C.ny - 1 - bj ? C.ny - 1 : bj + static_cast<int>(wb);
          for (int a = a0; a <= a1; ++a) {
            const double* row = grid.data() + static_cast<size_t>(a) * C.ny;
            for (int b = b0; b <= b1; ++b) {
              if (!(row[b] > h)) continue;
              const double dx = (a - aj) * C.hx, dy = (b - bj) * C.hy;
              h = std::max(h, row[b] - maxSlope * std::sqrt(dx * dx + dy * dy));
            }
          }
        }
        C.nodes[idx[j]].h = h;
      }
      return;
    }
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

}  // namespace pteryla::coat::draping
