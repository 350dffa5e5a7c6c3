#pragma once
// The draped packer's parts (drape.cpp): surface charts and how a chart reads and writes the coat's top
// (drape_chart.cpp), trims over later follicles and the crossing pairs near changed triangles
// (drape_trim.cpp), and what a DrapeCache keeps of a drape with the over-mature drape (drape_cache.cpp).
// Internal to src/coat.
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include <glm/vec3.hpp>

#include "pteryla/coat/check.hpp"
#include "pteryla/coat/drape.hpp"
#include "pteryla/core/error.hpp"
#include "drape_surfaces.hpp"
#include "spatial.hpp"

namespace pteryla::coat::draping {

// The chart of one feather: a grid of nodes over its flat footprint (vertices verts[0..count) of `mesh`,
// scaled by `scale` about the follicle of frame F), marched over the skin from the follicle along the
// feather and across it (Surface::march), with the nodes next to material marked active.
void buildChart(const Surface& S, const FeatherFrame& F, const feather::FeatherParams& p, const TriMesh& mesh,
                const uint32_t* verts, size_t count, double scale, const DrapeOptions& o, Chart& C);

// Does a cell holding material fold (corner normals on the skin more than 40 degrees apart) or have a
// corner the chart did not reach?
bool foldsOrLeaves(const Chart& C);

// Per node: the curvature of the skin toward its chart neighbours (normal turn over distance) and the
// dip of a chord of length `edge` there.
void setSag(Chart& C, double edge);

// Layer order agrees with the feathers: a feather never covers the follicle of a feather laid after it
// (that feather would rise out of the skin through it). The flat footprint (a raster of where the
// feather has vertices, local x, y) is tested against the root zones of the later follicles in reach,
// taken into the feather's tangent plane; the feather is scaled about its follicle by the largest factor
// in [minScale, 1] that covers none (bisection).
double shrinkScale(const FeatherFrame& F, const TriMesh& mesh, const uint32_t* verts, size_t count,
                   const std::vector<std::pair<glm::dvec2, double>>& later, int rx, int ry, double minScale);

// Gathers what laying a chart reads: its active nodes, the samples facing each within reqRadius, and the
// samples under its material (their chart coordinates from the nearest-in-order node's frame that reaches
// them; each sample once, cells whose corners are all on the chart).
void gatherSamples(Chart& C, const CoatTop& top, double reqRadius);

// What laying a chart reads of the coat laid so far: per active node the highest top among its
// requirement samples (and past the skin's edge, the highest laid point over it), then the top at every
// sample under its material. Laying depends on nothing else but the chart: equal reads, equal heights.
void readChart(const Chart& C, const CoatTop& top, const AirTop& air, std::vector<double>& reads);

// Heights of one chart's active nodes over the skin from what it read (readChart): above the coat's top
// near each node by the gap, as the smallest function with slope <= maxSlope over those requirements.
void layFromReads(Chart& C, const std::vector<double>& reads, double gap, double maxSlope, std::vector<double>& req);

// The laid feather becomes the coat's top over the samples its material covers (writeChart), and its
// nodes join the coat in the air (addToAir; only a chart with free nodes reads the air, readsAir).
void writeChart(const Chart& C, CoatTop& top);

void addToAir(const Chart& C, AirTop& air);

bool readsAir(const Chart& C);

// Moves a feather's vertices (vs[0..count), flat, at elevation 0 in frame F) onto its laid chart: each to
// its chart point plus its height along the chart normal, normals and tangents turned with the chart
// frame. Vertices over a cell that folds or that the chart did not reach are marked bad (trimmed).
// Returns the feather's elevation: the steepest rise of the spine's nodes past the calamus.
double placeOnChart(const Chart& C, const FeatherFrame& F, TriMesh& mesh, const uint32_t* vs, size_t count, bool hasN,
                    bool hasT, std::vector<glm::vec3>& surfacePoint, std::vector<uint8_t>& bad);

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
                              std::vector<uint8_t>& overFollicle, std::vector<LaterZone>& later);

inline bool isCut(const TriMesh& mesh, size_t t) {
  const uint32_t* tri = &mesh.indices[3 * t];
  return tri[1] == tri[0] && tri[2] == tri[0];
}

// Collapses triangle t of `mesh` (its corners onto the first: it meets nothing and draws nothing) and
// counts it in cut[its feather]; a triangle collapsed already is left as it is.
inline void collapseTriangle(TriMesh& mesh, size_t t, std::vector<size_t>& cut) {
  uint32_t* tri = &mesh.indices[3 * t];
  if (tri[1] == tri[0] && tri[2] == tri[0]) return;
  tri[1] = tri[2] = tri[0];
  ++cut[mesh.featherId[tri[0]]];
}

