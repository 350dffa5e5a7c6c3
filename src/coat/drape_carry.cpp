// A posed frame's drape carried from the rest pose's drape (drapeCarried, drape.hpp; issue #26).
//
// A skeleton or a host moves the skin every frame, and laying the whole coat again (drape.cpp) costs the
// coat's whole drape each frame. Here each feather keeps the chart it was laid on at rest, and every
// chart node moves with the skin point it was marched to (Node::face): where the skin moves rigidly the
// feather moves rigidly with it, where it bends the feather bends with it, as a groom bound to the skin
// does (MPC's mesh-driven feathers, ../shared/reference/how-others-lay-feathers.md). The drape's
// guarantees are then enforced as the drape enforces them, on the posed skin: material over a later
// follicle, vertices under the skin and the lower triangle of every crossing pair are trimmed. What did
// not move (skin, frame and flat mesh the same bits) is copied with what depends on it only.
//
// Where a whole piece of skin moves rigidly (a forearm under a bending elbow), a feather lying on it alone
// whose follicle frame and flat mesh moved with it is its rest drape moved by the piece's motion: nothing
// under or around it changed relative to it, so it is not placed again, and its trims, its under-skin test
// and its pairs with feathers on the same piece are the rest drape's. Only what it could meet off the
// piece is tested again: later follicles and skin not on the piece within reach, and every pair with a
// feather off the piece (RigidPieces below; DrapeOptions::rigidPieces).
#include "drape_internal.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace pteryla::coat::draping {

using glm::dvec3;

namespace {

// An orthonormal frame of face f (columns: first edge, normal x edge, normal).
glm::dmat3 faceFrame(const SkinMesh& s, size_t f) {
  const auto& t = s.faces[f];
  const dvec3 a = s.positions[t[0]], b = s.positions[t[1]], c = s.positions[t[2]];
  dvec3 e1 = b - a;
  const double l = glm::length(e1);
  e1 = l > 0 ? e1 / l : dvec3(1, 0, 0);
  dvec3 n = glm::cross(b - a, c - a);
  const double ln = glm::length(n);
  n = ln > 0 ? n / ln : s.faceNormals[f];
  n = glm::normalize(n - glm::dot(n, e1) * e1);
  return glm::dmat3(e1, glm::cross(n, e1), n);
}

glm::dmat3 frameBasis(const FeatherFrame& F) { return glm::dmat3(F.tangent, F.binormal, F.normal); }

// A laid chart's grid and nodes into `out` (all that placing a feather on it reads).
void copyGrid(const Chart& c, Chart& out) {
  out.x0 = c.x0;
  out.y0 = c.y0;
  out.hx = c.hx;
  out.hy = c.hy;
  out.diag = c.diag;
  out.nx = c.nx;
  out.ny = c.ny;
  out.ramp = c.ramp;
  out.scale = c.scale;
  out.nodes.assign(c.nodes.begin(), c.nodes.end());
}

// What a carried chart needs of a laid one: its grid and nodes, masks and counts (not what laying it
// gathered).
Chart chartShape(const Chart& c) {
  Chart out;
  copyGrid(c, out);
  out.material = c.material;
  out.fine = c.fine;
  out.active = c.active;
  out.overhanging = c.overhanging;
  out.faces = c.faces;
  return out;
}

// A rigid motion: p -> R p + t.
struct Motion {
  glm::dmat3 R{1.0};
  dvec3 t{0.0};
  dvec3 at(const dvec3& p) const { return R * p + t; }
};

// The pose's rigid pieces (issue #26: "where the skin moves rigidly, move the packed feather with its
// follicle frame"): moved faces whose corners and corner normals one rigid motion takes from rest to posed,
// within `tol` (positions) and kNormalTol (unit normals). Piece 0 is the unmoved skin; a face is given the
// first piece (in face order) whose motion takes it, or starts a new piece with its own motion.
struct RigidPieces {
  static constexpr double kRelTol = 1e-6;  // of the rest skin's bounding diagonal
  static constexpr double kNormalTol = 1e-6;
  static constexpr size_t kMaxPieces = 64;
  std::vector<int32_t> of;     // per face: 0 unmoved, g >= 1 its piece, -1 moved with no piece
  std::vector<Motion> motion;  // per piece (0: the identity)
  double tol = 0;

