#pragma once
// An independent check of a packed coat at full geometry (it does not trust the packer, Streit 2003,
// 6.3.4 / 9.1.2 claims "no feather-model or feather-feather interpenetrations"):
//  - intersecting_pairs: pairs of triangles of different feathers that intersect (a BVH per feather and
//    one over the feathers' bounds, shared with the coverage rays; only feathers whose bounds meet are
//    searched, tree against tree, which visits every pair of their triangles with overlapping boxes;
//    Moeller's triangle-triangle test in double precision, parallel);
//  - skin_penetrations: coat vertices (barb and shaft samples) below the skin: the sign of the offset to
//    the nearest skin point against the angle-weighted pseudo-normal of the nearest feature, which is
//    "inside" for closed meshes and "below the local surface" for open ones (points whose nearest skin
//    point lies on a boundary are outside by definition);
//  - coverage: the fraction of tract area whose outward normal ray hits a feather triangle (area-uniform
//    samples on the tract faces).
#include <glm/vec3.hpp>

#include <cstdint>
#include <optional>
#include <vector>

#include "pteryla/coat/coat_feathers.hpp"
#include "pteryla/coat/skin.hpp"
#include "pteryla/core/progress.hpp"
#include "pteryla/core/trimesh.hpp"

namespace pteryla::coat {

struct CheckOptions {
  bool intersections = true;
  bool penetrations = true;
  bool coverage = true;
  size_t coverageSamples = 20000;
  uint64_t seed = 1;          // coverage sample positions
  double skinTolerance = 0;   // scene units below the surface still counted as on it; 0 = auto (1e-6 x skin diagonal)
  double rayOffset = 0;       // scene units the coverage rays start above the skin; 0 = auto (1e-6 x skin diagonal)
  double maxRayDistance = 0;  // scene units; 0 = unlimited
  // Coat vertices of feather f within featherBaseRadius[f] of featherOrigins[f] are exempt from the skin
  // test (the calamus sits in its follicle). Empty = no exemption; see setFeatherBases().
  std::vector<glm::dvec3> featherOrigins;
  std::vector<double> featherBaseRadius;
  int threads = 0;  // 0 = all available
  // The straightforward search, kept to test the fast one against (same numbers, slower): one BVH over
  // the whole coat whose self-traversal gives the candidate pairs and which the coverage rays walk,
  // Moeller's test computed from scratch for each candidate, an unbounded nearest-skin search per vertex.
  bool reference = false;
  // Diagnostics: also list which feathers the intersecting pairs and skin penetrations belong to
  // (CheckResult::featherPairs, featherPenetrations). The counts are the same either way.
  bool attribute = false;
  // Called on the calling thread with ("check", fraction of the work done), several times per part
  // (the feather trees, the pair search, the skin test, the coverage rays). Returning false stops the check within a
  // fraction of a part: the result then has complete = false and holds only the parts finished.
  // An exception thrown by it leaves check() the same way.
  ProgressFn progress;
};

// Intersecting triangle pairs between two feathers (a < b): `pairs` of their triangles intersect.
struct FeatherPairCount {
  uint32_t a = 0, b = 0;
  uint32_t pairs = 0;
};

struct CheckResult {
  size_t intersectingPairs = 0;
  size_t coatTriangles = 0;
  size_t skinPenetrations = 0;
  size_t samplePoints = 0;                    // coat vertices tested against the skin
  std::vector<uint32_t> penetratingFeathers;  // featherIds with a penetrating vertex, ascending
  double coverage = 0;                        // [0,1]
  size_t coverageSamples = 0, coveredSamples = 0;
  double seconds = 0;
  bool complete = false;  // false: CheckOptions::progress asked to stop
  // CheckOptions::attribute only: per pair of feathers the intersecting triangle pairs (sorted by a, b;
  // the counts sum to intersectingPairs), and per featherId the penetrating vertices (sums to
  // skinPenetrations; sized to the largest featherId + 1).
  std::vector<FeatherPairCount> featherPairs;
  std::vector<uint32_t> featherPenetrations;
  std::vector<uint32_t> faceSamples, faceUncovered;  // per skin face: coverage samples, of them not covered
};

// `tractFaces`: skin triangle indices the coverage is measured on (empty = every face). The coat's
// featherId attribute tells which triangles belong to the same feather (required for intersections).
CheckResult check(const SkinMesh& skin, const std::vector<uint32_t>& tractFaces, const TriMesh& coat,
                  const CheckOptions& options = {});

// Only the intersecting pair count.
size_t countIntersectingPairs(const TriMesh& coat, int threads = 0);
// The same with progress ("check", as CheckOptions::progress): nullopt when the callback asked to stop.
std::optional<size_t> countIntersectingPairs(const TriMesh& coat, const ProgressFn& progress, int threads = 0);
// The intersecting pairs per pair of feathers (FeatherPairCount, sorted; counts sum to
// countIntersectingPairs).
std::vector<FeatherPairCount> intersectingFeatherPairs(const TriMesh& coat, int threads = 0);
// Every intersecting triangle pair of different feathers as (t << 32 | u), t < u, sorted.
std::vector<uint64_t> intersectingTrianglePairs(const TriMesh& coat);
// The same with progress ("check", as CheckOptions::progress): empty when the callback asked to stop.
std::vector<uint64_t> intersectingTrianglePairs(const TriMesh& coat, const ProgressFn& progress);
// The same, only for pairs with a triangle of a feather `feathers` marks (indexed by featherId; shorter
// means unmarked): exactly those pairs of intersectingTrianglePairs(coat).
std::vector<uint64_t> intersectingTrianglePairsWith(const TriMesh& coat, const std::vector<uint8_t>& feathers,
                                                    const ProgressFn& progress = {});
// Per coat vertex: 1 when check() counts it as a skin penetration (the same test, the same exemptions).
// Reports to options.progress during the search; empty when it asked to stop.
std::vector<uint8_t> verticesInsideSkin(const SkinMesh& skin, const TriMesh& coat, const CheckOptions& options);

// Fills featherOrigins / featherBaseRadius from the coat: radius = baseAllowance x total feather length
// (use the same value as PackOptions::baseAllowance), at least the calamus radius.
void setFeatherBases(CheckOptions& options, const CoatFeathers& coat, double baseAllowance);

// A simple full-geometry stand-in for the feather mesher: each vane as triangle strips between
// consecutive barbs (barb polylines from feather::generateBarbs), the shaft as a ribbon in the vane plane;
// unopened feathers (age < openingAge) as a straight ribbon. featherId = feather index.
struct ProxyMeshOptions {
  int barbStride = 1;    // use every n-th barb
  int barbSegments = 4;  // polyline segments per barb
  int shaftSegments = 12;
  double openingAge = 0.8;
};
TriMesh proxyCoatMesh(const CoatFeathers& coat, const std::vector<double>& elevation,
                      const std::vector<feather::FeatherParams>& params, const ProxyMeshOptions& options = {});

}  // namespace pteryla::coat