// The crossing pairs of live triangles (t < u, as t << 32 | u) with at least one changed triangle: the
// pair search over the live triangles of every feather whose live bounds meet those of a feather with a
// changed live triangle. A pair's test depends on its two triangles alone (and which comes first in the
// mesh, kept here), so these are exactly the changed triangles' pairs of a search over the whole coat.
// With `piece` (per feather), pairs of two feathers on different pieces count as changed too (a carried
// frame's feathers moved with different rigid pieces of skin, drape_carry.cpp).
std::vector<uint64_t> pairsWithChanged(const TriMesh& mesh, const std::vector<uint32_t>& order,
                                       const std::vector<uint32_t>& trisOf, const std::vector<uint32_t>& tris,
                                       const std::vector<uint8_t>& changedTri, const ProgressFn& progress,
                                       const std::vector<int32_t>* piece = nullptr);

// Per feather, a pair tree over its triangles (in CoatLayout order) that a reference drape keeps for the
// frames carried from it: each search refits it to the frame's corners, and builds it again only where
// the feather's triangle count changed (a growing feather). Between searches its corner pointers are
// stale; a search holds the lock.
struct PairTrees {
  std::mutex lock;
  std::vector<detail::TriangleBvh> tree;
  std::vector<uint32_t> count;  // triangles each tree was built over
};

// The same pairs, the feathers' trees taken from `cache` and refitted (a carried frame's search).
std::vector<uint64_t> pairsWithChanged(const TriMesh& mesh, const std::vector<uint32_t>& order,
                                       const std::vector<uint32_t>& trisOf, const std::vector<uint32_t>& tris,
                                       const std::vector<uint8_t>& changedTri, PairTrees& cache,
                                       const std::vector<int32_t>* piece = nullptr);

// Where laying a chart reads the coat in the air: around its free nodes, within the air radius of the
// line along the normal, to a depth of a quarter of its length (AirTop::highest's reach, and a little).
detail::Box airReadBox(const Chart& C, double airRadius);

// Where laying a chart reads: its requirement and covered samples, and the air (airReadBox).
detail::Box readBoxOf(const Chart& C, const CoatTop& top, double airRadius);

// Where a laid chart writes: the samples under its material, and its nodes' lifted points (the air).
detail::Box writeBoxOf(const Chart& C, const CoatTop& top);

// What the last drape kept of one feather (DrapeCache).
struct FeatherMemo {
  bool laid = false;  // it was draped
  // Inputs: the follicle frame, what the drape reads of the parameters, the flat mesh.
  FeatherFrame frame;
  double rachisWidth = 0, calamusLength = 0, totalLength = 0, baseRadius = 0;
  std::vector<glm::vec3> flatPos;
  std::vector<PackedDir> flatNrm, flatTan;
  std::vector<uint32_t> flatTris;  // local vertex indices
  // Outputs.
  double shrink = 1, scale = 1, flatEdge = 0, reach = 0, rootZone = 0, elevation = 0;
  Chart chart;                   // laid, after the fold test, with what it gathered
  std::vector<uint32_t> folded;  // nodes the fold test cleared
  std::vector<double> reads;     // what laying it read (readChart)
  std::vector<glm::vec3> pos, surface;
  std::vector<PackedDir> nrm, tan;
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
                   const std::vector<uint32_t>& feathers, const CheckOptions& co, std::vector<uint8_t>& inside);

// Is feather i of `mesh` (flat, as given to a drape) the one a memo was made from: the same vertices
// (positions, normals, tangents where the mesh has them) and triangles, in the same order?
bool sameFlat(const FeatherMemo& m, const TriMesh& mesh, const CoatLayout& L, uint32_t i);