  RigidPieces(const SkinMesh& rest, const SkinMesh& posed, const std::vector<uint8_t>& movedFace,
              const std::vector<glm::dmat3>& turn, bool enabled) {
    const size_t nf = rest.faces.size();
    of.assign(nf, 0);
    motion.assign(1, Motion{});
    detail::Box bb;
    for (const dvec3& p : rest.positions) bb.add(p);
    tol = bb.empty() ? 0.0 : kRelTol * glm::length(bb.hi - bb.lo);
    for (size_t f = 0; f < nf; ++f) {
      if (!movedFace[f]) continue;
      int32_t g = -1;
      for (size_t q = 1; enabled && q < motion.size() && g < 0; ++q)
        if (faceMoves(rest, posed, f, motion[q])) g = static_cast<int32_t>(q);
      if (enabled && g < 0 && motion.size() < kMaxPieces) {
        const auto& t = rest.faces[f];
        const dvec3 cr = (rest.positions[t[0]] + rest.positions[t[1]] + rest.positions[t[2]]) / 3.0;
        const dvec3 cp = (posed.positions[t[0]] + posed.positions[t[1]] + posed.positions[t[2]]) / 3.0;
        const Motion M{turn[f], cp - turn[f] * cr};
        if (faceMoves(rest, posed, f, M)) {
          g = static_cast<int32_t>(motion.size());
          motion.push_back(M);
        }
      }
      of[f] = g;
    }
  }
  bool faceMoves(const SkinMesh& rest, const SkinMesh& posed, size_t f, const Motion& M) const {
    for (uint32_t v : rest.faces[f]) {
      const dvec3 d = posed.positions[v] - M.at(rest.positions[v]);
      if (!(glm::dot(d, d) <= tol * tol)) return false;
      const dvec3 e = posed.vertexNormals[v] - M.R * rest.vertexNormals[v];
      if (!(glm::dot(e, e) <= kNormalTol * kNormalTol)) return false;
    }
    return true;
  }
  // The piece whose motion takes follicle frame a (rest) to b (posed): 0 for the same frame, -1 for none.
  int32_t frameOf(const FeatherFrame& a, const FeatherFrame& b) const {
    if (sameFrame(a, b)) return 0;
    for (size_t q = 1; q < motion.size(); ++q)
      if (frameMoves(a, b, motion[q])) return static_cast<int32_t>(q);
    return -1;
  }
  bool frameMoves(const FeatherFrame& a, const FeatherFrame& b, const Motion& M) const {
    const dvec3 d = b.origin - M.at(a.origin);
    if (!(glm::dot(d, d) <= tol * tol)) return false;
    const dvec3 axes[3][2] = {{a.normal, b.normal}, {a.tangent, b.tangent}, {a.binormal, b.binormal}};
    for (const auto& q : axes) {
      const dvec3 e = q[1] - M.R * q[0];
      if (!(glm::dot(e, e) <= kNormalTol * kNormalTol)) return false;
    }
    return true;
  }
};

// Is feather i's flat mesh in `mesh` the memo's moved by M: the same triangles, each vertex within `tol`,
// its normal and tangent within kFlatAxisTol (16-bit data, each rounded from a float made along another
// path: up to 1.6e-5 a component either side)?
constexpr double kFlatAxisTol = 1e-4;
bool flatMoves(const FeatherMemo& m, const TriMesh& mesh, const CoatLayout& L, uint32_t i, const Motion& M,
               double tol) {
  auto near = [](const dvec3& d, double r) { return glm::dot(d, d) <= r * r; };
  return flatLike(m, mesh, L, i, [&](size_t q, uint32_t v, bool hasN, bool hasT) {
    return near(dvec3(mesh.positions[v]) - M.at(dvec3(m.flatPos[q])), tol) &&
           (!hasN || near(dvec3(mesh.normals[v].get()) - M.R * dvec3(m.flatNrm[q].get()), kFlatAxisTol)) &&
           (!hasT || near(dvec3(mesh.tangents[v].get()) - M.R * dvec3(m.flatTan[q].get()), kFlatAxisTol));
  });
}

// Is q within r of box b on every axis?
bool nearBox(const dvec3& q, const detail::Box& b, double r) {
  return q.x >= b.lo.x - r && q.y >= b.lo.y - r && q.z >= b.lo.z - r && q.x <= b.hi.x + r && q.y <= b.hi.y + r &&
         q.z <= b.hi.z + r;
}

// Does skin of `restTree` come within reach[l] of vertex l of m as it lay, or skin of `posedTree` within
// reach of it moved by M (null: where it lay)? Vertices the chart trimmed are not searched.
bool skinNear(const FeatherMemo& m, const std::vector<double>& reach, const detail::TriangleBvh& restTree,
              const detail::TriangleBvh& posedTree, const Motion* M) {
  dvec3 bary;
  double d2 = 0;
  for (size_t l = 0; l < m.pos.size(); ++l) {
    if (m.bad[l]) continue;
    const dvec3 p(m.pos[l]);
    const double rr = reach[l] * reach[l];
    if (restTree.nearest(p, rr, bary, d2) >= 0 || posedTree.nearest(M ? M->at(p) : p, rr, bary, d2) >= 0) return true;
  }
  return false;
}

// The bounds of a box's eight corners moved by M.
detail::Box movedBox(const detail::Box& b, const Motion& M) {
  detail::Box out;
  if (b.empty()) return out;
  for (int c = 0; c < 8; ++c)
    out.add(M.at(dvec3(c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z)));
  return out;
}

}  // namespace

