// Draped packing (drape.hpp): feathers laid on the skin along surface charts and stacked by height over
// the skin, in layer order.
#include "pteryla/coat/drape.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <thread>
#include <unordered_map>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include "pteryla/core/error.hpp"
#include "pteryla/coat/check.hpp"
#include "drape_surfaces.hpp"
#include "spatial.hpp"

#include "drape_internal.hpp"

namespace pteryla::coat {

using glm::dvec3;

using namespace draping;

namespace {

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
  const std::vector<uint32_t>&first = L.first, &verts = L.verts;
  const std::vector<uint32_t>&trisOf = L.trisOf, &tris = L.tris;
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
                M->gridAcross == o.gridAcross && !M->carried && sameSkin(M->skin, skin);
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
      M->carried = false;
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
  // The flat inputs of the others, before the drape moves them (each feather's own memo: in parallel).
  if (M)
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(size_t(0), order.size(), [&](size_t z) {
        const uint32_t i = order[z];
        if (!sameInput[i]) keepFlat(M->feathers[i], mesh, L, i);
      });
    });
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
  // It and each feather's reach from its follicle (below) are the feather's own: found in parallel.
  std::vector<double> flatEdge(n, 0.0);
  std::vector<double> scale(n, 1.0), shrink(n, 1.0), reachOf(n, 0.0);
  detail::inArena(o.threads, [&] {
    tbb::parallel_for(size_t(0), order.size(), [&](size_t z) {
      const uint32_t i = order[z];
      if (sameInput[i]) {
        flatEdge[i] = memo(i).flatEdge;
        reachOf[i] = memo(i).reach;
        return;
      }
      for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) {
        const uint32_t* tri = &mesh.indices[3 * static_cast<size_t>(tris[q])];
        for (int k = 0; k < 3; ++k)
          flatEdge[i] =
              std::max(flatEdge[i], double(glm::length(mesh.positions[tri[k]] - mesh.positions[tri[(k + 1) % 3]])));
      }
      for (uint32_t q = first[i]; q < first[i + 1]; ++q)
        reachOf[i] = std::max(reachOf[i], double(glm::length(dvec3(mesh.positions[verts[q]]) - coat.frames[i].origin)));
    });
  });
  // Scale factors: no feather covers a later follicle's root zone.
  {
    std::vector<dvec3> origins;
    double reach = 0;
    for (uint32_t i : order) {
      origins.push_back(coat.frames[i].origin);
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
    // Cells of the median reach: a body feather's look-up does not scan the cells a flight feather needs
    // (the test below is whether any later follicle is covered: the order found does not matter).
    std::vector<double> reaches;
    for (uint32_t i : order) reaches.push_back(reachOf[i]);
    std::nth_element(reaches.begin(), reaches.begin() + reaches.size() / 2, reaches.end());
    detail::PointGrid og;
    og.build(origins, std::max(reaches.empty() ? reach : reaches[reaches.size() / 2], 1e-12 * std::max(reach, 1.0)));
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
      detail::inArena(o.threads, [&] { M->top = std::make_unique<CoatTop>(skin, spacing); });
    M->gap = gap;
    M->spacing = spacing;
  } else {
    detail::inArena(o.threads, [&] { ownTop = std::make_unique<CoatTop>(skin, spacing); });
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
    // Gathering (in parallel) and laying (in layer order, on this thread) overlap: a chart is gathered by
    // whichever thread claims it first, and laying waits only for the chart it lays next (it gathers that
    // one itself when no one has claimed it). Gathering reads the top's samples and never their heights,
    // which laying writes, so each chart gathers what it would have gathered before any laying.
    std::unique_ptr<std::atomic<uint8_t>[]> gathered(new std::atomic<uint8_t>[n]);  // 0 to do, 1 claimed, 2 done
    for (size_t i = 0; i < n; ++i) gathered[i].store(2, std::memory_order_relaxed);
    for (uint32_t i : todo) gathered[i].store(0, std::memory_order_relaxed);
    std::atomic<bool> gatherFailed{false};
    auto claimAndGather = [&](uint32_t i) {
      uint8_t expect = 0;
      if (!gathered[i].compare_exchange_strong(expect, 1, std::memory_order_acq_rel)) return;
      gatherSamples(charts[i], top, 1.5 * spacing);
      gathered[i].store(2, std::memory_order_release);
    };
    // Laying waits for chart i; while another thread gathers it, it gathers the next unclaimed ones.
    size_t ahead = 0;
    auto awaitGathered = [&](uint32_t i) {
      claimAndGather(i);
      while (gathered[i].load(std::memory_order_acquire) != 2) {
        if (gatherFailed.load(std::memory_order_acquire)) throw Error("gathering a chart failed", {}, "drape");
        while (ahead < todo.size() && gathered[todo[ahead]].load(std::memory_order_relaxed) != 0) ++ahead;
        if (ahead < todo.size())
          claimAndGather(todo[ahead]);
        else
          std::this_thread::yield();
      }
    };
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
    // When every chart reads anyway (a first drape, a new top or air), the dirty places are never looked
    // at: the read and write boxes are kept after the loop, in parallel.
    const bool allRead =
        !sameTop || !sameAir || std::all_of(order.begin(), order.end(), [&](uint32_t i) { return newChart[i] != 0; });
    auto layAll = [&] {
      for (size_t k = 0; k < order.size(); ++k) {
        const uint32_t i = order[k];
        awaitGathered(i);
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
            if (!allRead) {
              memo(i).readBox = readBoxOf(C, top, airReach);
              memo(i).writeBox = writeBoxOf(C, top);
              dirty.push_back(memo(i).writeBox);
            }
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
    };
    detail::inArena(o.threads, [&] {
      tbb::task_group gathering;
      gathering.run([&] {
        try {
          tbb::parallel_for(tbb::blocked_range<size_t>(0, todo.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t z = r.begin(); z < r.end(); ++z) claimAndGather(todo[z]);
          });
        } catch (...) {
          gatherFailed.store(true, std::memory_order_release);
          throw;
        }
      });
      try {
        layAll();
      } catch (...) {
        gathering.cancel();
        gathering.wait();
        throw;
      }
      gathering.wait();
    });
    step(0.37);
    if (M && allRead) {
      std::vector<uint32_t> laid;
      for (uint32_t i : order)
        if (laidNow[i]) laid.push_back(i);
      detail::inArena(o.threads, [&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, laid.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
          for (size_t z = r.begin(); z < r.end(); ++z) {
            const uint32_t i = laid[z];
            memo(i).readBox = readBoxOf(charts[i], top, airReach);
            memo(i).writeBox = writeBoxOf(charts[i], top);
          }
        });
      });
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
  if (M)
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(size_t(0), relaid.size(), [&](size_t z) {
        const uint32_t i = relaid[z];
        keepPlaced(memo(i), mesh, L, i, surfacePoint, bad);
        memo(i).elevation = res.elevation[i];
      });
    });
  for (uint32_t v = 0; v < nv; ++v)
    if (inside[v] && rank[mesh.featherId[v]] >= 0) bad[v] = 1;
  std::vector<size_t> kept(n, 0), cut(n, 0);
  auto collapse = [&](size_t t) { collapseTriangle(mesh, t, cut); };
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
    // Keep this drape for the next (each feather's own memo: in parallel).
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(size_t(0), n, [&](size_t i) {
        FeatherMemo& m = memo(static_cast<uint32_t>(i));
        if (rank[i] < 0) {
          m = FeatherMemo{};
          return;
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
      });
    });
    M->order = order;
    M->pairs = pairMemos(pairs, mesh, L);
    M->valid = true;
  }
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

DrapeResult drapeCarried(const SkinMesh& rest, const SkinMesh& posed, const CoatFeathers& coat, TriMesh& mesh,
                         const DrapeCache& reference, const DrapeOptions& o, DrapeCache* out) {
  if (out == &reference) throw Error("the carried drape cannot be kept in its own reference", {}, "reference");
  DrapeCache::State* W = nullptr;
  if (out) {
    W = &DrapeAccess::state(*out);
    const bool keepAlways = W->keepAlways;
    *W = DrapeCache::State{};
    W->keepAlways = keepAlways;
  }
  try {
    return carry(rest, posed, coat, mesh, DrapeAccess::state(reference), o, W);
  } catch (...) {
    if (out) out->clear();
    throw;
  }
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