// The test behind it, with the vertices compared by `like(q, v, hasN, hasT)` (memo vertex q, mesh vertex
// v): the same counts, each vertex alike, and the same triangles in the same local vertex indices.
template <class Like>
bool flatLike(const FeatherMemo& m, const TriMesh& mesh, const CoatLayout& L, uint32_t i, Like&& like) {
  const uint32_t* vs = L.verts.data() + L.first[i];
  const size_t cnt = L.first[i + 1] - L.first[i], tc = L.trisOf[i + 1] - L.trisOf[i];
  const bool hasN = mesh.normals.size() == mesh.positions.size(), hasT = mesh.tangents.size() == mesh.positions.size();
  if (m.flatPos.size() != cnt || m.flatTris.size() != 3 * tc) return false;
  if ((hasN && m.flatNrm.size() != cnt) || (hasT && m.flatTan.size() != cnt)) return false;
  for (size_t q = 0; q < cnt; ++q)
    if (!like(q, vs[q], hasN, hasT)) return false;
  for (size_t q = 0; q < tc; ++q)
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = mesh.indices[3 * static_cast<size_t>(L.tris[L.trisOf[i] + q]) + c];
      if (mesh.featherId[v] != i || m.flatTris[3 * q + c] != L.localVert[v]) return false;
    }
  return true;
}

// Keeps in m feather i's flat inputs as `mesh` holds them (before a drape moves them): its vertices'
// positions, normals and tangents (where the mesh has them) and its triangles in local vertex indices.
void keepFlat(FeatherMemo& m, const TriMesh& mesh, const CoatLayout& L, uint32_t i);

// Keeps in m what a drape placed of feather i before its trims move vertices: positions, normals and
// tangents (where the mesh has them), surface points and the chart's trims.
void keepPlaced(FeatherMemo& m, const TriMesh& mesh, const CoatLayout& L, uint32_t i,
                const std::vector<glm::vec3>& surfacePoint, const std::vector<uint8_t>& bad);

// The drape's counts: draped feathers, overhanging nodes of their charts, and those that lost triangles
// (`cut` per feather) or every triangle (`kept` none).
void tally(DrapeResult& res, const std::vector<uint32_t>& order, const std::vector<size_t>& cut,
           const std::vector<size_t>& kept, const std::function<const Chart&(uint32_t)>& chartOf);

// A crossing pair of triangles, as feather and triangle within the feather.
struct PairMemo {
  uint32_t fa, ta, fb, tb;
};

// Crossing pairs of mesh triangles (t << 32 | u) as a cache keeps them: feather and triangle within it.
std::vector<PairMemo> pairMemos(const std::vector<uint64_t>& pairs, const TriMesh& mesh, const CoatLayout& L);

bool sameSkin(const SkinMesh& a, const SkinMesh& b);

bool sameFrame(const FeatherFrame& a, const FeatherFrame& b);

template <class T>
bool sameRange(const std::vector<T>& a, const T* b, size_t count) {
  return a.size() == count && std::equal(a.begin(), a.end(), b);
}

// drapeCarried (drape.hpp): the posed frame from the rest pose's drape R; with `out`, keeps it there.
DrapeResult carry(const SkinMesh& rest, const SkinMesh& posed, const CoatFeathers& coat, TriMesh& mesh,
                  const DrapeCache::State& R, const DrapeOptions& o, DrapeCache::State* out);

// drapeOverMature (drape.hpp), over the mature coat's drape M.
DrapeResult drapeOver(const SkinMesh& skin, const CoatFeathers& coat, TriMesh& mesh, const DrapeCache::State& M,
                      const DrapeOptions& o);

}  // namespace pteryla::coat::draping

namespace pteryla::coat {

struct DrapeCache::State {
  bool valid = false;
  SkinMesh skin;  // the skin it was laid on (the Surface refers to it)
  std::unique_ptr<draping::Surface> surface;
  double gapOption = 0, spacingOption = 0, maxSlope = 0, baseAllowance = 0;
  int gridAlong = 0, gridAcross = 0;
  double gap = 0, spacing = 0, airRadius = 0;
  std::unique_ptr<draping::CoatTop> top;
  std::vector<draping::FeatherMemo> feathers;
  std::vector<uint32_t> order;
  std::vector<draping::PairMemo> pairs;
  // Pair trees for the frames carried from this drape (drapeCarried): a cache, not part of the result.
  mutable std::unique_ptr<draping::PairTrees> pairTrees = std::make_unique<draping::PairTrees>();
  // The skin of the last drape and how many drapes in a row found it moved (drapeCoatMesh).
  std::vector<glm::dvec3> lastSkin;
  int skinMoves = 0;
  bool keepAlways = false;  // keep every drape (drapeOverMature reads the mature coat's)
  // Carried from a rest pose's drape (drapeCarried): its charts were not marched on this skin, so a drape
  // lays everything again rather than reuse them.
  bool carried = false;
};

struct DrapeAccess {
  static DrapeCache::State& state(DrapeCache& c) { return *c.state_; }
  static const DrapeCache::State& state(const DrapeCache& c) { return *c.state_; }
};

}  // namespace pteryla::coat