DrapeResult carry(const SkinMesh& rest, const SkinMesh& posed, const CoatFeathers& coat, TriMesh& mesh,
                  const DrapeCache::State& R, const DrapeOptions& o, DrapeCache::State* out) {
  const auto t0 = std::chrono::steady_clock::now();
  const size_t n = coat.size(), nv = mesh.positions.size();
  if (mesh.featherId.size() != nv) throw Error("the coat mesh needs one featherId per vertex", {}, "featherId");
  if (coat.frames.size() != n || coat.params.size() != n)
    throw Error("the coat needs one frame and one parameter set per feather", {}, "frames");
  if (!R.valid) throw Error("the rest pose's coat has not been draped", {}, "reference");
  if (R.feathers.size() != n)
    throw Error(
        "the rest pose's drape has " + std::to_string(R.feathers.size()) + " feathers, this frame " + std::to_string(n),
        {}, "reference");
  if (!sameSkin(R.skin, rest)) throw Error("the rest pose's coat was draped over another skin", {}, "reference");
  if (posed.faces != rest.faces || posed.positions.size() != rest.positions.size() ||
      posed.vertexNormals.size() != rest.vertexNormals.size())
    throw Error("the posed skin is not the rest skin's mesh", {}, "skin");
  DrapeResult res;
  res.elevation.assign(n, 0.0);
  res.trimmed.assign(n, 0);
  res.hidden.assign(n, 0);
  res.stats.gap = R.gap;
  const CoatLayout L(coat, mesh);
  const std::vector<uint32_t>&first = L.first, &verts = L.verts, &trisOf = L.trisOf, &tris = L.tris;
  const std::vector<int64_t>& rank = L.rank;
  const std::vector<uint32_t>& order = L.order;
  for (uint32_t i : order)
    if (!R.feathers[i].laid) throw Error("feather " + std::to_string(i) + " has no reference drape", {}, "reference");
  {
    // This frame's layers keep the reference's order (feathers lost since may be missing).
    size_t k = 0;
    for (uint32_t i : R.order)
      if (k < order.size() && order[k] == i) ++k;
    if (k != order.size()) throw Error("the frame's layer order differs from the reference drape's", {}, "layerOrder");
  }
  const size_t nt = mesh.triangleCount();
  const bool hasN = mesh.normals.size() == nv, hasT = mesh.tangents.size() == nv;
  report(o.progress, "drape", 0);

  // Faces the pose moved (a corner or its normal), with the rotation that takes each from rest to posed.
  const size_t nf = rest.faces.size();
  std::vector<uint8_t> movedFace(nf, 0);
  std::vector<glm::dmat3> turn(nf, glm::dmat3(1.0));
  std::vector<uint32_t> movedIdx;  // the moved faces' corners, for the under-skin test below
  for (size_t f = 0; f < nf; ++f) {
    const auto& t = rest.faces[f];
    for (int c = 0; c < 3; ++c)
      if (rest.positions[t[c]] != posed.positions[t[c]] || rest.vertexNormals[t[c]] != posed.vertexNormals[t[c]])
        movedFace[f] = 1;
    if (!movedFace[f]) continue;
    turn[f] = faceFrame(posed, f) * glm::transpose(faceFrame(rest, f));
    movedIdx.insert(movedIdx.end(), t.begin(), t.end());
  }

  const RigidPieces pieces(rest, posed, movedFace, turn, o.rigidPieces);

  // Per feather: its chart carried by the skin, and whether anything of it moved. `piece`: 0 unmoved, g >= 1
  // moved rigidly with piece g (its chart's faces all on g, its frame moved by g's motion, its flat mesh
  // the reference's), -1 placed on its carried chart.
  std::vector<Chart> charts(n);
  std::vector<uint8_t> placed(n, 0);
  std::vector<int32_t> piece(n, -1);
  std::vector<glm::vec3> surfacePoint(nv);
  std::vector<uint8_t> bad(nv, 0), inside(nv, 0), overFollicle(nt, 0);
  if (out) {
    // The flat inputs, before placing moves them (drapeOverMature compares its frame's flat feathers).
    out->feathers.assign(n, FeatherMemo{});
  }
  detail::inArena(o.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        const uint32_t i = order[k];
        const FeatherMemo& m = R.feathers[i];
        const FeatherFrame& F = coat.frames[i];
        const bool footMoved = !sameFrame(m.frame, F);
        bool moved = footMoved;
        int32_t on = -2;  // the piece all its chart's faces lie on (-1: none, or more than one)
        for (int32_t f : m.chart.faces) {
          if (static_cast<size_t>(f) >= nf) throw Error("a chart node's face is out of range", {}, "reference");
          if (!moved && movedFace[static_cast<size_t>(f)]) moved = true;
          const int32_t g = pieces.of[static_cast<size_t>(f)];
          on = on == -2 || on == g ? g : -1;
        }
        const uint32_t* vs = verts.data() + first[i];
        const size_t cnt = first[i + 1] - first[i], tc = trisOf[i + 1] - trisOf[i];
        const bool same = !moved && sameFlat(m, mesh, L, i);
        const bool rigid = moved && on >= 1 && pieces.frameMoves(m.frame, F, pieces.motion[static_cast<size_t>(on)]) &&
                           flatMoves(m, mesh, L, i, pieces.motion[static_cast<size_t>(on)], pieces.tol);
        piece[i] = same ? 0 : rigid ? on : -1;
        // The reference's drape of the feather, with its trims and under-skin test: as it is, or moved by
        // its piece's motion M.
        auto copy = [&](const Motion* M = nullptr) {
          for (size_t l = 0; l < cnt; ++l) {
            const uint32_t v = vs[l];
            if (M) {
              mesh.positions[v] = glm::vec3(M->at(dvec3(m.pos[l])));
              if (hasN) mesh.normals[v] = glm::vec3(M->R * dvec3(m.nrm[l].get()));
              if (hasT) mesh.tangents[v] = glm::vec3(M->R * dvec3(m.tan[l].get()));
              surfacePoint[v] = glm::vec3(M->at(dvec3(m.surface[l])));
            } else {
              mesh.positions[v] = m.pos[l];
              if (hasN) mesh.normals[v] = m.nrm[l];
              if (hasT) mesh.tangents[v] = m.tan[l];
              surfacePoint[v] = m.surface[l];
            }
            bad[v] = m.bad[l];
            inside[v] = m.inside[l];
          }
          for (size_t q = 0; q < tc; ++q) overFollicle[tris[trisOf[i] + q]] = m.overFollicle[q];
          res.elevation[i] = m.elevation;
        };
        // The chart is copied only where this drape places the feather or keeps the chart.
        if (same && !out) {
          copy();
          continue;
        }
        if (rigid && !out) {
          copy(&pieces.motion[static_cast<size_t>(on)]);
          continue;
        }
        // Without `out` the carried chart only places the feather: it is made in this thread's scratch
        // (its grid and nodes, all that placing reads).
        thread_local Chart scratch;
        Chart& C = out ? charts[i] : scratch;
        if (out)
          C = chartShape(m.chart);
        else
          copyGrid(m.chart, C);
        // The follicle's motion carries what was marched to no skin point (the follicle's own node).
        const glm::dmat3 footTurn = frameBasis(F) * glm::transpose(frameBasis(m.frame));
        for (Node& nd : C.nodes) {
          if (!moved) break;
          if (nd.face < 0) {
            if (!footMoved) continue;
            nd.c = F.origin + footTurn * (nd.c - m.frame.origin);
            nd.n = footTurn * nd.n;
            nd.t = footTurn * nd.t;
            continue;
          }
          const auto f = static_cast<size_t>(nd.face);
          if (!movedFace[f]) continue;
          const glm::dvec3 bary(1 - nd.bu - nd.bv, nd.bu, nd.bv);
          const glm::dmat3& Rf = turn[f];
          const dvec3 p = pointAt(rest, static_cast<uint32_t>(f), bary),
                      q = pointAt(posed, static_cast<uint32_t>(f), bary);
          if (nd.free) {
            // Past the skin's edge: straight on from the last skin point, turned with its face.
            nd.c = q + Rf * (nd.c - p);
            nd.n = Rf * nd.n;
            nd.t = Rf * nd.t;
            continue;
          }
          nd.c = q + Rf * (nd.c - p);
          nd.n = normalAt(posed, static_cast<uint32_t>(f), bary);
          const dvec3 t = Rf * nd.t;
          const dvec3 tp = t - glm::dot(t, nd.n) * nd.n;
          const double tl = glm::length(tp);
          nd.t = tl > 1e-12 ? tp / tl : t;
        }
        if (out) {
          FeatherMemo& w = out->feathers[i];
          if (same) {
            w.flatPos = m.flatPos;
            w.flatNrm = m.flatNrm;
            w.flatTan = m.flatTan;
            w.flatTris = m.flatTris;
          } else {
            keepFlat(w, mesh, L, i);
          }
        }
        if (same) {
          copy();
        } else if (rigid) {
          copy(&pieces.motion[static_cast<size_t>(on)]);
        } else {
          placed[i] = 1;
          res.elevation[i] = placeOnChart(C, F, mesh, vs, cnt, hasN, hasT, surfacePoint, bad);
        }
      }
    });
  });
  report(o.progress, "drape", 0.3);

  // Copied feathers whose trims or under-skin test the pose can change are tested again (`changed`, with
  // the placed ones): a later follicle that moved near one's surface, moved skin near its vertices.
  std::vector<uint8_t> changed(placed);
  std::vector<uint32_t> movedFeet;
  for (uint32_t j : order)
    if (!sameFrame(R.feathers[j].frame, coat.frames[j])) movedFeet.push_back(j);
  detail::TriangleBvh movedRest, movedPosed;
  if (!movedIdx.empty()) {
    movedRest.build(rest.positions.data(), movedIdx.data(), movedIdx.size() / 3);
    movedPosed.build(posed.positions.data(), movedIdx.data(), movedIdx.size() / 3);
  }
  std::vector<uint8_t> retrim(n, 0);
  // The moved follicles, where they were and where they are (two points each), in a grid of the largest
  // root zone's reach.
  std::vector<dvec3> movedAt;
  double zoneMax = 0;
  for (uint32_t j : movedFeet) {
    movedAt.push_back(R.feathers[j].frame.origin);
    movedAt.push_back(coat.frames[j].origin);
    zoneMax = std::max(zoneMax, R.feathers[j].rootZone * (1 + 1e-6) + 1e-9);
  }
  detail::PointGrid movedGrid;
  if (!movedAt.empty()) movedGrid.build(movedAt, std::max(zoneMax, 1e-9));
  // The moved skin's bounds at rest and posed: a vertex whose reach meets neither finds no moved face.
  detail::Box movedBounds[2];
  for (int w = 0; w < 2 && !movedIdx.empty(); ++w) {
    glm::vec3 lo(0), hi(0);
    if (!(w ? movedPosed : movedRest).bounds(lo, hi)) continue;
    movedBounds[w].add(dvec3(lo));
    movedBounds[w].add(dvec3(hi));
  }
  // For the feathers moved with a piece: which piece moved each follicle, every follicle where it was and
  // where it is (grids by place in `order`), and per such piece the skin that is not on it within reach of
  // its feathers' vertex searches (a tree at rest and one posed).
  const size_t np = pieces.motion.size();
  std::vector<int32_t> footPiece(n, -1);
  std::vector<uint8_t> pieceUsed(np, 0);
  for (uint32_t j : order)
    if (piece[j] >= 1) pieceUsed[static_cast<size_t>(piece[j])] = 1;
  const bool anyRigid = std::find(pieceUsed.begin(), pieceUsed.end(), 1) != pieceUsed.end();
  std::vector<dvec3> restAt, posedAt;
  double zoneAll = 0;
  detail::PointGrid restGrid, posedGrid;
  std::vector<std::vector<uint32_t>> offIdx(2 * np);  // per piece: at rest, posed
  std::vector<detail::TriangleBvh> offTree(2 * np);
  // Where a vertex's search for the nearest skin point reaches: its height over its chart point, half a
  // chart cell, and the pieces' tolerance for the rounding of a moved copy.
  auto searchReach = [&](const FeatherMemo& m, size_t l) {
    return glm::length(dvec3(m.pos[l]) - dvec3(m.surface[l])) + 0.5 * m.chart.diag + pieces.tol;
  };
  if (anyRigid) {
    for (uint32_t j : order) {
      footPiece[j] = pieces.frameOf(R.feathers[j].frame, coat.frames[j]);
      restAt.push_back(R.feathers[j].frame.origin);
      posedAt.push_back(coat.frames[j].origin);
      zoneAll = std::max(zoneAll, R.feathers[j].rootZone * (1 + 1e-6) + 1e-9);
    }
    restGrid.build(restAt, std::max(zoneAll, 1e-9));
    posedGrid.build(posedAt, std::max(zoneAll, 1e-9));
    // Per piece, the bounds of its feathers' vertex searches, at rest and moved.
    std::vector<detail::Box> reachOf(2 * np);
    for (uint32_t i : order) {
      if (piece[i] < 1) continue;
      const FeatherMemo& m = R.feathers[i];
      const auto g = static_cast<size_t>(piece[i]);
      detail::Box b;
      for (size_t l = 0; l < m.pos.size(); ++l) {
        if (m.bad[l]) continue;
        const double r = searchReach(m, l);
        b.add(dvec3(m.pos[l]) - dvec3(r));
        b.add(dvec3(m.pos[l]) + dvec3(r));
      }
      reachOf[2 * g].add(b);
      reachOf[2 * g + 1].add(movedBox(b, pieces.motion[g]));
    }
    for (size_t g = 1; g < np; ++g) {
      if (!pieceUsed[g]) continue;
      for (int w = 0; w < 2; ++w) {
        const SkinMesh& s = w ? posed : rest;
        std::vector<uint32_t>& idx = offIdx[2 * g + w];
        for (size_t f = 0; f < nf; ++f) {
          if (pieces.of[f] == static_cast<int32_t>(g)) continue;
          detail::Box fb;
          for (uint32_t v : s.faces[f]) fb.add(s.positions[v]);
          if (fb.overlaps(reachOf[2 * g + w])) idx.insert(idx.end(), s.faces[f].begin(), s.faces[f].end());
        }
      }
    }
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(size_t(0), 2 * np, [&](size_t k) {
        if (!offIdx[k].empty())
          offTree[k].build((k % 2 ? posed : rest).positions.data(), offIdx[k].data(), offIdx[k].size() / 3);
      });
    });
  }
  // A feather moved with piece g: retrimmed where a later follicle not moved by g is within its root zone's
  // reach of the feather's surface points (at rest or posed), tested against the skin again where skin not
  // on g is within a vertex's search (at rest or posed).
  auto retestWithPiece = [&](uint32_t i, size_t k) {
    const FeatherMemo& m = R.feathers[i];
    const auto g = static_cast<size_t>(piece[i]);
    const Motion& M = pieces.motion[g];
    const double pad = pieces.tol;
    if (!m.box.empty()) {
      auto near = [&](const detail::PointGrid& grid, const std::vector<dvec3>& at, const detail::Box& b) {
        grid.query(b.lo - dvec3(zoneAll + pad), b.hi + dvec3(zoneAll + pad), [&](uint32_t a) {
          const uint32_t j = order[a];
          if (retrim[i] || a <= k || footPiece[j] == piece[i]) return;
          if (nearBox(at[a], b, R.feathers[j].rootZone * (1 + 1e-6) + 1e-9 + pad)) retrim[i] = 1;
        });
      };
      near(restGrid, restAt, m.box);
      near(posedGrid, posedAt, movedBox(m.box, M));
    }
    const detail::TriangleBvh &offRest = offTree[2 * g], &offPosed = offTree[2 * g + 1];  // (empty: no skin)
    if (offRest.empty() && offPosed.empty()) return;
    const size_t cnt = first[i + 1] - first[i];
    thread_local std::vector<double> reach;
    reach.assign(cnt, 0.0);
    detail::Box within;
    for (size_t l = 0; l < cnt; ++l) {
      if (m.bad[l]) continue;
      const dvec3 p(m.pos[l]);
      reach[l] = searchReach(m, l);
      within.add(p - dvec3(reach[l]));
      within.add(p + dvec3(reach[l]));
    }
    if (within.empty()) return;
    // The whole feather first: a ball around all its vertices' searches.
    const dvec3 c = 0.5 * (within.lo + within.hi);
    const double rad = 0.5 * glm::length(within.hi - within.lo) + pad;
    dvec3 bary;
    double d2 = 0;
    if (offRest.nearest(c, rad * rad, bary, d2) < 0 && offPosed.nearest(M.at(c), rad * rad, bary, d2) < 0) return;
    if (skinNear(m, reach, offRest, offPosed, &M)) changed[i] = 1;
  };
  detail::inArena(o.threads, [&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        const uint32_t i = order[k];
        if (placed[i]) continue;
        if (piece[i] >= 1) {
          retestWithPiece(i, k);
          continue;
        }
        const FeatherMemo& m = R.feathers[i];
        // A later follicle that moved within its root zone's reach of the feather's box.
        if (!m.box.empty() && !movedAt.empty())
          movedGrid.query(m.box.lo - dvec3(zoneMax), m.box.hi + dvec3(zoneMax), [&](uint32_t a) {
            const uint32_t j = movedFeet[a / 2];
            if (retrim[i] || rank[j] <= static_cast<int64_t>(k)) return;
            if (nearBox(movedAt[a], m.box, R.feathers[j].rootZone * (1 + 1e-6) + 1e-9)) retrim[i] = 1;
          });
        if (movedIdx.empty() || changed[i]) continue;
        // The nearest skin point of a vertex lies within its height over its chart point and half a chart
        // cell; moved skin (at rest or posed) that close can change which side of the skin it is on.
        const double cell = 0.5 * m.chart.diag;
        const size_t cnt = first[i + 1] - first[i];
        thread_local std::vector<double> reach;
        reach.assign(cnt, 0.0);
        detail::Box within;  // where the vertices' searches reach
        for (size_t l = 0; l < cnt; ++l) {
          if (m.bad[l]) continue;
          const dvec3 p(m.pos[l]);
          reach[l] = glm::length(p - dvec3(m.surface[l])) + cell;
          within.add(p - dvec3(reach[l]));
          within.add(p + dvec3(reach[l]));
        }
        if (!within.overlaps(movedBounds[0]) && !within.overlaps(movedBounds[1])) continue;
        if (skinNear(m, reach, movedRest, movedPosed, nullptr)) changed[i] = 1;
      }
    });
  });
  std::vector<uint32_t> trimList, insideList;
  for (uint32_t i : order) {
    if (placed[i] || retrim[i]) {
      trimList.push_back(i);
      changed[i] = 1;
      for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) overFollicle[tris[q]] = 0;
    }
    if (changed[i]) insideList.push_back(i);
  }
  {
    std::vector<dvec3> origins;
    std::vector<double> rootZone(n, 0.0);
    double reachMax = 0;
    for (uint32_t i : order) {
      origins.push_back(coat.frames[i].origin);
      rootZone[i] = R.feathers[i].rootZone;
      reachMax = std::max(reachMax, rootZone[i]);
    }
    detail::PointGrid grid;
    grid.build(origins, std::max(reachMax, 1e-12));
    const RootZones zones{order, coat, rootZone, reachMax, grid};
    detail::inArena(o.threads, [&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, trimList.size(), 4), [&](const tbb::blocked_range<size_t>& r) {
        std::vector<LaterZone> later;
        for (size_t z = r.begin(); z < r.end(); ++z) {
          const uint32_t i = trimList[z];
          trimOverFollicles(zones, static_cast<size_t>(rank[i]), mesh, tris.data() + trisOf[i],
                            trisOf[i + 1] - trisOf[i], surfacePoint, bad, overFollicle, later);
        }
      });
    });
  }
  if (!insideList.empty()) {
    CheckOptions co;
    setFeatherBases(co, coat, o.baseAllowance);
    insideSkinFor(posed, mesh, L, insideList, co, inside);
  }
  report(o.progress, "drape", 0.6);
  // Keep what drapeOverMature reads of this drape before trimming moves vertices.
  if (out)
    for (uint32_t i : order) {
      FeatherMemo& w = out->feathers[i];
      keepPlaced(w, mesh, L, i, surfacePoint, bad);
      const size_t cnt = first[i + 1] - first[i];
      w.inside.resize(cnt);
      for (size_t l = 0; l < cnt; ++l) w.inside[l] = inside[verts[first[i] + l]];
      const size_t tc = trisOf[i + 1] - trisOf[i];
      w.overFollicle.resize(tc);
      for (size_t q = 0; q < tc; ++q) w.overFollicle[q] = overFollicle[tris[trisOf[i] + q]];
    }
  for (uint32_t v = 0; v < nv; ++v)
    if (inside[v]) bad[v] = 1;
  std::vector<size_t> kept(n, 0), cut(n, 0);
  auto collapse = [&](size_t t) { collapseTriangle(mesh, t, cut); };
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    if (overFollicle[t] || bad[tri[0]] || bad[tri[1]] || bad[tri[2]]) collapse(t);
  }
  for (uint32_t v = 0; v < nv; ++v)
    if (bad[v] && rank[mesh.featherId[v]] >= 0) mesh.positions[v] = glm::vec3(coat.frames[mesh.featherId[v]].origin);
  // Crossing pairs: the rest drape's pairs of two unchanged feathers' live triangles, and those of the
  // changed feathers' triangles searched here.
  std::vector<uint64_t> pairs;
  for (const PairMemo& pm : R.pairs) {
    if (rank[pm.fa] < 0 || rank[pm.fb] < 0 || changed[pm.fa] || changed[pm.fb] || piece[pm.fa] != piece[pm.fb])
      continue;
    const uint32_t t = tris[trisOf[pm.fa] + pm.ta], u = tris[trisOf[pm.fb] + pm.tb];
    if (isCut(mesh, t) || isCut(mesh, u)) continue;
    pairs.push_back((uint64_t(std::min(t, u)) << 32) | std::max(t, u));
  }
  {
    std::vector<uint8_t> changedTri(nt, 0);
    for (uint32_t i : order)
      if (changed[i])
        for (uint32_t q = trisOf[i]; q < trisOf[i + 1]; ++q) changedTri[tris[q]] = 1;
    const std::vector<uint64_t> found =
        R.pairTrees ? pairsWithChanged(mesh, order, trisOf, tris, changedTri, *R.pairTrees, &piece)
                    : pairsWithChanged(mesh, order, trisOf, tris, changedTri, {}, &piece);
    pairs.insert(pairs.end(), found.begin(), found.end());
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<uint8_t> preCut;
  if (out) {
    preCut.resize(nt);
    for (size_t t = 0; t < nt; ++t) preCut[t] = isCut(mesh, t) ? 1 : 0;
  }
  for (uint64_t pr : pairs) {
    const size_t t = pr >> 32, u = pr & 0xffffffffu;
    const uint32_t ft = mesh.featherId[mesh.indices[3 * t]], fu = mesh.featherId[mesh.indices[3 * u]];
    collapse(rank[ft] < rank[fu] ? t : u);
  }
  for (size_t t = 0; t < nt; ++t)
    if (!isCut(mesh, t)) ++kept[mesh.featherId[mesh.indices[3 * t]]];
  tally(res, order, cut, kept,
        [&](uint32_t i) -> const Chart& { return charts[i].nodes.empty() ? R.feathers[i].chart : charts[i]; });
  size_t placedCount = 0;
  for (uint32_t i : order) {
    placedCount += placed[i];
    res.stats.rigid += piece[i] >= 1 ? 1 : 0;
  }
  res.stats.relaid = placedCount;
  res.stats.reused = order.size() - placedCount;
  if (out) {
    DrapeCache::State& W = *out;
    W.skin = posed;
    W.surface = std::make_unique<Surface>(W.skin);
    W.gapOption = R.gapOption;
    W.spacingOption = R.spacingOption;
    W.maxSlope = R.maxSlope;
    W.baseAllowance = R.baseAllowance;
    W.gridAlong = R.gridAlong;
    W.gridAcross = R.gridAcross;
    W.gap = R.gap;
    W.spacing = R.spacing;
    W.airRadius = R.airRadius;
    W.top.reset();
    W.order = order;
    W.carried = true;
    for (uint32_t i : order) {
      const FeatherMemo& m = R.feathers[i];
      FeatherMemo& w = W.feathers[i];
      w.laid = true;
      w.frame = coat.frames[i];
      w.rachisWidth = m.rachisWidth;
      w.calamusLength = m.calamusLength;
      w.totalLength = m.totalLength;
      w.baseRadius = m.baseRadius;
      w.shrink = m.shrink;
      w.scale = m.scale;
      w.flatEdge = m.flatEdge;
      w.reach = m.reach;
      w.rootZone = m.rootZone;
      w.elevation = res.elevation[i];
      w.chart = std::move(charts[i]);
      const size_t tc = trisOf[i + 1] - trisOf[i];
      w.preCut.resize(tc);
      w.cut.resize(tc);
      for (size_t q = 0; q < tc; ++q) {
        w.preCut[q] = preCut[tris[trisOf[i] + q]];
        w.cut[q] = isCut(mesh, tris[trisOf[i] + q]) ? 1 : 0;
      }
    }
    W.pairs = pairMemos(pairs, mesh, L);
    W.valid = true;
  }
  report(o.progress, "drape", 1);
  res.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace pteryla::coat::draping
